//! The implicit integrators: energy, equilibrium, and the cached Cholesky factor.

mod common;

use cloth3d::prelude::*;
use cloth3d::scenes::run;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use common::{max_distance, oscillator, spinning};

#[test]
fn implicit_euler_never_adds_energy_to_an_undamped_system() {
    for h in [1.0e-3f32, 0.01, 0.1, 0.5] {
        let mut cloth = oscillator(0.2, 500.0, 0.0, 0.1, Integrator::ImplicitEuler);
        let mut e = cloth.energy().total();
        for _ in 0..200 {
            cloth.step(h, &[]).unwrap();
            let now = cloth.energy().total();
            assert!(
                now <= e * (1.0 + 1e-6) + 1e-9,
                "h = {h}: energy rose from {e} to {now}"
            );
            e = now;
        }
    }
    // A free, undamped cloth thrown and spinning, at game steps.
    for h in [1.0f32 / 60.0, 0.1] {
        let mut cloth = spinning(Integrator::ImplicitEuler, Substeps::Fixed(1), false);
        let e0 = cloth.energy().total();
        for _ in 0..100 {
            cloth.step(h, &[]).unwrap();
        }
        let e1 = cloth.energy().total();
        assert!(e1 <= e0 * 1.0001, "h = {h}: energy rose from {e0} to {e1}");
    }
}

/// A 10×10 cloth hanging from its top row, brought to rest by each integrator.
fn hanging_equilibrium(integrator: Integrator, substeps: Substeps, frames: usize) -> Vec<Vector> {
    let mut cloth = Simulation::new(
        ClothBuilder::new(10, 10)
            .size(0.5, 0.5)
            .vertical(Vector::new(0.0, 1.0, 0.0))
            .pins(PinPreset::CurtainRow)
            .build()
            .unwrap(),
    );
    cloth.params.air_drag = 3.0;
    cloth.solver.settings.cg_tolerance = 1e-6;
    cloth.solver.settings.cg_max_iterations = 500;
    cloth.solver.settings.fms_iterations = 30;
    cloth.solver.settings.substeps = substeps;
    cloth.set_integrator(integrator);
    for _ in 0..frames {
        cloth.step(1.0 / 60.0, &[]).unwrap();
    }
    assert!(cloth.energy().kinetic < 1e-8, "{integrator}: still moving");
    cloth.positions().to_vec()
}

#[test]
fn implicit_solvers_reach_the_same_equilibrium_as_small_step_symplectic_euler() {
    let reference = hanging_equilibrium(Integrator::SymplecticEuler, Substeps::Auto, 900);
    for integrator in [Integrator::ImplicitEuler, Integrator::FastMassSpring] {
        let rest = hanging_equilibrium(integrator, Substeps::Fixed(1), 900);
        let worst = max_distance(&reference, &rest);
        assert!(
            worst < 0.001,
            "{integrator}: {worst} m from the reference equilibrium"
        );
    }
}

#[test]
fn the_cholesky_factor_is_reused_until_something_it_depends_on_changes() {
    let mut cloth = Simulation::new(
        ClothBuilder::new(12, 12)
            .pins(PinPreset::TwoCorners)
            .build()
            .unwrap(),
    );
    cloth.set_integrator(Integrator::FastMassSpring);
    cloth.solver.settings.substeps = Substeps::Fixed(1);
    assert_eq!(cloth.counters().factorizations, 0);
    for _ in 0..10 {
        cloth.step(1.0 / 60.0, &[]).unwrap();
    }
    assert_eq!(
        cloth.counters().factorizations,
        1,
        "one factor for ten identical steps"
    );
    // Wind, gravity and drag are not in the matrix.
    cloth.params.wind = Wind::new(Vector::X, 3.0);
    cloth.step(1.0 / 60.0, &[]).unwrap();
    assert_eq!(cloth.counters().factorizations, 1);
    // A new pin, a new step, a new stiffness or damping each need a new factor.
    cloth.pin(60).unwrap();
    cloth.step(1.0 / 60.0, &[]).unwrap();
    assert_eq!(cloth.counters().factorizations, 2);
    cloth.step(1.0 / 30.0, &[]).unwrap();
    assert_eq!(cloth.counters().factorizations, 3);
    cloth.material.stretch.stiffness *= 2.0;
    cloth.step(1.0 / 30.0, &[]).unwrap();
    assert_eq!(cloth.counters().factorizations, 4);
    cloth.material.shear.damping += 0.1;
    cloth.step(1.0 / 30.0, &[]).unwrap();
    cloth.step(1.0 / 30.0, &[]).unwrap();
    assert_eq!(cloth.counters().factorizations, 5);
}

#[test]
fn stiff_heavy_strongly_damped_cloth_is_stable_at_a_frame_step() {
    // Leather, ten times heavier, damping raised a hundredfold: no clamp anywhere.
    for integrator in [Integrator::ImplicitEuler, Integrator::FastMassSpring] {
        let mut m = Material::leather();
        for kind in SpringKind::ALL {
            m.params_mut(kind).damping *= 100.0;
        }
        let mut cloth = Simulation::new(
            ClothBuilder::new(24, 24)
                .total_mass(10.0)
                .material(m)
                .pins(PinPreset::TwoCorners)
                .build()
                .unwrap(),
        )
        .with_integrator(integrator);
        cloth.solver.settings.substeps = Substeps::Fixed(1);
        for _ in 0..120 {
            cloth.step(1.0 / 60.0, &[]).unwrap();
        }
        assert!(cloth.is_finite());
        // 10 kg on two corners: about 49 N through the few springs at each
        // corner, k L ≈ 350 N, so several percent of stretch is the physics.
        let stretch = cloth.max_strain(SpringKind::Stretch);
        assert!(
            stretch > 0.01 && stretch < 0.15,
            "{integrator}: stretch {stretch}"
        );
        // It hangs below its pins rather than floating.
        assert!(
            cloth.centroid().y < -0.1,
            "{integrator}: centroid {:?}",
            cloth.centroid()
        );
    }
}

/// The `drape` scene (64 × 64, a 1/60 s frame, one step a frame) with the
/// stretch springs made `k` N/m with damping `c` N·s/m.
fn stiff_drape(integrator: Integrator, k: f32, c: f32) -> cloth3d::scenes::RunMetrics {
    let mut material = Material::cotton();
    material.stretch = SpringParams::new(k, c);
    let mut scene = Scene::build(
        SceneKind::Drape,
        &SceneOptions {
            integrator: Some(integrator),
            substeps: Some(Substeps::Fixed(1)),
            material: Some(material),
            ..Default::default()
        },
    )
    .unwrap();
    let m = run(&mut scene, 120).unwrap();
    // Contacts changing only refactor the numbers: one ordering for the run.
    if integrator == Integrator::FastMassSpring {
        assert_eq!(scene.solver.counters().factorizations, 1);
        assert!(scene.solver.counters().refactorizations > 0);
    }
    m
}

#[test]
fn both_large_step_solvers_drape_stiff_cloth_at_one_step_a_frame() {
    for integrator in [Integrator::ImplicitEuler, Integrator::FastMassSpring] {
        for k in [1.0e5f32, 1.0e6] {
            // From no damping to far above critical (about 22 N·s/m at 1e6 N/m).
            for c in [0.0f32, 10.0, 100.0] {
                let m = stiff_drape(integrator, k, c);
                let what = format!("{integrator}, k = {k}, c = {c}: {m:?}");
                assert!(m.finite, "{what}");
                assert!(m.max_stretch < 0.05, "{what}");
                assert!(m.max_penetration_any_frame <= 0.002, "{what}");
                // It rests on the ball: the skirt hangs below the equator, the
                // top stays on the ball (a cloth sliding off falls past y = -0.4).
                assert!(m.min_y > -0.4 && m.min_y < 0.3, "{what}");
            }
        }
    }
}

/// One implicit step of a 32 × 32 curtain with stretch springs of `k` N/m,
/// solved to a tight tolerance: the iterations it took and the positions.
fn stiff_curtain_step(k: f32, preconditioner: Preconditioner) -> (u32, Vec<Vector>) {
    let mut material = Material::cotton();
    material.stretch.stiffness = k;
    let mut cloth = Simulation::new(
        ClothBuilder::new(32, 32)
            .size(0.5, 0.5)
            .vertical(Vector::new(0.0, 1.0, 0.0))
            .pins(PinPreset::CurtainRow)
            .material(material)
            .build()
            .unwrap(),
    )
    .with_integrator(Integrator::ImplicitEuler);
    cloth.solver.settings.substeps = Substeps::Fixed(1);
    cloth.solver.settings.newton_iterations = 1;
    cloth.solver.settings.cg_tolerance = 1e-6;
    cloth.solver.settings.cg_max_iterations = 20_000;
    cloth.solver.settings.preconditioner = preconditioner;
    // Stretched 5% down from its pinned top row and swung out of its plane:
    // the stiff springs recoil across the whole sheet and turn.
    for i in 0..cloth.particle_count() {
        let p = cloth.positions()[i];
        let drop = 1.0 - p.y;
        cloth
            .set_position(i, Vector::new(p.x, 1.0 - 1.05 * drop, p.z))
            .unwrap();
        cloth
            .set_velocity(i, Vector::new(0.0, 0.0, 3.0 * drop))
            .unwrap();
    }
    let report = cloth.step(1.0 / 60.0, &[]).unwrap();
    (report.iterations, cloth.positions().to_vec())
}

#[test]
fn the_spring_space_preconditioner_converges_whatever_the_stiffness() {
    let mut softest = None;
    for k in [1.0e4f32, 1.0e5, 1.0e6] {
        let (jacobi, xj) = stiff_curtain_step(k, Preconditioner::BlockJacobi);
        let (spring, xs) = stiff_curtain_step(k, Preconditioner::SpringSpace);
        let worst = max_distance(&xj, &xs);
        println!(
            "k = {k}: block Jacobi {jacobi}, spring space {spring} iterations; {worst} m apart"
        );
        // The same system solved, so the same step.
        assert!(worst < 1e-5, "k = {k}: the solutions differ by {worst} m");
        // The stretch springs taken exactly: under 0.7 of the iterations
        // (measured: 106 against 179 at 1e4 N/m, 130 against 195 at 1e5,
        // 82 against 134 at 1e6; the lighter border particles of the
        // area-shared masses leave more to the shear springs' block diagonal)...
        assert!(
            spring * 10 < jacobi * 7,
            "k = {k}: {spring} iterations against block Jacobi's {jacobi}"
        );
        // ... and stiffer springs need not many more.
        let first = *softest.get_or_insert(spring);
        assert!(
            2 * spring <= 3 * first,
            "k = {k}: {spring} iterations, {first} at 1e4 N/m"
        );
    }
}
