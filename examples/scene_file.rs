//! A scene of your own from a RON file: read it, run it, report.
//!
//! ```sh
//! cargo run --release --example scene_file                      # examples/scenes/capsule_drape.ron
//! cargo run --release --example scene_file -- path/to/scene.ron
//! ```
//!
//! `cloth3d export-scene drape > drape.ron` writes any canonical scene as such
//! a file to start from; `cloth3d run path/to/scene.ron` runs one from the
//! command line.

use cloth3d::scenes::{run, Scene, SceneOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/scenes/capsule_drape.ron"
        )
        .into()
    });
    // A bad file is reported with its line and field, for example
    // "line 12, column 19, field `cloth.material.Custom.stretch.stiffness`: invalid value -3000: ...".
    let mut scene = Scene::open(&path, &SceneOptions::default())?;
    let frames = scene.frames;
    let m = run(&mut scene, frames)?;
    println!(
        "{}: {} frames, {} particles, max stretch {:.2}%, max penetration {:.1} mm, lowest point y = {:.3} m",
        m.scene,
        m.frames,
        scene.cloth.particle_count(),
        100.0 * m.max_stretch,
        1000.0 * m.max_penetration_any_frame,
        m.min_y
    );
    Ok(())
}
