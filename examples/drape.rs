//! The simplest cloth: a tablecloth falling on a ball.
//!
//! `cargo run --release --example drape`

use cloth3d::prelude::*;

fn main() -> Result<(), ClothError> {
    let mut cloth = Simulation::new(
        ClothBuilder::new(48, 48)
            .size(1.0, 1.0)
            .horizontal(Vector::new(0.0, 0.6, 0.0))
            .total_mass(1.0)
            .build()?,
    );
    let ball = Obstacle::ball(Vector::ZERO, 0.3);
    for frame in 1..=120 {
        cloth.step(1.0 / 60.0, std::slice::from_ref(&ball))?;
        if frame % 30 == 0 {
            let c = cloth.centroid();
            println!(
                "t = {:.1} s  centroid ({:+.3}, {:+.3}, {:+.3}) m  stretch {:.2}%",
                cloth.time(),
                c.x,
                c.y,
                c.z,
                100.0 * cloth.max_strain(SpringKind::Stretch)
            );
        }
    }
    Ok(())
}
