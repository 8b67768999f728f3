//! What each block of a look keeps: its pairs, its candidates and its pairs in
//! the pass's parts.

use super::pair_lanes::{PairLanes, LANES};
use super::pairs::{EdgePair, SelfPair};
use crate::collision::spatial_hash::SpatialHash;
use crate::math::Vector;

/// The edge pairs a block of border edges or sharp folds found, alone on
/// its cache lines, and its scratch of candidate edges.
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
pub(super) struct EdgeList(pub(super) Vec<EdgePair>, pub(super) Vec<[u32; 2]>);

/// The pairs a block of triangles found, alone on its cache lines (blocks on
/// different threads push at once), in triangle order; the candidates of its
/// runs of triangles ([`Look::run`](super::look::Look::run)); and its pairs in
/// the pass's three parts ([`PassPlane`](super::pass_plane::PassPlane)), with
/// their lanes.
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
pub(super) struct PairList(
    pub(super) Vec<SelfPair>,
    pub(super) Candidates,
    pub(super) [PartPairs; 3],
);

/// The pairs of one block in one part of the pass, and their lanes.
#[derive(Debug, Default, Clone)]
pub(super) struct PartPairs {
    pub(super) pairs: Vec<SelfPair>,
    pub(super) lanes: PairLanes,
}

/// The particles within the box around a run of triangles, in the hash's
/// order, and their positions (m), coordinate by coordinate; all padded to whole
/// vector steps (with `u32::MAX`, and NaN, inside no box).
#[derive(Debug, Default, Clone)]
pub(super) struct Candidates {
    /// How many there are (before the padding).
    pub(super) len: usize,
    pub(super) p: Vec<u32>,
    pub(super) x: [Vec<f32>; 3],
}

impl Candidates {
    /// The particles of `hash` inside the box `lo..=hi` (m), at positions `x`.
    pub(super) fn gather(&mut self, hash: &SpatialHash, (lo, hi): (Vector, Vector), x: &[Vector]) {
        self.p.clear();
        hash.for_each_inside(lo, hi, |p, _| self.p.push(p));
        self.len = self.p.len();
        let padded = self.len.next_multiple_of(LANES);
        for coordinate in &mut self.x {
            coordinate.clear();
            coordinate.resize(padded, f32::NAN);
        }
        // One pass for the three coordinates (one each, by `extend`, read
        // each position three times).
        let [cx, cy, cz] = &mut self.x;
        let (cx, cy, cz) = (
            &mut cx[..self.len],
            &mut cy[..self.len],
            &mut cz[..self.len],
        );
        for (k, &p) in self.p.iter().enumerate() {
            let at = x[p as usize];
            (cx[k], cy[k], cz[k]) = (at.x, at.y, at.z);
        }
        self.p.resize(padded, u32::MAX);
    }

    /// The candidates: each particle and its position (m).
    pub(super) fn iter(&self) -> impl Iterator<Item = (u32, Vector)> + '_ {
        let [x, y, z] = &self.x;
        (0..self.len).map(move |k| (self.p[k], Vector::new(x[k], y[k], z[k])))
    }
}

/// Makes room for twice the list's length, so that a step whose pairs
/// grow by less than that allocates nothing (a warmed-up step allocates
/// only when the contacts more than double).
pub(super) fn headroom<T>(list: &mut Vec<T>) {
    if list.capacity() < 2 * list.len() {
        list.reserve(list.len());
    }
}
