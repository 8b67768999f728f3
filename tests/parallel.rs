//! The multi-threaded step gives exactly the single-threaded result.
#![cfg(feature = "parallel")]

mod common;

use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use common::bits;

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
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let parallel = pool.install(|| run(true));
        assert_eq!(parallel, run(false), "{integrator}");
    }
}
