//! Where a step's time went: wall-clock seconds per kind of stage, summed
//! over the substeps, for benchmarks and overlays (the physics never reads
//! them).

use std::time::Instant;

use serde::{Deserialize, Serialize};

/// Wall-clock seconds a step spent in each kind of stage, summed over its
/// substeps. `total` also holds what the others leave out: validation,
/// backups, the obstacles' candidate caches, the divergence check, tearing
/// and sleep.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StageTimes {
    /// The integrator's substeps: springs, forces and integration (s).
    pub integrate: f64,
    /// Self-collision: the look for close pairs and their pass (s).
    pub self_collision: f64,
    /// Of `self_collision`, the looks for pairs (s): the `stack` spends
    /// most of its frame in them, and a look's share tells whether the
    /// cloth's parts near each other move (BENCHMARKS.md).
    #[serde(default)]
    pub self_looks: f64,
    /// The stretch limit and tethers run between integration and contacts (s).
    pub constraints: f64,
    /// The obstacles: their motion, contact detection and resolution, the
    /// edge pass and the stretch limit held against the contacts (s).
    pub contacts: f64,
    /// The whole step (s).
    pub total: f64,
}

/// A stopwatch over consecutive stages: each [`Lap::lap`] adds the time
/// since the last one to a stage's sum.
pub(crate) struct Lap(Instant);

impl Lap {
    /// Starts timing now.
    pub fn start() -> Lap {
        Lap(Instant::now())
    }

    /// Adds the seconds since the last lap (or the start) to `sum`.
    pub fn lap(&mut self, sum: &mut f64) {
        let now = Instant::now();
        *sum += now.duration_since(self.0).as_secs_f64();
        self.0 = now;
    }
}
