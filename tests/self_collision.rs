//! Self-collision: a cloth's layers are kept a thickness apart, by every
//! integrator, and without it they pass through each other.

mod common;

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use common::bits;

/// Columns of the folded strip; the right half is laid over the left.
const COLS: usize = 20;
const ROWS: usize = 10;
const THICKNESS: f32 = 0.01;

/// A 0.5 m × 0.25 m strip folded in two: its right half lies `gap` metres
/// above its left half, mirrored about the middle (column c over column
/// `COLS − 1 − c`), so each upper particle sits right above a lower one.
fn folded_strip(gap: f32, self_collision: bool) -> Cloth {
    let mut cloth = ClothBuilder::new(COLS, ROWS)
        .size(0.5, 0.25)
        .horizontal(Vector::new(0.0, 0.0, 0.0))
        .material(Material::by_name("cotton").unwrap())
        .self_collision(self_collision)
        .build()
        .unwrap();
    cloth.params.thickness = THICKNESS;
    for r in 0..ROWS {
        for c in COLS / 2..COLS {
            let i = cloth.index(r, c).unwrap();
            let below = cloth.positions()[cloth.index(r, COLS - 1 - c).unwrap()];
            cloth
                .set_position(i, below + Vector::new(0.0, gap, 0.0))
                .unwrap();
        }
    }
    cloth
}

/// Upper particles (right half, away from the hinge) and the lower
/// particle right under each.
fn layers(cloth: &Cloth) -> Vec<(usize, usize)> {
    (0..ROWS)
        .flat_map(|r| (COLS / 2 + 2..COLS).map(move |c| (r, c)))
        .map(|(r, c)| {
            (
                cloth.index(r, c).unwrap(),
                cloth.index(r, COLS - 1 - c).unwrap(),
            )
        })
        .collect()
}

/// The lower layer pinned flat, and the upper one at the fold (where the
/// two are neighbours in the rest shape and only the bending springs keep
/// them apart); the upper layer falls onto the lower one and one of its
/// particles is thrown down at 3 m/s. With self-collision every upper
/// particle stays about a thickness above the particle under it (the
/// thrown one too); without, the thrown particle goes through.
#[test]
fn a_particle_driven_into_the_cloth_is_kept_out_by_the_thickness() {
    let run = |self_collision: bool| {
        let mut cloth = folded_strip(0.05, self_collision);
        for r in 0..ROWS {
            for c in 0..COLS / 2 + 2 {
                cloth.pin_cell(r, c).unwrap();
            }
        }
        let thrown = cloth.index(ROWS / 2, COLS - 3).unwrap();
        cloth
            .set_velocity(thrown, Vector::new(0.0, -3.0, 0.0))
            .unwrap();
        let mut solver = ClothSolver::default();
        let mut lowest = f32::INFINITY;
        for _ in 0..60 {
            solver.step(&mut cloth, 1.0 / 60.0, &[]).unwrap();
            let x = cloth.positions();
            for &(up, down) in &layers(&cloth) {
                lowest = lowest.min(x[up].y - x[down].y);
            }
        }
        (lowest, cloth.positions()[thrown].y)
    };
    let layer = folded_strip(0.05, true).self_thickness();
    assert!(layer > 0.0 && layer <= THICKNESS);
    let (gap, _) = run(true);
    assert!(
        gap > 0.5 * layer,
        "an upper particle came {gap} m above the lower layer (thickness {layer})"
    );
    let (gap_off, thrown_y) = run(false);
    assert!(
        gap_off < -THICKNESS && thrown_y < -THICKNESS,
        "without self-collision the thrown particle should pass through: gap {gap_off}, y {thrown_y}"
    );
}

/// The folded strip dropped on the ground: the two layers land on each
/// other and stay at least half the layers' thickness apart in every
/// frame (symplectic Euler and xpbd alike).
#[test]
fn two_layers_dropped_on_the_ground_stay_apart() {
    for integrator in [Integrator::Xpbd, Integrator::SymplecticEuler] {
        let mut cloth = folded_strip(0.04, true);
        for i in 0..cloth.particle_count() {
            let p = cloth.positions()[i];
            cloth
                .set_position(i, p + Vector::new(0.0, 0.3, 0.0))
                .unwrap();
        }
        let ground = Obstacle::cuboid(
            Vector::new(2.0, 0.1, 2.0),
            Pose::from_translation(Vector::new(0.0, -0.1, 0.0)),
        );
        let mut solver = ClothSolver::with_integrator(integrator);
        let layer = cloth.self_thickness();
        let mut gap = f32::INFINITY;
        for _ in 0..90 {
            solver
                .step(&mut cloth, 1.0 / 60.0, std::slice::from_ref(&ground))
                .unwrap();
            // Away from the fold itself (two cells each side of it), whose
            // two sides are neighbours in the rest shape.
            let x = cloth.positions();
            for &(up, down) in &layers(&cloth) {
                gap = gap.min(x[up].y - x[down].y);
            }
        }
        assert!(
            gap >= 0.5 * layer,
            "{integrator}: layers came {gap} m apart (thickness {layer})"
        );
        let x = cloth.positions();
        let lowest = x.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
        assert!(
            lowest > 0.0,
            "{integrator}: the strip did not land ({lowest})"
        );
        assert!(
            lowest < 2.0 * THICKNESS,
            "{integrator}: the strip is not on the ground ({lowest})"
        );
    }
}

/// The `fold` scene (self-collision on by default) ends with no
/// self-intersection and has few in any frame; with self-collision off
/// the halves pass through each other under the bar.
#[test]
fn the_fold_scene_needs_self_collision() {
    let run = |on: bool| {
        let mut scene = Scene::build(
            SceneKind::Fold,
            &SceneOptions {
                self_collision: Some(on),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(scene.cloth.params.self_collision, on);
        cloth3d::scenes::run(&mut scene, 120).unwrap()
    };
    let on = run(true);
    assert!(on.finite);
    assert_eq!(on.self_intersections, 0, "{on:?}");
    assert!(on.self_intersections_any_frame <= 10, "{on:?}");
    assert!(on.max_penetration_any_frame <= 0.001, "{on:?}");
    let off = run(false);
    assert!(off.self_intersections > 100, "{off:?}");
}

/// A snapshot taken while the layers touch continues bit for bit. A look
/// for pairs carries over from step to step (the layers at rest take
/// steps without one), so where it looked is part of the solver's state: a
/// clone (fresh scratch, the same state) finds the pairs of that look
/// again and goes on to the bit.
#[test]
fn a_snapshot_during_self_contact_continues_bit_for_bit() {
    // The lower layer pinned flat: the upper one falls onto it, lands and
    // comes to rest there, where a look lasts several steps.
    let mut cloth = folded_strip(0.02, true);
    for r in 0..ROWS {
        for c in 0..COLS / 2 + 2 {
            cloth.pin_cell(r, c).unwrap();
        }
    }
    let mut solver = ClothSolver::default();
    let step = |solver: &mut ClothSolver, cloth: &mut Cloth| {
        let report = solver.step(cloth, 1.0 / 60.0, &[]).unwrap();
        (report.self_contacts, report.self_looks)
    };
    let mut carried = false;
    let mut steps = 0;
    for at in [10, 120] {
        while steps < at {
            step(&mut solver, &mut cloth);
            steps += 1;
        }
        // The solver goes on with its warm scratch; the clone and the bare
        // solver start from the same cloth.
        let (mut copy, mut clone) = (cloth.clone(), solver.clone());
        let mut touching = 0;
        for _ in 0..20 {
            let (contacts, looks) = step(&mut solver, &mut cloth);
            touching += contacts;
            carried |= looks == 0;
            assert_eq!(step(&mut clone, &mut copy).1, looks);
            steps += 1;
        }
        assert!(touching > 0, "the layers never touched (from step {at})");
        assert_eq!(bits(&cloth), bits(&copy), "from step {at}");
    }
    assert!(carried, "no look carried over from one step to the next");
}

/// Bad input is refused: a negative friction between layers.
#[test]
fn a_negative_self_friction_is_refused() {
    let mut cloth = folded_strip(0.05, true);
    cloth.params.self_friction = -0.1;
    let err = ClothSolver::default()
        .step(&mut cloth, 1.0 / 60.0, &[])
        .unwrap_err();
    assert!(err.to_string().contains("self friction"), "{err}");
}

/// The layers' thickness: the collision thickness, but at most a quarter
/// of the spacing, unless set.
#[test]
fn the_layer_thickness_follows_the_spacing_unless_set() {
    let mut cloth = folded_strip(0.05, true);
    // 0.5 m over 19 cells: a quarter of 26 mm is under the 10 mm thickness.
    let quarter = 0.25 * 0.5 / 19.0;
    assert!((cloth.self_thickness() - quarter).abs() < 1e-6);
    cloth.params.thickness = 0.004;
    assert_eq!(cloth.self_thickness(), 0.004);
    cloth.params.self_thickness = Some(0.002);
    assert_eq!(cloth.self_thickness(), 0.002);
    cloth.params.self_thickness = Some(-1.0);
    let err = ClothSolver::default()
        .step(&mut cloth, 1.0 / 60.0, &[])
        .unwrap_err();
    assert!(err.to_string().contains("self thickness"), "{err}");
}

/// At one step a frame the layers would cross between passes: the large-step
/// integrators refuse self-collision unless given enough substeps, and say
/// how many; with them they keep the fold's layers apart.
#[test]
fn large_step_integrators_refuse_self_collision_without_substeps() {
    for integrator in [Integrator::FastMassSpring, Integrator::ImplicitEuler] {
        let options = |substeps| SceneOptions {
            integrator: Some(integrator),
            substeps,
            ..Default::default()
        };
        let mut scene = Scene::build(SceneKind::Fold, &options(None)).unwrap();
        let before = bits(&scene.cloth);
        let err = scene.step_frame().unwrap_err();
        assert!(
            matches!(
                err,
                ClothError::SelfCollisionNeedsSubsteps { needed: 16, .. }
            ),
            "{integrator}: {err}"
        );
        assert!(err.to_string().contains("--substeps 16"), "{err}");
        assert_eq!(
            bits(&scene.cloth),
            before,
            "{integrator}: a refused step moved the cloth"
        );
        let mut scene = Scene::build(SceneKind::Fold, &options(Some(Substeps::Fixed(16)))).unwrap();
        let run = cloth3d::scenes::run(&mut scene, 60).unwrap();
        assert_eq!(run.self_intersections_any_frame, 0, "{integrator}: {run:?}");
    }
}

/// Automatic substeps rise to what self-collision needs: a coarse fold
/// (10 × 10, where xpbd's own choice without its chain solves is 9
/// substeps; with them it takes 16 anyway) steps with 16, and so does fast
/// mass-spring asked for automatic substeps.
#[test]
fn automatic_substeps_rise_to_what_self_collision_needs() {
    for (integrator, own) in [(Integrator::Xpbd, 9), (Integrator::FastMassSpring, 1)] {
        let options = |self_collision| SceneOptions {
            n: Some(10),
            integrator: Some(integrator),
            substeps: Some(Substeps::Auto),
            self_collision: Some(self_collision),
            solver: cloth3d::scenes::SolverTuning {
                xpbd_chains: Some(false),
                ..Default::default()
            },
            ..Default::default()
        };
        let mut off = Scene::build(SceneKind::Fold, &options(false)).unwrap();
        assert_eq!(off.step_frame().unwrap().substeps, own, "{integrator}");
        let mut on = Scene::build(SceneKind::Fold, &options(true)).unwrap();
        assert_eq!(on.step_frame().unwrap().substeps, 16, "{integrator}");
    }
}

/// The `stack` (here 24 × 24 a cloth) at rest on its ball keeps still:
/// no particle's motion changes by more than 4 mm from one frame to the
/// next, and nine in ten by under 0.5 mm (1.9 and 0.12 mm now). Before
/// the layers thinned out in the outer rim of a triangle and at folds
/// about as sharp as the looks pair (`rim_taper`, `fold_share`),
/// particles sliding into a rim or a fold crossing the threshold were
/// pushed by up to half the thickness at once: the cloths shook by up
/// to 12.6 mm (3.3 mm at the 90th percentile) over these frames.
#[test]
fn the_stack_at_rest_keeps_still() {
    let options = SceneOptions {
        n: Some(24),
        ..Default::default()
    };
    let mut scene = Scene::build(SceneKind::Stack, &options).unwrap();
    for _ in 0..300 {
        scene.step_frame().unwrap();
    }
    let mut frames = vec![scene.cloth.positions().to_vec()];
    for _ in 0..60 {
        scene.step_frame().unwrap();
        frames.push(scene.cloth.positions().to_vec());
    }
    // Each particle's largest change of motion from a frame to the next (m).
    let mut shake: Vec<f32> = (0..scene.cloth.particle_count())
        .map(|i| {
            frames
                .windows(3)
                .map(|w| (w[2][i] - 2.0 * w[1][i] + w[0][i]).length())
                .fold(0.0, f32::max)
        })
        .collect();
    shake.sort_by(f32::total_cmp);
    let (ninetieth, most) = (shake[shake.len() * 9 / 10], shake[shake.len() - 1]);
    assert!(most < 0.004, "shook by {most} m");
    assert!(
        ninetieth < 0.0005,
        "nine in ten shook by up to {ninetieth} m"
    );
    assert_eq!(cloth3d::collision::self_intersections(&scene.cloth), 0);
}
