//! The context of one substep, handed down the step schedule to every
//! stage instead of long argument lists (after Box2D's `b2StepContext`).

use crate::math::Vector;

/// Where in a step the solver is, and the physical constants every stage reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepContext {
    /// The whole step, in seconds.
    pub dt: f32,
    /// This substep, in seconds (`dt / substeps`).
    pub h: f32,
    /// Which substep, from 0.
    pub substep: u32,
    /// How many substeps the step takes.
    pub substeps: u32,
    /// Simulated time at the start of the step, in seconds.
    pub time: f64,
    /// Gravity, in m/s².
    pub gravity: Vector,
    /// Collision thickness, in metres.
    pub thickness: f32,
}

impl StepContext {
    /// Seconds from the start of the step to the end of this substep.
    pub fn substep_end(&self) -> f32 {
        (self.substep + 1) as f32 * self.h
    }
}
