//! A flag on its pole in the wind: F = c A (n·d) n on every triangle.
//!
//! `cargo run --release --example flag`

use cloth3d::prelude::*;

fn main() -> Result<(), ClothError> {
    let mut cloth = Simulation::new(
        ClothBuilder::new(32, 20)
            .size(1.6, 1.0)
            .vertical(Vector::new(0.8, 1.5, 0.0))
            .material(Material::silk())
            .pins(PinPreset::FlagColumn)
            .build()?,
    );
    cloth.params.wind = Wind::new(Vector::new(1.0, 0.0, 0.3), 8.0);
    for frame in 1..=240 {
        // Gusts: the wind strength breathes between 4 and 12 N/m².
        cloth.params.wind.strength = 8.0 + 4.0 * (frame as f32 * 0.05).sin();
        cloth.step(1.0 / 60.0, &[])?;
        if frame % 60 == 0 {
            let tip = cloth.positions()[cloth.index(10, 31)?];
            println!(
                "t = {:.0} s  flag tip at ({:+.2}, {:+.2}, {:+.2}) m",
                cloth.time(),
                tip.x,
                tip.y,
                tip.z
            );
        }
    }
    Ok(())
}
