//! How a look's pairs are parted so that a pass takes two parts at once.

use super::lists::{headroom, PartPairs};
use super::pairs::SelfPair;
use crate::math::Vector;

/// How a look's pairs are parted for the pass
/// ([`SelfContacts::resolve`](super::SelfContacts::resolve)): those whose
/// particles (the pair's own and its triangle's corners) all lay below a plane
/// across the cloth at the look, those whose all lay above it, and the rest.
/// The first two share no particle, so that a pass may take them on two threads
/// at once, then the rest: the same bits on one thread or two. The plane is
/// across the widest side of the particles' box, through their median. Each
/// block of triangles parts its own pairs, on its thread.
#[derive(Debug, Default, Clone)]
pub(super) struct PassPlane {
    /// Per particle: below the plane.
    pub(super) below: Vec<bool>,
    /// The particles' coordinates across the plane (scratch).
    pub(super) across: Vec<f32>,
}

/// Pairs from which the two parts of a pass run on two threads.
pub(super) const PARALLEL_MIN_PAIRS: usize = 4096;

impl PassPlane {
    /// The plane through the median of positions `x`.
    pub(super) fn update(&mut self, x: &[Vector]) {
        let (mut lo, mut hi) = (Vector::INFINITY, Vector::NEG_INFINITY);
        for p in x.iter().filter(|p| p.is_finite()) {
            (lo, hi) = (lo.min(*p), hi.max(*p));
        }
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        self.across.clear();
        self.across.extend(x.iter().map(|p| p[axis]));
        let median = if self.across.is_empty() {
            0.0
        } else {
            let middle = self.across.len() / 2;
            *self.across.select_nth_unstable_by(middle, f32::total_cmp).1
        };
        self.below.clear();
        self.below.extend(x.iter().map(|p| p[axis] < median));
    }

    /// Parts `pairs` of `triangles` into `parts`, with lanes for a CPU
    /// with AVX2 (`simd`) on `particles` particles.
    pub(super) fn part(
        &self,
        pairs: &[SelfPair],
        (triangles, particles): (&[[u32; 3]], usize),
        simd: bool,
        parts: &mut [PartPairs; 3],
    ) {
        for part in parts.iter_mut() {
            part.pairs.clear();
            part.lanes.clear(simd, particles);
        }
        let below = |i: u32| self.below.get(i as usize).copied();
        for pair in pairs {
            let corners = triangles.get(pair.triangle as usize).copied();
            let sides = corners.map(|[a, b, c]| [pair.particle, a, b, c].map(below));
            let k = match sides {
                Some([Some(true), Some(true), Some(true), Some(true)]) => 0,
                Some([Some(false), Some(false), Some(false), Some(false)]) => 1,
                _ => 2,
            };
            parts[k].pairs.push(*pair);
            parts[k].lanes.push(pair, corners);
        }
        for part in parts.iter_mut() {
            part.lanes.pad();
            headroom(&mut part.pairs);
        }
    }
}
