//! What every integrator reads during one substep, in one value.

use crate::cloth::LaneGrid;
use crate::collision::Obstacle;
use crate::context::StepContext;
use crate::forces::ForceModel;
use crate::parallel::Team;

use super::settings::SolverSettings;

/// The read-only inputs of one substep of an integrator.
pub(crate) struct Substep<'a> {
    /// Where in the step, and the physical constants.
    pub ctx: &'a StepContext,
    /// Forces of the cloth (topology, material, masses, gravity, wind, drag).
    pub model: ForceModel<'a>,
    /// Iterations and tolerances.
    pub settings: &'a SolverSettings,
    /// The obstacles, at the poses the collision stage holds.
    pub obstacles: &'a [Obstacle],
    /// The cloth's masses and pins, for caches derived from them.
    pub mass_revision: u64,
    /// The grid the small-steps solver lays the particles out on, if any
    /// (for grid-specialised kernels): the cloth's, or its pieces' stacked.
    pub grid: Option<LaneGrid>,
    /// The threads the substep's loops may run on.
    pub team: Team<'a>,
    /// A stage after the integrator moves the particles this substep
    /// (self-collision, tethers): the integrator must hand its state back
    /// in the particles' arrays every substep.
    pub moved_after: bool,
    /// An edge or corner of an obstacle may meet the cloth this step
    /// (the schedule's test, from the cloth's box grown by the step's
    /// motion): without one, no spring can cut an edge.
    pub edges_near: bool,
}
