//! The `cloth3d` command: run, list, compare, bench and export the scenes.
//! One file per subcommand; the scene flags are the library's
//! `cloth3d::cli::args::SceneArgs`, shared with the showcase.

mod bench;
mod compare;
mod export_scene;
mod list;
mod output;
mod run;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use bench::{bench_command, BenchArgs};
use compare::{compare_command, CompareArgs};
use export_scene::{export_scene_command, ExportSceneArgs};
use output::one_line;
use run::{run_command, RunArgs};

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
            list::list();
            ExitCode::SUCCESS
        }
        Command::Run(args) => run_command(args),
        Command::Bench(args) => bench_command(args),
        Command::Compare(args) => compare_command(args),
        Command::ExportScene(args) => export_scene_command(args),
    }
}
