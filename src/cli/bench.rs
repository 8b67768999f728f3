//! Benchmarks on the canonical scenes, against rapier's built-in soft-body
//! cloth in the same process: what `cloth3d bench` prints.

use std::time::Instant;

use rapier3d::prelude::{
    ColliderBuilder, PhysicsWorld, RigidBodyBuilder, SoftBodyBuilder, SoftBodyEdgeKind,
    SpringCoefficients,
};
use serde::{Deserialize, Serialize};

use crate::math::Vector;
use crate::scenes::SceneError;
use crate::scenes::{Scene, SceneKind, SceneOptions, CLOTH_MASS, FRAME_DT};
use crate::solver::Integrator;

/// One line of the benchmark.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchRow {
    /// Scene name.
    pub scene: String,
    /// Particles along a row.
    pub n: usize,
    /// `cloth3d` or `rapier-softbody`.
    pub engine: String,
    /// Integrator (`rapier-softbody` for rapier's solver).
    pub integrator: String,
    /// Threads used.
    pub threads: usize,
    /// Substeps per frame.
    pub substeps: u32,
    /// Self-collision on (cloth3d rows).
    #[serde(default)]
    pub self_collision: bool,
    /// Median wall time of one frame, in seconds.
    pub frame_wall_s: f64,
    /// Particles × substeps per second.
    pub particle_substeps_per_s: f64,
    /// Spring evaluations per second (explicit integrators: springs × substeps × force evaluations).
    pub spring_evals_per_s: Option<f64>,
    /// Largest stretch-spring strain over every frame of the run (warm-up and timed).
    pub max_stretch: f32,
    /// Deepest any particle lay inside an obstacle over every frame, in metres.
    pub max_penetration: f32,
    /// rapier's frame time over this one's at the same N (cloth3d rows).
    pub speedup_vs_rapier: Option<f64>,
    /// How a timed frame's wall time splits (cloth3d rows): medians over
    /// the timed frames.
    #[serde(default)]
    pub split: Option<FrameSplit>,
}

/// How a frame's wall time splits among the stages (seconds, medians over
/// the timed frames; see [`crate::solver::StageTimes`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameSplit {
    /// The integrator's substeps: springs, forces and integration (s).
    pub integrate_s: f64,
    /// Obstacles and self-collision: detection, resolution, the edge pass,
    /// the stretch limit held against the contacts (s).
    pub collision_s: f64,
    /// The stretch limit and tethers outside the integrator (s).
    pub constraints_s: f64,
    /// The small-steps solver (xpbd): its substep time per spring update
    /// (springs × substeps × sweeps), in nanoseconds; the particle passes
    /// of its substep (prediction, velocities) are counted in.
    pub ns_per_spring: Option<f64>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Runs `warmup + frames` frames of a cloth3d scene and times the last
/// `frames`. `tuning` carries the user's other overrides (substeps, solver
/// iterations); its `n` and `integrator` are replaced by the row's, and
/// without substeps the integrator's default ones are used.
pub fn bench_cloth3d(
    kind: SceneKind,
    n: usize,
    integrator: Integrator,
    (warmup, frames): (u32, u32),
    tuning: &SceneOptions,
) -> Result<BenchRow, SceneError> {
    let mut scene = Scene::build(
        kind,
        &SceneOptions {
            n: Some(n),
            integrator: Some(integrator),
            substeps: Some(tuning.substeps.unwrap_or(integrator.default_substeps())),
            ..tuning.clone()
        },
    )?;
    // Stretch and penetration are measured after every frame, outside the timing.
    let (mut stretch, mut deepest) = (0.0f32, 0.0f32);
    let mut measure = |scene: &Scene| {
        stretch = stretch.max(crate::metrics::max_stretch(&scene.cloth));
        deepest = deepest.max(scene.max_penetration());
    };
    for _ in 0..warmup {
        scene.step_frame()?;
        measure(&scene);
    }
    let mut times = Vec::with_capacity(frames as usize);
    let mut stages: [Vec<f64>; 3] = Default::default();
    let mut substeps = 0;
    for _ in 0..frames {
        let start = Instant::now();
        let report = scene.step_frame()?;
        times.push(start.elapsed().as_secs_f64());
        substeps = report.substeps;
        let t = report.times;
        for (all, s) in
            stages
                .iter_mut()
                .zip([t.integrate, t.contacts + t.self_collision, t.constraints])
        {
            all.push(s);
        }
        measure(&scene);
    }
    let frame = median(times);
    let [integrate_s, collision_s, constraints_s] = stages.map(median);
    let sweeps = scene.solver.settings.xpbd_iterations as f64;
    let updates = scene.cloth.springs().len() as f64 * substeps as f64 * sweeps;
    let split = FrameSplit {
        integrate_s,
        collision_s,
        constraints_s,
        ns_per_spring: (integrator == Integrator::Xpbd && updates > 0.0)
            .then(|| 1e9 * integrate_s / updates),
    };
    let particles = scene.cloth.particle_count() as f64;
    let springs = scene.cloth.springs().len() as f64;
    let per_s = |x: f64| if frame > 0.0 { x / frame } else { 0.0 };
    Ok(BenchRow {
        scene: kind.name().to_string(),
        n,
        engine: "cloth3d".into(),
        integrator: integrator.name().into(),
        threads: threads(),
        substeps,
        self_collision: scene.cloth.params.self_collision,
        frame_wall_s: frame,
        particle_substeps_per_s: per_s(particles * substeps as f64),
        spring_evals_per_s: integrator
            .is_explicit()
            .then(|| per_s(springs * substeps as f64 * integrator.force_evaluations() as f64)),
        max_stretch: stretch,
        max_penetration: deepest,
        speedup_vs_rapier: None,
        split: Some(split),
    })
}

/// How much more arithmetic two threads of rayon's current pool get
/// through together than one alone: about 2 where each has a CPU to
/// itself, about 1 where they take turns on one (a virtual machine whose
/// two CPUs get one, or a machine busy with other work; a build beside it
/// gave 1.2–1.4). Each thread runs 24 independent chains of multiplies
/// and adds, more than one core's units finish at once, so two threads
/// on one core's two hyperthreads should read well under 2 (not checked:
/// the machines measured so far expose none). It does not see memory: two
/// threads that contend for the cache or memory still read 2. The bench
/// prints it after its rows, so that a two-thread figure can be read
/// against what the machine gave at the time. The median of five tries of
/// about 10 ms (1 without the `parallel` feature).
pub fn two_thread_gain() -> f64 {
    /// Rounds of a try, each a multiply and an add on every chain.
    const ROUNDS: u64 = 1_500_000;
    fn half(seed: f64) -> f64 {
        let mut acc = [seed; 24];
        for _ in 0..ROUNDS {
            for (k, a) in acc.iter_mut().enumerate() {
                *a = *a * 0.999_999_9 + 1.0e-7 * k as f64;
            }
        }
        std::hint::black_box(acc.iter().sum())
    }
    let mut gains = Vec::new();
    for _ in 0..5 {
        let start = Instant::now();
        half(1.0);
        let one = start.elapsed().as_secs_f64();
        let start = Instant::now();
        #[cfg(feature = "parallel")]
        rayon::join(|| half(1.0), || half(2.0));
        #[cfg(not(feature = "parallel"))]
        (half(1.0), half(2.0));
        let two = start.elapsed().as_secs_f64();
        gains.push(2.0 * one / two.max(1e-12));
    }
    median(gains)
}

/// Threads the step uses: rayon's current pool with the `parallel` feature, else 1.
pub fn threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}

/// Softness of rapier's cloth in the comparison: its constraints' natural
/// frequency (Hz) and damping ratio, with 4 solver iterations (rapier's default).
pub const RAPIER_SOFTNESS: (f32, f32) = (30.0, 1.0);

/// The `drape` scene with rapier's built-in soft-body cloth: an N×N, 1 kg,
/// 1 × 1 m cloth at y = 0.6 over a fixed ball of radius 0.3, at 1/60 s.
pub fn bench_rapier_drape(n: usize, warmup: u32, frames: u32) -> BenchRow {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = FRAME_DT;
    world.insert(RigidBodyBuilder::fixed(), ColliderBuilder::ball(0.3));
    let spacing = 1.0 / (n - 1) as f32;
    let builder = SoftBodyBuilder::cloth(
        Vector::new(-0.5, 0.6, -0.5),
        Vector::new(spacing, 0.0, 0.0),
        Vector::new(0.0, 0.0, spacing),
        n,
        n,
    )
    .particle_mass(CLOTH_MASS / (n * n) as f32)
    .softness(SpringCoefficients::new(
        RAPIER_SOFTNESS.0,
        RAPIER_SOFTNESS.1,
    ));
    let handle = world.insert_soft_body(builder);
    for _ in 0..warmup {
        world.step();
    }
    let mut times = Vec::with_capacity(frames as usize);
    for _ in 0..frames {
        let start = Instant::now();
        world.step();
        times.push(start.elapsed().as_secs_f64());
    }
    let frame = median(times);
    let (mut stretch, mut penetration) = (0.0f32, 0.0f32);
    if let Some(body) = world.soft_bodies.get(handle) {
        let x: Vec<Vector> = body.particle_positions().collect();
        for e in body.edges() {
            let [a, b] = e.vertices.map(|i| i as usize);
            let straight = e.rest_length < 1.01 * spacing;
            if e.kind == SoftBodyEdgeKind::Structural && straight {
                stretch = stretch.max((x[b] - x[a]).length() / e.rest_length - 1.0);
            }
        }
        for p in &x {
            penetration = penetration.max(0.3 - p.length());
        }
    }
    BenchRow {
        scene: "drape".into(),
        n,
        engine: "rapier-softbody".into(),
        integrator: "rapier-softbody".into(),
        threads: 1,
        substeps: world.integration_parameters.num_solver_iterations as u32,
        self_collision: false,
        frame_wall_s: frame,
        particle_substeps_per_s: if frame > 0.0 {
            (n * n) as f64 / frame
        } else {
            0.0
        },
        spring_evals_per_s: None,
        max_stretch: stretch,
        max_penetration: penetration.max(0.0),
        speedup_vs_rapier: None,
        split: None,
    }
}

/// Wall time per frame against particle count, one curve per engine and
/// integrator, both axes in powers of ten: the picture in BENCHMARKS.md.
pub fn plot(rows: &[BenchRow], width: u32, height: u32) -> Result<image::RgbImage, String> {
    let panel = super::plot::Panel {
        title: "drape: wall time per frame (1/60 s); one thread unless the label says".into(),
        y_label: "log10 ms per frame".into(),
        curves: curves(rows),
    };
    super::plot::draw(&[panel], "log10 particles", width, height)
}

/// The rows as curves of log10 ms per frame against log10 particles.
fn curves(rows: &[BenchRow]) -> Vec<super::plot::Curve> {
    let mut curves: Vec<super::plot::Curve> = Vec::new();
    // An engine and integrator keeps its colour; more threads draw it darker.
    let mut hues: Vec<String> = Vec::new();
    for row in rows {
        let base = match (row.engine.as_str(), row.self_collision) {
            ("cloth3d", false) => format!("cloth3d {}", row.integrator),
            ("cloth3d", true) => format!("cloth3d {} self-collision", row.integrator),
            _ => row.engine.clone(),
        };
        let label = match row.threads {
            1 => base.clone(),
            t => format!("{base}, {t} threads"),
        };
        let point = (
            ((row.n * row.n) as f64).log10(),
            (1000.0 * row.frame_wall_s).log10(),
        );
        match curves.iter_mut().find(|c| c.label == label) {
            Some(c) => c.points.push(point),
            None => {
                let hue = hues.iter().position(|h| *h == base).unwrap_or_else(|| {
                    hues.push(base);
                    hues.len() - 1
                });
                let color = super::plot::COLORS[hue % super::plot::COLORS.len()];
                let shade = 1.0 / row.threads.max(1) as f32;
                curves.push(super::plot::Curve {
                    label,
                    points: vec![point],
                    color: color.map(|c| (f32::from(c) * (0.4 + 0.6 * shade)) as u8),
                });
            }
        }
    }
    curves
}

/// How the rows compare with issue 7's targets, one line each, saying by how
/// much a missed target is missed: spring evaluations of symplectic Euler at
/// N = 128 (≥ 1e8/s), implicit Euler and fast mass-spring at N = 128
/// (≤ 1/120 s a frame), and every cloth3d row against rapier's cloth (≥ 3×).
pub fn target_lines(rows: &[BenchRow]) -> Vec<String> {
    let verdict = |ratio: f64| {
        if ratio >= 1.0 {
            "met".to_string()
        } else {
            format!("missed by {:.1}x", 1.0 / ratio.max(1e-12))
        }
    };
    let mut lines = Vec::new();
    // Self-collision's cost (issue 17): the row with it against the row
    // without, same scene, size, integrator and threads.
    for on in rows.iter().filter(|r| r.self_collision && r.n == 64) {
        let off = rows.iter().find(|r| {
            !r.self_collision
                && r.engine == on.engine
                && (&r.scene, r.n, &r.integrator, r.threads)
                    == (&on.scene, on.n, &on.integrator, on.threads)
        });
        if let Some(off) = off {
            let extra = on.frame_wall_s / off.frame_wall_s.max(1e-12) - 1.0;
            lines.push(format!(
                "{} {} N=64 {} thr: self-collision adds <= 50%: {:+.0}% ({})",
                on.scene,
                on.integrator,
                on.threads,
                100.0 * extra,
                verdict(1.5 / (1.0 + extra).max(1e-12))
            ));
        }
    }
    // The other targets are without self-collision.
    let plain: Vec<BenchRow> = rows.iter().filter(|r| !r.self_collision).cloned().collect();
    let rows = &plain[..];
    // Every target is for one thread, but the one that says so.
    for row in rows
        .iter()
        .filter(|r| r.engine == "cloth3d" && r.n == 128 && r.threads == 1)
    {
        if row.integrator == Integrator::SymplecticEuler.name() {
            if let Some(s) = row.spring_evals_per_s {
                lines.push(format!(
                    "{} N=128 spring evaluations >= 1e8/s: {s:.2e}/s ({})",
                    row.integrator,
                    verdict(s / 1e8)
                ));
            }
        }
        if row.integrator == Integrator::ImplicitEuler.name()
            || row.integrator == Integrator::FastMassSpring.name()
        {
            let ms = 1000.0 * row.frame_wall_s;
            lines.push(format!(
                "{} N=128 <= 8.33 ms a frame: {ms:.1} ms ({})",
                row.integrator,
                verdict(1000.0 / 120.0 / ms)
            ));
        }
    }
    // The real-time targets of the small-steps solver (one thread, drape).
    let xpbd = |r: &&BenchRow| r.engine == "cloth3d" && r.integrator == Integrator::Xpbd.name();
    for row in rows.iter().filter(xpbd).filter(|r| r.threads == 1) {
        let budget = match row.n {
            64 => Some(2.0),
            128 => Some(8.0),
            256 => Some(40.0),
            _ => None,
        };
        if let Some(budget) = budget {
            let ms = 1000.0 * row.frame_wall_s;
            lines.push(format!(
                "{} N={} <= {budget} ms a frame: {ms:.2} ms ({})",
                row.integrator,
                row.n,
                verdict(budget / ms)
            ));
            lines.push(format!(
                "{} N={} stretch < 5% in every frame: {:.2}% ({})",
                row.integrator,
                row.n,
                100.0 * row.max_stretch,
                verdict(0.05 / (row.max_stretch as f64).max(1e-9))
            ));
        }
        if let (Some(x), 64 | 128) = (row.speedup_vs_rapier, row.n) {
            lines.push(format!(
                "{} N={} >= 10x rapier's cloth: {x:.2}x ({})",
                row.integrator,
                row.n,
                verdict(x / 10.0)
            ));
        }
    }
    // Two threads against one, on the same scene and size.
    for two in rows
        .iter()
        .filter(xpbd)
        .filter(|r| r.threads == 2 && r.n == 128)
    {
        let one = rows
            .iter()
            .filter(xpbd)
            .find(|r| r.threads == 1 && r.n == two.n && r.scene == two.scene);
        if let Some(one) = one {
            let x = one.frame_wall_s / two.frame_wall_s.max(1e-12);
            lines.push(format!(
                "{} N={} 2 threads >= 1.7x one: {x:.2}x ({})",
                two.integrator,
                two.n,
                verdict(x / 1.7)
            ));
        }
    }
    for row in rows
        .iter()
        .filter(|r| r.engine == "cloth3d" && r.threads == 1)
    {
        if let Some(x) = row.speedup_vs_rapier {
            lines.push(format!(
                "{} N={} >= 3x rapier's cloth: {x:.2}x ({})",
                row.integrator,
                row.n,
                verdict(x / 3.0)
            ));
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(integrator: &str, frame_ms: f64, springs: Option<f64>) -> BenchRow {
        BenchRow {
            scene: "drape".into(),
            n: 128,
            engine: "cloth3d".into(),
            integrator: integrator.into(),
            threads: 1,
            substeps: 1,
            self_collision: false,
            frame_wall_s: frame_ms / 1000.0,
            particle_substeps_per_s: 1.0,
            spring_evals_per_s: springs,
            max_stretch: 0.01,
            max_penetration: 0.0,
            speedup_vs_rapier: Some(6.0),
            split: None,
        }
    }

    #[test]
    fn each_thread_count_is_its_own_curve() {
        let two = BenchRow {
            threads: 2,
            ..row("xpbd", 8.0, None)
        };
        let c = curves(&[row("xpbd", 16.0, None), two, row("xpbd", 30.0, None)]);
        let labels: Vec<&str> = c.iter().map(|c| c.label.as_str()).collect();
        assert_eq!(labels, ["cloth3d xpbd", "cloth3d xpbd, 2 threads"]);
        assert_eq!(c[0].points.len(), 2);
        assert_eq!(c[1].points.len(), 1);
        // The same hue, darker.
        let [r0, g0, b0] = c[0].color.map(u32::from);
        let [r1, g1, b1] = c[1].color.map(u32::from);
        assert!(
            r1 < r0 && g1 < g0 && b1 < b0,
            "{:?} {:?}",
            c[0].color,
            c[1].color
        );
    }

    #[test]
    fn target_lines_say_by_how_much_a_target_is_missed() {
        let lines = target_lines(&[
            row("symplectic-euler", 100.0, Some(5.0e7)),
            row("fast-mass-spring", 4.0, None),
            row("implicit-euler", 25.0, None),
        ]);
        let find = |s: &str| lines.iter().find(|l| l.starts_with(s)).cloned().unwrap();
        assert!(find("symplectic-euler N=128 spring").ends_with("(missed by 2.0x)"));
        assert!(find("fast-mass-spring N=128 <=").ends_with("(met)"));
        assert!(find("implicit-euler N=128 <=").ends_with("(missed by 3.0x)"));
        assert!(find("implicit-euler N=128 >= 3x").ends_with("(met)"));
        // The small-steps solver's real-time targets at N = 128.
        let lines = target_lines(&[row("xpbd", 16.0, None)]);
        let find = |s: &str| lines.iter().find(|l| l.starts_with(s)).cloned().unwrap();
        assert!(find("xpbd N=128 <= 8 ms").ends_with("(missed by 2.0x)"));
        assert!(find("xpbd N=128 stretch < 5%").ends_with("(met)"));
        assert!(find("xpbd N=128 >= 10x").ends_with("(missed by 1.7x)"));
        // Two threads against one; the one-thread targets only from one thread.
        let two = BenchRow {
            threads: 2,
            ..row("xpbd", 8.0, None)
        };
        let lines = target_lines(&[row("xpbd", 16.0, None), two.clone()]);
        let find = |s: &str| lines.iter().find(|l| l.starts_with(s)).cloned().unwrap();
        assert!(find("xpbd N=128 2 threads >= 1.7x one: 2.00x").ends_with("(met)"));
        assert_eq!(lines.iter().filter(|l| l.contains("<= 8 ms")).count(), 1);
        assert!(target_lines(&[two]).is_empty());
        let two_symplectic = BenchRow {
            threads: 2,
            ..row("symplectic-euler", 100.0, Some(5.0e7))
        };
        assert!(target_lines(&[two_symplectic]).is_empty());
    }
}
