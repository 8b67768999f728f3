//! `cloth3d bench`: the scenes timed at several sizes, beside rapier's cloth.

use std::process::ExitCode;

use cloth3d::cli::args::{
    parse_count, parse_frames, parse_integrator, parse_iterations, parse_n, parse_on_off,
    parse_scene, parse_substeps,
};
use cloth3d::scenes::SceneKind;
use cloth3d::scenes::{SceneOptions, SolverTuning};
use cloth3d::solver::{Integrator, Substeps};

use crate::output::emit;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenes to time (repeatable; rapier's cloth is compared on `drape`).
    #[arg(long, value_parser = parse_scene, default_values = ["drape"])]
    pub scene: Vec<SceneKind>,
    /// Particles along a row (repeatable).
    #[arg(long, value_parser = parse_n, default_values = ["32", "64", "128", "256"], allow_hyphen_values = true)]
    pub n: Vec<usize>,
    /// Integrators (repeatable).
    #[arg(long, value_parser = parse_integrator, default_values = ["xpbd", "symplectic-euler", "implicit-euler", "fast-mass-spring"])]
    pub integrator: Vec<Integrator>,
    /// Frames run before timing (the cloth lands on the obstacle).
    #[arg(long, value_parser = parse_count, default_value = "30", allow_hyphen_values = true)]
    pub warmup: u32,
    /// Frames timed (the median is reported).
    #[arg(long, value_parser = parse_frames, default_value = "10", allow_hyphen_values = true)]
    pub frames: u32,
    /// Threads a cloth3d row runs on (repeatable: each row once per count).
    /// Rapier's cloth runs on one.
    #[arg(long, value_parser = parse_frames, default_values = ["1"], allow_hyphen_values = true)]
    pub threads: Vec<u32>,
    /// Self-collision on or off (repeatable: each row once per value;
    /// default: the scene's own).
    #[arg(long = "self-collision", value_name = "on|off", value_parser = parse_on_off)]
    pub self_collision: Vec<bool>,
    /// Substeps per frame for every row (`auto` or a count; default: each integrator's own).
    #[arg(long, value_parser = parse_substeps)]
    pub substeps: Option<Substeps>,
    /// Spring sweeps per substep of the small-steps solver (xpbd).
    #[arg(long, value_parser = parse_iterations, allow_hyphen_values = true)]
    pub xpbd_iterations: Option<u32>,
    /// Direct solves along rows and columns in the small-steps solver
    /// (xpbd on a grid; default on).
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    pub xpbd_chains: Option<bool>,
    /// Skip rapier's built-in cloth.
    #[arg(long)]
    pub no_rapier: bool,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Draw wall time per frame against particle count to this PNG.
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<std::path::PathBuf>,
}

/// Above this N the fast mass-spring solver's Cholesky factor (and a
/// frame of it, seconds at N = 256) grows too large for the bench.
const FMS_MAX_N: usize = 256;

/// Times the rows and prints them (a table, or JSON lines), with the targets.
pub fn bench_command(args: BenchArgs) -> ExitCode {
    let mut pools = Vec::new();
    for &threads in &args.threads {
        match Threads::start(threads) {
            Ok(pool) => pools.push(pool),
            Err(e) => {
                eprintln!("error: --threads {threads}: {e}");
                return ExitCode::from(2);
            }
        }
    }
    bench_rows(&args, &pools)
}

/// A thread count the rows run on: a rayon pool of that many threads (the
/// `cli` feature brings `parallel` along).
struct Threads {
    pool: rayon::ThreadPool,
}

impl Threads {
    fn start(threads: u32) -> Result<Threads, String> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads as usize)
            .build()
            .map(|pool| Threads { pool })
            .map_err(|e| format!("cannot start the threads: {e}"))
    }

    /// How many threads the pool has.
    fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Runs `f` on these threads.
    fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }
}

fn bench_rows(args: &BenchArgs, pools: &[Threads]) -> ExitCode {
    use cloth3d::cli::bench::{bench_cloth3d, bench_rapier_drape, BenchRow};
    if !args.json {
        emit(&format!(
            "{:<8} {:>5} {:<18} {:>3} {:>4} {:>8} {:>11} {:>14} {:>14} {:>9} {:>9} {:>9}\n",
            "scene",
            "n",
            "integrator",
            "thr",
            "self",
            "substeps",
            "ms/frame",
            "part.sub/s",
            "springs/s",
            "stretch",
            "penetr.",
            "vs rapier"
        ));
    }
    let tuning = SceneOptions {
        substeps: args.substeps,
        solver: SolverTuning {
            xpbd_iterations: args.xpbd_iterations,
            xpbd_chains: args.xpbd_chains,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut rows = Vec::new();
    let mut print = |row: &BenchRow| {
        rows.push(row.clone());
        if args.json {
            emit(&format!(
                "{}\n",
                serde_json::to_string(row).unwrap_or_default()
            ));
        } else {
            emit(&format!(
                "{:<8} {:>5} {:<18} {:>3} {:>4} {:>8} {:>11.2} {:>14.3e} {:>14} {:>8.2}% {:>8.4} {:>9}\n",
                row.scene,
                row.n,
                row.integrator,
                row.threads,
                match (row.engine.as_str(), row.self_collision) {
                    ("cloth3d", true) => "on",
                    ("cloth3d", false) => "off",
                    _ => "-",
                },
                row.substeps,
                1000.0 * row.frame_wall_s,
                row.particle_substeps_per_s,
                row.spring_evals_per_s
                    .map(|s| format!("{s:.3e}"))
                    .unwrap_or_else(|| "-".into()),
                100.0 * row.max_stretch,
                row.max_penetration,
                row.speedup_vs_rapier
                    .map(|s| format!("{s:.2}x"))
                    .unwrap_or_else(|| "-".into()),
            ));
        }
    };
    for &kind in &args.scene {
        for &n in &args.n {
            let rapier = (kind == SceneKind::Drape && !args.no_rapier)
                .then(|| bench_rapier_drape(n, args.warmup, args.frames));
            if let Some(row) = &rapier {
                print(row);
            }
            for &integrator in &args.integrator {
                if integrator == Integrator::FastMassSpring && n > FMS_MAX_N {
                    if !args.json {
                        emit(&format!("{:<8} {n:>5} {:<18} skipped: the Cholesky factor above N = {FMS_MAX_N} is too large\n", kind.name(), integrator.name()));
                    }
                    continue;
                }
                let choices: Vec<Option<bool>> = if args.self_collision.is_empty() {
                    vec![None]
                } else {
                    args.self_collision.iter().map(|&on| Some(on)).collect()
                };
                for (pool, self_collision) in pools
                    .iter()
                    .flat_map(|p| choices.iter().map(move |&c| (p, c)))
                {
                    let frames = (args.warmup, args.frames);
                    let tuning = SceneOptions {
                        self_collision,
                        ..tuning.clone()
                    };
                    match pool.run(|| bench_cloth3d(kind, n, integrator, frames, &tuning)) {
                        Ok(mut row) => {
                            row.speedup_vs_rapier = rapier
                                .as_ref()
                                .map(|r| r.frame_wall_s / row.frame_wall_s.max(1e-12));
                            print(&row);
                        }
                        Err(e) => eprintln!("{} N={n} {}: {e}", kind.name(), integrator.name()),
                    }
                }
            }
        }
    }
    if !args.json {
        print_split(&rows);
        let lines = cloth3d::cli::bench::target_lines(&rows);
        if !lines.is_empty() {
            emit("\ntargets (issues 7 and 16):\n");
            for line in lines {
                emit(&format!("  {line}\n"));
            }
        }
        // What the machine's two threads gave just now: a two-thread row
        // is read against it (where the two CPUs take turns it is near 1,
        // and no step can do better).
        if let Some(two) = pools.iter().find(|p| p.threads() == 2) {
            let gain = two.run(cloth3d::cli::bench::two_thread_gain);
            emit(&format!(
                "\nhost: two threads did {gain:.2}x one thread's independent arithmetic just after the rows\n"
            ));
        }
    }
    if let Some(path) = &args.plot {
        let written = cloth3d::cli::bench::plot(&rows, 900, 560)
            .and_then(|img| img.save(path).map_err(|e| e.to_string()));
        if let Err(e) = written {
            eprintln!("error: {}: {e}", path.display());
            return ExitCode::from(2);
        }
    }
    ExitCode::SUCCESS
}

/// How the cloth3d rows' frames split among the stages, in ms a frame.
fn print_split(rows: &[cloth3d::cli::bench::BenchRow]) {
    let split: Vec<_> = rows
        .iter()
        .filter_map(|r| r.split.map(|s| (r, s)))
        .collect();
    if split.is_empty() {
        return;
    }
    emit(&format!(
        "\n{:<8} {:>5} {:<18} {:>3} {:>10} {:>10} {:>10} {:>10} {:>9}\n",
        "split", "n", "integrator", "thr", "integrate", "collision", "limits", "rest", "ns/spring"
    ));
    for (row, s) in split {
        let frame = row.frame_wall_s;
        let rest = frame - s.integrate_s - s.collision_s - s.constraints_s;
        emit(&format!(
            "{:<8} {:>5} {:<18} {:>3} {:>10.2} {:>10.2} {:>10.2} {:>10.2} {:>9}\n",
            row.scene,
            row.n,
            row.integrator,
            row.threads,
            1000.0 * s.integrate_s,
            1000.0 * s.collision_s,
            1000.0 * s.constraints_s,
            1000.0 * rest,
            s.ns_per_spring
                .map(|ns| format!("{ns:.2}"))
                .unwrap_or_else(|| "-".into()),
        ));
    }
    emit("(ms a frame, medians over the timed frames; rest: the frame less the others)\n");
}
