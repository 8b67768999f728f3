//! Every integrator on the same scene at the same frame step: the comparison
//! `cloth3d compare` prints and plots.

use std::time::Instant;

use image::RgbImage;
use serde::{Deserialize, Serialize};

use super::plot::{draw, Curve, Panel};
use crate::error::ClothError;
use crate::scenes::{Scene, SceneDesc, SceneError, SceneKind, SceneOptions};
use crate::solver::Integrator;

/// How one integrator did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Integrator name.
    pub integrator: String,
    /// False when a step diverged (the run stops there).
    pub stable: bool,
    /// Why the integrator refused the scene, if it did (it then has no frames).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
    /// Substeps per frame.
    pub substeps: u32,
    /// Solver iterations per frame, for the iterative integrators.
    pub iterations: Option<u32>,
    /// Largest stretch-spring strain on the last frame.
    pub max_stretch: f32,
    /// Total energy on the last frame minus on the first, in joules (the
    /// cloth falls, so it is negative; compare it between integrators).
    pub energy_change: f64,
    /// Mean wall time of a frame, in seconds.
    pub frame_wall_s: f64,
    /// Total energy after every frame, in joules.
    pub energy: Vec<f64>,
    /// Largest stretch after every frame.
    pub stretch: Vec<f32>,
}

/// Runs every integrator on `kind` for `frames` frames at frame step `dt`:
/// explicit ones with automatic substeps, implicit ones with one step a frame.
pub fn compare(
    kind: SceneKind,
    options: &SceneOptions,
    frames: u32,
) -> Result<Vec<Comparison>, SceneError> {
    compare_desc(&kind.desc(options)?, frames)
}

/// [`compare`] on any scene description (a scene file's, for one).
pub fn compare_desc(desc: &SceneDesc, frames: u32) -> Result<Vec<Comparison>, SceneError> {
    let mut rows = Vec::new();
    for integrator in Integrator::ALL {
        let mut desc = desc.clone();
        desc.apply(&SceneOptions {
            integrator: Some(integrator),
            substeps: Some(integrator.default_substeps()),
            ..Default::default()
        })?;
        let mut scene = Scene::from_desc(desc)?;
        let start_energy = scene.cloth.energy().total();
        let mut row = Comparison {
            integrator: integrator.name().into(),
            stable: true,
            refused: None,
            substeps: scene.solver.substeps_for(&scene.cloth, scene.dt),
            iterations: None,
            max_stretch: 0.0,
            energy_change: 0.0,
            frame_wall_s: 0.0,
            energy: Vec::new(),
            stretch: Vec::new(),
        };
        let mut wall = 0.0;
        let mut iterations = 0u64;
        for _ in 0..frames {
            let t = Instant::now();
            match scene.step_frame() {
                Ok(report) => {
                    iterations += report.iterations as u64;
                    row.substeps = report.substeps;
                }
                Err(ClothError::Diverged { .. }) => {
                    row.stable = false;
                    break;
                }
                Err(
                    e @ (ClothError::CannotCarryBodies { .. }
                    | ClothError::SelfCollisionNeedsSubsteps { .. }),
                ) => {
                    row.refused = Some(e.to_string());
                    break;
                }
                Err(e) => return Err(e.into()),
            }
            wall += t.elapsed().as_secs_f64();
            row.energy.push(scene.cloth.energy().total());
            row.stretch.push(crate::metrics::max_stretch(&scene.cloth));
        }
        let done = row.energy.len().max(1);
        row.frame_wall_s = wall / done as f64;
        row.iterations = (iterations > 0).then(|| (iterations / done as u64) as u32);
        row.max_stretch = row.stretch.last().copied().unwrap_or(0.0);
        row.energy_change = row.energy.last().map_or(0.0, |e| e - start_energy);
        rows.push(row);
    }
    Ok(rows)
}

/// A line colour per integrator, in the order of [`Integrator::ALL`].
pub const COLORS: [[u8; 3]; 7] = super::plot::COLORS;

/// The plot: energy (top) and max stretch (bottom) against the frame, one
/// line per integrator in the colours of [`COLORS`], with a legend.
pub fn plot(rows: &[Comparison], width: u32, height: u32) -> Result<RgbImage, String> {
    let curves = |value: &dyn Fn(&Comparison) -> Vec<f64>| {
        rows.iter()
            .enumerate()
            .map(|(k, r)| Curve {
                label: r.integrator.clone(),
                points: value(r)
                    .into_iter()
                    .enumerate()
                    .map(|(i, v)| ((i + 1) as f64, v))
                    .collect(),
                color: COLORS[k % COLORS.len()],
            })
            .collect()
    };
    let panels = [
        Panel {
            title: "total energy".into(),
            y_label: "energy (J)".into(),
            curves: curves(&|r| r.energy.clone()),
        },
        Panel {
            title: "max stretch".into(),
            y_label: "stretch (%)".into(),
            curves: curves(&|r| r.stretch.iter().map(|&s| 100.0 * s as f64).collect()),
        },
    ];
    draw(&panels, "frame", width, height)
}
