//! What a user may override when building a scene (the command's and the
//! showcase's flags), and how the overrides apply to a description.

use super::desc::{MaterialDesc, PinsDesc, SceneDesc};
use crate::cloth::{Material, PinPreset};
use crate::error::ClothError;
use crate::solver::{Integrator, Preconditioner, Substeps};

/// Choices a user can override when building a scene; `None` keeps the scene's default.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneOptions {
    /// Particles along a row; rows follow the scene's aspect ratio.
    pub n: Option<usize>,
    /// The integrator (default: the scene's, the small-steps solver `xpbd`);
    /// without `substeps`, it brings its own
    /// default substeps ([`Integrator::default_substeps`]).
    pub integrator: Option<Integrator>,
    /// The material (default: cotton).
    pub material: Option<Material>,
    /// The pin variant of the `pins` scene (default: `center`).
    pub variant: Option<PinPreset>,
    /// Frame step in seconds (default 1/60).
    pub dt: Option<f32>,
    /// Substeps per frame (default: auto).
    pub substeps: Option<Substeps>,
    /// Frames to run (default: the scene's length).
    pub frames: Option<u32>,
    /// Friction of every obstacle (default 0.5).
    pub friction: Option<f32>,
    /// Keep the cloth from passing through itself (default: the scene's).
    pub self_collision: Option<bool>,
    /// Tethers to the pins (default: the scene's).
    pub tethers: Option<bool>,
    /// Air speed of the wind, m/s (default: the scene's).
    pub wind_speed: Option<f32>,
    /// Gusts of the wind, a share of its speed (default: the scene's).
    pub turbulence: Option<f32>,
    /// The solver's iterations and tolerances.
    pub solver: SolverTuning,
}

/// Solver settings a user can override; `None` keeps the scene's.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SolverTuning {
    /// Linearisations per substep of implicit Euler.
    pub newton_iterations: Option<u32>,
    /// Maximum conjugate-gradient iterations of implicit Euler.
    pub cg_iterations: Option<u32>,
    /// Relative residual at which conjugate gradient stops.
    pub cg_tolerance: Option<f32>,
    /// Preconditioner of that conjugate gradient.
    pub preconditioner: Option<Preconditioner>,
    /// Local/global iterations of the fast mass-spring solver.
    pub fms_iterations: Option<u32>,
    /// Spring sweeps per substep of the small-steps (XPBD) solver.
    pub xpbd_iterations: Option<u32>,
    /// Direct solves along rows and columns in the small-steps solver.
    pub xpbd_chains: Option<bool>,
    /// Keep stretch and shear springs out of obstacles too.
    pub edge_collisions: Option<bool>,
    /// Let a still cloth sleep.
    pub sleep: Option<bool>,
}

impl SceneDesc {
    /// Applies the user's overrides: grid (rows follow the aspect ratio),
    /// material and self-collision (of every cloth), integrator, pin preset
    /// (of the first cloth), dt, substeps, self-collision, frames,
    /// friction.
    pub fn apply(&mut self, options: &SceneOptions) -> Result<(), ClothError> {
        let cloths = std::iter::once(&mut self.cloth).chain(&mut self.cloths);
        for cloth in cloths {
            if let Some(n) = options.n {
                let (c, r) = (cloth.cols, cloth.rows);
                cloth.cols = n;
                cloth.rows = ((n as f32 * r as f32 / c as f32).round() as usize).max(2);
            }
            if let Some(m) = &options.material {
                cloth.material = MaterialDesc::of(m);
            }
            if let Some(on) = options.self_collision {
                cloth.self_collision = on;
            }
            if let Some(on) = options.tethers {
                cloth.tethers = on;
            }
        }
        if let Some(i) = options.integrator {
            self.solver.integrator = i;
            if options.substeps.is_none() {
                // The scene's substeps were chosen for its own integrator.
                self.solver.substeps = i.default_substeps();
            }
        }
        if let Some(v) = options.variant {
            self.cloth.pins = PinsDesc::preset(v);
        }
        if let Some(dt) = options.dt {
            self.dt = crate::error::positive("dt", dt)?;
        }
        if let Some(s) = options.substeps {
            self.solver.substeps = s;
        }
        let tuning = &options.solver;
        let settings = &mut self.solver;
        if let Some(it) = tuning.newton_iterations {
            settings.newton_iterations = it;
        }
        if let Some(it) = tuning.cg_iterations {
            settings.cg_max_iterations = it;
        }
        if let Some(tol) = tuning.cg_tolerance {
            settings.cg_tolerance = tol;
        }
        if let Some(p) = tuning.preconditioner {
            settings.preconditioner = p;
        }
        if let Some(it) = tuning.fms_iterations {
            settings.fms_iterations = it;
        }
        if let Some(it) = tuning.xpbd_iterations {
            settings.xpbd_iterations = it;
        }
        if let Some(on) = tuning.xpbd_chains {
            settings.xpbd_chains = on;
        }
        if let Some(edges) = tuning.edge_collisions {
            settings.edge_collisions = edges;
        }
        if let Some(sleep) = tuning.sleep {
            settings.sleep = sleep;
        }
        settings.validate()?;
        if let Some(f) = options.frames {
            self.frames = f;
        }
        if let Some(s) = options.wind_speed {
            self.wind.speed = crate::error::non_negative("wind speed", s)?;
        }
        if let Some(t) = options.turbulence {
            self.wind.turbulence = crate::error::non_negative("turbulence", t)?;
        }
        if let Some(f) = options.friction {
            self.friction = crate::error::non_negative("friction", f)?;
            for o in &mut self.obstacles {
                o.friction = None;
            }
        }
        Ok(())
    }
}
