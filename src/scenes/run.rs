//! A run of a scene: its frames stepped and measured, with what every run
//! reports (docs/SCENES.md), and the measures frame by frame for plots.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::world::Scene;
use crate::collision::self_intersections;
use crate::error::ClothError;
use crate::metrics::{max_stretch, pieces};
use crate::solver::SolverSettings;

/// The metrics of one run of a scene, as `cloth3d run --json` prints them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunMetrics {
    /// Scene name.
    pub scene: String,
    /// Pin variant, when the scene has one.
    pub variant: Option<String>,
    /// Particles along a row.
    pub n: usize,
    /// Grid as (columns, rows).
    pub grid: [usize; 2],
    /// Integrator name.
    pub integrator: String,
    /// Every setting of the solver the run used (integrator, substeps,
    /// iterations, tolerances).
    pub solver: SolverSettings,
    /// Material name.
    pub material: String,
    /// Frame step, in seconds.
    pub dt: f32,
    /// Substeps per frame (the largest used, when chosen automatically).
    pub substeps: u32,
    /// Solver iterations per frame, for the integrators that iterate.
    pub iterations: Option<u32>,
    /// Frames simulated.
    pub frames: u32,
    /// Deepest particle inside any obstacle on the final frame, in metres.
    pub max_penetration: f32,
    /// Deepest particle inside any obstacle over all frames, in metres.
    pub max_penetration_any_frame: f32,
    /// Largest stretch-spring strain on the final frame.
    pub max_stretch: f32,
    /// Largest stretch-spring strain over all frames (a landing's peak).
    #[serde(default)]
    pub max_stretch_any_frame: f32,
    /// Where the cloth passes through itself on the final frame: pairs of a
    /// particle and a triangle not its neighbours closer than half the
    /// thickness, and triangle edges crossing triangles
    /// ([`crate::collision::self_intersections`]).
    pub self_intersections: usize,
    /// The most self-intersections of any frame.
    pub self_intersections_any_frame: usize,
    /// Stretch springs that tore over the run (0 unless the material has a
    /// tear strain, as the `tear` scene's has).
    #[serde(default)]
    pub torn_springs: u64,
    /// True when the cloth slept through the final frame (with sleeping on).
    #[serde(default)]
    pub asleep: bool,
    /// Frames the cloth slept through.
    #[serde(default)]
    pub asleep_frames: u32,
    /// Pieces the cloth is in on the final frame (1 for a whole cloth;
    /// see [`crate::metrics::pieces`]).
    #[serde(default = "one")]
    pub pieces: usize,
    /// Lowest particle height on the final frame, in metres.
    pub min_y: f32,
    /// Centre of the cloth on the final frame, in metres.
    pub centroid: [f32; 3],
    /// Total energy on the final frame (kinetic + gravity + elastic), in joules.
    pub energy: f64,
    /// False if any position or velocity became NaN or infinite.
    pub finite: bool,
    /// Fastest the scene's moving rapier bodies moved during the final frame,
    /// in m/s: distance travelled over the frame step (`curtain`, `hammock`).
    pub bodies_max_speed: Option<f32>,
    /// Largest rapier `linvel` of the scene's moving bodies after the final
    /// frame, in m/s. For a body resting in a contact rapier keeps resolving
    /// (the hammock's boxes lean on each other) it is not the body's motion:
    /// rapier moves the body with a position-correction velocity that it
    /// removes from `linvel` afterwards.
    pub bodies_max_linvel: Option<f32>,
    /// Lowest centre height of the scene's rapier bodies on the final frame, in metres.
    pub bodies_min_y: Option<f32>,
    /// Wall time spent stepping, in seconds.
    pub step_wall_s: f64,
    /// Particles × substeps simulated per second of stepping.
    pub particle_substeps_per_s: f64,
}

fn one() -> usize {
    1
}

/// Runs a scene for `frames` frames and gathers its metrics.
///
/// A diverging step ends the run with its error; the scene keeps its last finite state.
pub fn run(scene: &mut Scene, frames: u32) -> Result<RunMetrics, ClothError> {
    run_with(scene, frames, |_, _, _| {})
}

/// Like [`run`], calling `on_frame(scene, frame, max_penetration)` after
/// every frame, with the frame's [`Scene::max_penetration`] (metres).
pub fn run_with(
    scene: &mut Scene,
    frames: u32,
    mut on_frame: impl FnMut(&Scene, u32, f32),
) -> Result<RunMetrics, ClothError> {
    let mut wall = 0.0f64;
    let mut substeps_total = 0u64;
    let mut max_substeps = 0u32;
    let mut iterations = 0u64;
    let mut deepest_any = 0.0f32;
    let mut stretch_any = 0.0f32;
    let mut crossings_any = 0;
    let mut torn = 0u64;
    let (mut asleep, mut asleep_frames) = (false, 0);
    for f in 0..frames {
        let start = Instant::now();
        let report = scene.step_frame()?;
        wall += start.elapsed().as_secs_f64();
        substeps_total += report.substeps as u64;
        max_substeps = max_substeps.max(report.substeps);
        iterations += report.iterations as u64;
        torn += report.torn_springs as u64;
        asleep = report.asleep;
        asleep_frames += u32::from(report.asleep);
        let deepest = scene.max_penetration();
        deepest_any = deepest_any.max(deepest);
        stretch_any = stretch_any.max(max_stretch(&scene.cloth));
        crossings_any = crossings_any.max(self_intersections(&scene.cloth));
        on_frame(scene, f, deepest);
    }
    let cloth = &scene.cloth;
    // A torn cloth's cells are still its grid's; several cloths report the
    // first's.
    let grid = cloth
        .topology()
        .cells()
        .map(|g| [g.cols, g.rows])
        .unwrap_or(match scene.desc.cloth.mesh {
            // A mesh has no grid: its particles in one row.
            Some(_) => [cloth.particle_count(), 1],
            None => [scene.desc.cloth.cols, scene.desc.cloth.rows],
        });
    let min_y = cloth
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::INFINITY, f32::min);
    let c = cloth.centroid();
    let iterative = iterations > 0;
    Ok(RunMetrics {
        scene: scene.name.clone(),
        variant: scene.variant.map(|v| v.name().to_string()),
        n: grid[0],
        grid,
        integrator: scene.solver.integrator().name().to_string(),
        solver: scene.solver.settings.clone(),
        material: cloth.material.name.clone(),
        dt: scene.dt,
        substeps: max_substeps,
        iterations: iterative.then(|| (iterations / frames.max(1) as u64) as u32),
        frames,
        max_penetration: scene.max_penetration(),
        max_penetration_any_frame: deepest_any,
        max_stretch: max_stretch(cloth),
        max_stretch_any_frame: stretch_any,
        self_intersections: self_intersections(cloth),
        self_intersections_any_frame: crossings_any,
        torn_springs: torn,
        asleep,
        asleep_frames,
        pieces: pieces(cloth),
        min_y,
        centroid: [c.x, c.y, c.z],
        energy: cloth.energy().total(),
        finite: cloth.is_finite(),
        bodies_max_speed: scene
            .rapier
            .as_ref()
            .map(|side| side.last_speeds.iter().copied().fold(0.0, f32::max)),
        bodies_max_linvel: scene.rapier.as_ref().map(|side| {
            side.bodies
                .iter()
                .filter_map(|h| side.world.bodies.get(*h))
                .map(|b| b.linvel().length())
                .fold(0.0, f32::max)
        }),
        bodies_min_y: scene.rapier.as_ref().map(|side| {
            side.bodies
                .iter()
                .filter_map(|h| side.world.bodies.get(*h))
                .map(|b| b.translation().y)
                .fold(f32::INFINITY, f32::min)
        }),
        step_wall_s: wall,
        particle_substeps_per_s: if wall > 0.0 {
            cloth.particle_count() as f64 * substeps_total as f64 / wall
        } else {
            0.0
        },
    })
}

/// The run metrics frame by frame, for plotting (`cloth3d run --plot`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Simulated time at the end of each frame, in seconds.
    pub time: Vec<f64>,
    /// Total energy (kinetic + gravity + elastic), in joules.
    pub energy: Vec<f64>,
    /// Largest stretch-spring strain (length / rest length − 1).
    pub max_stretch: Vec<f64>,
    /// Deepest particle inside an obstacle, in metres.
    pub max_penetration: Vec<f64>,
}

impl Series {
    /// Records the scene as it is now, whose deepest particle lies
    /// `max_penetration` metres inside an obstacle ([`Scene::max_penetration`]).
    pub fn push(&mut self, scene: &Scene, max_penetration: f32) {
        self.time.push(scene.frame as f64 * scene.dt as f64);
        self.energy.push(scene.cloth.energy().total());
        self.max_stretch.push(max_stretch(&scene.cloth) as f64);
        self.max_penetration.push(max_penetration as f64);
    }

    /// Frames recorded.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }
}
