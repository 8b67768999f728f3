//! The catalogue's `flag` on its pole, in gusts: F = c A (n·d) n on every
//! triangle, with the wind's strength breathing between 4 and 12 N/m².
//!
//! `cargo run --release --example flag`

use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut scene = Scene::build(SceneKind::Flag, &SceneOptions::default())?;
    for frame in 1..=scene.frames {
        scene.cloth.params.wind.strength = 8.0 + 4.0 * (frame as f32 * 0.05).sin();
        scene.step_frame()?;
        if frame % 60 == 0 {
            let cloth = &scene.cloth;
            let grid = cloth.grid().ok_or("the flag is a grid")?;
            let tip = cloth.positions()[cloth.index(grid.rows / 2, grid.cols - 1)?];
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
