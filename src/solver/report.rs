//! What a step did, what a solver counted, and when a step has diverged.

use serde::{Deserialize, Serialize};

use super::stage_times::StageTimes;

/// Speeds (m/s) and distances from the origin (m) beyond which a step is
/// taken to have exploded even if the numbers are still finite.
pub const MAX_SPEED: f32 = 1.0e4;
/// See [`MAX_SPEED`].
pub const MAX_DISTANCE: f32 = 1.0e7;
/// A stretch spring longer than `1 + MAX_STRAIN` times its rest length after a
/// step means the step exploded: no cloth stretches to eleven times its length.
pub const MAX_STRAIN: f32 = 10.0;

/// What a step did.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StepReport {
    /// Substeps taken.
    pub substeps: u32,
    /// Solver iterations over the whole step (0 for explicit integrators).
    pub iterations: u32,
    /// Particle–obstacle contacts the collision stage resolved, summed over
    /// the substeps it ran: every substep, but only the last when the
    /// integrator held every contact itself (xpbd among still balls,
    /// capsules, half-spaces and cuboids). When the integrator left it nothing to do at the last
    /// either (every stretch spring within the limit, no spring able to cut
    /// an obstacle), the stage does not run, and this counts the particles
    /// the integrator pushed out of an obstacle in that substep.
    pub contacts: u32,
    /// Particle–triangle contacts within the cloth resolved, summed over
    /// substeps (0 without self-collision).
    #[serde(default)]
    pub self_contacts: u32,
    /// Looks self-collision took for pairs this step (0 without it, or when
    /// the last look still held: it carries over while no particle moved
    /// half the margin relative to the others).
    #[serde(default)]
    pub self_looks: u32,
    /// Rounds of the stretch limit and the obstacles after the collision
    /// stage, summed over the substeps (`contact_follow.rs`; each a pass
    /// over every stretch spring): 0 in most steps, a few where an
    /// obstacle's push stretched the cloth past its limit.
    #[serde(default)]
    pub follow_rounds: u32,
    /// Stretch springs that tore at the end of the step (0 unless the
    /// material has a tear strain); see [`crate::solver::ClothSolver::tear_events`].
    #[serde(default)]
    pub torn_springs: u32,
    /// True when the cloth slept through the step (nothing was solved; see
    /// `SolverSettings::sleep`).
    #[serde(default)]
    pub asleep: bool,
    /// Where the step's wall-clock time went.
    #[serde(default)]
    pub times: StageTimes,
}

/// What a solver has done since it was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct SolverCounters {
    /// Steps taken (diverged ones not counted).
    pub steps: u64,
    /// Cholesky factors the fast mass-spring solver computed from scratch
    /// (ordering, symbolic and numeric): once, then again only when pins,
    /// masses, the substep or the stiffness change.
    pub factorizations: u64,
    /// Numeric refactorisations of that factor (same ordering and pattern)
    /// for a new set of particles held by friction on an obstacle.
    pub refactorizations: u64,
}
