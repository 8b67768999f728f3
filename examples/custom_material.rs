//! A material of your own, compared with the presets on the same hanging cloth.
//!
//! `cargo run --release --example custom_material`

use cloth3d::prelude::*;

fn main() -> Result<(), ClothError> {
    let chainmail = Material::new(
        "chainmail",
        SpringParams::new(20_000.0, 2.0), // stretch: N/m, N·s/m
        SpringParams::new(50.0, 0.5),     // shear: it shears freely
        SpringParams::new(0.5, 0.05),     // bend: it drapes like liquid
        6.0,                              // kg/m²
        [0.6, 0.6, 0.65],
    );
    let mut materials = Material::presets();
    materials.push(chainmail);
    for material in materials {
        let name = material.name.clone();
        let mut cloth = Simulation::new(
            ClothBuilder::new(24, 24)
                .vertical(Vector::new(0.0, 1.0, 0.0))
                .material(material)
                .mass_from_density()
                .pins(PinPreset::TwoCorners)
                .build()?,
        )
        .with_integrator(Integrator::ImplicitEuler);
        for _ in 0..120 {
            cloth.step(1.0 / 60.0, &[])?;
        }
        println!(
            "{name:<10} {:5.2} kg  sag {:.3} m  stretch {:5.2}%",
            cloth.total_mass(),
            1.5 - cloth
                .positions()
                .iter()
                .map(|p| p.y)
                .fold(f32::INFINITY, f32::min),
            100.0 * cloth.max_strain(SpringKind::Stretch)
        );
    }
    Ok(())
}
