//! The multi-threaded step gives exactly the single-threaded result.
#![cfg(feature = "parallel")]

mod common;

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use common::{bits, on_threads};

#[test]
fn parallel_and_serial_steps_are_bit_identical() {
    // N = 96: colour classes large enough to be split across threads.
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::Rk4,
        Integrator::ImplicitEuler,
    ] {
        let run = |parallel: bool| {
            let mut scene = Scene::build(
                SceneKind::Drape,
                &SceneOptions {
                    n: Some(96),
                    integrator: Some(integrator),
                    substeps: Some(Substeps::Fixed(if integrator.is_explicit() {
                        150
                    } else {
                        1
                    })),
                    ..Default::default()
                },
            )
            .unwrap();
            scene.solver.settings.parallel = parallel;
            for _ in 0..3 {
                scene.step_frame().unwrap();
            }
            bits(&scene.cloth)
        };
        let parallel = on_threads(2, || run(true));
        assert_eq!(parallel, run(false), "{integrator}");
    }
}

#[test]
fn the_default_solver_gives_the_same_bits_on_two_threads_as_on_one() {
    // xpbd's sweep in bands, its particle loops and the collision stage's
    // blocks on a team; the drape lying on its ball (contacts, friction,
    // the edge pass), the box on its cube (contact planes held inside the
    // substep, in chunks on the team) and the hammock with its dynamic boxes (momentum
    // handed to rapier, summed in particle order); the fold's
    // self-collision, whose look for pairs runs on the team; the torn
    // sheet, its grid's runs on the team and the torn springs one by one.
    for (kind, n, frames) in [
        (SceneKind::Tear, 128, 45),
        (SceneKind::Drape, 64, 40),
        (SceneKind::Box, 64, 40),
        (SceneKind::Hammock, 64, 60),
        (SceneKind::Fold, 48, 60),
        (SceneKind::Stack, 28, 50),
    ] {
        let run = |threads: usize| {
            on_threads(threads, || {
                let options = SceneOptions {
                    n: Some(n),
                    substeps: Some(Substeps::Fixed(24)),
                    ..Default::default()
                };
                let mut scene = Scene::build(kind, &options).unwrap();
                assert_eq!(scene.solver.settings.integrator, Integrator::Xpbd);
                let (mut contacts, mut self_contacts, mut torn) = (0, 0, 0);
                for _ in 0..frames {
                    let report = scene.step_frame().unwrap();
                    contacts += report.contacts;
                    self_contacts += report.self_contacts;
                    torn += report.torn_springs;
                }
                let bodies: Vec<u32> = scene
                    .rapier
                    .iter()
                    .flat_map(|side| side.all_bodies.iter().map(|h| &side.world.bodies[*h]))
                    .flat_map(|b| {
                        let (t, v) = (b.translation().to_array(), b.linvel().to_array());
                        t.into_iter().chain(v).map(f32::to_bits)
                    })
                    .collect();
                (bits(&scene.cloth), bodies, (contacts, self_contacts, torn))
            })
        };
        let one = run(1);
        let (contacts, self_contacts, torn) = one.2;
        if kind == SceneKind::Tear {
            assert!(torn > 0, "the sheet never tore");
        } else {
            assert!(contacts > 0, "{kind:?}: no contact in the run");
        }
        if matches!(kind, SceneKind::Fold | SceneKind::Stack) {
            assert!(self_contacts > 0, "{kind:?}: the layers never touched");
        }
        if kind == SceneKind::Hammock {
            assert!(!one.1.is_empty(), "the hammock has bodies");
        }
        assert!(one == run(2), "{kind:?}: two threads differ from one");
    }
}
