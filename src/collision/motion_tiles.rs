//! Whether self-collision's pairs may be stale, told region by region: the
//! cloth's particles in tiles (a grid piece's in squares of
//! [`TILE_SIDE`]², any others in runs of as many indices), each with the
//! corners of every triangle at it (its *reach*: any triangle or edge with
//! a corner in the tile lies in the box around them).
//!
//! A pair the last look missed lay more than the reach (thickness plus
//! margin) from its triangle; the pass needs it once the particle is
//! within the thickness of the triangle's plane and over it (the rim, at
//! most the thickness, outside its edges): within twice the thickness of
//! the triangle. Then the particle and the triangle's corners have closed
//! in by more than the margin. A pair the look found is taken as crossed
//! (pushed back to its side) down to the reach on the other side, where
//! it cannot have gone around the triangle's edge without moving more than
//! the margin against its corners: within twice the thickness plus the
//! margin of the triangle. Either way the particle and the corners lie in
//! the boxes around two tiles' reaches within that distance of each other
//! now: if every two such tiles' particles have moved apart by at most the
//! margin since the look (the diagonal of the box around their motions),
//! the look's pairs still hold. The same for the edge pairs of the border
//! and of the folds the look found sharp (which folds are sharp is the
//! look's: one that sharpens later waits for the next). The
//! whole cloth's test ([`super::SelfContacts::due`]) bounds every two
//! particles' motion; this one only those near each other, which spares
//! the looks of a cloth whose far parts move apart (the `stack`, whose
//! skirts swing, whose layers fall towards each other from afar).
//!
//! Two tiles whose boxes say they may have closed in are then told
//! particle by particle ([`ParticleTest`]): the bound above needs only the
//! particle and the corners of a triangle within `near` of it now, which
//! lie within `near` plus the triangle's longest edge of each other (any
//! point of a triangle lies within its longest edge of each corner); and
//! for an edge pair (a border edge and any edge near it, or two sharp
//! folds' edges), the ends of two edges whose closest points lie within
//! `near`: within `near` plus both edges, for every two particles of
//! which one ends a border or fold edge. An edge of a triangle in a
//! tile's reach is now at most the longest edge at the look plus the
//! diagonal of the box around the reach's motions. Every two particles
//! of the two reaches that close must have moved against each other by at
//! most the margin. A tile's reach spans six particles a side, and a
//! tile bending as the cloth drapes spreads its motions by more than the
//! margin long before any two particles near each other have closed in
//! by it (at the `stack`'s looks, the tile pair that fired had motion
//! boxes 5.5 and 8.8 mm across and their centres 3.7 mm apart); curved
//! tiles' boxes meet while their particles lie 6 cm apart. Told particle
//! by particle, the `stack` looks 2.89 times a frame instead of 3.30 and
//! the `fold` 2.31 instead of 2.67, crossing itself as often over 147
//! starts (BENCHMARKS.md, fifty-sixth session).

use super::neighbours::TopologyKey;
use crate::cloth::Topology;
#[cfg(target_arch = "x86_64")]
use crate::math::load_vectors;
use crate::math::{simd_available, Vector};

/// What the test particle by particle takes besides the positions (module
/// docs).
#[derive(Clone, Copy)]
pub(crate) struct ParticleTest<'a> {
    /// Per particle: an end of an edge a look may pair (the border's, the
    /// look's sharp folds'); a particle past its end counts as one.
    pub edge_ends: &'a [bool],
    /// The longest triangle edge at the look (m).
    pub longest: f32,
}

/// Particles along a side of a grid piece's tile. Measured on the `stack`
/// (looks a frame, 120 frames; 4.83 with the whole cloth's test alone):
/// 3.39 with tiles of 2, 3.59 of 3, 3.80 of 4, 3.92 of 6, 4.09 of 8; the
/// test's own time grows as the tiles shrink.
pub(crate) const TILE_SIDE: usize = 4;

/// A tile's reach is padded to whole steps of this many particles (with
/// its last, which changes no box) for the AVX2 kernel.
const STEP: usize = 8;

/// The cloth's particles in tiles with their triangles' corners (module
/// docs), and scratch for the test.
#[derive(Debug, Default, Clone)]
pub(crate) struct MotionTiles {
    /// Per tile: where its reach starts in `reach` (one more entry than
    /// tiles); each tile's a whole number of [`STEP`]s.
    start: Vec<u32>,
    /// Particles of each tile's reach, ascending, padded with its last.
    reach: Vec<u32>,
    /// Per tile at the last test: the box around its reach (m) and around
    /// its reach's motions since the look (m).
    boxes: Vec<TileBoxes>,
    /// Tiles by the low end of their box along x (scratch).
    order: Vec<u32>,
    /// The boxes in that order, coordinate by coordinate (scratch).
    sorted: SortedBoxes,
    /// What the tiles were made from.
    made_for: Option<TopologyKey>,
    /// A reach's particles for the test particle by particle (scratch).
    lanes: ReachLanes,
}

/// A tile's reach as the AVX2 test particle by particle reads it: each
/// particle's position (m) and motion (m), coordinate by coordinate, and
/// whether it is an edge end (all bits set) or not (none).
#[derive(Debug, Default, Clone)]
struct ReachLanes {
    x: [Vec<f32>; 3],
    moved: [Vec<f32>; 3],
    end: Vec<f32>,
}

/// The boxes of a tile at a test: around its reach's positions (m) and
/// around their motions since the look (m).
#[derive(Debug, Clone, Copy, PartialEq)]
struct TileBoxes {
    lo: Vector,
    hi: Vector,
    moved_lo: Vector,
    moved_hi: Vector,
}

impl MotionTiles {
    /// Makes the tiles for `topology`, whose key is `key`
    /// ([`TopologyKey::of`]), unless they were made for it already
    /// (allocates then, never in a test).
    pub(crate) fn update(&mut self, topology: &Topology, key: TopologyKey) {
        if self.made_for == Some(key) {
            return;
        }
        self.made_for = Some(key);
        let n = key.particles();
        let (tile, tiles) = tiles_of(topology, n);
        // Each tile's reach: its particles and the corners of every
        // triangle with a corner in it.
        let own = (0..n).map(|p| (tile[p], p as u32));
        let corners = topology.triangles.iter().flat_map(|tri| {
            let in_range = tri.iter().all(|&c| (c as usize) < n);
            let tiles = tri.map(|c| if in_range { tile[c as usize] } else { u32::MAX });
            (0..3)
                .filter(move |&k| in_range && !tiles[..k].contains(&tiles[k]))
                .flat_map(move |k| tri.map(|c| (tiles[k], c)))
        });
        let mut members: Vec<(u32, u32)> = own.chain(corners).collect();
        members.sort_unstable();
        members.dedup();
        self.start.clear();
        self.start.push(0);
        self.reach.clear();
        let mut k = 0;
        for t in 0..tiles as u32 {
            let first = self.reach.len();
            while let Some(&(_, p)) = members.get(k).filter(|m| m.0 == t) {
                self.reach.push(p);
                k += 1;
            }
            // Every tile holds a particle of its own; padded with its last.
            if let Some(&last) = self.reach.last().filter(|_| self.reach.len() > first) {
                let padded = first + (self.reach.len() - first).next_multiple_of(STEP);
                self.reach.resize(padded, last);
            }
            self.start.push(self.reach.len() as u32);
        }
    }

    /// True when a particle and a triangle (or two edges' ends) within
    /// `near` metres of each other now may have closed in by more than
    /// `margin` since the positions `at` (by their tiles' boxes, then
    /// particle by particle: module docs), or a position, a motion or the
    /// longest edge is not finite; also when `x` is not of the particles
    /// the tiles were made for.
    pub(crate) fn closed_in(
        &mut self,
        x: &[Vector],
        at: &[Vector],
        (near, margin): (f32, f32),
        by: ParticleTest,
    ) -> bool {
        self.closed_in_with(x, at, (near, margin), by, simd_available())
    }

    /// [`Self::closed_in`], with the AVX2 kernels only when `simd`.
    fn closed_in_with(
        &mut self,
        x: &[Vector],
        at: &[Vector],
        (near, margin): (f32, f32),
        by: ParticleTest,
        simd: bool,
    ) -> bool {
        if self.made_for.map(TopologyKey::particles) != Some(x.len()) || at.len() != x.len() {
            return true;
        }
        if !self.measure(x, at, simd) {
            return true; // lost: look again
        }
        // The tiles by the low end of their box along x: the last test's
        // order sorted again (by insertion: little changes between tests).
        let boxes = &self.boxes;
        if self.order.len() != boxes.len() {
            self.order.clear();
            self.order.extend(0..boxes.len() as u32);
        }
        let key = |t: u32| boxes[t as usize].lo.x;
        for k in 1..self.order.len() {
            let t = self.order[k];
            let mut j = k;
            while j > 0 && key(self.order[j - 1]) > key(t) {
                self.order[j] = self.order[j - 1];
                j -= 1;
            }
            self.order[j] = t;
        }
        self.sorted.fill(boxes, &self.order);
        let (order, start, reach) = (&self.order, &self.start, &self.reach);
        let lanes = &mut self.lanes;
        let reach_of = |k: usize| {
            let t = order[k] as usize;
            &reach[start[t] as usize..start[t + 1] as usize]
        };
        let sorted = &self.sorted;
        // Boxes `i` and `j` in the sorted order, told particle by particle.
        let mut apart = |i: usize, j: usize| {
            let spread = |k: usize| {
                let b = sorted.get(k);
                (b.moved_hi - b.moved_lo).length()
            };
            let longest = by.longest + spread(i).max(spread(j));
            let (close, far) = (near + longest, near + 2.0 * longest);
            if !far.is_finite() {
                return true; // lost: look again
            }
            let reaches = (reach_of(i), reach_of(j));
            let within = (close, far, margin);
            #[cfg(target_arch = "x86_64")]
            if simd && simd_available() {
                lanes.fill(reaches.1, (x, at), by.edge_ends);
                // SAFETY: only where the CPU has AVX2; every index in the
                // reaches is below the particle count, `x.len()` and
                // `at.len()` (checked above).
                return unsafe { lanes.apart_avx2(reaches.0, (x, at), within, by.edge_ends) };
            }
            particles_apart(reaches, (x, at), within, by.edge_ends)
        };
        sorted.any_near_apart((near, margin), simd, &mut apart)
    }

    /// Each tile's boxes at positions `x` and motions `x - at` (both of
    /// the tiles' particles, checked by the caller) into `boxes`; false
    /// when a position or motion is not finite.
    fn measure(&mut self, x: &[Vector], at: &[Vector], simd: bool) -> bool {
        let tiles = self.start.len().saturating_sub(1);
        self.boxes.clear();
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        #[cfg(target_arch = "x86_64")]
        if simd && simd_available() {
            // SAFETY: only where the CPU has AVX2; every index in `reach`
            // is below the particle count the tiles were made for, which
            // is `x.len()` and `at.len()` (the caller's check).
            return unsafe { self.measure_avx2(x, at, tiles) };
        }
        for t in 0..tiles {
            let members = &self.reach[self.start[t] as usize..self.start[t + 1] as usize];
            let mut b = TileBoxes::EMPTY;
            let mut finite = true;
            for &p in members {
                let (xp, d) = (x[p as usize], x[p as usize] - at[p as usize]);
                finite &= d.is_finite();
                (b.lo, b.hi) = (b.lo.min(xp), b.hi.max(xp));
                (b.moved_lo, b.moved_hi) = (b.moved_lo.min(d), b.moved_hi.max(d));
            }
            if !finite {
                return false;
            }
            self.boxes.push(b);
        }
        true
    }

    /// [`Self::measure`] eight particles of a tile at a time.
    ///
    /// # Safety
    /// The CPU has AVX2; every index in `reach` is below `x.len()` and
    /// `at.len()`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn measure_avx2(&mut self, x: &[Vector], at: &[Vector], tiles: usize) -> bool {
        use std::arch::x86_64::*;
        let (xs, ats) = (x.as_ptr() as *const f32, at.as_ptr() as *const f32);
        // SAFETY: every index below the arrays' length (the caller's
        // promise).
        let points = |base: *const f32, i: &[u32]| unsafe {
            load_vectors(base, std::array::from_fn(|l| *i.get_unchecked(l) as usize))
        };
        let mut lost = _mm256_setzero_ps();
        for t in 0..tiles {
            let members = &self.reach[self.start[t] as usize..self.start[t + 1] as usize];
            let mut lo = [_mm256_set1_ps(f32::INFINITY); 3];
            let mut hi = [_mm256_set1_ps(f32::NEG_INFINITY); 3];
            let (mut moved_lo, mut moved_hi) = (lo, hi);
            // Whole steps: each tile's reach is padded to them.
            for step in members.chunks_exact(STEP) {
                let (p, a) = (points(xs, step), points(ats, step));
                for c in 0..3 {
                    let d = _mm256_sub_ps(p[c], a[c]);
                    // Not finite: d - d is not a number.
                    let z = _mm256_sub_ps(d, d);
                    lost = _mm256_or_ps(lost, _mm256_cmp_ps::<_CMP_UNORD_Q>(z, z));
                    lo[c] = _mm256_min_ps(lo[c], p[c]);
                    hi[c] = _mm256_max_ps(hi[c], p[c]);
                    moved_lo[c] = _mm256_min_ps(moved_lo[c], d);
                    moved_hi[c] = _mm256_max_ps(moved_hi[c], d);
                }
            }
            let least = |v: [__m256; 3]| {
                Vector::from_array(v.map(|v| lanes(v).into_iter().fold(f32::INFINITY, f32::min)))
            };
            let most = |v: [__m256; 3]| {
                Vector::from_array(
                    v.map(|v| lanes(v).into_iter().fold(f32::NEG_INFINITY, f32::max)),
                )
            };
            self.boxes.push(TileBoxes {
                lo: least(lo),
                hi: most(hi),
                moved_lo: least(moved_lo),
                moved_hi: most(moved_hi),
            });
        }
        _mm256_movemask_ps(lost) == 0
    }
}

/// Tiles' boxes ([`TileBoxes`]) in order of their boxes' low x, each
/// coordinate of each corner in an array of its own (`lo`, `hi`,
/// `moved_lo`, `moved_hi`: x, y and z of each), padded to whole steps of
/// [`STEP`] with boxes far past the last along x.
#[derive(Debug, Default, Clone)]
struct SortedBoxes {
    len: usize,
    c: [Vec<f32>; 12],
}

impl SortedBoxes {
    /// `boxes` in `order`.
    fn fill(&mut self, boxes: &[TileBoxes], order: &[u32]) {
        self.len = order.len();
        let padded = order.len().next_multiple_of(STEP) + STEP;
        for (k, c) in self.c.iter_mut().enumerate() {
            c.clear();
            // Far past any box along x, and apart from nothing.
            let pad = if k < 3 { f32::INFINITY } else { 0.0 };
            c.resize(padded, pad);
        }
        for (k, &t) in order.iter().enumerate() {
            let b = boxes[t as usize];
            for (a, corner) in [b.lo, b.hi, b.moved_lo, b.moved_hi].into_iter().enumerate() {
                for (i, v) in corner.to_array().into_iter().enumerate() {
                    self.c[3 * a + i][k] = v;
                }
            }
        }
    }

    /// Box `k`.
    fn get(&self, k: usize) -> TileBoxes {
        let v =
            |a: usize| Vector::new(self.c[3 * a][k], self.c[3 * a + 1][k], self.c[3 * a + 2][k]);
        TileBoxes {
            lo: v(0),
            hi: v(1),
            moved_lo: v(2),
            moved_hi: v(3),
        }
    }

    /// Whether a box's motions span more than `margin` (the diagonal of
    /// their box), or two boxes within `near` of each other do together,
    /// and `particles_apart` then says so of that box (`(i, i)`) or those
    /// two (`(i, j)`, in this order); eight boxes at a time where `simd`
    /// and the CPU has AVX2.
    fn any_near_apart(
        &self,
        (near, margin): (f32, f32),
        simd: bool,
        particles_apart: &mut dyn FnMut(usize, usize) -> bool,
    ) -> bool {
        let apart = |moved_lo: Vector, moved_hi: Vector| {
            (moved_hi - moved_lo).length_squared() > margin * margin
        };
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        for i in 0..self.len {
            let a = self.get(i);
            if apart(a.moved_lo, a.moved_hi) && particles_apart(i, i) {
                return true;
            }
            #[cfg(target_arch = "x86_64")]
            if simd && simd_available() {
                // SAFETY: only where the CPU has AVX2.
                if unsafe { self.near_apart_avx2(i, a, (near, margin), particles_apart) } {
                    return true;
                }
                continue;
            }
            for j in i + 1..self.len {
                let b = self.get(j);
                // Along x in order: the rest lie further still.
                if b.lo.x > a.hi.x + near {
                    break;
                }
                let gap = (b.lo - a.hi).max(a.lo - b.hi).max(Vector::ZERO);
                if gap.length_squared() <= near * near
                    && apart(a.moved_lo.min(b.moved_lo), a.moved_hi.max(b.moved_hi))
                    && particles_apart(i, j)
                {
                    return true;
                }
            }
        }
        false
    }

    /// The boxes after `i` against box `i` (`a`), eight at a time: the
    /// scalar loop's answer, with the same floats in each comparison.
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn near_apart_avx2(
        &self,
        i: usize,
        a: TileBoxes,
        (near, margin): (f32, f32),
        particles_apart: &mut dyn FnMut(usize, usize) -> bool,
    ) -> bool {
        use std::arch::x86_64::*;
        let splat = |v: f32| _mm256_set1_ps(v);
        let (near2, margin2) = (splat(near * near), splat(margin * margin));
        let reach_x = splat(a.hi.x + near);
        let zero = _mm256_setzero_ps();
        let a_lo = a.lo.to_array().map(splat);
        let a_hi = a.hi.to_array().map(splat);
        let a_mlo = a.moved_lo.to_array().map(splat);
        let a_mhi = a.moved_hi.to_array().map(splat);
        let mut j = i + 1;
        while j < self.len {
            // SAFETY: every array holds `len` padded by at least a step.
            let load = |k: usize| unsafe { _mm256_loadu_ps(self.c[k].as_ptr().add(j)) };
            // Along x in order: lanes from the first past reach on are
            // past it too (and the padding is past every reach).
            let within = _mm256_cmp_ps::<_CMP_LE_OQ>(load(0), reach_x);
            let lanes_within = _mm256_movemask_ps(within) as u32;
            let mut gap2 = zero;
            let mut span2 = zero;
            for c in 0..3 {
                // As the scalar loop: max(b.lo - a.hi, a.lo - b.hi, 0).
                let g = _mm256_max_ps(
                    _mm256_max_ps(
                        _mm256_sub_ps(load(c), a_hi[c]),
                        _mm256_sub_ps(a_lo[c], load(3 + c)),
                    ),
                    zero,
                );
                gap2 = _mm256_add_ps(gap2, _mm256_mul_ps(g, g));
                let s = _mm256_sub_ps(
                    _mm256_max_ps(a_mhi[c], load(9 + c)),
                    _mm256_min_ps(a_mlo[c], load(6 + c)),
                );
                span2 = _mm256_add_ps(span2, _mm256_mul_ps(s, s));
            }
            let hit = _mm256_and_ps(
                within,
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LE_OQ>(gap2, near2),
                    _mm256_cmp_ps::<_CMP_GT_OQ>(span2, margin2),
                ),
            );
            let mut hits = _mm256_movemask_ps(hit) as u32;
            while hits != 0 {
                if particles_apart(i, j + hits.trailing_zeros() as usize) {
                    return true;
                }
                hits &= hits - 1;
            }
            if lanes_within != 0xff {
                return false;
            }
            j += STEP;
        }
        false
    }
}

/// Whether two particles of the reaches `a` and `b`, within `close`
/// metres of each other at positions `x` (`far` when either is an edge
/// end: `edge_ends`, past its end counted as one), have moved against
/// each other by more than `margin` since `at` (module docs).
fn particles_apart(
    (a, b): (&[u32], &[u32]),
    (x, at): (&[Vector], &[Vector]),
    (close, far, margin): (f32, f32, f32),
    edge_ends: &[bool],
) -> bool {
    for &p in a {
        let (xp, moved) = (x[p as usize], x[p as usize] - at[p as usize]);
        let end = is_edge_end(edge_ends, p);
        for &c in b {
            let xc = x[c as usize];
            let within = if end || is_edge_end(edge_ends, c) {
                far
            } else {
                close
            };
            if (xp - xc).length_squared() <= within * within
                && (moved - (xc - at[c as usize])).length_squared() > margin * margin
            {
                return true;
            }
        }
    }
    false
}

/// Whether particle `p` ends an edge a look may pair, by `edge_ends`; a
/// particle past its end counts as one (the wider reach is the safe one).
fn is_edge_end(edge_ends: &[bool], p: u32) -> bool {
    edge_ends.get(p as usize).copied().unwrap_or(true)
}

impl ReachLanes {
    /// The particles `reach` (whole steps of [`STEP`]) at positions `x`,
    /// moved from `at`, edge ends by `edge_ends` (past its end: one).
    fn fill(&mut self, reach: &[u32], (x, at): (&[Vector], &[Vector]), edge_ends: &[bool]) {
        for v in self.x.iter_mut().chain(&mut self.moved) {
            v.clear();
        }
        self.end.clear();
        for &c in reach {
            let (xc, moved) = (x[c as usize], x[c as usize] - at[c as usize]);
            for k in 0..3 {
                self.x[k].push(xc[k]);
                self.moved[k].push(moved[k]);
            }
            let end = is_edge_end(edge_ends, c);
            self.end
                .push(if end { f32::from_bits(u32::MAX) } else { 0.0 });
        }
    }

    /// [`particles_apart`] of the reach `a` and the one in these lanes,
    /// eight of these at a time: the same floats in each comparison.
    ///
    /// # Safety
    /// The CPU has AVX2; every index in `a` is below `x.len()` and
    /// `at.len()`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn apart_avx2(
        &self,
        a: &[u32],
        (x, at): (&[Vector], &[Vector]),
        (close, far, margin): (f32, f32, f32),
        edge_ends: &[bool],
    ) -> bool {
        use std::arch::x86_64::*;
        let n = self.end.len();
        assert!(n.is_multiple_of(STEP) && self.x.iter().chain(&self.moved).all(|v| v.len() == n));
        let splat = |v: f32| _mm256_set1_ps(v);
        let (close2, far2, margin2) = (
            splat(close * close),
            splat(far * far),
            splat(margin * margin),
        );
        let square = |v: [__m256; 3]| {
            _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(v[0], v[0]), _mm256_mul_ps(v[1], v[1])),
                _mm256_mul_ps(v[2], v[2]),
            )
        };
        for &p in a {
            let (xp, moved) = (x[p as usize], x[p as usize] - at[p as usize]);
            let end = is_edge_end(edge_ends, p);
            let (xp, moved) = (xp.to_array().map(splat), moved.to_array().map(splat));
            for k in (0..n).step_by(STEP) {
                // SAFETY: `k + STEP <= n`, every array's length (asserted).
                let load = |v: &Vec<f32>| unsafe { _mm256_loadu_ps(v.as_ptr().add(k)) };
                let apart = [0, 1, 2].map(|c| _mm256_sub_ps(xp[c], load(&self.x[c])));
                let against = [0, 1, 2].map(|c| _mm256_sub_ps(moved[c], load(&self.moved[c])));
                // An edge end either side: `far`; else `close` (as the
                // plain loop).
                let within2 = if end {
                    far2
                } else {
                    _mm256_blendv_ps(close2, far2, load(&self.end))
                };
                let hit = _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LE_OQ>(square(apart), within2),
                    _mm256_cmp_ps::<_CMP_GT_OQ>(square(against), margin2),
                );
                if _mm256_movemask_ps(hit) != 0 {
                    return true;
                }
            }
        }
        false
    }
}

/// The eight lanes of a register.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn lanes(v: std::arch::x86_64::__m256) -> [f32; 8] {
    let mut out = [0.0; 8];
    // SAFETY: eight floats stored into eight.
    unsafe { std::arch::x86_64::_mm256_storeu_ps(out.as_mut_ptr(), v) };
    out
}

impl TileBoxes {
    /// Boxes around nothing.
    const EMPTY: TileBoxes = TileBoxes {
        lo: Vector::INFINITY,
        hi: Vector::NEG_INFINITY,
        moved_lo: Vector::INFINITY,
        moved_hi: Vector::NEG_INFINITY,
    };
}

/// Each of `n` particles' tile, and how many tiles: a grid piece's by its
/// square of [`TILE_SIDE`]², the rest by runs of as many indices after the
/// pieces' tiles.
fn tiles_of(topology: &Topology, n: usize) -> (Vec<u32>, usize) {
    const NONE: u32 = u32::MAX;
    let mut tile = vec![NONE; n];
    let mut tiles = 0usize;
    for piece in topology.grid_pieces() {
        let (cols, rows) = (piece.grid.cols, piece.grid.rows);
        let across = cols.div_ceil(TILE_SIDE);
        for r in 0..rows {
            for c in 0..cols {
                let p = piece.first_particle.saturating_add(r * cols + c);
                if let Some(t) = tile.get_mut(p) {
                    *t = (tiles + (r / TILE_SIDE) * across + c / TILE_SIDE) as u32;
                }
            }
        }
        tiles += across * rows.div_ceil(TILE_SIDE);
    }
    let mut in_run = TILE_SIDE * TILE_SIDE;
    for t in tile.iter_mut().filter(|t| **t == NONE) {
        if in_run == TILE_SIDE * TILE_SIDE {
            (tiles, in_run) = (tiles + 1, 0);
        }
        *t = (tiles - 1) as u32;
        in_run += 1;
    }
    (tile, tiles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Cloth, ClothBuilder, ClothMesh, MassSpec, Material};
    use crate::collision::contact::nearest_on_triangle;
    use crate::collision::neighbours::MeshNeighbours;

    /// Two 10 × 10 sheets of 0.3 m in one cloth, the second `apart`
    /// metres above the first: grids joined, or one mesh of their quads
    /// (no grid: tiles of runs of indices).
    fn two_sheets(apart: f32, mesh: bool) -> (Cloth, Vec<Vector>) {
        let cloth = if mesh {
            let n = 10u32;
            let step = 0.3 / (n - 1) as f32;
            let positions = (0..2 * n * n)
                .map(|i| {
                    let k = i % (n * n);
                    Vector::new((k % n) as f32 * step, 0.0, (k / n) as f32 * step)
                })
                .collect();
            let faces = (0..2 * (n - 1) * (n - 1))
                .map(|q| {
                    let (sheet, q) = (q / ((n - 1) * (n - 1)), q % ((n - 1) * (n - 1)));
                    let i = sheet * n * n + (q / (n - 1)) * n + q % (n - 1);
                    vec![i, i + n, i + n + 1, i + 1]
                })
                .collect();
            let mesh = ClothMesh {
                positions,
                faces,
                uvs: Vec::new(),
            };
            Cloth::from_mesh(&mesh, Material::cotton(), MassSpec::FromDensity).unwrap()
        } else {
            let sheet = ClothBuilder::new(10, 10).size(0.3, 0.3).build().unwrap();
            Cloth::join(vec![sheet; 2]).unwrap()
        };
        let x = cloth
            .positions()
            .iter()
            .enumerate()
            .map(|(i, &p)| p + Vector::new(0.0, if i >= 100 { apart } else { 0.0 }, 0.0))
            .collect();
        (cloth, x)
    }

    fn tiles_for(cloth: &Cloth) -> MotionTiles {
        let mut tiles = MotionTiles::default();
        let key = TopologyKey::of(&cloth.topology, cloth.particle_count());
        tiles.update(&cloth.topology, key);
        tiles
    }

    /// The cloth's triangle edges, and per particle whether it ends a
    /// border edge (as a look without sharp folds marks them).
    fn edges_of(cloth: &Cloth) -> (MeshNeighbours, Vec<bool>) {
        let mut neighbours = MeshNeighbours::default();
        let key = TopologyKey::of(&cloth.topology, cloth.particle_count());
        neighbours.update_for(&cloth.topology, key);
        let mut ends = vec![false; cloth.particle_count()];
        for &edge in neighbours.border_edges() {
            for p in edge {
                ends[p as usize] = true;
            }
        }
        (neighbours, ends)
    }

    /// The test of the boxes alone: a longest edge not finite says apart
    /// for every two tiles the boxes let through.
    const BOXES_ALONE: ParticleTest = ParticleTest {
        edge_ends: &[],
        longest: f32::INFINITY,
    };

    /// The distance (m) between segments `a`–`b` and `p`–`q`.
    fn segments_apart((a, b): (Vector, Vector), (p, q): (Vector, Vector)) -> f32 {
        // The nearest of each segment's points to the other segment, by
        // alternating projections from both ends, then the ends' own.
        let onto = |x: Vector, (s, e): (Vector, Vector)| {
            let d = e - s;
            let t = ((x - s).dot(d) / d.length_squared().max(1.0e-12)).clamp(0.0, 1.0);
            s + d * t
        };
        let mut best = f32::INFINITY;
        for start in [a, b, (a + b) * 0.5] {
            let mut x = start;
            for _ in 0..50 {
                let y = onto(x, (p, q));
                x = onto(y, (a, b));
                best = best.min((x - onto(x, (p, q))).length());
            }
        }
        best
    }

    /// Every particle is in one tile, each triangle in the reach of the
    /// tile of each of its corners, and each reach is whole steps.
    #[test]
    fn each_tile_reaches_the_triangles_at_its_particles() {
        for mesh in [false, true] {
            each_tile_reaches_the_triangles_at_its_particles_of(mesh);
        }
    }

    fn each_tile_reaches_the_triangles_at_its_particles_of(mesh: bool) {
        let (cloth, _) = two_sheets(0.1, mesh);
        let tiles = tiles_for(&cloth);
        let count = tiles.start.len() - 1;
        // 10 × 10 in tiles of 4: 3 × 3 a sheet; a mesh's 200 particles in
        // runs of 16.
        let want = if mesh {
            200usize.div_ceil(TILE_SIDE * TILE_SIDE)
        } else {
            2 * 10usize.div_ceil(TILE_SIDE).pow(2)
        };
        assert_eq!(count, want);
        let reach = |t: usize| &tiles.reach[tiles.start[t] as usize..tiles.start[t + 1] as usize];
        let mut owners = vec![0; cloth.particle_count()];
        let (tile, _) = tiles_of(&cloth.topology, cloth.particle_count());
        for t in 0..count {
            assert_eq!(reach(t).len() % STEP, 0);
            for p in 0..cloth.particle_count() {
                if tile[p] as usize == t {
                    owners[p] += 1;
                    assert!(reach(t).contains(&(p as u32)));
                }
            }
        }
        assert!(owners.iter().all(|&o| o == 1));
        for tri in &cloth.topology.triangles {
            for &c in tri {
                let own = reach(tile[c as usize] as usize);
                assert!(tri.iter().all(|k| own.contains(k)), "{tri:?}");
            }
        }
    }

    /// The test's claim, checked one pair at a time on random motions:
    /// when it finds no tiles near each other closed in, every particle
    /// now within `near` of a triangle has moved against each of its
    /// corners by at most the margin, and the ends of a border edge and
    /// of any edge within `near` of it against each other. The sheets
    /// lie one over the other or side by side (the sweep along x then
    /// decides); both answers occur, the plain loops give each, and the
    /// particles' test spares looks the boxes alone would ask for.
    #[test]
    fn no_particle_near_a_triangle_closed_in_on_it_unseen() {
        for mesh in [false, true] {
            no_particle_near_a_triangle_closed_in_on_it_unseen_of(mesh);
        }
    }

    fn no_particle_near_a_triangle_closed_in_on_it_unseen_of(mesh: bool) {
        let (cloth, rest) = two_sheets(0.0, mesh);
        let mut tiles = tiles_for(&cloth);
        let (neighbours, edge_ends) = edges_of(&cloth);
        let edges: Vec<[u32; 2]> = (0..rest.len() as u32)
            .flat_map(|p| neighbours.edges_from(p).iter().map(move |&q| [p, q]))
            .collect();
        let (near, margin) = (0.015, 0.01);
        let mut spared = 0;
        let mut seed = 7u32;
        let mut random = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let (mut quiet, mut due) = ([0; 2], [0; 2]);
        for trial in 0..200 {
            // Over (2 cm up) or beside (0.5 to 2 cm apart along x).
            let beside = trial % 2;
            let offset = if beside == 1 {
                Vector::new(0.3 + 0.0125 + 0.015 * random(), 0.0, 0.0)
            } else {
                Vector::new(0.0, 0.02, 0.0)
            };
            let at: Vec<Vector> = rest
                .iter()
                .enumerate()
                .map(|(i, &p)| if i >= 100 { p + offset } else { p })
                .collect();
            // The second sheet slides and turns against the first, each
            // with a ripple and a jitter, by up to a few margins.
            let size = 0.004 * (1 + trial % 6) as f32;
            let (slide, turn) = (
                Vector::new(random(), random(), random()) * size,
                random() * size,
            );
            let x: Vec<Vector> = at
                .iter()
                .enumerate()
                .map(|(i, &p)| {
                    let jitter = Vector::new(random(), random(), random()) * 0.002;
                    let ripple = Vector::new(0.0, (p.x * 20.0).sin() * size * 0.3, 0.0);
                    let moved = if i >= 100 {
                        let (s, c) = turn.sin_cos();
                        Vector::new(c * p.x - s * p.z, p.y, s * p.x + c * p.z) + slide
                    } else {
                        p
                    };
                    moved + ripple + jitter
                })
                .collect();
            let by = ParticleTest {
                edge_ends: &edge_ends,
                longest: neighbours.longest_at(&at),
            };
            let closed = tiles.closed_in(&x, &at, (near, margin), by);
            let plain = tiles.closed_in_with(&x, &at, (near, margin), by, false);
            assert_eq!(closed, plain);
            let by_boxes = tiles.closed_in(&x, &at, (near, margin), BOXES_ALONE);
            assert!(
                by_boxes || !closed,
                "trial {trial}: the particles' test is the stricter"
            );
            if closed {
                due[beside] += 1;
                continue;
            }
            quiet[beside] += 1;
            spared += usize::from(by_boxes);
            // A border edge and any edge (a look pairs them).
            for &[a, b] in neighbours.border_edges() {
                for &[p, q] in &edges {
                    let ends = |[i, j]: [u32; 2]| (x[i as usize], x[j as usize]);
                    if [a, b].iter().any(|e| [p, q].contains(e))
                        || segments_apart(ends([a, b]), ends([p, q])) > near
                    {
                        continue;
                    }
                    for (i, j) in [(a, p), (a, q), (b, p), (b, q)] {
                        let (i, j) = (i as usize, j as usize);
                        let against = (x[i] - at[i]) - (x[j] - at[j]);
                        assert!(
                            against.length() <= margin * (1.0 + 1.0e-5),
                            "trial {trial} (mesh: {mesh}): edge end {i} moved {} against {j}",
                            against.length()
                        );
                    }
                }
            }
            for (p, &xp) in x.iter().enumerate() {
                for tri in &cloth.topology.triangles {
                    let [a, b, c] = tri.map(|c| x[c as usize]);
                    if (nearest_on_triangle(xp, (a, b, c)) - xp).length() > near {
                        continue;
                    }
                    let moved = xp - at[p];
                    for &c in tri {
                        let against = moved - (x[c as usize] - at[c as usize]);
                        assert!(
                            against.length() <= margin * (1.0 + 1.0e-5),
                            "trial {trial} (mesh: {mesh}): particle {p} moved {} against corner {c}",
                            against.length()
                        );
                    }
                }
            }
        }
        assert!(
            quiet.iter().chain(&due).all(|&n| n >= 10),
            "{quiet:?} quiet, {due:?} due (over, beside), mesh: {mesh}"
        );
        assert!(
            spared >= 5,
            "the particles' test spared {spared} looks (mesh: {mesh})"
        );
    }

    /// A cloth's far parts moving apart need no look (the whole cloth's
    /// test would ask for one); near ones do, through the solver's test.
    #[test]
    fn far_parts_moving_apart_need_no_look_and_near_ones_do() {
        use crate::collision::{LookBasis, SelfContacts};
        use crate::parallel::Team;
        for (apart, due) in [(0.5, false), (0.012, true)] {
            let (cloth, at) = two_sheets(apart, false);
            // The upper sheet slides 3 cm (three margins) over the other.
            let x: Vec<Vector> = at
                .iter()
                .enumerate()
                .map(|(i, &p)| p + Vector::new(if i >= 100 { 0.03 } else { 0.0 }, 0.0, 0.0))
                .collect();
            let basis = LookBasis {
                topology: &cloth.topology,
                particles: at.len(),
                revision: cloth.mass_revision,
                thickness: 0.002,
                margin: 0.01,
            };
            let (mut contacts, mut look) = (SelfContacts::default(), None);
            contacts.begin_step(&mut look, &basis, Team::ALONE);
            contacts.find(&mut look, (&at, &[], 0.0), &basis, Team::ALONE);
            assert!(!contacts.due(&look, &at), "unmoved");
            assert_eq!(contacts.due(&look, &x), due, "{apart} m apart");
        }
    }

    /// The AVX2 kernels measure the boxes the plain loops do, bit for
    /// bit; a position not a number, or of another cloth, asks for a
    /// look.
    #[test]
    fn boxes_the_same_either_way_and_lost_positions_look_again() {
        let (cloth, at) = two_sheets(0.05, true);
        let mut tiles = tiles_for(&cloth);
        let x: Vec<Vector> = at
            .iter()
            .enumerate()
            .map(|(i, &p)| p + Vector::new(0.001 * (i % 7) as f32, -0.002 * (i % 3) as f32, 0.0))
            .collect();
        assert!(tiles.measure(&x, &at, true));
        let simd = tiles.boxes.clone();
        assert!(tiles.measure(&x, &at, false));
        let bits = |b: &[TileBoxes]| -> Vec<[u32; 12]> {
            b.iter()
                .map(|b| {
                    let mut out = [0; 12];
                    for (k, v) in [b.lo, b.hi, b.moved_lo, b.moved_hi].into_iter().enumerate() {
                        out[3 * k..3 * k + 3].copy_from_slice(&v.to_array().map(f32::to_bits));
                    }
                    out
                })
                .collect()
        };
        assert_eq!(bits(&simd), bits(&tiles.boxes));
        let (neighbours, edge_ends) = edges_of(&cloth);
        let within = (0.01, 0.01);
        let test = |x: &[Vector], tiles: &mut MotionTiles, simd: bool| {
            let by = ParticleTest {
                edge_ends: &edge_ends,
                longest: neighbours.longest_at(&at),
            };
            tiles.closed_in_with(x, &at[..x.len()], within, by, simd)
        };
        assert!(!test(&x, &mut tiles, true));
        let mut lost = x.clone();
        lost[137].y = f32::NAN;
        assert!(test(&lost, &mut tiles, true));
        assert!(test(&lost, &mut tiles, false));
        lost[137].y = f32::INFINITY;
        assert!(test(&lost, &mut tiles, true));
        assert!(test(&x[1..], &mut tiles, true));
    }
}
