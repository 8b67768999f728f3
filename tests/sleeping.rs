//! Sleeping: a still cloth stops being solved, and wakes when something
//! near it moves or changes.

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

mod common;
use common::bits;

/// A 24 × 24 drape with sleeping on, stepped until it sleeps (at most
/// 33 s; measured: it falls asleep at frame 1610, 26.8 s, as its skirt's
/// last slow creep over the ball stops).
fn settled_drape() -> Scene {
    let mut scene = Scene::build(
        SceneKind::Drape,
        &SceneOptions {
            n: Some(24),
            ..Default::default()
        },
    )
    .unwrap();
    scene.solver.settings.sleep = true;
    for _ in 0..2000 {
        if scene.step_frame().unwrap().asleep {
            return scene;
        }
    }
    panic!("the drape never fell asleep");
}

/// Once settled, the drape sleeps: steps solve nothing and leave it as it
/// is. Its ball moving up into it wakes it, and it is carried up.
#[test]
fn a_settled_drape_sleeps_and_wakes_when_its_ball_moves() {
    let mut scene = settled_drape();
    assert!(scene.solver.is_asleep());
    let before = bits(&scene.cloth);
    for _ in 0..30 {
        let report = scene.step_frame().unwrap();
        assert!(report.asleep && report.substeps == 0, "{report:?}");
    }
    assert_eq!(bits(&scene.cloth), before, "a sleeping cloth moved");
    let top = |s: &Scene| {
        s.cloth
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::MIN, f32::max)
    };
    let height = top(&scene);
    // The ball rises at 0.5 m/s.
    scene.obstacles[0].linvel = Vector::new(0.0, 0.5, 0.0);
    let report = scene.step_frame().unwrap();
    assert!(!report.asleep && report.substeps > 0, "{report:?}");
    for _ in 0..20 {
        assert!(!scene.step_frame().unwrap().asleep);
    }
    assert!(
        top(&scene) > height + 0.1,
        "the cloth stayed at {}",
        top(&scene)
    );
}

/// A sleeping cloth wakes when it is pinned, pushed or its world changes,
/// and a still ball far from it does not wake it.
#[test]
fn a_sleeping_cloth_wakes_when_touched_or_changed() {
    let scene = settled_drape();
    type Touch = fn(&mut Scene);
    let touches: [(&str, Touch); 4] = [
        ("pinned", |s| s.cloth.pin(5).unwrap()),
        ("pushed", |s| {
            s.cloth.set_velocity(7, Vector::new(0.0, 1.0, 0.0)).unwrap()
        }),
        ("wind", |s| s.cloth.params.wind = Wind::new(Vector::X, 5.0)),
        ("softer", |s| s.cloth.material.stretch.stiffness *= 0.5),
    ];
    for (what, touch) in touches {
        let mut s = Scene::from_desc(scene.desc.clone()).unwrap();
        s.cloth = scene.cloth.clone();
        s.solver = scene.solver.clone();
        assert!(s.step_frame().unwrap().asleep, "{what}: asleep before");
        touch(&mut s);
        assert!(!s.step_frame().unwrap().asleep, "{what}: still asleep");
    }
    // An obstacle far away moving does not wake it.
    let mut s = Scene::from_desc(scene.desc.clone()).unwrap();
    s.cloth = scene.cloth.clone();
    s.solver = scene.solver.clone();
    s.obstacles.push(
        Obstacle::ball(Vector::new(5.0, 0.0, 0.0), 0.2).with_velocity(Vector::X, Vector::ZERO),
    );
    assert!(s.step_frame().unwrap().asleep);
    // Sleeping off wakes it.
    s.solver.settings.sleep = false;
    assert!(!s.step_frame().unwrap().asleep);
}

/// A snapshot of a sleeping cloth sleeps on, and one taken without
/// sleeping never sleeps.
#[test]
fn sleep_is_part_of_a_snapshot() {
    let scene = settled_drape();
    let sim = Simulation {
        cloth: scene.cloth.clone(),
        solver: scene.solver.clone(),
    };
    let json = serde_json::to_string(&sim).unwrap();
    let mut back: Simulation = serde_json::from_str(&json).unwrap();
    assert!(back.solver.is_asleep());
    let ball = Obstacle::ball(Vector::ZERO, 0.3);
    assert!(
        back.step(1.0 / 60.0, std::slice::from_ref(&ball))
            .unwrap()
            .asleep
    );
    let mut awake = Simulation::new(ClothBuilder::new(8, 8).build().unwrap());
    for _ in 0..60 {
        assert!(!awake.step(1.0 / 60.0, &[]).unwrap().asleep);
    }
}
