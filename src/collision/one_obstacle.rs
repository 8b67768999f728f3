//! The one obstacle of a step as the particle pass's lanes
//! (`one_obstacle_lanes.rs`) take it, when it is a ball or a cuboid: its
//! shape where it is now, its bounds and its surface's motion
//! ([`super::tracks::ObstacleTracks::one_obstacle_law`] makes it).

use super::contact::PoseF64;
use crate::math::Vector;

/// The one obstacle's shape, where it is now.
// Made on the stack once a block; boxing the cuboid's pose would allocate
// every substep.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub(super) enum LaneShape {
    /// A ball: its centre (m) and radius (m).
    Ball { centre: Vector, radius: f32 },
    /// A cuboid: its half extents (m) and its pose in double precision.
    Cuboid { half: Vector, pose: PoseF64 },
}

/// What the lanes need of the one obstacle, a ball or a cuboid, where it is now.
#[derive(Debug, Clone, Copy)]
pub(super) struct OneObstacleLaw {
    pub shape: LaneShape,
    /// Its bounds over the step, grown by the reach (m): a particle outside
    /// them has no candidate.
    pub bounds_min: Vector,
    pub bounds_max: Vector,
    /// How far (m, along any axis) a particle may drift from where the
    /// step's cache found its candidates before it is looked up afresh.
    pub cache_margin: f32,
    /// The sphere that bounds it: centre (m) and radius (m), as the
    /// general pass's far test takes it.
    pub bound_centre: Vector,
    pub bound_radius: f32,
    /// Its surface's velocity at `p` is `linear + angular × (p - about)`
    /// (m/s, rad/s, m).
    pub linear: Vector,
    pub angular: Vector,
    pub about: Vector,
    /// Coulomb friction coefficient.
    pub friction: f32,
    /// Fixed or kinematic: the cloth's push does not move it.
    pub immovable: bool,
}
