//! `cloth3d compare`: every integrator on one scene, a table and a plot.

use std::process::ExitCode;

use cloth3d::cli::args::SceneArgs;
use cloth3d::scenes::Scene;

use crate::outln;
use crate::output::emit;

#[derive(clap::Args)]
pub struct CompareArgs {
    /// Scene name, or path to a RON scene file.
    pub scene: String,
    /// The scene's flags; every integrator runs in turn at its default
    /// substeps, so `--integrator` and `--substeps` are replaced per row.
    #[command(flatten)]
    pub options: SceneArgs,
    /// Where to write the plot of energy (top) and max stretch (bottom).
    #[arg(long, default_value = "compare.png")]
    pub plot: std::path::PathBuf,
    /// One JSON object per integrator instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs the comparison and prints it.
pub fn compare_command(args: CompareArgs) -> ExitCode {
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
                match (&row.refused, row.stable) {
                    (Some(_), _) => "refused",
                    (None, true) => "yes",
                    (None, false) => "DIVERGED",
                },
                row.substeps,
                row.iterations
                    .map(|i| i.to_string())
                    .unwrap_or_else(|| "-".into()),
                100.0 * row.max_stretch,
                row.energy_change,
                1000.0 * row.frame_wall_s,
            );
        }
        for row in &rows {
            if let Some(reason) = &row.refused {
                outln!(out, "refused: {reason}");
            }
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
