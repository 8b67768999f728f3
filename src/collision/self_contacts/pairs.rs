//! What a look finds: a particle near a triangle, an edge near an edge, and
//! where the look was taken.

use crate::math::Vector;
use serde::{Deserialize, Serialize};

/// A particle near a triangle of its own cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct SelfPair {
    pub(super) particle: u32,
    pub(super) triangle: u32,
    /// +1 when the particle lay on the side the triangle's normal points to a
    /// substep before the look
    /// ([`Look::side_before`](super::look::Look::side_before)), −1 on the
    /// other.
    pub(super) side: f32,
}

/// An edge of the cloth's border or of a sharp fold
/// ([`SHARP_FOLD`](super::edge_pairs::SHARP_FOLD)) near another edge of the
/// same cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct EdgePair {
    /// The border edge, or the lower of two edges of which one is a sharp
    /// fold's.
    pub(super) edge: [u32; 2],
    /// The other edge.
    pub(super) other: [u32; 2],
    /// +1 when `edge` lay on the side `(b − a) × (q − p)` points to from
    /// the other edge a substep before the look, −1 on the other.
    pub(super) side: f32,
    /// For two sharp folds' edges, the two triangles of `edge` and the
    /// two of `other`: the pass keeps the layers apart by less where a
    /// fold is less sharp now ([`fold_share`](super::edge_pairs::fold_share));
    /// [`NO_FOLDS`] for a border edge's pair.
    pub(super) folds: [[u32; 2]; 2],
}

/// [`EdgePair::folds`] of a border edge's pair.
pub(super) const NO_FOLDS: [[u32; 2]; 2] = [[u32::MAX; 2]; 2];

/// Where self-collision last looked for pairs: solver state, since when it
/// looks next depends on it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SelfLook {
    /// The particles' positions (m) at the look.
    pub(super) at: Vec<Vector>,
    /// Where each particle was a substep before the look (m; its velocity
    /// back from `at`): the pairs take their sides from these (empty:
    /// from `at`).
    #[serde(default)]
    pub(super) from: Vec<Vector>,
    /// The layers' thickness and the margin (m) it looked with.
    pub(super) thickness: f32,
    pub(super) margin: f32,
    /// Looks so far: which look the scratch's pairs are of.
    pub(super) number: u64,
}
