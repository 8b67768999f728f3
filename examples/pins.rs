//! Pinning: presets, pins by (row, column), releasing a pin at run time.
//!
//! `cargo run --release --example pins`

use cloth3d::prelude::*;

fn main() -> Result<(), ClothError> {
    let mut cloth = Simulation::new(
        ClothBuilder::new(33, 33)
            .horizontal(Vector::new(0.0, 0.6, 0.0))
            .pins(PinPreset::FourCorners)
            .build()?,
    );
    for _ in 0..60 {
        cloth.step(1.0 / 60.0, &[])?;
    }
    println!(
        "hanging from four corners: lowest point {:.3} m",
        lowest(&cloth)
    );
    // Let go of one corner and pin the middle instead.
    cloth.unpin_cell(32, 32)?;
    cloth.pin_cell(16, 16)?;
    for _ in 0..120 {
        cloth.step(1.0 / 60.0, &[])?;
    }
    println!("one corner released: lowest point {:.3} m", lowest(&cloth));
    println!("pinned now: {:?}", cloth.pinned());
    Ok(())
}

fn lowest(cloth: &Cloth) -> f32 {
    cloth
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min)
}
