//! # cloth3d
//!
//! Mass-spring cloth for the dimforge physics stack. Particles on a grid are
//! joined by stretch, shear and bend springs; the cloth falls under gravity,
//! blows in the wind, and collides with parry3d shapes.
//!
//! ```
//! use cloth3d::prelude::*;
//!
//! // A 1 × 1 m, 1 kg cotton tablecloth 0.6 m above a ball of radius 0.3 m.
//! let mut cloth = ClothBuilder::new(24, 24)
//!     .horizontal(Vector::new(0.0, 0.6, 0.0))
//!     .material(Material::cotton())
//!     .build()?;
//! // The solver steps the cloth (the small-steps solver, xpbd, by default).
//! let mut solver = ClothSolver::default();
//! let ball = Obstacle::ball(Vector::ZERO, 0.3);
//! for _frame in 0..60 {
//!     solver.step(&mut cloth, 1.0 / 60.0, std::slice::from_ref(&ball))?;
//! }
//! assert!(cloth.is_finite());
//! // It rests on the ball: nothing is inside it.
//! assert!(cloth.positions().iter().all(|p| p.length() > 0.3));
//! # Ok::<(), cloth3d::ClothError>(())
//! ```
#![warn(missing_docs)]
// Numeric kernels index several structure-of-arrays buffers with one index.
#![allow(clippy::needless_range_loop)]

#[cfg(feature = "cli")]
pub mod cli;
pub mod cloth;
pub mod collision;
pub mod context;
pub mod error;
pub mod export;
pub mod forces;
pub mod math;
pub mod metrics;
mod parallel;
pub mod rapier;
pub mod scenes;
pub mod simulation;
pub mod solver;
#[cfg(feature = "viewer")]
pub mod viewer;

pub use cloth::{
    Cloth, ClothBuilder, Material, PhysicsParams, PinPreset, SpringKind, SpringParams, Topology,
    Wind,
};
pub use collision::Obstacle;
pub use error::ClothError;
pub use scenes::{Scene, SceneDesc, SceneError, SceneKind};
pub use simulation::Simulation;
pub use solver::{ClothSolver, Integrator, Preconditioner, SolverSettings, StepReport, Substeps};

/// Everything a typical user needs, in one import.
pub mod prelude {
    pub use crate::cloth::{
        Cloth, ClothBuilder, ClothMesh, Energy, MassSpec, Material, ParticleSplit, PhysicsParams,
        PinPreset, Spring, SpringKind, SpringParams, Wind,
    };
    pub use crate::collision::Obstacle;
    pub use crate::error::ClothError;
    pub use crate::math::{Pose, Rotation, Vector};
    pub use crate::simulation::Simulation;
    pub use crate::solver::{
        ClothSolver, Integrator, Preconditioner, SolverSettings, StepReport, Substeps, TearEvent,
    };
}

/// The README's code, compiled and run as doctests so it stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
