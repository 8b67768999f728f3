//! How a solver steps a cloth: the integrator, the substeps, and each
//! method's iteration counts and tolerances. Apart from the cloth's physics
//! (`crate::cloth::PhysicsParams`), as rapier keeps its
//! `IntegrationParameters` apart from its bodies' materials.

use serde::{Deserialize, Serialize};

use super::integrator::Integrator;
use super::preconditioner::Preconditioner;
use super::substeps::Substeps;
use crate::error::{positive, ClothError};

/// The solver's settings; all can change between steps.
///
/// Every field has a default, so a scene file may give only some of them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSettings {
    /// The time integrator (default: [`Integrator::Xpbd`], stable at any
    /// step and safe with dynamic bodies).
    pub integrator: Integrator,
    /// How each frame step is split.
    #[serde(deserialize_with = "super::substeps::de_substeps")]
    pub substeps: Substeps,
    /// Linearisations per substep of the implicit integrator (1 is Baraff and
    /// Witkin's single linear solve; more are Newton iterations that keep
    /// large steps of strongly bent cloth from overshooting).
    #[serde(deserialize_with = "crate::error::de::at_least_one")]
    pub newton_iterations: u32,
    /// Maximum conjugate-gradient iterations of the implicit integrator, per linearisation.
    #[serde(deserialize_with = "crate::error::de::at_least_one")]
    pub cg_max_iterations: u32,
    /// Relative residual at which conjugate gradient stops.
    #[serde(deserialize_with = "crate::error::de::positive")]
    pub cg_tolerance: f32,
    /// Preconditioner of that conjugate gradient.
    pub preconditioner: Preconditioner,
    /// Local/global iterations of the fast mass-spring solver.
    #[serde(deserialize_with = "crate::error::de::at_least_one")]
    pub fms_iterations: u32,
    /// Solves of the springs per substep of the small-steps (XPBD)
    /// solver: Gauss–Seidel sweeps over the springs, of which on a grid
    /// cloth the chain solves ([`Self::xpbd_chains`]) count as the first
    /// (one sweep fewer follows them, never none). More substeps converge
    /// better, more sweeps cost no collision work. On a grid the sweeps
    /// after the first leave out bend springs a tenth as stiff as the
    /// stretch springs or softer (every preset's), which one sweep meets.
    #[serde(deserialize_with = "crate::error::de::at_least_one")]
    pub xpbd_iterations: u32,
    /// Before each substep's sweeps, solve the stretch springs of every
    /// row and every column of a grid cloth directly, one tridiagonal
    /// solve a row or column (`grid_chains.rs`): a correction then crosses
    /// the cloth in one substep, and the automatic substeps are fewer (16
    /// instead of 55 for the drape at N = 64, 24 instead of 109 at
    /// N = 128; see `ClothSolver::substeps_among` for when they are not).
    /// No effect on cloth that is not a whole grid (a mesh, a torn grid).
    pub xpbd_chains: bool,
    /// Also keep stretch and shear springs (not only particles) out of obstacles,
    /// so cloth cannot cut through edges and corners.
    pub edge_collisions: bool,
    /// Evaluate spring forces on several threads (with the `parallel` feature;
    /// ignored without it). The results are bit-identical either way.
    pub parallel: bool,
    /// Let a still cloth fall asleep: after 30 steps with every particle
    /// slower than 3 cm/s (Jolt's default for bodies) it is no longer stepped until something could
    /// move it (`sleep.rs`). Off by default.
    pub sleep: bool,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            integrator: Integrator::Xpbd,
            substeps: Substeps::Auto,
            newton_iterations: 2,
            cg_max_iterations: 100,
            cg_tolerance: 1e-4,
            preconditioner: Preconditioner::BlockJacobi,
            fms_iterations: 10,
            xpbd_iterations: 2,
            xpbd_chains: true,
            edge_collisions: true,
            parallel: true,
            sleep: false,
        }
    }
}

impl SolverSettings {
    /// The default settings with another integrator and the substeps it
    /// wants by default ([`Integrator::default_substeps`]).
    pub fn for_integrator(integrator: Integrator) -> Self {
        Self {
            integrator,
            substeps: integrator.default_substeps(),
            ..Self::default()
        }
    }

    /// Checks every value and says which one is wrong.
    pub fn validate(&self) -> Result<(), ClothError> {
        let at_least_one = |name: &'static str, value: u32| {
            if value == 0 {
                Err(ClothError::InvalidParameter {
                    name,
                    value: 0.0,
                    expected: "a whole number >= 1",
                })
            } else {
                Ok(())
            }
        };
        if let Substeps::Fixed(0) = self.substeps {
            return Err(ClothError::InvalidParameter {
                name: "substeps",
                value: 0.0,
                expected: "a whole number >= 1 or auto",
            });
        }
        at_least_one("newton iterations", self.newton_iterations)?;
        at_least_one("cg iterations", self.cg_max_iterations)?;
        positive("cg tolerance", self.cg_tolerance)?;
        at_least_one("fast mass-spring iterations", self.fms_iterations)?;
        at_least_one("xpbd iterations", self.xpbd_iterations)?;
        Ok(())
    }
}
