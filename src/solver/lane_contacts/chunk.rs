//! What a pass's kernels take: the law a chunk of lanes is held by, and the
//! chunk.

use super::shape::StillShape;
use crate::math::Vector;

/// What a pass applies: the shapes, and the friction coefficient of each
/// when it applies friction.
pub(super) struct Law<'a> {
    pub(super) shapes: &'a [StillShape],
    pub(super) friction: Option<&'a [f32]>,
    /// With friction, when a shape moves: how far (m) each shape's surface
    /// moves over the substep
    /// ([`LaneContacts::shifts`](super::contacts::LaneContacts::shifts)); a
    /// slide is taken relative to it.
    pub(super) shifts: Option<&'a [Vector]>,
    /// The cuboids' planes
    /// ([`LaneContacts::planes`](super::contacts::LaneContacts::planes)) and
    /// the lanes of a slot.
    pub(super) planes: [&'a [f32]; 4],
    pub(super) lanes: usize,
}

impl Law<'_> {
    /// Checks that every cuboid's planes hold lanes `0..end` (the plane
    /// arrays all one length, each slot's `end` lanes within it): then a
    /// step of lanes below `end` may load them unchecked.
    #[inline]
    pub(super) fn check_planes(&self, end: usize) {
        let [px, py, pz, po] = self.planes;
        let len = po.len();
        assert!([px.len(), py.len(), pz.len()] == [len; 3]);
        for shape in self.shapes {
            if let Some(slot) = shape.slot() {
                assert!(
                    slot * self.lanes + end <= len,
                    "a held shape's planes for its lanes"
                );
            }
        }
    }

    /// The plane (normal, offset) of lane `i` in `slot`.
    #[inline(always)]
    pub(super) fn plane(&self, slot: usize, i: usize) -> ([f32; 3], f32) {
        let at = slot * self.lanes + i;
        let [x, y, z, offset] = self.planes;
        ([x[at], y[at], z[at]], offset[at])
    }
}

/// A chunk of lanes: positions now and at the substep's start (m),
/// inverse masses (1/kg), and the record of the pushes.
pub(super) struct Chunk<'a> {
    /// The index of its first lane among all.
    pub(super) first: usize,
    pub(super) x: &'a mut [f32],
    pub(super) y: &'a mut [f32],
    pub(super) z: &'a mut [f32],
    pub(super) start: [&'a [f32]; 3],
    pub(super) w: &'a [f32],
    pub(super) depth: &'a mut [f32],
    pub(super) touch: &'a mut [u32],
}

impl<'a> Chunk<'a> {
    /// The lanes in the chunk, every array checked to hold them all (once
    /// a pass, so that the steps' indexing needs no more checks).
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        let n = self.x.len();
        let lens = [self.y.len(), self.z.len(), self.w.len()];
        assert!(lens == [n; 3] && [self.depth.len(), self.touch.len()] == [n; 2]);
        assert!(self.start.iter().all(|s| s.len() == n));
        n
    }

    /// The lanes of this chunk from `start` on.
    #[cfg(target_arch = "x86_64")]
    pub(super) fn from(self, start: usize) -> Chunk<'a> {
        Chunk {
            first: self.first + start,
            x: &mut self.x[start..],
            y: &mut self.y[start..],
            z: &mut self.z[start..],
            start: self.start.map(|s| &s[start..]),
            w: &self.w[start..],
            depth: &mut self.depth[start..],
            touch: &mut self.touch[start..],
        }
    }
}
