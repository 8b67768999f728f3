//! A cloth and its solver in one value: the one-line convenience for the
//! common case of one cloth stepped by one solver.

use serde::{Deserialize, Serialize};

use crate::cloth::Cloth;
use crate::collision::{Obstacle, ObstacleImpulse};
use crate::error::ClothError;
use crate::solver::{
    ClothSolver, Integrator, SolverCounters, SolverSettings, StepReport, TearEvent,
};

/// A [`Cloth`] (the data) with the [`ClothSolver`] that steps it.
///
/// It reads as its cloth (`Deref`), so `sim.positions()` or
/// `sim.pin(3)` work as on the cloth itself; `sim.solver.settings` holds
/// how it is stepped. A snapshot is the simulation serialised: both halves,
/// and it resumes bit for bit.
///
/// ```
/// use cloth3d::prelude::*;
/// let cloth = ClothBuilder::new(16, 16).horizontal(Vector::new(0.0, 0.6, 0.0)).build()?;
/// let mut sim = Simulation::new(cloth).with_integrator(Integrator::Verlet);
/// let ball = Obstacle::ball(Vector::ZERO, 0.3);
/// sim.step(1.0 / 60.0, std::slice::from_ref(&ball))?;
/// assert!(sim.is_finite());
/// # Ok::<(), cloth3d::ClothError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Simulation {
    /// The cloth: particles, topology, material, physical parameters.
    pub cloth: Cloth,
    /// The solver: settings, state, scratch.
    pub solver: ClothSolver,
}

impl Simulation {
    /// `cloth` stepped by a solver with the default settings (the small-steps solver, xpbd, at automatic substeps).
    pub fn new(cloth: Cloth) -> Self {
        Simulation {
            cloth,
            solver: ClothSolver::default(),
        }
    }

    /// The same simulation stepped with `integrator` at the substeps it
    /// wants by default (other settings are kept).
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        self.solver.settings.integrator = integrator;
        self.solver.settings.substeps = integrator.default_substeps();
        self
    }

    /// The same simulation with these solver settings.
    pub fn with_settings(mut self, settings: SolverSettings) -> Self {
        self.solver.settings = settings;
        self
    }

    /// Switches the integrator (the substeps setting stays); the cloth keeps its state.
    pub fn set_integrator(&mut self, integrator: Integrator) {
        self.solver.set_integrator(integrator);
    }

    /// Advances the cloth by `dt` seconds among `obstacles`: see [`ClothSolver::step`].
    pub fn step(&mut self, dt: f32, obstacles: &[Obstacle]) -> Result<StepReport, ClothError> {
        self.solver.step(&mut self.cloth, dt, obstacles)
    }

    /// The number of substeps a frame step of `dt` seconds takes.
    pub fn substeps_for(&self, dt: f32) -> u32 {
        self.solver.substeps_for(&self.cloth, dt)
    }

    /// Momentum the cloth gave each obstacle during the last step.
    pub fn obstacle_impulses(&self) -> &[ObstacleImpulse] {
        self.solver.obstacle_impulses()
    }

    /// Where the cloth tore during the last step (see [`ClothSolver::tear_events`]).
    pub fn tear_events(&self) -> &[TearEvent] {
        self.solver.tear_events()
    }

    /// What the solver has done: steps, factorisations.
    pub fn counters(&self) -> SolverCounters {
        self.solver.counters()
    }
}

impl std::ops::Deref for Simulation {
    type Target = Cloth;
    fn deref(&self) -> &Cloth {
        &self.cloth
    }
}

impl std::ops::DerefMut for Simulation {
    fn deref_mut(&mut self) -> &mut Cloth {
        &mut self.cloth
    }
}
