//! `cloth3d export-scene`: a scene, with the flags applied, as a RON file.

use std::process::ExitCode;

use cloth3d::cli::args::SceneArgs;
use cloth3d::scenes::{file, Scene};

use crate::output::emit;

#[derive(clap::Args)]
pub struct ExportSceneArgs {
    /// Scene name, or a scene file to rewrite with the options applied.
    pub scene: String,
    #[command(flatten)]
    pub options: SceneArgs,
    /// Write to this file instead of stdout.
    #[arg(long, short)]
    pub output: Option<std::path::PathBuf>,
}

/// Writes the scene on stdout or to `--output`.
pub fn export_scene_command(args: ExportSceneArgs) -> ExitCode {
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
