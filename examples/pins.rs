//! Pinning: the catalogue's `pins` scene with its four-corner variant, then
//! pins changed at run time by (row, column).
//!
//! `cargo run --release --example pins`

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let options = SceneOptions {
        variant: Some(PinPreset::FourCorners),
        ..Default::default()
    };
    let mut scene = Scene::build(SceneKind::Pins, &options)?;
    for _ in 0..60 {
        scene.step_frame()?;
    }
    println!(
        "hanging from four corners: lowest point {:.3} m",
        lowest(&scene.cloth)
    );
    // Let go of one corner and pin the middle instead.
    let last = scene.cloth.grid().ok_or("the pins scene is a grid")?.cols - 1;
    scene.cloth.unpin_cell(last, last)?;
    scene.cloth.pin_cell(last / 2, last / 2)?;
    for _ in 0..120 {
        scene.step_frame()?;
    }
    println!(
        "one corner released: lowest point {:.3} m",
        lowest(&scene.cloth)
    );
    println!("pinned now: {:?}", scene.cloth.pinned());
    Ok(())
}

fn lowest(cloth: &Cloth) -> f32 {
    cloth
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min)
}
