//! The self-collision stage of a cloth's solver: its state and scratch, when it
//! looks again and the look's record.

use super::lists::{EdgeList, PairList};
use super::pairs::{EdgePair, SelfLook};
use super::params::LookBasis;
use super::pass_plane::PassPlane;
use crate::collision::motion_tiles::{MotionTiles, ParticleTest};
use crate::collision::neighbours::{MeshNeighbours, TopologyKey};
use crate::collision::patches::Patches;
use crate::collision::spatial_hash::SpatialHash;
use crate::math::{simd_available, Vector, VECTOR_F32S};
use crate::parallel::Team;

/// The self-collision stage of a cloth's solver: its pairs and scratch.
/// The pairs are those of the last look (`SelfLook`, in the solver's
/// state), found again from its positions when the scratch is fresh or
/// the cloth changed.
#[derive(Debug, Default, Clone)]
pub struct SelfContacts {
    /// The particles by cell, at the last look.
    pub(super) hash: SpatialHash,
    /// The cloth's patches, and which need no look.
    pub(super) patches: Patches,
    /// Per block of triangles: the pairs it found at the last look.
    pub(super) blocks: Vec<PairList>,
    /// Per block of border edges: the edge pairs it found at the last look.
    pub(super) border_blocks: Vec<EdgeList>,
    /// Per block of sharp folds' edges: the edge pairs it found at the
    /// last look.
    pub(super) fold_blocks: Vec<EdgeList>,
    /// The sharp folds' edges of the last look (indices into
    /// [`MeshNeighbours::inner_edges`]), and each triangle's unit normal
    /// then (scratch).
    pub(super) folds: Vec<u32>,
    pub(super) normals: Vec<Vector>,
    /// Per triangle edge ([`MeshNeighbours::edge_index`]): a sharp fold's
    /// at the last look; per particle: at one (scratch).
    pub(super) sharp: Vec<bool>,
    pub(super) on_fold: Vec<bool>,
    /// Per particle: an end of a border edge or of the last look's sharp
    /// folds' edges (the edges a look may pair), for the test of the
    /// motions ([`ParticleTest`]).
    pub(super) edge_ends: Vec<bool>,
    /// The longest triangle edge at the last look (m), for the same test.
    pub(super) longest_edge: f32,
    /// Per triangle: where its pairs start and end in its block's list,
    /// at the last look.
    pub(super) triangle_pairs: Vec<[u32; 2]>,
    pub(super) neighbours: MeshNeighbours,
    /// The particles in tiles, for the test of the motions of those near
    /// each other.
    pub(super) tiles: MotionTiles,
    /// The blocks of triangles the last look used, and the pairs they found.
    pub(super) used_blocks: usize,
    pub(super) pairs: usize,
    /// Border edges near other edges, found by the last look.
    pub(super) edge_pairs: Vec<EdgePair>,
    /// Which look the pairs are of ([`SelfLook::number`]) and the cloth's
    /// revision then (its masses, pins and topology).
    pub(super) pairs_of: Option<(u64, u64)>,
    /// How far (m) particles may close in on each other between looks.
    pub(super) margin: f32,
    /// The plane that parts the pairs for a pass on two threads.
    pub(super) plane: PassPlane,
    /// Look and pass without AVX2 even where the CPU has it (the tests'
    /// reference).
    pub(super) portable: bool,
}

impl SelfContacts {
    /// At the start of a step: looks reach `margin` metres beyond the
    /// thickness. The last look carries over unless the cloth's particles,
    /// the thickness or the margin changed (then the next substep looks);
    /// if the pairs in scratch are not of it (fresh scratch, a snapshot,
    /// a changed topology), they are found again at its positions.
    pub(crate) fn begin_step(
        &mut self,
        look: &mut Option<SelfLook>,
        basis: &LookBasis,
        team: Team,
    ) {
        // One pass over the triangles keys both.
        let key = TopologyKey::of(basis.topology, basis.particles);
        self.neighbours.update_for(basis.topology, key);
        self.tiles.update(basis.topology, key);
        self.margin = basis.margin.max(1.0e-4);
        let Some(last) = look.as_ref() else {
            return;
        };
        if last.at.len() != basis.particles
            || last.thickness.to_bits() != basis.thickness.to_bits()
            || last.margin.to_bits() != self.margin.to_bits()
        {
            *look = None;
        } else if self.pairs_of != Some((last.number, basis.revision)) {
            self.find_pairs(
                (&last.at, &last.from),
                basis.topology,
                basis.thickness,
                team,
            );
            self.pairs_of = Some((last.number, basis.revision));
        }
    }

    /// True when particles at `x` may have closed in on each other by more
    /// than the margin since the `look` (or there is none), by the module's
    /// three bounds.
    pub(crate) fn due(&mut self, look: &Option<SelfLook>, x: &[Vector]) -> bool {
        let Some(look) = look else {
            return true;
        };
        if look.at.len() != x.len() {
            return true;
        }
        // Two particles closed in by at most the diagonal of the box
        // around every motion: one of the `stack`'s three cloths falling
        // onto the others has closed in by its fall, where twice its
        // particles' distance from the mean motion counts 4/3 of it.
        let Some((lo, hi)) = motion_box(x, &look.at) else {
            return true; // lost: look again
        };
        if (hi - lo).length_squared() <= self.margin * self.margin {
            return false;
        }
        // And by at most twice the farthest motion from the mean (the
        // smaller bound for a cloth that turns), summed in particle order.
        let moved = x.iter().zip(&look.at).map(|(&x, &at)| x - at);
        let sum = moved.clone().fold(Vector::ZERO, |sum, d| sum + d);
        let mean = sum / x.len().max(1) as f32;
        let half = 0.5 * self.margin;
        if !moved
            .into_iter()
            .any(|d| (d - mean).length_squared() > half * half)
        {
            return false;
        }
        // And by the motions of the particles near each other alone, tile
        // by tile ([`MotionTiles`]): near, as far as the pass reaches
        // from a triangle (on a pair's far side, the thickness and the
        // margin; over the rim, at most the thickness).
        let near = 2.0 * look.thickness + self.margin;
        let by = ParticleTest {
            edge_ends: &self.edge_ends,
            longest: self.longest_edge,
        };
        self.tiles.closed_in(x, &look.at, (near, self.margin), by)
    }

    /// Looks for pairs at positions `x` (the `basis`'s thickness and
    /// margin) and records the look in `look`; each pair takes its side
    /// from where its particles were a substep of `h` seconds before, at
    /// velocities `v` (m/s): a layer that crossed another within the
    /// substep that asked for the look is pushed back, not kept on the far
    /// side (a rubber `stack`'s corner swept through another cloth's
    /// border in one substep, and the look took the far side for good).
    pub(crate) fn find(
        &mut self,
        look: &mut Option<SelfLook>,
        (x, v, h): (&[Vector], &[Vector], f32),
        basis: &LookBasis,
        team: Team,
    ) {
        let last = look.get_or_insert_with(SelfLook::default);
        // The positions' buffers are reused: no allocation once warmed up.
        last.at.clear();
        last.at.extend_from_slice(x);
        last.from.clear();
        if v.len() == x.len() {
            last.from.extend(x.iter().zip(v).map(|(&x, &v)| x - v * h));
        }
        self.find_pairs(
            (&last.at, &last.from),
            basis.topology,
            basis.thickness,
            team,
        );
        last.thickness = basis.thickness;
        last.margin = self.margin;
        last.number += 1;
        self.pairs_of = Some((last.number, basis.revision));
    }
}

/// The box (m) around the motions `x − at` of every particle; none where
/// one is not finite. Where the CPU has AVX2, eight particles' 24
/// coordinates at a time, each register's lanes of fixed axes (the due
/// test, run every substep, was 3% of the `fold`'s instructions).
pub(super) fn motion_box(x: &[Vector], at: &[Vector]) -> Option<(Vector, Vector)> {
    let n = x.len().min(at.len());
    let (mut lo, mut hi) = (Vector::INFINITY, Vector::NEG_INFINITY);
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if simd_available() {
        // SAFETY: only where the CPU has AVX2; both arrays hold `n`.
        (done, lo, hi) = unsafe { motion_box_avx2(&x[..n], &at[..n])? };
    }
    for (&x, &at) in x[done..n].iter().zip(&at[done..n]) {
        let d = x - at;
        if !d.is_finite() {
            return None;
        }
        (lo, hi) = (lo.min(d), hi.max(d));
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// [`motion_box`] over the whole steps of eight particles: how many it
/// took and their box; none where a motion is not a number (an infinite
/// one the box shows).
///
/// # Safety
/// The CPU has AVX2; `x` and `at` are of one length.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn motion_box_avx2(
    x: &[Vector],
    at: &[Vector],
) -> Option<(usize, Vector, Vector)> {
    use std::arch::x86_64::*;
    let steps = x.len().min(at.len()) / 8;
    let (xs, ats) = (x.as_ptr() as *const f32, at.as_ptr() as *const f32);
    let mut lo = [_mm256_set1_ps(f32::INFINITY); 3];
    let mut hi = [_mm256_set1_ps(f32::NEG_INFINITY); 3];
    let mut nan = _mm256_setzero_ps();
    for step in 0..steps {
        for r in 0..3 {
            // SAFETY: floats 24 step + 8 r .. + 8 are of particles 8 step
            // .. 8 step + 8, in both arrays.
            let at = VECTOR_F32S * (8 * step) + 8 * r;
            let d = _mm256_sub_ps(_mm256_loadu_ps(xs.add(at)), _mm256_loadu_ps(ats.add(at)));
            nan = _mm256_or_ps(nan, _mm256_cmp_ps::<_CMP_UNORD_Q>(d, d));
            lo[r] = _mm256_min_ps(lo[r], d);
            hi[r] = _mm256_max_ps(hi[r], d);
        }
    }
    if _mm256_movemask_ps(nan) != 0 {
        return None;
    }
    let (mut l, mut h) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
    for r in 0..3 {
        _mm256_storeu_ps(l[r].as_mut_ptr(), lo[r]);
        _mm256_storeu_ps(h[r].as_mut_ptr(), hi[r]);
    }
    let (mut low, mut high) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for r in 0..3 {
        for j in 0..8 {
            // Float 8 r + j of a step is coordinate (8 r + j) mod 3.
            let a = (8 * r + j) % 3;
            (low[a], high[a]) = (low[a].min(l[r][j]), high[a].max(h[r][j]));
        }
    }
    Some((8 * steps, Vector::from_array(low), Vector::from_array(high)))
}
