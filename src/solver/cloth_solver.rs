//! The solver of a cloth: its settings, the state it carries between steps,
//! its scratch and its counters. It steps any cloth it is handed (see
//! `schedule.rs` for the order of a step), as rapier's `PhysicsPipeline`
//! steps the sets passed to it.

use serde::{Deserialize, Serialize};

use super::integrator::Integrator;
use super::report::SolverCounters;
use super::settings::SolverSettings;
use super::stability::{
    chains_lengthen, joined_self_substeps, self_closing_substeps, stable_substeps,
};
use super::state::SolverState;
use super::strain_limit::limit_stretch_weighted;
use super::substeps::{self_collision_substeps, Substeps};
use super::tearing::TearEvent;
use super::workspace::Workspace;
use crate::cloth::Cloth;
use crate::collision::ObstacleImpulse;
use crate::math::Pose;

/// Steps a [`Cloth`] with the integrator and settings it holds.
///
/// A snapshot of a simulation is the cloth and its solver: both serialise
/// (the solver its settings and [`SolverState`], not its scratch), and a
/// restored pair continues bit for bit. Cloning gives a solver with the same
/// settings and state and fresh scratch.
#[derive(Debug, Default, Serialize, Deserialize)]
pub struct ClothSolver {
    /// How to step: integrator, substeps, iterations.
    pub settings: SolverSettings,
    /// What the solver carries from one step to the next.
    #[serde(default)]
    pub(crate) state: SolverState,
    #[serde(skip)]
    pub(crate) workspace: Workspace,
    #[serde(skip)]
    pub(crate) steps: u64,
}

impl Clone for ClothSolver {
    fn clone(&self) -> Self {
        ClothSolver {
            settings: self.settings.clone(),
            state: self.state.clone(),
            workspace: Workspace::default(),
            steps: self.steps,
        }
    }
}

impl PartialEq for ClothSolver {
    fn eq(&self, other: &Self) -> bool {
        self.settings == other.settings && self.state == other.state
    }
}

impl ClothSolver {
    /// A solver with these settings.
    pub fn new(settings: SolverSettings) -> Self {
        ClothSolver {
            settings,
            ..Default::default()
        }
    }

    /// A solver with the default settings for `integrator` (its default substeps).
    pub fn with_integrator(integrator: Integrator) -> Self {
        Self::new(SolverSettings::for_integrator(integrator))
    }

    /// The integrator.
    pub fn integrator(&self) -> Integrator {
        self.settings.integrator
    }

    /// Switches the integrator (the substeps setting stays); the cloth keeps its state.
    pub fn set_integrator(&mut self, integrator: Integrator) {
        self.settings.integrator = integrator;
    }

    /// The state the solver carries between steps.
    pub fn state(&self) -> &SolverState {
        &self.state
    }

    /// The number of substeps a frame step of `dt` seconds takes on `cloth`:
    /// automatic ones are at least as many as self-collision needs, when the
    /// cloth has it ([`super::MAX_SELF_SUBSTEP`]).
    pub fn substeps_for(&self, cloth: &Cloth, dt: f32) -> u32 {
        substeps_with(&self.settings, cloth, dt)
    }

    /// Momentum the cloth gave each obstacle during the last step (same order
    /// as the obstacles passed to [`ClothSolver::step`]).
    pub fn obstacle_impulses(&self) -> &[ObstacleImpulse] {
        self.workspace.collision.impulses()
    }

    /// Where the last step left each obstacle (same order as the obstacles
    /// passed to [`ClothSolver::step`]; m and rad): a moving one on its
    /// path, a dynamic body where the cloth's substeps moved it with its
    /// velocity, gravity and the cloth's push. Empty before the first step;
    /// stale while the cloth sleeps (its steps move nothing).
    pub fn obstacle_end_poses(&self) -> &[Pose] {
        self.workspace.collision.poses()
    }

    /// The material's stretch limit over the whole cloth, each particle
    /// moved by its `weight` (1/kg; 0 holds it where it is), positions
    /// only, in over-relaxed passes (at most 80): for a
    /// stage between steps that placed particles on its own
    /// ([`crate::rapier::RapierCoupling::push_out_of_bodies`]). Returns the
    /// springs it shortened; none for a material without a limit or
    /// weights of another length.
    pub(crate) fn limit_stretch_between_steps(&mut self, cloth: &mut Cloth, weight: &[f32]) -> u32 {
        let factor = cloth.material.stretch_limit_factor();
        if !factor.is_finite() || weight.len() != cloth.particle_count() {
            return 0;
        }
        let springs = &cloth.topology.springs;
        limit_stretch_weighted(
            &mut self.workspace.limit_scratch,
            (springs, weight),
            &mut cloth.particles.x,
            factor,
        )
    }

    /// Where the cloth tore during the last step: one event per stretch
    /// spring strained past the material's tear strain (empty when nothing
    /// tore or the material does not tear).
    pub fn tear_events(&self) -> &[TearEvent] {
        &self.workspace.tearing.events
    }

    /// True while the cloth this solver steps sleeps (see
    /// [`SolverSettings::sleep`]).
    pub fn is_asleep(&self) -> bool {
        self.state.sleep.is_asleep()
    }

    /// Wakes the cloth: the next step solves it again (for a change the
    /// solver cannot see, such as a particle moved with `set_position`).
    pub fn wake(&mut self) {
        self.state.sleep.wake();
    }

    /// What the solver has done since it was made (or cloned).
    pub fn counters(&self) -> SolverCounters {
        SolverCounters {
            steps: self.steps,
            factorizations: self.workspace.fms.factorizations,
            refactorizations: self.workspace.fms.refactorizations,
        }
    }
}

/// [`ClothSolver::substeps_for`] with `settings`.
pub(super) fn substeps_with(settings: &SolverSettings, cloth: &Cloth, dt: f32) -> u32 {
    match settings.substeps {
        Substeps::Fixed(k) => k.max(1),
        Substeps::Auto => {
            if cloth.params.self_collision {
                // Layers cross at the chains' longer substeps (the fold's
                // 71 self-intersections at 16 substeps, none at 55): the
                // sweeps' count, or where the chains apply, as many as
                // keep a layer closing at `SELF_CLOSING_SPEED` within the
                // thickness a substep (fewer; stability.rs says why).
                // Cloths joined into one (their grids stacked, the chains
                // apply) land on each other: at least
                // `JOINED_SELF_SUBSTEPS_PER_SECOND` (the `stack` at 60 Hz:
                // 20, against the sweeps' 28).
                let sweeps = stable_substeps(cloth, &unshortened(settings), dt);
                let joined = cloth.grid().is_none();
                let stable = if chains_lengthen(cloth, settings) {
                    let closing = self_closing_substeps(cloth.self_thickness(), dt);
                    let least = if joined {
                        closing.max(joined_self_substeps(dt))
                    } else {
                        closing
                    };
                    stable_substeps(cloth, settings, dt).max(least).min(sweeps)
                } else {
                    sweeps
                };
                stable.max(self_collision_substeps(dt))
            } else {
                stable_substeps(cloth, settings, dt)
            }
        }
    }
}

/// `settings` with the automatic substeps the sweeps alone would take: not
/// lengthened by the chain solves (which still run).
pub(super) fn unshortened(settings: &SolverSettings) -> SolverSettings {
    SolverSettings {
        xpbd_chains: false,
        ..settings.clone()
    }
}
