//! The simplest cloth: the catalogue's `drape`, a tablecloth falling on a ball.
//!
//! `cargo run --release --example drape`

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut scene = Scene::build(SceneKind::Drape, &SceneOptions::default())?;
    for frame in 1..=scene.frames {
        scene.step_frame()?;
        if frame % 30 == 0 {
            let cloth = &scene.cloth;
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
