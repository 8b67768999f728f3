//! Criterion benches of the hot kernels, so regressions show:
//! `cargo bench --bench kernels` (add `-- NAME` to pick some).
//!
//! - `spring_forces`: every spring's Hooke and damping force on a 64 × 64
//!   cloth (12 K springs) in the middle of a fall;
//! - `substep/INTEGRATOR`: one substep of a 64 × 64 cloth draped on a ball
//!   (contacts included), at the integrator's own substep;
//! - `contact_queries`: 4096 point-against-shape queries (ball, cuboid);
//! - `hundred_balls/{under,far,none}`: one symplectic-Euler substep of a
//!   64 × 64 cloth with 100 balls just under it, the same 100 balls far
//!   away, and none: the bounding-volume culling makes far obstacles cost
//!   next to nothing, and near ones cost by the particles near them.

use std::hint::black_box;

use cloth3d::collision::contact;
use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use criterion::{criterion_group, criterion_main, Criterion};
use parry3d::shape::{Ball, Cuboid, Shape};

/// The catalogue's `drape` at 64 × 64 with `integrator`, 30 frames in (resting on its ball).
fn draped(integrator: Integrator) -> Scene {
    let mut scene = Scene::build(
        SceneKind::Drape,
        &SceneOptions {
            n: Some(64),
            integrator: Some(integrator),
            ..Default::default()
        },
    )
    .expect("valid scene");
    for _ in 0..30 {
        scene.step_frame().expect("stable");
    }
    scene
}

fn spring_forces(c: &mut Criterion) {
    let cloth = draped(Integrator::SymplecticEuler).cloth;
    let mut f = vec![Vector::ZERO; cloth.particle_count()];
    c.bench_function("spring_forces", |b| {
        b.iter(|| cloth.forces_into(black_box(&mut f)))
    });
}

fn substep(c: &mut Criterion) {
    let mut group = c.benchmark_group("substep");
    group.sample_size(20);
    for integrator in Integrator::ALL {
        let Scene {
            mut cloth,
            mut solver,
            obstacles,
            dt,
            ..
        } = draped(integrator);
        let h = dt / solver.substeps_for(&cloth, dt) as f32;
        solver.settings.substeps = Substeps::Fixed(1);
        // The same cloth and solver, resting on the ball, step after step (a
        // clone would start with empty scratch memory and no Cholesky factor).
        group.bench_function(integrator.name(), |b| {
            b.iter(|| solver.step(&mut cloth, h, &obstacles).expect("stable"))
        });
    }
    group.finish();
}

fn contact_queries(c: &mut Criterion) {
    let points: Vec<Vector> = (0..4096)
        .map(|i| {
            let (x, z) = ((i % 64) as f32 / 63.0 - 0.5, (i / 64) as f32 / 63.0 - 0.5);
            Vector::new(x, 0.31 - 0.2 * (x * x + z * z), z)
        })
        .collect();
    let pose = Pose::IDENTITY;
    let ball = Ball::new(0.3);
    let cuboid = Cuboid::new(Vector::splat(0.25));
    let mut group = c.benchmark_group("contact_queries");
    let shapes: [(&str, &dyn Shape); 2] = [("ball", &ball), ("cuboid", &cuboid)];
    for (name, shape) in shapes {
        group.bench_function(name, |b| {
            b.iter(|| {
                points
                    .iter()
                    .filter_map(|&p| contact(shape, &pose, black_box(p)))
                    .count()
            })
        });
    }
    group.finish();
}

/// 100 balls of radius 0.02 m on a 10 × 10 grid, their tops `height` m up.
fn balls(height: f32) -> Vec<Obstacle> {
    (0..100)
        .map(|i| {
            let (x, z) = ((i % 10) as f32 / 9.0 - 0.5, (i / 10) as f32 / 9.0 - 0.5);
            Obstacle::ball(Vector::new(x * 0.9, height - 0.02, z * 0.9), 0.02)
        })
        .collect()
}

fn hundred_balls(c: &mut Criterion) {
    let cloth = ClothBuilder::new(64, 64)
        .horizontal(Vector::new(0.0, 0.005, 0.0))
        .build()
        .expect("valid cloth");
    let mut sim = Simulation::new(cloth);
    let h = 1.0 / 60.0 / sim.substeps_for(1.0 / 60.0).max(1) as f32;
    sim.solver.settings.substeps = Substeps::Fixed(1);
    let cloth = sim;
    let mut group = c.benchmark_group("hundred_balls");
    group.sample_size(30);
    for (name, obstacles) in [
        ("under", balls(0.0)),
        ("far", balls(-10.0)),
        ("none", Vec::new()),
    ] {
        let mut cloth = cloth.clone();
        group.bench_function(name, |b| {
            b.iter(|| cloth.step(h, &obstacles).expect("stable"))
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    spring_forces,
    substep,
    contact_queries,
    hundred_balls
);
criterion_main!(benches);
