//! Helpers shared by the integration tests.
#![allow(dead_code)]

use cloth3d::prelude::*;

/// A material whose stretch springs have stiffness `k` (N/m) and damping
/// `c` (N·s/m), and no stretch limit: springs alone.
pub fn spring_material(k: f32, c: f32) -> Material {
    let mut m = Material::cotton().with_stretch_limit(None);
    m.stretch = SpringParams::new(k, c);
    m
}

/// One particle of mass `m` (kg) hanging on a spring of stiffness `k` and
/// damping `c` from a pinned particle at the origin; rest length 1 m,
/// stretched by `amplitude` m; no gravity, no drag.
pub fn oscillator(m: f32, k: f32, c: f32, amplitude: f32, integrator: Integrator) -> Simulation {
    let springs = vec![Spring {
        a: 0,
        b: 1,
        rest_length: 1.0,
        kind: SpringKind::Stretch,
    }];
    let positions = vec![Vector::ZERO, Vector::new(1.0 + amplitude, 0.0, 0.0)];
    let mut cloth = Simulation::new(
        Cloth::from_parts(
            positions,
            vec![1.0, m],
            springs,
            vec![],
            spring_material(k, c),
        )
        .unwrap(),
    );
    cloth.pin(0).unwrap();
    cloth.params.gravity = Vector::ZERO;
    cloth.params.air_drag = 0.0;
    cloth.solver.settings.substeps = Substeps::Fixed(1);
    cloth.set_integrator(integrator);
    cloth
}

/// Displacement of the oscillator's free particle from rest, in metres.
pub fn displacement(cloth: &Cloth) -> f32 {
    cloth.positions()[1].x - 1.0
}

/// Positions and velocities as raw bits, for bit-for-bit comparisons.
pub fn bits(cloth: &Cloth) -> Vec<u32> {
    cloth
        .positions()
        .iter()
        .chain(cloth.velocities())
        .flat_map(|v| v.to_array())
        .map(f32::to_bits)
        .collect()
}

/// A canonical scene at `n` particles a row with `integrator`: automatic
/// substeps for the explicit ones, one step per frame for the implicit ones.
pub fn scene_with(
    kind: cloth3d::scenes::SceneKind,
    n: usize,
    integrator: Integrator,
) -> cloth3d::scenes::Scene {
    cloth3d::scenes::Scene::build(
        kind,
        &cloth3d::scenes::SceneOptions {
            n: Some(n),
            integrator: Some(integrator),
            substeps: Some(integrator.default_substeps()),
            ..Default::default()
        },
    )
    .unwrap()
}

/// Runs the `cloth3d` command with `args`.
pub fn cloth3d(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_cloth3d"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs the `cloth3d` command with `args`, expects it to succeed and returns its stdout.
pub fn cloth3d_ok(args: &[&str]) -> String {
    let out = cloth3d(args);
    assert!(
        out.status.success(),
        "cloth3d {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The JSON objects of a `--json` output with one object a line.
pub fn json_lines(stdout: &str) -> Vec<serde_json::Value> {
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The largest distance between matching points of two lists, in metres.
pub fn max_distance(a: &[Vector], b: &[Vector]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f32::max)
}

/// A free 8×8 cloth thrown and spinning (a rigid turn at 2 rad/s, and every
/// third particle faster upwards than its neighbours), without gravity or
/// drag; without the material's damping when `damped` is false.
pub fn spinning(integrator: Integrator, substeps: Substeps, damped: bool) -> Simulation {
    let mut cloth = Simulation::new(ClothBuilder::new(8, 8).build().unwrap());
    cloth.set_integrator(integrator);
    cloth.solver.settings.substeps = substeps;
    cloth.params.gravity = Vector::ZERO;
    cloth.params.air_drag = 0.0;
    if !damped {
        for kind in SpringKind::ALL {
            cloth.material.params_mut(kind).damping = 0.0;
        }
    }
    for i in 0..cloth.particle_count() {
        let p = cloth.positions()[i];
        cloth
            .set_velocity(
                i,
                Vector::new(-p.z, 0.3, p.x) * 2.0 + Vector::new(0.0, (i % 3) as f32, 0.0),
            )
            .unwrap();
    }
    cloth
}

/// Runs `f` on a rayon pool of `threads` threads (the solver's team takes
/// its threads from the pool it runs in).
pub fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}
