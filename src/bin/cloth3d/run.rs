//! `cloth3d run`: a scene simulated, its metrics printed, its frames exported.

use std::process::ExitCode;

use cloth3d::cli::args::SceneArgs;
use cloth3d::scenes::{run_with, RunMetrics, Scene};

use crate::outln;
use crate::output::{emit, progress_bar};

#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene name (see `cloth3d list`) or path to a RON scene file.
    pub scene: String,
    #[command(flatten)]
    pub options: SceneArgs,
    /// Write the cloth of every frame as DIR/frame_0001.obj, ... (Blender's OBJ sequence import).
    #[arg(long, value_name = "DIR")]
    pub export_obj: Option<std::path::PathBuf>,
    /// Write the animation as one glTF 2.0 binary file: the final frame's
    /// mesh, with every frame as a morph target played by an animation.
    #[arg(long, value_name = "FILE.glb")]
    pub export_glb: Option<std::path::PathBuf>,
    /// Draw energy, max stretch and max penetration over time to a PNG.
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<std::path::PathBuf>,
    /// No progress bar (it is only ever shown when stdout is a terminal).
    #[arg(long, short)]
    pub quiet: bool,
    /// Print exactly one JSON object and nothing else on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Runs the scene and prints its metrics.
pub fn run_command(args: RunArgs) -> ExitCode {
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
    outln!(
        out,
        "max_stretch_any_frame      {:.4} ({:.2}%)",
        m.max_stretch_any_frame,
        100.0 * m.max_stretch_any_frame
    );
    outln!(
        out,
        "self_intersections         {} (worst frame {})",
        m.self_intersections,
        m.self_intersections_any_frame
    );
    outln!(
        out,
        "torn_springs               {} ({} piece{})",
        m.torn_springs,
        m.pieces,
        if m.pieces == 1 { "" } else { "s" }
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
