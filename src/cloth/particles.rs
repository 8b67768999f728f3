//! The particles of a cloth: positions, velocities and masses, as structure-of-arrays.

use serde::{Deserialize, Serialize};

use crate::math::Vector;

/// The particles of a cloth, as structure-of-arrays.
///
/// A particle with inverse mass 0 is pinned: no force moves it; it moves only
/// with the velocity it is given (a kinematic pin) or when it is set on purpose.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Particles {
    /// Positions, in metres.
    pub(crate) x: Vec<Vector>,
    /// Velocities, in m/s.
    pub(crate) v: Vec<Vector>,
    /// Positions at the start of the last substep, in metres.
    pub(crate) x_prev: Vec<Vector>,
    /// Masses, in kg (kept while pinned, so unpinning restores them).
    pub(crate) mass: Vec<f32>,
    /// Inverse masses, in 1/kg; 0 for a pinned particle.
    pub(crate) inv_mass: Vec<f32>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there is no particle.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}
