//! The flag flies: in its wind it streams out from its pole and flutters.

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

/// What the flag's free edge did over the last three seconds of a ten
/// second run: its mean angle from straight down (degrees), its mean and
/// least distance downwind of the pole (m), and how far it moved (m, the
/// mean distance its particles travelled per frame times the frames).
fn fly() -> (f32, f32, f32, f32) {
    let mut scene = Scene::build(
        SceneKind::Flag,
        &SceneOptions {
            frames: Some(600),
            ..Default::default()
        },
    )
    .unwrap();
    let (cols, rows) = (32, 20);
    let wind = scene.cloth.params.wind.direction;
    let downwind = Vector::new(wind.x, 0.0, wind.z).normalize();
    let (mut angle, mut along, mut least, mut travel, mut count) = (0.0, 0.0, f32::MAX, 0.0, 0);
    let mut last: Option<Vec<Vector>> = None;
    for frame in 0..600 {
        scene.step_frame().unwrap();
        if frame < 420 {
            continue;
        }
        let x = scene.cloth.positions();
        let edge: Vec<Vector> = (0..rows).map(|r| x[r * cols + cols - 1]).collect();
        for r in 0..rows {
            let e = edge[r] - x[r * cols];
            angle += e
                .normalize()
                .dot(-Vector::Y)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
            along += e.dot(downwind);
            least = least.min(e.dot(downwind));
            count += 1;
        }
        if let Some(prev) = &last {
            travel += edge
                .iter()
                .zip(prev)
                .map(|(a, b)| (*a - *b).length())
                .sum::<f32>()
                / rows as f32;
        }
        last = Some(edge);
    }
    assert!(scene.cloth.is_finite());
    (angle / count as f32, along / count as f32, least, travel)
}

#[test]
fn the_flag_streams_out_downwind_and_flutters() {
    let (angle, along, least, travel) = fly();
    assert!(angle > 60.0, "{angle}° from straight down");
    assert!(along > 0.6 * 1.6, "{along} m downwind");
    assert!(least > 0.0, "upwind of the pole: {least}");
    assert!(travel > 0.5, "the edge moved {travel} m in 3 s");
}
