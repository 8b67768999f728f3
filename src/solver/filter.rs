//! What constrains a particle in the implicit solve: nothing, a pin, a
//! contact plane or static friction.

use crate::math::Vector;

/// What constrains a particle during the solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Filter {
    /// Free in every direction.
    Free,
    /// Pinned: no velocity change.
    Fixed,
    /// Against a surface with this unit normal: free only in its tangent plane.
    Plane(Vector),
    /// Held by static friction on a surface with this unit normal: moves
    /// with the surface.
    Stick(Vector),
}

impl Filter {
    #[inline(always)]
    pub(crate) fn apply(self, v: Vector) -> Vector {
        match self {
            Filter::Free => v,
            Filter::Fixed | Filter::Stick(_) => Vector::ZERO,
            Filter::Plane(n) => v - n * n.dot(v),
        }
    }
}
