//! The `cloth3d` command: run the canonical scenes and print their metrics.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use cloth3d::cli::args::{
    parse_count, parse_frames, parse_integrator, parse_n, parse_scene, SceneArgs,
};
use cloth3d::cloth::{Material, PinPreset};
use cloth3d::scenes::{file, run_with, RunMetrics, Scene, SceneKind};
use cloth3d::solver::Integrator;

#[derive(Parser)]
#[command(
    name = "cloth3d",
    version,
    about = "Mass-spring cloth for rapier3d and parry3d: run the canonical scenes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and print its metrics.
    Run(RunArgs),
    /// List the scenes, variants, integrators and materials.
    List,
    /// Time the scenes at several sizes, against rapier's built-in soft-body cloth.
    Bench(BenchArgs),
    /// Run every integrator on one scene at the same frame step: a table and a plot.
    Compare(CompareArgs),
    /// Write a canonical scene as a RON scene file (on stdout, or to --output).
    ExportScene(ExportSceneArgs),
}

#[derive(clap::Args)]
struct ExportSceneArgs {
    /// Scene name, or a scene file to rewrite with the options applied.
    scene: String,
    #[command(flatten)]
    options: SceneArgs,
    /// Write to this file instead of stdout.
    #[arg(long, short)]
    output: Option<std::path::PathBuf>,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// Scene name, or path to a RON scene file.
    scene: String,
    /// The scene's flags; every integrator runs in turn at its default
    /// substeps, so `--integrator` and `--substeps` are replaced per row.
    #[command(flatten)]
    options: SceneArgs,
    /// Where to write the plot of energy (top) and max stretch (bottom).
    #[arg(long, default_value = "compare.png")]
    plot: std::path::PathBuf,
    /// One JSON object per integrator instead of a table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scenes to time (repeatable; rapier's cloth is compared on `drape`).
    #[arg(long, value_parser = parse_scene, default_values = ["drape"])]
    scene: Vec<SceneKind>,
    /// Particles along a row (repeatable).
    #[arg(long, value_parser = parse_n, default_values = ["32", "64", "128", "256"], allow_hyphen_values = true)]
    n: Vec<usize>,
    /// Integrators (repeatable).
    #[arg(long, value_parser = parse_integrator, default_values = ["symplectic-euler", "implicit-euler", "fast-mass-spring"])]
    integrator: Vec<Integrator>,
    /// Frames run before timing (the cloth lands on the obstacle).
    #[arg(long, value_parser = parse_count, default_value = "30", allow_hyphen_values = true)]
    warmup: u32,
    /// Frames timed (the median is reported).
    #[arg(long, value_parser = parse_frames, default_value = "10", allow_hyphen_values = true)]
    frames: u32,
    /// Threads (only 1 until the parallel step lands).
    #[arg(long, value_parser = parse_frames, default_value = "1", allow_hyphen_values = true)]
    threads: u32,
    /// Skip rapier's built-in cloth.
    #[arg(long)]
    no_rapier: bool,
    /// One JSON object per line instead of a table.
    #[arg(long)]
    json: bool,
    /// Draw wall time per frame against particle count to this PNG.
    #[arg(long, value_name = "FILE.png")]
    plot: Option<std::path::PathBuf>,
}

#[derive(clap::Args)]
struct RunArgs {
    /// Scene name (see `cloth3d list`) or path to a RON scene file.
    scene: String,
    #[command(flatten)]
    options: SceneArgs,
    /// Write the cloth of every frame as DIR/frame_0001.obj, ... (Blender's OBJ sequence import).
    #[arg(long, value_name = "DIR")]
    export_obj: Option<std::path::PathBuf>,
    /// Write the animation as one glTF 2.0 binary file: the final frame's
    /// mesh, with every frame as a morph target played by an animation.
    #[arg(long, value_name = "FILE.glb")]
    export_glb: Option<std::path::PathBuf>,
    /// Draw energy, max stretch and max penetration over time to a PNG.
    #[arg(long, value_name = "FILE.png")]
    plot: Option<std::path::PathBuf>,
    /// No progress bar (it is only ever shown when stdout is a terminal).
    #[arg(long, short)]
    quiet: bool,
    /// Print exactly one JSON object and nothing else on stdout.
    #[arg(long)]
    json: bool,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                print!("{e}");
                return ExitCode::SUCCESS;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                eprint!("{e}");
                return ExitCode::from(2);
            }
            eprintln!("{}", one_line(&e.to_string()));
            return ExitCode::from(2);
        }
    };
    match cli.command {
        Command::List => {
            list();
            ExitCode::SUCCESS
        }
        Command::Run(args) => run_command(args),
        Command::Bench(args) => bench_command(args),
        Command::Compare(args) => compare_command(args),
        Command::ExportScene(args) => export_scene_command(args),
    }
}

/// `writeln!` into a `String` (which cannot fail).
macro_rules! outln {
    ($out:expr) => {
        $out.push('\n')
    };
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($out, $($arg)*);
    }};
}

/// `write!` into a `String` (which cannot fail).
macro_rules! outp {
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = write!($out, $($arg)*);
    }};
}

/// Writes to stdout; a closed pipe (`cloth3d list | head`) is not an error.
fn emit(text: &str) {
    use std::io::Write as _;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// The first paragraph of a clap error, on one line.
fn one_line(message: &str) -> String {
    message
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(" ")
}

fn list() {
    let mut out = String::new();
    outln!(out, "scenes:");
    for s in SceneKind::ALL {
        let variants = s.variants().iter().map(|v| v.name()).collect::<Vec<_>>();
        let (c, r) = s.default_grid();
        outp!(
            out,
            "  {:<8} {c}×{r}, {} frames: {}",
            s.name(),
            s.default_frames(),
            s.description()
        );
        if !variants.is_empty() {
            outp!(out, " [variants: {}]", variants.join(", "));
        }
        outln!(out);
    }
    outln!(out, "integrators:");
    for i in Integrator::ALL {
        outln!(out, "  {}", i.name());
    }
    outln!(out, "materials:");
    for m in Material::presets() {
        outln!(
            out,
            "  {:<8} stretch {} N/m, shear {} N/m, bend {} N/m, {} kg/m²",
            m.name,
            m.stretch.stiffness,
            m.shear.stiffness,
            m.bend.stiffness,
            m.density
        );
    }
    outln!(out, "pin presets:");
    for p in PinPreset::ALL {
        outln!(out, "  {}", p.name());
    }
    emit(&out);
}

fn export_scene_command(args: ExportSceneArgs) -> ExitCode {
    let options = args.options.options();
    let text = match Scene::open(&args.scene, &options).and_then(|s| file::to_ron(&s.desc)) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    match &args.output {
        None => emit(&text),
        Some(path) => {
            if let Err(e) = std::fs::write(path, text) {
                eprintln!("error: cannot write {}: {e}", path.display());
                return ExitCode::from(1);
            }
        }
    }
    ExitCode::SUCCESS
}

/// A progress bar on stderr when stdout is a terminal and not `--quiet`;
/// hidden otherwise, so piped or `--json` output never carries progress text.
fn progress_bar(frames: u32, quiet: bool, name: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal as _;
    if quiet || !std::io::stdout().is_terminal() || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(frames as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:40}] {pos}/{len} frames, {per_sec}, {eta} left",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(name.to_string());
    bar
}

fn run_command(args: RunArgs) -> ExitCode {
    let options = args.options.options();
    let mut scene = match Scene::open(&args.scene, &options) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let frames = scene.frames;
    if let Some(dir) = &args.export_obj {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!("error: cannot create {}: {e}", dir.display());
            return ExitCode::from(2);
        }
    }
    let mut export_error = None;
    let mut animation = args
        .export_glb
        .as_ref()
        .map(|_| cloth3d::export::Animation::new(scene.dt));
    let mut series = cloth3d::scenes::Series::default();
    let bar = progress_bar(frames, args.quiet, &scene.name);
    let result = run_with(&mut scene, frames, |scene, frame, max_penetration| {
        bar.inc(1);
        if let (Some(dir), None) = (&args.export_obj, &export_error) {
            let path = dir.join(format!("frame_{:04}.obj", frame + 1));
            if let Err(e) = cloth3d::export::write_obj(&scene.cloth, &path) {
                export_error = Some(format!("cannot write {}: {e}", path.display()));
            }
        }
        if let Some(anim) = &mut animation {
            anim.push(&scene.cloth);
        }
        if args.plot.is_some() {
            series.push(scene, max_penetration);
        }
    });
    bar.finish_and_clear();
    if let (Some(path), Some(anim), None) = (&args.export_glb, &animation, &export_error) {
        if let Err(e) = std::fs::write(path, anim.to_glb(&scene.cloth)) {
            export_error = Some(format!("cannot write {}: {e}", path.display()));
        }
    }
    if let (Some(path), None) = (&args.plot, &export_error) {
        if let Err(e) = cloth3d::cli::plot::series(&series, &scene.name, 900, 900)
            .and_then(|img| img.save(path).map_err(|e| e.to_string()))
        {
            export_error = Some(format!("cannot write {}: {e}", path.display()));
        }
    }
    if let Some(e) = export_error {
        eprintln!("error: {e}");
        return ExitCode::from(1);
    }
    match result {
        Ok(m) => {
            if args.json {
                match serde_json::to_string(&m) {
                    Ok(s) => emit(&format!("{s}\n")),
                    Err(e) => {
                        eprintln!("error: {e}");
                        return ExitCode::from(1);
                    }
                }
            } else {
                print_table(&m);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn compare_command(args: CompareArgs) -> ExitCode {
    use cloth3d::cli::compare::{compare_desc, plot, COLORS};
    let options = args.options.options();
    let rows = Scene::open(&args.scene, &options)
        .and_then(|scene| compare_desc(&scene.desc, scene.frames));
    let rows = match rows {
        Ok(rows) => rows,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    if let Err(e) =
        plot(&rows, 900, 700).and_then(|img| img.save(&args.plot).map_err(|e| e.to_string()))
    {
        eprintln!("error: cannot write {}: {e}", args.plot.display());
        return ExitCode::from(1);
    }
    let mut out = String::new();
    if args.json {
        for row in &rows {
            let mut row = row.clone();
            row.energy.clear();
            row.stretch.clear();
            outln!(out, "{}", serde_json::to_string(&row).unwrap_or_default());
        }
    } else {
        outln!(
            out,
            "{:<18} {:<8} {:>8} {:>10} {:>10} {:>14} {:>11}  {}",
            "integrator",
            "stable",
            "substeps",
            "iterations",
            "stretch",
            "energy change",
            "ms/frame",
            "plot colour"
        );
        for (k, row) in rows.iter().enumerate() {
            let [r, g, b] = COLORS[k % COLORS.len()];
            outln!(
                out,
                "{:<18} {:<8} {:>8} {:>10} {:>9.2}% {:>12.4} J {:>11.2}  #{r:02x}{g:02x}{b:02x}",
                row.integrator,
                if row.stable { "yes" } else { "DIVERGED" },
                row.substeps,
                row.iterations
                    .map(|i| i.to_string())
                    .unwrap_or_else(|| "-".into()),
                100.0 * row.max_stretch,
                row.energy_change,
                1000.0 * row.frame_wall_s,
            );
        }
        outln!(
            out,
            "plot: {} (energy on top, max stretch below, against time)",
            args.plot.display()
        );
    }
    emit(&out);
    ExitCode::SUCCESS
}

/// Above this N the fast mass-spring solver's Cholesky factor (and a
/// frame of it, seconds at N = 256) grows too large for the bench.
const FMS_MAX_N: usize = 256;

fn bench_command(args: BenchArgs) -> ExitCode {
    #[cfg(not(feature = "parallel"))]
    if args.threads != 1 {
        eprintln!(
            "error: --threads {}: this build is single-threaded; build with --features parallel",
            args.threads
        );
        return ExitCode::from(2);
    }
    #[cfg(feature = "parallel")]
    {
        let pool = match rayon::ThreadPoolBuilder::new()
            .num_threads(args.threads as usize)
            .build()
        {
            Ok(pool) => pool,
            Err(e) => {
                eprintln!("error: cannot start {} threads: {e}", args.threads);
                return ExitCode::from(2);
            }
        };
        pool.install(|| bench_rows(&args))
    }
    #[cfg(not(feature = "parallel"))]
    bench_rows(&args)
}

fn bench_rows(args: &BenchArgs) -> ExitCode {
    use cloth3d::cli::bench::{bench_cloth3d, bench_rapier_drape, BenchRow};
    if !args.json {
        emit(&format!(
            "{:<8} {:>5} {:<18} {:>8} {:>11} {:>14} {:>14} {:>9} {:>9} {:>9}\n",
            "scene",
            "n",
            "integrator",
            "substeps",
            "ms/frame",
            "part.sub/s",
            "springs/s",
            "stretch",
            "penetr.",
            "vs rapier"
        ));
    }
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
                "{:<8} {:>5} {:<18} {:>8} {:>11.2} {:>14.3e} {:>14} {:>8.2}% {:>8.4} {:>9}\n",
                row.scene,
                row.n,
                row.integrator,
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
                match bench_cloth3d(kind, n, integrator, args.warmup, args.frames) {
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
    if !args.json {
        let lines = cloth3d::cli::bench::target_lines(&rows);
        if !lines.is_empty() {
            emit("\ntargets (issue 7):\n");
            for line in lines {
                emit(&format!("  {line}\n"));
            }
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

fn print_table(m: &RunMetrics) {
    let mut out = String::new();
    let variant = m
        .variant
        .as_deref()
        .map(|v| format!(" ({v})"))
        .unwrap_or_default();
    outln!(out, "scene                      {}{variant}", m.scene);
    outln!(
        out,
        "grid                       {}×{}",
        m.grid[0],
        m.grid[1]
    );
    outln!(out, "integrator                 {}", m.integrator);
    outln!(out, "material                   {}", m.material);
    outln!(
        out,
        "dt                         {} s × {} frames",
        m.dt,
        m.frames
    );
    outln!(out, "substeps                   {}", m.substeps);
    if let Some(it) = m.iterations {
        outln!(out, "iterations per frame       {it}");
    }
    outln!(out, "max_penetration            {:.6} m", m.max_penetration);
    outln!(
        out,
        "max_penetration_any_frame  {:.6} m",
        m.max_penetration_any_frame
    );
    outln!(
        out,
        "max_stretch                {:.4} ({:.2}%)",
        m.max_stretch,
        100.0 * m.max_stretch
    );
    outln!(out, "min_y                      {:.4} m", m.min_y);
    outln!(
        out,
        "centroid                   ({:.4}, {:.4}, {:.4}) m",
        m.centroid[0],
        m.centroid[1],
        m.centroid[2]
    );
    outln!(out, "energy                     {:.4} J", m.energy);
    outln!(out, "finite                     {}", m.finite);
    outln!(
        out,
        "step_wall_s                {:.4} s ({:.3} ms/frame)",
        m.step_wall_s,
        1000.0 * m.step_wall_s / m.frames.max(1) as f64
    );
    outln!(
        out,
        "particle_substeps_per_s    {:.3e}",
        m.particle_substeps_per_s
    );
    emit(&out);
}
