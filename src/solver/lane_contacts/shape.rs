//! A still shape as the lanes hold it.

use super::still_cuboid::StillCuboid;
use crate::math::Vector;
use crate::solver::lane_convex::StillConvex;
use crate::solver::lane_mesh::StillMesh;

/// One still shape, as its lanes pass takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum StillShape {
    /// A ball: centre (m) and radius plus the thickness (m).
    Ball { centre: Vector, reach: f32 },
    /// A capsule (a bar, a rod): the ball of radius plus thickness `reach`
    /// (m) around the point of its axis nearest the lane; the axis from
    /// `from` (m) along the unit vector `axis` for `length` (m). A lane on
    /// the axis (within [`ON_AXIS`](super::contacts::ON_AXIS) of the reach)
    /// goes out along `across`, a unit vector square to the axis (the rounding
    /// of its nearest point gives it no direction, or one along the axis, which
    /// does not lead out).
    Capsule {
        from: Vector,
        axis: Vector,
        across: Vector,
        length: f32,
        reach: f32,
        /// The square (m²) of [`ON_AXIS`](super::contacts::ON_AXIS) of the
        /// reach, worked out here rather than in each pass: the pass's code
        /// reads it (and did the product) before it knows the shape is a
        /// capsule, and the bytes there for a ball are whatever was left, often
        /// a subnormal float, whose product stalled the drape's lane pass for a
        /// hundred cycles a chunk (43% of its frame in `perf`).
        on_axis2: f32,
    },
    /// A half-space: outward unit normal, and the offset (m) of its
    /// boundary moved out by the thickness (`n · x = offset` on it).
    Plane { normal: Vector, offset: f32 },
    /// A cuboid (a table, a box), rounded by the thickness: centre (m),
    /// its local axes in the world (unit vectors), half extents (m) and
    /// the thickness (m).
    Cuboid(StillCuboid),
    /// Any other convex shape (a cylinder, a cone, a convex hull), held
    /// as a cuboid is, by a plane a lane (`lane_convex.rs`).
    Convex(StillConvex),
    /// A triangle mesh or a heightfield, held by a plane a lane through
    /// its nearest point (`lane_mesh.rs`).
    Mesh(StillMesh),
}

impl StillShape {
    /// The centre (m) of the ball that holds a lane at `p` (m): a ball's
    /// own, a capsule's axis point nearest `p` (the same operations as the
    /// AVX2 pass); the origin for the other shapes, which take no centre.
    #[inline(always)]
    pub(super) fn centre_for(&self, p: [f32; 3]) -> [f32; 3] {
        match *self {
            StillShape::Ball { centre, .. } => [centre.x, centre.y, centre.z],
            StillShape::Capsule {
                from, axis, length, ..
            } => {
                let d = [p[0] - from.x, p[1] - from.y, p[2] - from.z];
                let along = d[0] * axis.x + d[1] * axis.y + d[2] * axis.z;
                let t = along.max(0.0).min(length);
                [
                    from.x + axis.x * t,
                    from.y + axis.y * t,
                    from.z + axis.z * t,
                ]
            }
            StillShape::Plane { .. }
            | StillShape::Cuboid(_)
            | StillShape::Convex(_)
            | StillShape::Mesh(_) => [0.0; 3],
        }
    }

    /// The slot of the lanes' plane records of a cuboid or other convex
    /// shape; none for the shapes held without planes.
    #[inline(always)]
    pub(super) fn slot(&self) -> Option<usize> {
        match *self {
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => Some(slot),
            _ => None,
        }
    }

    /// Which way (a unit vector) a ball or capsule puts out a lane at its
    /// centre, and within what squared distance (m²) of it a lane is
    /// there: a ball's top, at the centre itself; a capsule's `across`,
    /// within [`ON_AXIS`](super::contacts::ON_AXIS) of its reach.
    #[inline(always)]
    pub(super) fn way_out(&self) -> (Vector, f32) {
        match *self {
            StillShape::Capsule {
                across, on_axis2, ..
            } => (across, on_axis2),
            _ => (Vector::Y, 0.0),
        }
    }
}
