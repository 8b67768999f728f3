//! Every canonical scene runs its default length with finite, sensible results.

use cloth3d::prelude::*;
use cloth3d::scenes::run;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

fn run_scene(kind: SceneKind, options: SceneOptions) -> cloth3d::scenes::RunMetrics {
    let mut scene = Scene::build(kind, &options).unwrap();
    let frames = scene.frames;
    let m = run(&mut scene, frames).unwrap();
    assert!(m.finite, "{}: not finite", kind.name());
    assert_eq!(m.frames, kind.default_frames());
    m
}

#[test]
fn drape_rests_on_the_ball() {
    let m = run_scene(SceneKind::Drape, SceneOptions::default());
    assert_eq!(m.grid, [64, 64]);
    assert!(m.max_penetration <= 0.001, "{m:?}");
    assert!(m.max_stretch < 0.05, "{m:?}");
    // Resting on the ball: its top is at 0.3 + thickness, the skirt hangs below.
    assert!(m.min_y < 0.0 && m.min_y > -0.35, "{m:?}");
    assert!(m.centroid[1] > 0.0 && m.centroid[1] < 0.3, "{m:?}");
    assert!(
        m.centroid[0].abs() < 0.01 && m.centroid[2].abs() < 0.01,
        "{m:?}"
    );
}

#[test]
fn box_rests_on_the_cube() {
    let m = run_scene(SceneKind::Box, SceneOptions::default());
    assert!(m.max_penetration <= 0.001, "{m:?}");
    assert!(m.centroid[1] > 0.0, "{m:?}");
}

#[test]
fn flag_flies_downwind_from_its_pole() {
    let m = run_scene(SceneKind::Flag, SceneOptions::default());
    assert_eq!(m.grid, [32, 20]);
    // The wind (1, 0, 0.3) lifts it off the pole towards +x and +z.
    assert!(m.centroid[0] > 0.3, "{m:?}");
    assert!(m.max_stretch < 0.1, "{m:?}");
}

#[test]
fn pins_variants_hang_from_their_pins() {
    for variant in SceneKind::Pins.variants() {
        let m = run_scene(
            SceneKind::Pins,
            SceneOptions {
                variant: Some(*variant),
                ..Default::default()
            },
        );
        assert_eq!(m.variant.as_deref(), Some(variant.name()));
        // The cloth hangs below its pins at y = 0.6 and does not fall away.
        assert!(
            m.centroid[1] < 0.6 && m.min_y > -0.6,
            "{}: {m:?}",
            variant.name()
        );
    }
}

#[test]
fn scene_options_are_validated() {
    let bad = |o: SceneOptions| Scene::build(SceneKind::Drape, &o).is_err();
    assert!(bad(SceneOptions {
        n: Some(1),
        ..Default::default()
    }));
    assert!(bad(SceneOptions {
        dt: Some(-0.1),
        ..Default::default()
    }));
    assert!(bad(SceneOptions {
        friction: Some(f32::NAN),
        ..Default::default()
    }));
    assert!(bad(SceneOptions {
        variant: Some(PinPreset::Center),
        ..Default::default()
    }));
    assert!(Scene::build(
        SceneKind::Pins,
        &SceneOptions {
            variant: Some(PinPreset::FlagColumn),
            ..Default::default()
        }
    )
    .is_err());
}
