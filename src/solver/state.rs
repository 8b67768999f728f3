//! Solver state that changes results and so belongs in a snapshot: what the
//! solver remembers from one step to the next.

use serde::{Deserialize, Serialize};

use super::global_matrix::FactorHistory;
use super::sleep::SleepState;
use crate::collision::SelfLook;
use crate::math::Vector;

/// What a solver carries from one substep to the next.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SolverState {
    /// Per particle: the pull (in the fast mass-spring solver's units) with
    /// which static friction held it on a surface in the last substep, zero
    /// when not held; the next substep keeps the hold while it stays in the
    /// friction cone. Empty until that solver runs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) held_force: Vec<Vector>,
    /// How the fast mass-spring solver's factor came to be (its full
    /// factorisation's contacts and its rank-one updates since), so that a
    /// resumed solver rebuilds it bit for bit. Empty until that solver runs.
    #[serde(default, skip_serializing_if = "FactorHistory::is_empty")]
    pub(crate) fms_factor: FactorHistory,
    /// Whether the cloth sleeps (with `SolverSettings::sleep`).
    #[serde(default, skip_serializing_if = "SleepState::is_awake")]
    pub(crate) sleep: SleepState,
    /// Where self-collision last looked for pairs (a look carries over
    /// from step to step). None until it looks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) self_look: Option<SelfLook>,
}
