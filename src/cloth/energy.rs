//! The energy of a cloth, split by kind.

use serde::{Deserialize, Serialize};

/// Kinetic, gravitational and elastic energy of a cloth, in joules.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Energy {
    /// `Σ ½ m v²` over free particles.
    pub kinetic: f64,
    /// `Σ -m g·x` over free particles.
    pub gravity: f64,
    /// `Σ ½ k (|x_ij| - L)²` over all springs.
    pub elastic: f64,
}

impl Energy {
    /// The sum of the three parts.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravity + self.elastic
    }
}
