//! Snapshots, determinism, and properties over random cloths, obstacles and steps.

mod common;

use cloth3d::collision::penetration_depth;
use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use common::{bits, scene_with};
use parry3d::shape::SharedShape;
use proptest::prelude::*;

/// Steps `scene` for `before` frames, snapshots its cloth and solver as
/// JSON, restores them, and checks that both go on identically for `after` frames.
fn snapshot_resumes(mut scene: Scene, before: u32, after: u32, what: &str) {
    for _ in 0..before {
        scene.step_frame().unwrap();
    }
    let snapshot = serde_json::to_string(&(&scene.cloth, &scene.solver)).unwrap();
    let (cloth, solver): (Cloth, ClothSolver) = serde_json::from_str(&snapshot).unwrap();
    assert_eq!(
        cloth, scene.cloth,
        "{what}: the snapshot lost some of the cloth"
    );
    assert_eq!(
        solver, scene.solver,
        "{what}: the snapshot lost some of the solver"
    );
    // Run both on: the uninterrupted one and the one resumed from the snapshot.
    let mut resumed = Simulation { cloth, solver };
    for frame in 0..after {
        scene.step_frame().unwrap();
        resumed.step(scene.dt, &scene.obstacles).unwrap();
        assert_eq!(
            bits(&scene.cloth),
            bits(&resumed),
            "{what}: frame {frame} differs after resuming"
        );
    }
}

#[test]
fn a_snapshot_restores_exactly_and_resumes_bit_for_bit() {
    for parallel in [false, true] {
        for integrator in Integrator::ALL {
            let mut scene = scene_with(SceneKind::Drape, 16, integrator);
            scene.solver.settings.parallel = parallel;
            snapshot_resumes(scene, 20, 20, &format!("{integrator}, parallel {parallel}"));
        }
    }
}

/// A snapshot resumes bit for bit where the solver carries more between
/// steps than the drape asks of it: the box's still cube, whose contacts
/// the small-steps solver holds as planes (found afresh at a step's first
/// substep: before, a restored solver had none there and went on to other
/// bits from the first frame), the fold's bar, ground and layers and the
/// stack's three cloths (self-collision's last look, which carries over
/// from step to step), and the flag's gusts.
#[test]
fn a_snapshot_resumes_bit_for_bit_among_edges_and_self_contact() {
    let scenes = [
        (SceneKind::Box, 16, 40),
        (SceneKind::Fold, 24, 100),
        (SceneKind::Stack, 12, 60),
        (SceneKind::Flag, 16, 30),
    ];
    for (kind, n, before) in scenes {
        let scene = Scene::build(
            kind,
            &SceneOptions {
                n: Some(n),
                ..Default::default()
            },
        )
        .unwrap();
        snapshot_resumes(scene, before, 10, kind.name());
    }
}

#[test]
fn a_snapshot_resumes_bit_for_bit_with_spring_classes_split_across_threads() {
    // N = 96: colour classes large enough for the parallel feature to split them.
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::ImplicitEuler,
        Integrator::FastMassSpring,
    ] {
        let mut scene = scene_with(SceneKind::Drape, 96, integrator);
        if integrator.is_explicit() {
            scene.solver.settings.substeps = Substeps::Fixed(150);
        }
        snapshot_resumes(scene, 3, 3, integrator.name());
    }
}

#[test]
fn the_same_inputs_give_bit_identical_results() {
    for kind in [SceneKind::Box, SceneKind::Flag, SceneKind::Hammock] {
        let run = || {
            let mut scene = Scene::build(
                kind,
                &SceneOptions {
                    n: Some(16),
                    ..Default::default()
                },
            )
            .unwrap();
            for _ in 0..40 {
                scene.step_frame().unwrap();
            }
            bits(&scene.cloth)
        };
        assert_eq!(run(), run(), "{}", kind.name());
    }
}

fn shape_strategy() -> impl Strategy<Value = SharedShape> {
    prop_oneof![
        (0.05f32..0.6).prop_map(SharedShape::ball),
        (0.05f32..0.5, 0.05f32..0.5, 0.05f32..0.5)
            .prop_map(|(x, y, z)| SharedShape::cuboid(x, y, z)),
        (0.05f32..0.4, 0.05f32..0.3).prop_map(|(h, r)| SharedShape::capsule_y(h, r)),
    ]
}

fn pose_strategy() -> impl Strategy<Value = Pose> {
    (
        -0.5f32..0.5,
        -0.5f32..0.5,
        -0.5f32..0.5,
        -1.0f32..1.0,
        -1.0f32..1.0,
        -1.0f32..1.0,
        0.0f32..6.3,
    )
        .prop_map(|(x, y, z, ax, ay, az, angle)| {
            let axis = Vector::new(ax, ay, az).normalize_or(Vector::Y);
            Pose::from_parts(Vector::new(x, y, z), Rotation::from_axis_angle(axis, angle))
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_cloths_never_panic_never_go_bad_and_keep_their_pins(
        cols in 2usize..9,
        rows in 2usize..9,
        preset in prop::sample::select(PinPreset::ALL.to_vec()),
        material in prop::sample::select(Material::PRESET_NAMES.to_vec()),
        stiffness_scale in 0.1f32..20.0,
        integrator in prop::sample::select(Integrator::ALL.to_vec()),
        fixed_substeps in prop::option::of(1u32..4),
        dt in 0.001f32..0.05,
        wind in 0.0f32..20.0,
        shape in shape_strategy(),
        pose in pose_strategy(),
    ) {
        let mut m = Material::by_name(material).unwrap();
        m.stretch.stiffness *= stiffness_scale;
        let mut cloth = Simulation::new(ClothBuilder::new(cols, rows).size(0.8, 0.6).material(m).pins(preset).build().unwrap()).with_integrator(integrator);
        cloth.solver.settings.substeps = fixed_substeps.map_or(Substeps::Auto, Substeps::Fixed);
        cloth.params.wind = Wind::new(Vector::new(1.0, 0.2, 0.5), wind);
        let obstacle = Obstacle::new(shape, pose);
        let pinned: Vec<(usize, Vector)> = cloth.pinned().into_iter().map(|i| (i, cloth.positions()[i])).collect();
        let mut diverged = false;
        for _ in 0..20 {
            let before = cloth.positions().to_vec();
            match cloth.step(dt, std::slice::from_ref(&obstacle)) {
                Ok(_) => prop_assert!(cloth.is_finite()),
                Err(ClothError::Diverged { suggested_substeps, .. }) => {
                    prop_assert!(suggested_substeps >= 1);
                    prop_assert_eq!(cloth.positions(), &before[..]);
                    diverged = true;
                    break;
                }
                Err(e) => prop_assert!(false, "unexpected error {e}"),
            }
            for &(i, p) in &pinned {
                prop_assert_eq!(cloth.positions()[i], p);
            }
        }
        // With a stable step (automatic substeps), nothing ends deep inside.
        if fixed_substeps.is_none() && !diverged {
            for (i, &p) in cloth.positions().iter().enumerate() {
                if cloth.is_pinned(i) {
                    continue;
                }
                let depth = penetration_depth(&*obstacle.shape, &obstacle.pose, p);
                prop_assert!(depth <= 1e-3, "particle {} is {} m inside", i, depth);
            }
        }
    }
}
