//! Self-collision: particles kept a layer's thickness
//! ([`crate::cloth::Cloth::self_thickness`]) away from the triangles of
//! their own cloth that the springs do not hold them to: not their
//! corners, nor off a grid their neighbours in the rest mesh
//! ([`MeshNeighbours::left_to_springs`]), with Coulomb friction between
//! the layers.
//!
//! Found ahead, solved every substep (as the obstacles are): a spatial
//! hash of the particles ([`SpatialHash`]) gives each triangle the
//! particles within reach of it, `thickness + margin`. A look costs a pass
//! over the triangles, so it is taken again only when it may have missed
//! a pair: whenever two particles may have closed in by more than the
//! margin since the last look (a neighbour list with a skin, as in
//! molecular dynamics), by the smallest of three bounds: the diagonal of
//! the box around the particles' motions, twice the farthest motion from
//! their mean, and the same diagonal for the particles near each other
//! alone, tile by tile ([`MotionTiles`]); and when the
//! cloth, its thickness or the margin changed. Every substep for a cloth
//! in violent motion, seldom for one at rest or in free fall: a look
//! carries over from step to step (the `stack` at rest looked once a step
//! before, 5 ms of its frame). Where it looked is solver state
//! ([`SelfLook`], in a snapshot); the pairs are scratch, found again from
//! those positions by a solver with fresh scratch, to the same list. The
//! triangles of quiet patches ([`Patches`]: a bent sheet that cannot touch
//! itself) are skipped. Each pair keeps the side
//! of the triangle the particle was on a substep before the look (back
//! along its velocity: a layer that crossed within the substep that asked
//! for the look is pushed back). The cloth's border
//! edges are also paired with the other edges near them, so that two
//! borders cannot slip past each other; and so are the edges of sharp
//! folds ([`SHARP_FOLD`]), with the edges at the particles paired with
//! their two triangles: a crease's edge and another layer's can pass
//! through each other between particles that each keep the thickness from
//! the other layer's triangles.
//!
//! A look takes the triangles in runs of a few ([`RUN`]: a grid's cells
//! along a row), the particles inside the box around a run found once and
//! tested against each triangle eight at a time where the CPU has AVX2.
//!
//! A substep's pass, in pair order (Gauss–Seidel) within each of three
//! parts ([`PassPlane`]): the pairs below a plane across the cloth and
//! those above it on two threads at once, then those across it (the same
//! bits on any number of threads). Where the CPU has AVX2 a vector test
//! of eight pairs at a time passes over those the pass would leave as
//! they are (the pairs of layers apart), with the same bits. For a
//! particle `p` whose projection falls inside
//! triangle `abc` or within a rim outside its edges (where the cloth bends,
//! a particle near a common edge may project outside both triangles;
//! barycentrics `u, v, w`, clamped to the triangle), closer than the
//! thickness `t` along the side's normal `n`, the constraint
//! `C = (x_p − x_a)·n − t ≥ 0` moves `p` by `w_p s n` and each corner `i` by
//! `−w_i b_i s n`, with `s = −C / (w_p + Σ w_i b_i²)` (the inverse masses
//! weigh who moves; at most half the thickness a pass). Velocities then
//! lose the part of the relative velocity that closes the gap, and Coulomb
//! friction (coefficient μ) takes up to μ times the normal velocity change
//! (that change and the correction over the substep) from the sliding
//! part. No velocity is added: the pass never pumps energy. Edge pairs
//! are kept apart the same way at their closest points.

use serde::{Deserialize, Serialize};

use super::motion_tiles::{MotionTiles, ParticleTest};
use super::neighbours::{MeshNeighbours, Sheet, TopologyKey};
use super::patches::Patches;
use super::spatial_hash::SpatialHash;
use crate::cloth::{Particles, Topology};
#[cfg(target_arch = "x86_64")]
use crate::math::{cross_lanes, dot_lanes, load_vectors};
use crate::math::{simd_available, Vector, VECTOR_F32S};
use crate::parallel::{Disjoint, Team};

/// A particle near a triangle of its own cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SelfPair {
    particle: u32,
    triangle: u32,
    /// +1 when the particle lay on the side the triangle's normal points
    /// to a substep before the look ([`Look::side_before`]), −1 on the
    /// other.
    side: f32,
}

/// An edge of the cloth's border or of a sharp fold ([`SHARP_FOLD`]) near
/// another edge of the same cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
struct EdgePair {
    /// The border edge, or the lower of two edges of which one is a sharp
    /// fold's.
    edge: [u32; 2],
    /// The other edge.
    other: [u32; 2],
    /// +1 when `edge` lay on the side `(b − a) × (q − p)` points to from
    /// the other edge a substep before the look, −1 on the other.
    side: f32,
}

/// Where self-collision last looked for pairs: solver state, since when it
/// looks next depends on it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SelfLook {
    /// The particles' positions (m) at the look.
    at: Vec<Vector>,
    /// Where each particle was a substep before the look (m; its velocity
    /// back from `at`): the pairs take their sides from these (empty:
    /// from `at`).
    #[serde(default)]
    from: Vec<Vector>,
    /// The layers' thickness and the margin (m) it looked with.
    thickness: f32,
    margin: f32,
    /// Looks so far: which look the scratch's pairs are of.
    number: u64,
}

/// The self-collision stage of a cloth's solver: its pairs and scratch.
/// The pairs are those of the last look ([`SelfLook`]), found again from
/// its positions when the scratch is fresh or the cloth changed.
#[derive(Debug, Default, Clone)]
pub struct SelfContacts {
    /// The particles by cell, at the last look.
    hash: SpatialHash,
    /// The cloth's patches, and which need no look.
    patches: Patches,
    /// Per block of triangles: the pairs it found at the last look.
    blocks: Vec<PairList>,
    /// Per block of border edges: the edge pairs it found at the last look.
    border_blocks: Vec<EdgeList>,
    /// Per block of sharp folds' edges: the edge pairs it found at the
    /// last look.
    fold_blocks: Vec<EdgeList>,
    /// The sharp folds' edges of the last look (indices into
    /// [`MeshNeighbours::inner_edges`]), and each triangle's unit normal
    /// then (scratch).
    folds: Vec<u32>,
    normals: Vec<Vector>,
    /// Per triangle edge ([`MeshNeighbours::edge_index`]): a sharp fold's
    /// at the last look; per particle: at one (scratch).
    sharp: Vec<bool>,
    on_fold: Vec<bool>,
    /// Per particle: an end of a border edge or of the last look's sharp
    /// folds' edges (the edges a look may pair), for the test of the
    /// motions ([`ParticleTest`]).
    edge_ends: Vec<bool>,
    /// The longest triangle edge at the last look (m), for the same test.
    longest_edge: f32,
    /// Per triangle: where its pairs start and end in its block's list,
    /// at the last look.
    triangle_pairs: Vec<[u32; 2]>,
    neighbours: MeshNeighbours,
    /// The particles in tiles, for the test of the motions of those near
    /// each other.
    tiles: MotionTiles,
    /// The blocks of triangles the last look used, and the pairs they found.
    used_blocks: usize,
    pairs: usize,
    /// Border edges near other edges, found by the last look.
    edge_pairs: Vec<EdgePair>,
    /// Which look the pairs are of ([`SelfLook::number`]) and the cloth's
    /// revision then (its masses, pins and topology).
    pairs_of: Option<(u64, u64)>,
    /// How far (m) particles may close in on each other between looks.
    margin: f32,
    /// The plane that parts the pairs for a pass on two threads.
    plane: PassPlane,
    /// Look and pass without AVX2 even where the CPU has it (the tests'
    /// reference).
    portable: bool,
}

/// A look's pairs as lanes ([`SelfContacts::resolve`]'s vector test):
/// each pair's particle, its triangle's corners and its side, padded to
/// whole vector steps.
#[derive(Debug, Default, Clone)]
struct PairLanes {
    /// The CPU has AVX2 and the lanes are to be used (else they are left
    /// empty).
    simd: bool,
    /// Pairs, before the padding; the particles their indices are below.
    len: usize,
    particles: usize,
    /// A pair had an index out of range, or no triangle: not to be used.
    broken: bool,
    p: Vec<i32>,
    corners: [Vec<i32>; 3],
    side: Vec<f32>,
}

impl PairLanes {
    /// Empties the lanes, for pairs on `particles` particles, to be used
    /// on a CPU with AVX2 (`simd`).
    fn clear(&mut self, simd: bool, particles: usize) {
        self.simd = simd;
        self.len = 0;
        self.particles = particles;
        self.broken = false;
        self.p.clear();
        self.corners.iter_mut().for_each(Vec::clear);
        self.side.clear();
    }

    /// Adds `pair`, of the triangle with `corners` (none: no triangle,
    /// and the lanes are not to be used); nothing without AVX2.
    fn push(&mut self, pair: &SelfPair, corners: Option<[u32; 3]>) {
        if !self.simd {
            return;
        }
        let particles = self.particles;
        // Within the particles, and an index the lanes hold as an `i32`
        // (a quarter of its range, as when they were gathers' offsets).
        let fits = |i: u32| (i as usize) < particles && i <= i32::MAX as u32 / 4;
        match corners {
            Some(tri) if fits(pair.particle) && tri.into_iter().all(fits) => {
                self.p.push(pair.particle as i32);
                for (corners, c) in self.corners.iter_mut().zip(tri) {
                    corners.push(c as i32);
                }
                self.side.push(pair.side);
                self.len += 1;
            }
            _ => self.broken = true,
        }
    }

    /// Pads the lanes to whole vector steps.
    fn pad(&mut self) {
        let padded = self.len.next_multiple_of(LANES);
        self.p.resize(padded, 0);
        self.corners.iter_mut().for_each(|c| c.resize(padded, 0));
        self.side.resize(padded, 0.0);
    }

    /// True when the lanes hold `pairs` pairs on `particles` particles and
    /// the CPU has AVX2.
    fn usable(&self, pairs: usize, particles: usize) -> bool {
        self.simd && !self.broken && self.len == pairs && self.particles == particles && pairs > 0
    }

    /// Which of the eight pairs from `k` the pass may act on at positions
    /// `x`, for layers `(thickness, margin)` (m), a bit each (lane `l` bit
    /// `l`): those not idle by [`SelfContacts::pair_pass`]'s tests up to
    /// the barycentrics, each made a hair looser; every pair's bit when
    /// the lanes are not usable. None past the last pair.
    fn busy(&self, k: usize, x: &Points, layers: (f32, f32)) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.usable(self.len, x.len) && k < self.len {
            // SAFETY: usable only with AVX2, with every index below
            // `x.len`, and `k` a pair's; the pairs' particles are this
            // part's.
            return unsafe { self.busy_avx2(k, x, layers) };
        }
        let _ = (x, layers);
        (1u32 << self.len.saturating_sub(k).min(LANES)) - 1
    }

    /// [`Self::busy`] in AVX2.
    ///
    /// # Safety
    /// The CPU has AVX2; the lanes' indices are below `x.len`; `k` is
    /// below `self.len`; no other thread writes the particles of these
    /// pairs meanwhile.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn busy_avx2(&self, k: usize, x: &Points, (thickness, margin): (f32, f32)) -> u32 {
        use std::arch::x86_64::*;
        assert!(k + LANES <= self.p.len() && self.p.len() == self.side.len());
        assert!(self.corners.iter().all(|c| c.len() == self.p.len()));
        let base = x.ptr as *const f32;
        // SAFETY: `k + LANES` within the lanes (asserted); each index below
        // `x.len()` (the caller's promise) and not negative (`push`), so
        // each masked load reads the three floats of a particle.
        unsafe {
            // Each lane's point by one masked load (`load_vectors`).
            let point = |v: &Vec<i32>| {
                let index = std::array::from_fn(|l| *v.get_unchecked(k + l) as usize);
                load_vectors(base, index)
            };
            let p = point(&self.p);
            let a = point(&self.corners[0]);
            let b = point(&self.corners[1]);
            let c = point(&self.corners[2]);
            let sub = |u: [__m256; 3], v: [__m256; 3]| [0, 1, 2].map(|i| _mm256_sub_ps(u[i], v[i]));
            let (e1, e2, d) = (sub(b, a), sub(c, a), sub(p, a));
            // e1 × e2, as `Vector::cross`.
            let m = _mm256_mul_ps;
            let normal = cross_lanes(e1, e2);
            let dot = |u: [__m256; 3], v: [__m256; 3]| dot_lanes(u, v);
            let len2 = dot(normal, normal);
            let side = _mm256_loadu_ps(self.side.as_ptr().add(k));
            let out = m(dot(d, normal), side);
            let splat = _mm256_set1_ps;
            let (ge, lt) = (
                |u, v| _mm256_cmp_ps::<_CMP_GE_OQ>(u, v),
                |u, v| _mm256_cmp_ps::<_CMP_LT_OQ>(u, v),
            );
            let or = _mm256_or_ps;
            let t2 = thickness * thickness;
            let apart = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(out, _mm256_setzero_ps()),
                _mm256_cmp_ps::<_CMP_GT_OQ>(
                    m(out, out),
                    m(m(splat(t2), len2), splat(1.0 + 2.0e-4)),
                ),
            );
            // The distance along the unit normal on the pair's side: at or
            // past the thickness, or further on the other side than the
            // margin. Approximate inverses and roots (relative error under
            // 3.7e-4) with thresholds looser by more: what the pass itself
            // finds idle, and a few more.
            let tol = 2.0e-3;
            let inv_len = _mm256_rsqrt_ps(len2);
            let scale = m(side, inv_len);
            let n = normal.map(|c| m(c, scale));
            let dist = dot(d, n);
            let far = or(
                ge(dist, splat(thickness * (1.0 + tol))),
                lt(dist, splat(-(thickness + margin) * (1.0 + tol))),
            );
            // The projection's barycentrics beyond the rim's slack
            // (`barycentric`, `rim`, `rim_slack`).
            let q = [0, 1, 2].map(|i| _mm256_sub_ps(d[i], m(n[i], dist)));
            let (d11, d12, d22) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
            let (dq1, dq2) = (dot(q, e1), dot(q, e2));
            let denom = _mm256_sub_ps(m(d11, d22), m(d12, d12));
            let inv_denom = _mm256_rcp_ps(denom);
            let vb = m(_mm256_sub_ps(m(d22, dq1), m(d12, dq2)), inv_denom);
            let w = m(_mm256_sub_ps(m(d11, dq2), m(d12, dq1)), inv_denom);
            let u = _mm256_sub_ps(_mm256_sub_ps(splat(1.0), vb), w);
            let e3 = sub(e2, e1);
            let d33 = dot(e3, e3);
            let shortest = _mm256_sqrt_ps(_mm256_min_ps(_mm256_min_ps(d11, d22), d33));
            let rim = _mm256_min_ps(splat(thickness), m(splat(0.25), shortest));
            let reach = m(m(rim, inv_len), splat(1.0 + tol));
            let slack = |edge2: __m256| {
                let edge = m(edge2, _mm256_rsqrt_ps(edge2));
                _mm256_sub_ps(
                    _mm256_setzero_ps(),
                    _mm256_add_ps(m(reach, edge), splat(tol)),
                )
            };
            let outside = or(lt(u, slack(d33)), or(lt(vb, slack(d22)), lt(w, slack(d11))));
            // A degenerate triangle: left to the pass itself.
            let flat = _mm256_cmp_ps::<_CMP_NGT_UQ>(denom, _mm256_setzero_ps());
            let idle = or(apart, _mm256_andnot_ps(flat, or(far, outside)));
            // Lanes past the last pair are idle.
            let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
            let left = _mm256_set1_epi32((self.len - k).min(LANES) as i32);
            let real = _mm256_castsi256_ps(_mm256_cmpgt_epi32(left, lane));
            _mm256_movemask_ps(_mm256_andnot_ps(idle, real)) as u32
        }
    }
}

/// How a look's pairs are parted for the pass ([`SelfContacts::resolve`]):
/// those whose particles (the pair's own and its triangle's corners) all
/// lay below a plane across the cloth at the look, those whose all lay
/// above it, and the rest. The first two share no particle, so that a
/// pass may take them on two threads at once, then the rest: the same
/// bits on one thread or two. The plane is across the widest side of the
/// particles' box, through their median. Each block of triangles parts
/// its own pairs, on its thread.
#[derive(Debug, Default, Clone)]
struct PassPlane {
    /// Per particle: below the plane.
    below: Vec<bool>,
    /// The particles' coordinates across the plane (scratch).
    across: Vec<f32>,
}

/// Pairs from which the two parts of a pass run on two threads.
const PARALLEL_MIN_PAIRS: usize = 4096;

impl PassPlane {
    /// The plane through the median of positions `x`.
    fn update(&mut self, x: &[Vector]) {
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
    fn part(
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

/// A particle array as the parts of a pass share it
/// ([`SelfContacts::resolve`]): each part reads and writes only particles
/// no other part running at the same time touches.
struct Points<'a> {
    ptr: *mut Vector,
    len: usize,
    _array: std::marker::PhantomData<&'a mut [Vector]>,
}

impl<'a> Points<'a> {
    /// The array `of`, for one part.
    ///
    /// # Safety
    /// While this lives, no other user of the array touches a particle
    /// this one does.
    unsafe fn new(of: Disjoint<'a, Vector>) -> Points<'a> {
        Points {
            ptr: of.as_ptr(),
            len: of.len(),
            _array: std::marker::PhantomData,
        }
    }
}

impl std::ops::Index<usize> for Points<'_> {
    type Output = Vector;
    #[inline(always)]
    fn index(&self, i: usize) -> &Vector {
        assert!(i < self.len);
        // SAFETY: in bounds; no other part touches particle `i` (`new`).
        unsafe { &*self.ptr.add(i) }
    }
}

impl std::ops::IndexMut<usize> for Points<'_> {
    #[inline(always)]
    fn index_mut(&mut self, i: usize) -> &mut Vector {
        assert!(i < self.len);
        // SAFETY: as for `index`.
        unsafe { &mut *self.ptr.add(i) }
    }
}

/// Triangles a thread takes at a time in a look for pairs (a quarter of
/// 1024: the `fold`'s look, on two threads, 3.40 → 3.35 ms a frame).
const TRIANGLE_BLOCK: usize = 256;

/// Border edges a thread takes at a time in a look for pairs.
const BORDER_BLOCK: usize = 64;

/// The edge pairs a block of border edges or sharp folds found, alone on
/// its cache lines, and its scratch of candidate edges.
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
struct EdgeList(Vec<EdgePair>, Vec<[u32; 2]>);

/// How sharply two triangles meet (the angle between their normals, in
/// radians) for a look to pair their common edge with the other such
/// edges at the particles near its triangles. Between two layers'
/// creases, two edges can pass through each other while their particles
/// each keep the thickness from the other layer's triangles (each of the
/// crossings below had both edges' triangles 60–160° apart): the `stack`
/// (N = 26–38 in cotton, silk and denim, at 50 and 60 Hz: 42 starts)
/// crossed itself in some frame in 16 starts (in 4 still at the end) with
/// only the border's edges paired; in 1 (none at the end) with these. A
/// look that paired every fold's edge over 60°, 45° or 30° with every
/// edge near it (from the hash, as the border's are) crossed in 8 (2), 5
/// (0) and 2 (0) starts, and one pairing every edge with every edge near
/// it in 2 (0), at four times the frame.
const SHARP_FOLD: f32 = 30.0 * std::f32::consts::PI / 180.0;

/// Sharp folds' edges a thread takes at a time in a look for pairs.
const FOLD_BLOCK: usize = 64;

/// The pairs a block of triangles found, alone on its cache lines (blocks
/// on different threads push at once), in triangle order; the candidates
/// of its runs of triangles ([`Look::run`]); and its pairs in the pass's
/// three parts ([`PassPlane`]), with their lanes.
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
struct PairList(Vec<SelfPair>, Candidates, [PartPairs; 3]);

/// The pairs of one block in one part of the pass, and their lanes.
#[derive(Debug, Default, Clone)]
struct PartPairs {
    pairs: Vec<SelfPair>,
    lanes: PairLanes,
}

/// Triangles a look takes together ([`Look::run`]): one scan of the hash
/// over the box around them all.
const RUN: usize = 8;

/// The particles within the box around a run of triangles, in the hash's
/// order, and their positions (m), coordinate by coordinate; all padded to whole
/// vector steps (with `u32::MAX`, and NaN, inside no box).
#[derive(Debug, Default, Clone)]
struct Candidates {
    /// How many there are (before the padding).
    len: usize,
    p: Vec<u32>,
    x: [Vec<f32>; 3],
}

/// Lanes of a vector step over the candidates.
const LANES: usize = 8;

impl Candidates {
    /// The particles of `hash` inside the box `lo..=hi` (m), at positions `x`.
    fn gather(&mut self, hash: &SpatialHash, (lo, hi): (Vector, Vector), x: &[Vector]) {
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
    fn iter(&self) -> impl Iterator<Item = (u32, Vector)> + '_ {
        let [x, y, z] = &self.x;
        (0..self.len).map(move |k| (self.p[k], Vector::new(x[k], y[k], z[k])))
    }
}

/// One look for pairs: the positions and how far to look.
struct Look<'a> {
    x: &'a [Vector],
    /// Where the particles were a substep before (m), for the pairs'
    /// sides; empty: from `x`.
    from: &'a [Vector],
    topology: &'a Topology,
    thickness: f32,
    /// Thickness plus margin, in metres.
    reach: f32,
    margin: f32,
    /// The CPU has AVX2 ([`Look::facing_candidates`]).
    simd: bool,
}

/// A triangle as a look tests particles against it: its corners' indices,
/// first corner `a` and edges `e1`, `e2` (m), unit normal, how far outside
/// each edge a projection is still taken (barycentric, [`rim_slack`]), the
/// particles of its smooth sheet, and the box (m) a particle within reach
/// of it lies in.
struct Facing<'a> {
    t: u32,
    tri: [u32; 3],
    a: Vector,
    e1: Vector,
    e2: Vector,
    n: Vector,
    slack: [f32; 3],
    sheet: Sheet<'a>,
    lo: Vector,
    hi: Vector,
}

impl Look<'_> {
    /// Triangle `t` as the look tests particles against it; none for a
    /// triangle of no area.
    #[inline(always)]
    fn facing<'n>(&self, t: usize, neighbours: &'n MeshNeighbours) -> Option<Facing<'n>> {
        let (x, tri) = (self.x, self.topology.triangles[t]);
        let [a, b, c] = tri.map(|i| x[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let normal = e1.cross(e2);
        let area2 = normal.length();
        if !is_positive(area2) {
            return None;
        }
        let (n, reach) = (normal / area2, self.reach);
        let edges = edge_lengths((e1, e2));
        let rim = rim(self.thickness, edges);
        // A particle may slide `margin` towards the triangle before the next
        // look: accept projections that far outside.
        let slack = rim_slack(self.margin + rim, edges, area2);
        // Particles of the same smooth sheet as the triangle, up to as far as
        // a pair can reach from its corners, are left to the springs.
        let [_, ac, ab] = edges;
        let sheet = neighbours.sheet(tri, reach + rim + ab.max(ac));
        let pad = Vector::splat(reach);
        Some(Facing {
            t: t as u32,
            tri,
            a,
            e1,
            e2,
            n,
            slack,
            sheet,
            lo: a.min(b).min(c) - pad,
            hi: a.max(b).max(c) + pad,
        })
    }

    /// The pair of particle `p` at `xp` (m) with the triangle `f`, if it
    /// lies within reach of it, outside its sheet and not left to the
    /// springs ([`MeshNeighbours::left_to_springs`]).
    #[inline(always)]
    fn pair(
        &self,
        f: &Facing,
        (p, xp): (u32, Vector),
        neighbours: &MeshNeighbours,
    ) -> Option<SelfPair> {
        let d = (xp - f.a).dot(f.n);
        if d.abs() >= self.reach || f.sheet.holds(p) {
            return None;
        }
        let [u, v, w] = barycentric(xp - f.n * d - f.a, f.e1, f.e2);
        let slack = f.slack;
        if u < -slack[0] || v < -slack[1] || w < -slack[2] || neighbours.left_to_springs(p, f.tri) {
            return None;
        }
        Some(SelfPair {
            particle: p,
            triangle: f.t,
            side: self.side_before(f.tri, p).unwrap_or(side_at(d)),
        })
    }

    /// The side (±1) of triangle `tri` particle `p` lay on a substep
    /// before the look, if the look knows where and it lay off the
    /// triangle's plane.
    #[inline]
    fn side_before(&self, tri: [u32; 3], p: u32) -> Option<f32> {
        let from = self.from;
        let [a, b, c] = tri.map(|i| from.get(i as usize).copied());
        let (a, b, c, xp) = (a?, b?, c?, from.get(p as usize).copied()?);
        sign((xp - a).dot((b - a).cross(c - a)))
    }

    /// The side (±1) `edge` lay on from `other` a substep before the look
    /// (by the two lines' orientation, [`closest`]'s normal), if the look
    /// knows where and the lines were neither parallel nor met.
    #[inline]
    fn edge_side_before(&self, edge: [u32; 2], other: [u32; 2]) -> Option<f32> {
        let from = self.from;
        let at = |i: u32| from.get(i as usize).copied();
        let (a, b, p, q) = (at(edge[0])?, at(edge[1])?, at(other[0])?, at(other[1])?);
        sign((a - p).dot((b - a).cross(q - p)))
    }

    /// Pushes the pairs of the triangles `ts` (at most [`RUN`]) that `skip`
    /// does not skip to `out`, in triangle order, each triangle's in
    /// particle order: the particles inside the box around them all
    /// gathered once (`cand`), each then tested against the triangles
    /// whose own box holds it. A run too spread out for one box (a mesh's
    /// triangles in no spatial order) takes a box a triangle.
    fn run(
        &self,
        ts: std::ops::Range<usize>,
        skip: impl Fn(usize) -> bool,
        (hash, neighbours): (&SpatialHash, &MeshNeighbours),
        cand: &mut Candidates,
        out: &mut Vec<SelfPair>,
    ) {
        // Each built in its place (built apart and moved in, a run's
        // triangles were two copies each of a `Facing`).
        let mut faces: [Option<Facing>; RUN] = [const { None }; RUN];
        for (face, t) in faces.iter_mut().zip(ts.clone()) {
            if !skip(t) {
                *face = self.facing(t, neighbours);
            }
        }
        let (mut lo, mut hi) = (Vector::INFINITY, Vector::NEG_INFINITY);
        let mut widest = Vector::ZERO;
        for f in faces.iter().flatten() {
            (lo, hi) = (lo.min(f.lo), hi.max(f.hi));
            widest = widest.max(f.hi - f.lo);
        }
        if !lo.cmple(hi).all() {
            return; // none to look at
        }
        // A grid's row of cells spans RUN / 2 cells along the row: up to
        // that many boxes across one side, about one across the others.
        let together = (hi - lo).cmple(widest * (RUN as f32 / 2.0 + 1.0)).all();
        if together {
            cand.gather(hash, (lo, hi), self.x);
        }
        for f in faces.iter().flatten() {
            if !together {
                cand.gather(hash, (f.lo, f.hi), self.x);
            }
            self.facing_candidates(f, cand, neighbours, out);
        }
    }

    /// Pushes the pairs of the triangle `f` among the candidates `cand`
    /// (those inside its box: [`Look::pair`]) to `out`, in their order.
    fn facing_candidates(
        &self,
        f: &Facing,
        cand: &Candidates,
        neighbours: &MeshNeighbours,
        out: &mut Vec<SelfPair>,
    ) {
        let first = out.len();
        #[cfg(target_arch = "x86_64")]
        let done = self.simd && {
            // SAFETY: `simd` only when the CPU has AVX2.
            unsafe { self.facing_candidates_avx2(f, cand, neighbours, out) };
            true
        };
        #[cfg(not(target_arch = "x86_64"))]
        let done = false;
        if !done {
            for (p, xp) in cand.iter() {
                self.candidate(f, (p, xp), neighbours, out);
            }
        }
        // The hash hands the candidates out by bucket: the triangle's few
        // pairs in particle order, for the same list whatever the table's
        // size (a sort of the run's candidates took longer).
        insertion_sort(&mut out[first..]);
    }

    /// The pair of candidate `p` at `xp` with `f`, pushed to `out`, if it
    /// lies inside the triangle's box and is a pair ([`Look::pair`]).
    #[inline(always)]
    fn candidate(
        &self,
        f: &Facing,
        (p, xp): (u32, Vector),
        neighbours: &MeshNeighbours,
        out: &mut Vec<SelfPair>,
    ) {
        // The hash's own test of its points (ordered: NaN is outside).
        if xp.cmpge(f.lo).all() && xp.cmple(f.hi).all() {
            if let Some(pair) = self.pair(f, (p, xp), neighbours) {
                out.push(pair);
            }
        }
    }

    /// [`Look::facing_candidates`] eight candidates a step: a vector test
    /// lets through every candidate that may be a pair (its box, its
    /// distance from the plane and its projection's barycentrics, each a
    /// hair looser than [`Look::pair`]'s; not a corner), and each of those
    /// then takes [`Look::candidate`]: the same pairs as one at a time.
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn facing_candidates_avx2(
        &self,
        f: &Facing,
        cand: &Candidates,
        neighbours: &MeshNeighbours,
        out: &mut Vec<SelfPair>,
    ) {
        use std::arch::x86_64::*;
        crate::math::align_frame();
        let [cx, cy, cz] = &cand.x;
        let len = cand.len;
        let padded = len.next_multiple_of(LANES);
        assert!(cx.len() == padded && cy.len() == padded && cz.len() == padded);
        assert!(cand.p.len() == padded);
        let splat = _mm256_set1_ps;
        let (lo, hi, a, n) = (f.lo, f.hi, f.a, f.n);
        let (e1, e2) = (f.e1, f.e2);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let denom = d11 * d22 - d12 * d12;
        if !is_positive(denom) {
            return; // every candidate outside (`barycentric`)
        }
        let inv = splat(1.0 / denom);
        // Looser than the exact test: the inverse instead of a division.
        let reach = splat(self.reach * (1.0 + 1.0e-4));
        let slack = f.slack.map(|s| splat(-s - 1.0e-3));
        let corner = f.tri.map(|c| _mm256_set1_epi32(c as i32));
        let abs = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX));
        let one = splat(1.0);
        let mut k = 0;
        while k < len {
            // SAFETY: `k + LANES <= padded`, the arrays' length (asserted).
            let (x, y, z, p) = unsafe {
                (
                    _mm256_loadu_ps(cx.as_ptr().add(k)),
                    _mm256_loadu_ps(cy.as_ptr().add(k)),
                    _mm256_loadu_ps(cz.as_ptr().add(k)),
                    _mm256_loadu_si256(cand.p.as_ptr().add(k) as *const __m256i),
                )
            };
            let within = |v, lo: f32, hi: f32| {
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GE_OQ>(v, splat(lo)),
                    _mm256_cmp_ps::<_CMP_LE_OQ>(v, splat(hi)),
                )
            };
            let boxed = _mm256_and_ps(
                within(x, lo.x, hi.x),
                _mm256_and_ps(within(y, lo.y, hi.y), within(z, lo.z, hi.z)),
            );
            // The offsets from corner a, the distance from the plane.
            let (dx, dy, dz) = (
                _mm256_sub_ps(x, splat(a.x)),
                _mm256_sub_ps(y, splat(a.y)),
                _mm256_sub_ps(z, splat(a.z)),
            );
            let d = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(dx, splat(n.x)), _mm256_mul_ps(dy, splat(n.y))),
                _mm256_mul_ps(dz, splat(n.z)),
            );
            let near = _mm256_cmp_ps::<_CMP_NGE_UQ>(_mm256_and_ps(d, abs), reach);
            // The projection's barycentrics.
            let (qx, qy, qz) = (
                _mm256_sub_ps(dx, _mm256_mul_ps(splat(n.x), d)),
                _mm256_sub_ps(dy, _mm256_mul_ps(splat(n.y), d)),
                _mm256_sub_ps(dz, _mm256_mul_ps(splat(n.z), d)),
            );
            let dot = |e: Vector| {
                _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(qx, splat(e.x)), _mm256_mul_ps(qy, splat(e.y))),
                    _mm256_mul_ps(qz, splat(e.z)),
                )
            };
            let (dq1, dq2) = (dot(e1), dot(e2));
            let vb = _mm256_mul_ps(
                _mm256_sub_ps(
                    _mm256_mul_ps(splat(d22), dq1),
                    _mm256_mul_ps(splat(d12), dq2),
                ),
                inv,
            );
            let w = _mm256_mul_ps(
                _mm256_sub_ps(
                    _mm256_mul_ps(splat(d11), dq2),
                    _mm256_mul_ps(splat(d12), dq1),
                ),
                inv,
            );
            let u = _mm256_sub_ps(_mm256_sub_ps(one, vb), w);
            let inside = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_NLT_UQ>(u, slack[0]),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_NLT_UQ>(vb, slack[1]),
                    _mm256_cmp_ps::<_CMP_NLT_UQ>(w, slack[2]),
                ),
            );
            // Not a corner (the padding is outside every box).
            let corner = _mm256_or_si256(
                _mm256_cmpeq_epi32(p, corner[0]),
                _mm256_or_si256(
                    _mm256_cmpeq_epi32(p, corner[1]),
                    _mm256_cmpeq_epi32(p, corner[2]),
                ),
            );
            let keep = _mm256_andnot_ps(
                _mm256_castsi256_ps(corner),
                _mm256_and_ps(_mm256_and_ps(boxed, near), inside),
            );
            let mut bits = _mm256_movemask_ps(keep) as u32;
            while bits != 0 {
                let j = k + bits.trailing_zeros() as usize;
                let xp = Vector::new(cx[j], cy[j], cz[j]);
                self.candidate(f, (cand.p[j], xp), neighbours, out);
                bits &= bits - 1;
            }
            k += LANES;
        }
    }
}

impl Look<'_> {
    /// Pushes the edges within reach of the border edge `[a, b]` that are
    /// neither its neighbours nor of its smooth sheet (each such pair of
    /// border edges once).
    fn border_edge(
        &self,
        [ia, ib]: [u32; 2],
        (hash, neighbours): (&SpatialHash, &MeshNeighbours),
        out: &mut Vec<EdgePair>,
    ) {
        let x = self.x;
        let (a, b) = (x[ia as usize], x[ib as usize]);
        let u = b - a;
        let length = u.length();
        // An edge within reach has its nearer end within reach plus half
        // its length (this one's length, or 0.625 of the mesh's longest
        // edge as stretched: the edge is at most twice this one, or a
        // quarter over the longest): the box around this edge so padded
        // holds that end, and each edge is taken from it (from its lower
        // end when both are inside). Padded by the whole length, the box
        // held 2.4 times the particles (the border edges were a sixth of
        // the `stack`'s frame).
        let span = length.max(0.625 * neighbours.longest());
        let pad = Vector::splat(self.reach + span);
        let (lo, hi) = (a.min(b) - pad, a.max(b) + pad);
        // The hash's own test of its points (the same positions).
        let inside = |p: Vector| p.cmpge(lo).all() && p.cmple(hi).all();
        let sheet = neighbours.sheet([ia, ib, ib], self.reach + 2.0 * length);
        let borders = neighbours.border_edges();
        let first = out.len();
        // An edge with a point within reach of this one meets the box
        // around this edge padded by the reach (a hair more spares the
        // rounding): most of the edges from the particles in the wider
        // box do not, and skip the closest points (a test of how far each
        // particle lay beyond reach, with a root each, spared fewer: the
        // look of the `stack` 14.7 → 13.4 ms a frame on one thread).
        let near = Vector::splat(self.reach * 1.01);
        let (near_lo, near_hi) = (a.min(b) - near, a.max(b) + near);
        hash.for_each_inside(lo, hi, |e, xe| {
            if sheet.holds(e) || e == ia || e == ib {
                return;
            }
            let ring = neighbours.ring(e);
            for (k, chunk) in ring.chunks(LANES).enumerate() {
                // The edges of the ring whose box meets the near box,
                // eight at a time (a tenth of the `stack`'s frame went to
                // this test one edge at a time).
                let mut meets = self.ring_near(chunk, xe, (near_lo, near_hi), (a, u));
                while meets != 0 {
                    let j = meets.trailing_zeros() as usize;
                    meets &= meets - 1;
                    let f = ring[k * LANES + j];
                    self.border_pair([e, f], (ia, ib, a, u), (&sheet, borders), out, inside);
                }
            }
        });
        // In edge order, whatever the hash's layout.
        out[first..].sort_unstable_by_key(|e| e.other);
    }

    /// The pair of the border edge `[ia, ib]` (from `a`, along `u`) with
    /// the edge from particle `e` to `f`, whose box meets the near box,
    /// pushed to `out` when it lies within reach: each edge once (from its
    /// lower end when both ends are `inside` the look's box), neither the
    /// border edge's neighbour nor of its `sheet`, and two border edges
    /// once.
    #[inline(always)]
    fn border_pair(
        &self,
        [e, f]: [u32; 2],
        (ia, ib, a, u): (u32, u32, Vector, Vector),
        (sheet, borders): (&Sheet, &[[u32; 2]]),
        out: &mut Vec<EdgePair>,
        inside: impl Fn(Vector) -> bool,
    ) {
        let x = self.x;
        let xf = x[f as usize];
        if f < e && inside(xf) {
            return;
        }
        if f == ia || f == ib || sheet.holds(f) {
            return;
        }
        let (p, q) = (e.min(f), e.max(f));
        // Two border edges meet from both sides: keep the lower one's.
        if [p, q] < [ia, ib] && borders.binary_search(&[p, q]).is_ok() {
            return;
        }
        let (xp, xq) = (x[p as usize], x[q as usize]);
        out.extend(self.within_reach(([ia, ib], a, u), ([p, q], xp, xq - xp)));
    }

    /// The pair of `edge` (from `a` along `u`, m) and `other` (from `p`
    /// along `v`) when their closest points lie inside both and within
    /// reach, with the side `edge` lies on.
    #[inline(always)]
    fn within_reach(
        &self,
        (edge, a, u): ([u32; 2], Vector, Vector),
        (other, p, v): ([u32; 2], Vector, Vector),
    ) -> Option<EdgePair> {
        let (s, t, n) = closest(a, u, p, v)?;
        let gap = (a + u * s - p - v * t).dot(n);
        (gap.abs() < self.reach).then(|| EdgePair {
            edge,
            other,
            side: self.edge_side_before(edge, other).unwrap_or(side_at(gap)),
        })
    }

    /// The pair of a sharp fold's `edge` with another fold's edge `other`,
    /// pushed to `out` (the lower edge first) when their closest points
    /// lie within reach: sharing no particle with the fold's edge, and not
    /// of its smooth `sheet` (as far as a pair reaches plus twice its
    /// length).
    #[inline]
    fn fold_pair(&self, edge: [u32; 2], other: [u32; 2], sheet: &Sheet, out: &mut Vec<EdgePair>) {
        if other.iter().any(|p| edge.contains(p) || sheet.holds(*p)) {
            return;
        }
        let x = self.x;
        let (first, second) = if edge <= other {
            (edge, other)
        } else {
            (other, edge)
        };
        let [a, b] = first.map(|i| x[i as usize]);
        let [p, q] = second.map(|i| x[i as usize]);
        out.extend(self.within_reach((first, a, b - a), (second, p, q - p)));
    }

    /// Which of the edges from `xe` to the particles `ends` (at most
    /// [`LANES`]) have a box that meets the box `near`, as bits (bit `j`
    /// for `ends[j]`): `min(xe, xf) <= hi` and `max(xe, xf) >= lo`, the
    /// floats of one edge at a time. Where the CPU has AVX2, those too
    /// that [`Self::border_pair`] would find apart from the border edge
    /// from `a` along `u` (m) are left out.
    #[inline(always)]
    fn ring_near(
        &self,
        ends: &[u32],
        xe: Vector,
        (lo, hi): (Vector, Vector),
        (a, u): (Vector, Vector),
    ) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.simd && xe.is_finite() && ends.len() <= LANES {
            // SAFETY: `simd` only when the CPU has AVX2; the ends are
            // particles (a ring's).
            return unsafe { self.ring_near_avx2(ends, xe, (lo, hi), (a, u)) };
        }
        let _ = (a, u);
        let x = self.x;
        let mut bits = 0;
        for (j, &f) in ends.iter().enumerate() {
            let xf = x[f as usize];
            if xe.min(xf).cmple(hi).all() && xe.max(xf).cmpge(lo).all() {
                bits |= 1 << j;
            }
        }
        bits
    }

    /// [`Self::ring_near`] in AVX2, for a finite `xe`: `min(xf, xe)` takes
    /// `xe` where `xf` is not a number, as `f32::min(xe, xf)` does (and
    /// `max` likewise). Then the test of [`closest`] and of the gap that
    /// [`Self::border_pair`] makes of each edge against the border edge
    /// from `a` along `u`, each a hair looser (with the inverse square
    /// root's and reciprocal's relative error under 3.7e-4): an edge it
    /// leaves out, `border_pair` would too. Of the `stack`'s edges whose
    /// box met the near box, 30 a border edge for half a pair; the
    /// closest points of each made most of the border edges' time.
    ///
    /// # Safety
    /// The CPU has AVX2; every end is below `self.x.len()`; at most
    /// [`LANES`] ends.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn ring_near_avx2(
        &self,
        ends: &[u32],
        xe: Vector,
        (lo, hi): (Vector, Vector),
        (a, u): (Vector, Vector),
    ) -> u32 {
        use std::arch::x86_64::*;
        let x = self.x;
        assert!(ends.len() <= LANES && ends.iter().all(|&f| (f as usize) < x.len()));
        // The ends' points (the lanes past them repeat the first).
        let end = |l: usize| ends.get(l).or(ends.first()).map_or(0, |&f| f as usize);
        // SAFETY: each end below `x.len()` (asserted).
        let f = unsafe { load_vectors(x.as_ptr() as *const f32, std::array::from_fn(end)) };
        let (e, lo, hi) = (xe.to_array(), lo.to_array(), hi.to_array());
        let mut meets = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
        for c in 0..3 {
            let e = _mm256_set1_ps(e[c]);
            let (least, most) = (_mm256_min_ps(f[c], e), _mm256_max_ps(f[c], e));
            meets = _mm256_and_ps(
                meets,
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_LE_OQ>(least, _mm256_set1_ps(hi[c])),
                    _mm256_cmp_ps::<_CMP_GE_OQ>(most, _mm256_set1_ps(lo[c])),
                ),
            );
        }
        let real = (1u32 << ends.len()) - 1;
        let boxed = _mm256_movemask_ps(meets) as u32 & real;
        if boxed == 0 {
            return 0;
        }
        // The edge from `xe` along `v = xf − xe` against `a + s u`
        // (`closest` with the edge the other way round: the same cross
        // product but for its sign, `s` and `1 − t`, the same gap's size).
        let splat = |r: f32| _mm256_set1_ps(r);
        let m = |p, q| _mm256_mul_ps(p, q);
        let sub = |p, q| _mm256_sub_ps(p, q);
        let v = [0, 1, 2].map(|c| sub(f[c], splat(e[c])));
        let (u, w) = (u.to_array().map(splat), (a - xe).to_array().map(splat));
        let dot = |p: [__m256; 3], q: [__m256; 3]| dot_lanes(p, q);
        let cross = cross_lanes(u, v);
        let len2 = dot(cross, cross);
        let (uu, uv, vv, uw, vw) = (dot(u, u), dot(u, v), dot(v, v), dot(u, w), dot(v, w));
        let tol = 1.0e-3;
        // Near parallel: `closest` finds none (looser: a hair more kept).
        let parallel = _mm256_cmp_ps::<_CMP_LT_OQ>(len2, m(splat(0.01 * (1.0 - tol)), m(uu, vv)));
        let denom = sub(m(uu, vv), m(uv, uv));
        let inv = _mm256_rcp_ps(denom);
        let s = m(sub(m(uv, vw), m(vv, uw)), inv);
        let t = m(sub(m(uu, vw), m(uv, uw)), inv);
        let (lt, gt) = (
            |p, q| _mm256_cmp_ps::<_CMP_LT_OQ>(p, q),
            |p, q| _mm256_cmp_ps::<_CMP_GT_OQ>(p, q),
        );
        let outside = |r| _mm256_or_ps(lt(r, splat(-tol)), gt(r, splat(1.0 + tol)));
        // |gap| = |w · cross| / |cross| at or past the reach.
        let gap = _mm256_andnot_ps(splat(-0.0), m(dot(w, cross), _mm256_rsqrt_ps(len2)));
        let apart = _mm256_cmp_ps::<_CMP_GE_OQ>(gap, splat(self.reach * (1.0 + tol)));
        let idle = _mm256_or_ps(
            _mm256_or_ps(parallel, apart),
            _mm256_or_ps(outside(s), outside(t)),
        );
        boxed & !(_mm256_movemask_ps(idle) as u32)
    }
}

/// Where two segments `a + s u` and `p + t v` come closest, when that is
/// inside both (`0 < s, t < 1`) and they are not near parallel: `(s, t)`
/// and the unit normal `u × v / |u × v|`.
#[inline]
fn closest(a: Vector, u: Vector, p: Vector, v: Vector) -> Option<(f32, f32, Vector)> {
    let cross = u.cross(v);
    let len2 = cross.length_squared();
    // Within about 6° of parallel the faces' pairs take over.
    if !is_positive(len2 - 0.01 * u.length_squared() * v.length_squared()) {
        return None;
    }
    let w = a - p;
    let (uu, uv, vv, uw, vw) = (u.dot(u), u.dot(v), v.dot(v), u.dot(w), v.dot(w));
    let denom = uu * vv - uv * uv;
    let s = (uv * vw - vv * uw) / denom;
    let t = (uu * vw - uv * uw) / denom;
    let inside = |r: f32| r > 0.0 && r < 1.0;
    (inside(s) && inside(t)).then(|| (s, t, cross / len2.sqrt()))
}

/// What a self-collision pass works with.
pub(crate) struct SelfContactParams {
    /// Distance layers keep, in metres.
    pub thickness: f32,
    /// Coulomb friction between layers.
    pub friction: f32,
    /// The substep, in seconds.
    pub h: f32,
}

/// What a step's looks go by: the cloth's `topology` of `particles`, its
/// `revision` (`Cloth::mass_revision`, which changes with its topology),
/// the layers' `thickness` and the `margin` (m).
pub(crate) struct LookBasis<'a> {
    pub topology: &'a Topology,
    pub particles: usize,
    pub revision: u64,
    pub thickness: f32,
    pub margin: f32,
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

    /// Finds the particles within reach of triangles they are not
    /// neighbours of, at positions `x`: blocks of triangles on the `team`,
    /// their pairs then joined in triangle order (the same list on any
    /// number of threads).
    fn find_pairs(
        &mut self,
        (x, from): (&[Vector], &[Vector]),
        topology: &Topology,
        thickness: f32,
        team: Team,
    ) {
        (self.pairs, self.used_blocks) = (0, 0);
        self.edge_pairs.clear();
        // For the test of the motions: the look's longest edge, and the
        // ends of the edges it may pair (none yet: every particle counts
        // as one).
        self.longest_edge = self.neighbours.longest_at(x);
        self.edge_ends.clear();
        let triangles = &topology.triangles;
        if triangles.is_empty() {
            return;
        }
        let simd = simd_available() && !self.portable;
        let look = Look {
            x,
            from: if from.len() == x.len() { from } else { &[] },
            topology,
            thickness,
            reach: thickness + self.margin,
            margin: self.margin,
            simd,
        };
        // Cells about twice a triangle's width or the reach: a triangle's
        // box meets a few (drape N = 64: 8% faster a frame than cells of
        // one width, 6% than three).
        let longest = self.neighbours.longest();
        self.hash
            .build(x, 2.0 * longest.max(look.reach).max(1.0e-4));
        self.patches
            .update(x, topology.grid_pieces(), triangles, look.reach);
        let blocks = triangles.len().div_ceil(TRIANGLE_BLOCK);
        if self.blocks.len() < blocks {
            self.blocks.resize_with(blocks, PairList::default);
        }
        let borders = self.neighbours.border_edges();
        let border_blocks = borders.len().div_ceil(BORDER_BLOCK);
        if self.border_blocks.len() < border_blocks {
            self.border_blocks
                .resize_with(border_blocks, EdgeList::default);
        }
        self.plane.update(x);
        self.triangle_pairs.resize(triangles.len(), [0, 0]);
        self.normals.resize(triangles.len(), Vector::ZERO);
        let (hash, neighbours, patches) = (&self.hash, &self.neighbours, &self.patches);
        let plane = &self.plane;
        let ranges = Disjoint::new(&mut self.triangle_pairs[..]);
        let normals = Disjoint::new(&mut self.normals[..]);
        let lists = Disjoint::new(&mut self.blocks[..blocks]);
        let edge_lists = Disjoint::new(&mut self.border_blocks[..border_blocks]);
        // The triangles' blocks, then the border edges' (serial, they
        // were a tenth of the `fold`'s frame), in one handout.
        let found = team.sum_count_uneven(blocks + border_blocks, |k| {
            if k >= blocks {
                let e = k - blocks;
                // SAFETY: block `e` alone uses edge list `e`.
                let EdgeList(list, _) = unsafe { &mut edge_lists.range(e..e + 1)[0] };
                list.clear();
                let end = ((e + 1) * BORDER_BLOCK).min(borders.len());
                for &border in &borders[e * BORDER_BLOCK..end] {
                    if !border.iter().all(|&p| patches.quiet_particle(p as usize)) {
                        look.border_edge(border, (hash, neighbours), list);
                    }
                }
                return 0;
            }
            // SAFETY: block `k` alone uses list `k`.
            let PairList(list, candidates, parts) = unsafe { &mut lists.range(k..k + 1)[0] };
            list.clear();
            let end = ((k + 1) * TRIANGLE_BLOCK).min(triangles.len());
            // A run at a time: a grid's triangles of a few cells along a
            // row (and a mesh's neighbours, mostly) share most of their
            // box, whose scan of the hash is then paid once.
            for t in (k * TRIANGLE_BLOCK..end).step_by(RUN) {
                let run = t..(t + RUN).min(end);
                let quiet = |t| patches.quiet_triangle(t);
                look.run(run, quiet, (hash, neighbours), candidates, list);
            }
            // Where each triangle's pairs lie in the list (for the sharp
            // folds' edges).
            // SAFETY: block `k` alone writes its triangles' ranges.
            let ranges = unsafe { ranges.range(k * TRIANGLE_BLOCK..end) };
            ranges.fill([0, 0]);
            let mut start = 0;
            for run in list.chunk_by(|a, b| a.triangle == b.triangle) {
                let t = run[0].triangle as usize - k * TRIANGLE_BLOCK;
                ranges[t] = [start as u32, (start + run.len()) as u32];
                start += run.len();
            }
            // Its triangles' unit normals (for the sharp folds).
            // SAFETY: block `k` alone writes its triangles' normals.
            let normals = unsafe { normals.range(k * TRIANGLE_BLOCK..end) };
            for (n, tri) in normals.iter_mut().zip(&triangles[k * TRIANGLE_BLOCK..end]) {
                let [a, b, c] = tri.map(|i| x[i as usize]);
                *n = (b - a).cross(c - a).normalize_or_zero();
            }
            // The block's pairs in the pass's parts, on its own thread.
            plane.part(list, (triangles, x.len()), simd, parts);
            headroom(list);
            list.len() as u32
        }) as usize;
        (self.pairs, self.used_blocks) = (found, blocks);
        self.edge_pairs.clear();
        for list in &mut self.border_blocks[..border_blocks] {
            self.edge_pairs.extend_from_slice(&list.0);
            headroom(&mut list.0);
        }
        let first_fold = self.edge_pairs.len();
        self.find_folds(x.len());
        // The ends of the edges this look may pair: the border's and the
        // sharp folds'.
        self.edge_ends.clone_from(&self.on_fold);
        for &border in self.neighbours.border_edges() {
            for p in border {
                if let Some(end) = self.edge_ends.get_mut(p as usize) {
                    *end = true;
                }
            }
        }
        self.pair_folds(&look, team);
        let fold_blocks = self.folds.len().div_ceil(FOLD_BLOCK);
        for list in &mut self.fold_blocks[..fold_blocks] {
            self.edge_pairs.extend_from_slice(&list.0);
            headroom(&mut list.0);
        }
        // Two folds' edges near each other are found from both: once, in
        // the order of their edges whatever the blocks. (The border's
        // pairs before them are each found once: the dedup leaves them.)
        self.edge_pairs[first_fold..].sort_unstable_by_key(|e| (e.edge, e.other));
        self.edge_pairs.dedup_by_key(|e| (e.edge, e.other));
        headroom(&mut self.edge_pairs);
    }

    /// The sharp folds' edges of the look ([`SHARP_FOLD`]), from the
    /// triangles' normals it found: the edges between two triangles whose
    /// normals lie further apart (or one of no area), as indices into
    /// [`MeshNeighbours::inner_edges`], and which edges and which of the
    /// `particles` they are.
    fn find_folds(&mut self, particles: usize) {
        let cos = SHARP_FOLD.cos();
        let normals = &self.normals;
        let normal = |t: u32| normals.get(t as usize).copied().unwrap_or(Vector::ZERO);
        let (inner, faces) = self.neighbours.inner_edges();
        self.folds.clear();
        self.folds.extend(
            (0..faces.len() as u32)
                // At or below: a triangle of no area (its normal zero) counts
                // as sharp.
                .filter(|&k| {
                    let [t0, t1] = faces[k as usize];
                    let between = normal(t0).dot(normal(t1));
                    between.is_nan() || between <= cos
                }),
        );
        self.sharp.clear();
        self.sharp.resize(self.neighbours.edge_count(), false);
        self.on_fold.clear();
        self.on_fold.resize(particles, false);
        for &k in &self.folds {
            let edge = inner[k as usize];
            if let Some(e) = self.neighbours.edge_index(edge) {
                self.sharp[e] = true;
                for p in edge {
                    self.on_fold[p as usize] = true;
                }
            }
        }
    }

    /// Pairs each sharp fold's edge ([`Self::find_folds`]) with the other
    /// folds' edges at the particles the `look` paired with its two
    /// triangles (blocks of folds on the `team`): each pair of edges with
    /// the lower first.
    fn pair_folds(&mut self, look: &Look, team: Team) {
        let blocks = self.folds.len().div_ceil(FOLD_BLOCK);
        if self.fold_blocks.len() < blocks {
            self.fold_blocks.resize_with(blocks, EdgeList::default);
        }
        let (inner, faces) = self.neighbours.inner_edges();
        let (neighbours, patches) = (&self.neighbours, &self.patches);
        let (folds, pairs, ranges) = (&self.folds, &self.blocks, &self.triangle_pairs);
        let (sharp, on_fold) = (&self.sharp, &self.on_fold);
        let on_fold = |p: u32| on_fold.get(p as usize).copied().unwrap_or(false);
        let is_fold = |e: [u32; 2]| neighbours.edge_index(e).is_some_and(|e| sharp[e]);
        let lists = Disjoint::new(&mut self.fold_blocks[..blocks]);
        team.sum_count_uneven(blocks, |k| {
            // SAFETY: block `k` alone uses list `k`.
            let EdgeList(list, candidates) = unsafe { &mut lists.range(k..k + 1)[0] };
            list.clear();
            let end = ((k + 1) * FOLD_BLOCK).min(folds.len());
            for &fold in &folds[k * FOLD_BLOCK..end] {
                let edge = inner[fold as usize];
                if edge.iter().all(|&p| patches.quiet_particle(p as usize)) {
                    continue;
                }
                candidates.clear();
                for t in faces[fold as usize] {
                    let (block, [start, stop]) = (t as usize / TRIANGLE_BLOCK, ranges[t as usize]);
                    let near = &pairs[block].0[start as usize..stop as usize];
                    for p in near
                        .iter()
                        .map(|pair| pair.particle)
                        .filter(|&p| on_fold(p))
                    {
                        let ring = neighbours.ring(p).iter().filter(|&&q| on_fold(q));
                        let edges = ring.map(|&q| [p.min(q), p.max(q)]);
                        candidates.extend(edges.filter(|&e| is_fold(e)));
                    }
                }
                candidates.sort_unstable();
                candidates.dedup();
                let x = look.x;
                let length = (x[edge[1] as usize] - x[edge[0] as usize]).length();
                let sheet =
                    neighbours.sheet([edge[0], edge[1], edge[1]], look.reach + 2.0 * length);
                for &other in candidates.iter() {
                    look.fold_pair(edge, other, &sheet, list);
                }
            }
            0
        });
    }

    /// The pairs of the last look's blocks, in the pass's `part`.
    fn part_blocks(&self, part: usize) -> impl Iterator<Item = &PartPairs> + '_ {
        self.blocks[..self.used_blocks]
            .iter()
            .map(move |b| &b.2[part])
    }

    /// One pass over the pairs (module docs), its two parts on the
    /// `team` ([`PassPlane`]); returns how many were closer than the
    /// thickness.
    pub(crate) fn resolve(
        &self,
        particles: &mut Particles,
        topology: &Topology,
        params: &SelfContactParams,
        team: Team,
    ) -> u32 {
        let Particles { x, v, inv_mass, .. } = particles;
        let thickness = params.thickness;
        let mut touching = {
            let (xs, vs) = (Disjoint::new(&mut x[..]), Disjoint::new(&mut v[..]));
            let part = |k: usize| {
                // SAFETY: parts 0 and 1 share no particle, and part 2 runs
                // after both.
                let (mut x, mut v) = unsafe { (Points::new(xs), Points::new(vs)) };
                self.part_pass(k, (&mut x, &mut v, inv_mass), (topology, params))
            };
            let team = team.for_work(self.pairs, PARALLEL_MIN_PAIRS);
            team.sum_count(2, part) + part(2)
        };
        for pair in &self.edge_pairs {
            let ([ia, ib], [ip, iq]) = (
                pair.edge.map(|i| i as usize),
                pair.other.map(|i| i as usize),
            );
            let (a, b, p, q) = (x[ia], x[ib], x[ip], x[iq]);
            let Some((s, t, n)) = closest(a, b - a, p, q - p) else {
                continue;
            };
            let n = n * pair.side;
            let gap = (a + (b - a) * s - p - (q - p) * t).dot(n);
            // As for faces: apart, or turned away since the look.
            if gap >= thickness || gap < -(thickness + self.margin) {
                continue;
            }
            let shares = [1.0 - s, s, 1.0 - t, t];
            let w = [ia, ib, ip, iq].map(|i| inv_mass[i]);
            let weight: f32 = (0..4).map(|k| w[k] * shares[k] * shares[k]).sum();
            if !is_positive(weight) {
                continue;
            }
            touching += 1;
            let depth = (thickness - gap).min(0.5 * thickness);
            let lambda = depth / weight;
            // The first edge's side moves along n, the other edge's against it.
            let signs = [1.0, 1.0, -1.0, -1.0];
            for (k, i) in [ia, ib, ip, iq].into_iter().enumerate() {
                x[i] += n * (signs[k] * w[k] * shares[k] * lambda);
            }
            let rel =
                (v[ia] * shares[0] + v[ib] * shares[1]) - (v[ip] * shares[2] + v[iq] * shares[3]);
            let closing = (-rel.dot(n)).max(0.0) / weight;
            for (k, i) in [ia, ib, ip, iq].into_iter().enumerate() {
                v[i] += n * (signs[k] * w[k] * shares[k] * closing);
            }
        }
        touching
    }

    /// The pass over part `k` of the pairs ([`PassPlane`]); returns how
    /// many were closer than the thickness.
    fn part_pass(
        &self,
        k: usize,
        (x, v, inv_mass): (&mut Points, &mut Points, &[f32]),
        (topology, params): (&Topology, &SelfContactParams),
    ) -> u32 {
        self.part_blocks(k)
            .map(|part| self.block_pass(part, (x, v, inv_mass), (topology, params)))
            .sum()
    }

    /// The pass over one block's pairs of a part; returns how many were
    /// closer than the thickness.
    fn block_pass(
        &self,
        part: &PartPairs,
        (x, v, inv_mass): (&mut Points, &mut Points, &[f32]),
        (topology, params): (&Topology, &SelfContactParams),
    ) -> u32 {
        let (pairs, lanes) = (&part.pairs, &part.lanes);
        let mut touching = 0;
        // The pairs come by triangle (a block's, in triangle order): what
        // depends on the triangle alone is found once for its run of
        // pairs, and found again after any pair moved a particle (it may
        // have moved a corner). The same values as a pair's own: the same
        // expressions of the same positions.
        let mut near: Option<Near> = None;
        let n = pairs.len();
        let layers = (params.thickness, self.margin);
        if lanes.usable(n, x.len) {
            // Eight pairs at a time: a vector test finds those the pass
            // may act on, and each of them takes the pass in turn; the
            // others would change nothing and are passed over. A pair
            // that moved particles may have moved those of the pairs
            // after it: they are tested again from the new positions.
            // The bits of the pass one pair at a time.
            for k in (0..n).step_by(LANES) {
                let mut bits = lanes.busy(k, x, layers);
                while bits != 0 {
                    let j = bits.trailing_zeros() as usize;
                    let moved = self.pair_pass(
                        &pairs[k + j],
                        &mut near,
                        (x, v, inv_mass),
                        (topology, params),
                    );
                    touching += moved;
                    // The lanes after `j`.
                    let after = !((2u32 << j) - 1);
                    bits = if moved > 0 {
                        lanes.busy(k, x, layers) & after
                    } else {
                        bits & after
                    };
                }
            }
        } else {
            for pair in pairs {
                touching += self.pair_pass(pair, &mut near, (x, v, inv_mass), (topology, params));
            }
        }
        touching
    }

    /// The pass of one pair (module docs), with the triangle's values of
    /// `near` when it is that pair's triangle (else found again there);
    /// returns 1 when the pair was closer than the thickness, else 0.
    #[inline(always)]
    fn pair_pass(
        &self,
        pair: &SelfPair,
        near: &mut Option<Near>,
        (x, v, inv_mass): (&mut Points, &mut Points, &[f32]),
        (topology, params): (&Topology, &SelfContactParams),
    ) -> u32 {
        let SelfContactParams {
            thickness,
            friction,
            h,
        } = *params;
        let f = match near {
            Some(f) if f.t == pair.triangle => f,
            _ => {
                let Some(&tri) = topology.triangles.get(pair.triangle as usize) else {
                    return 0;
                };
                near.insert(Near::of(pair.triangle, tri, x))
            }
        };
        let [ia, ib, ic] = f.tri;
        let ip = pair.particle as usize;
        let (a, xp, normal, len2) = (f.a, x[ip], f.normal, f.len2);
        // Surely further than the thickness out on its side, told
        // without the root and the division (most pairs of layers at
        // rest; a fifth of the `stack`'s frame went to this pass). A
        // hair of margin: a pair near the thickness takes the exact
        // test below, so the pass keeps its bits.
        let out = (xp - a).dot(normal) * pair.side;
        if out > 0.0 && out * out > thickness * thickness * len2 * (1.0 + 1.0e-4) {
            return 0;
        }
        let Some((len, slack)) = f.rim_slack(thickness) else {
            return 0;
        };
        let (e1, e2) = (f.e1, f.e2);
        let n = normal * (pair.side / len);
        let d = (xp - a).dot(n);
        if d >= thickness {
            return 0;
        }
        // Further on the other side than particles can have moved since
        // the look (the margin): not a crossing but a pair the cloth has
        // turned away from (a fold, a swing).
        if d < -(thickness + self.margin) {
            return 0;
        }
        let bary = barycentric(xp - n * d - a, e1, e2);
        if (0..3).any(|k| bary[k] < -slack[k]) {
            return 0;
        }
        // Just outside the rim, the nearest point of the edge takes it.
        let [u, vb, w] = clamped(bary);
        let [wp, wa, wb, wc] = [ip, ia, ib, ic].map(|i| inv_mass[i]);
        let weight = wp + wa * u * u + wb * vb * vb + wc * w * w;
        if !is_positive(weight) {
            return 0;
        }
        // Positions: out to the thickness along n.
        // At most half the thickness a pass: a layer pressed from both
        // sides (a crumpled fold) is eased apart over a few substeps,
        // not yanked by contradicting pairs.
        let depth = (thickness - d).min(0.5 * thickness);
        let s = depth / weight;
        x[ip] += n * (wp * s);
        x[ia] -= n * (wa * u * s);
        x[ib] -= n * (wb * vb * s);
        x[ic] -= n * (wc * w * s);
        // Velocities: no closing, then friction on the sliding part.
        let surface = v[ia] * u + v[ib] * vb + v[ic] * w;
        let rel = v[ip] - surface;
        let vn = rel.dot(n);
        let closing = (-vn).max(0.0);
        let slide = rel - n * vn;
        let speed = slide.length();
        let grip = friction * (closing + depth / h);
        let slide_change = if speed > 0.0 {
            slide * -(grip / speed).min(1.0)
        } else {
            Vector::ZERO
        };
        // The change of relative velocity `dv` takes an impulse `dv / weight`
        // (per unit inverse mass), shared as the positions were.
        let j = (n * closing + slide_change) / weight;
        v[ip] += j * wp;
        v[ia] -= j * (wa * u);
        v[ib] -= j * (wb * vb);
        v[ic] -= j * (wc * w);
        // Positions moved: the next pair finds its triangle afresh.
        *near = None;
        1
    }
}

/// A triangle as [`SelfContacts::resolve`] tests its run of pairs: its
/// corners, first corner `a` and edges `e1`, `e2` (m), `e1 × e2` and its
/// squared length, and, once a pair needs them, its length and the rim's
/// slack ([`rim_slack`]).
struct Near {
    t: u32,
    tri: [usize; 3],
    a: Vector,
    e1: Vector,
    e2: Vector,
    normal: Vector,
    len2: f32,
    slack: Option<Option<(f32, [f32; 3])>>,
}

impl Near {
    /// Triangle `t` with corners `tri` at positions `x`.
    #[inline]
    fn of(t: u32, tri: [u32; 3], x: &impl std::ops::Index<usize, Output = Vector>) -> Near {
        let tri = tri.map(|i| i as usize);
        let [a, b, c] = tri.map(|i| x[i]);
        let (e1, e2) = (b - a, c - a);
        let normal = e1.cross(e2);
        Near {
            t,
            tri,
            a,
            e1,
            e2,
            normal,
            len2: normal.length_squared(),
            slack: None,
        }
    }

    /// `|e1 × e2|` and the rim's slack for layers `thickness` thick (m);
    /// none for a triangle of no area. Found at the first call.
    #[inline]
    fn rim_slack(&mut self, thickness: f32) -> Option<(f32, [f32; 3])> {
        *self.slack.get_or_insert_with(|| {
            let len = self.len2.sqrt();
            let edges = edge_lengths((self.e1, self.e2));
            is_positive(len).then(|| (len, rim_slack(rim(thickness, edges), edges, len)))
        })
    }
}

/// The lengths (m) of a triangle's edges opposite its corners a, b and c,
/// from its edges `e1 = b − a` and `e2 = c − a`: `|e2 − e1|`, `|e2|`,
/// `|e1|` (three roots a triangle, shared by [`rim`], [`rim_slack`] and a
/// look's sheet).
#[inline]
fn edge_lengths((e1, e2): (Vector, Vector)) -> [f32; 3] {
    [(e2 - e1).length(), e2.length(), e1.length()]
}

/// How far outside each edge of a triangle a particle is still taken, in
/// barycentric terms (`[u, v, w]` may go that far below 0): `out` metres
/// beyond every edge, over the altitude onto that edge. Where the cloth
/// bends, the projections of a particle near the common edge may fall
/// outside both triangles (a gap a particle slipped through in the `fold`
/// scene); a rim closes it. `len` is `|e1 × e2|`, twice the area, and
/// `edges` the edges' lengths ([`edge_lengths`]).
#[inline]
fn rim_slack(out: f32, edges: [f32; 3], len: f32) -> [f32; 3] {
    // The altitude onto an edge is `len / |edge|`; u belongs to corner a,
    // whose opposite edge is `e2 − e1`.
    edges.map(|edge| out * edge / len)
}

/// The rim of a triangle (m): the thickness, but at most a quarter of its
/// shortest edge, so that the particles beyond the rest-mesh neighbours of
/// a flat cloth never fall within it. `edges` are the edges' lengths
/// ([`edge_lengths`]; the least of the roots is the root of the least
/// square, to the bit, roots being rounded correctly).
#[inline]
fn rim(thickness: f32, [bc, ac, ab]: [f32; 3]) -> f32 {
    thickness.min(0.25 * ab.min(ac).min(bc))
}

/// Barycentric coordinates clamped to the triangle and summing to one.
#[inline]
fn clamped([u, v, w]: [f32; 3]) -> [f32; 3] {
    let [u, v, w] = [u.max(0.0), v.max(0.0), w.max(0.0)];
    let sum = u + v + w;
    [u / sum, v / sum, w / sum]
}

/// Sorts a few pairs by particle (the pairs of one triangle: a handful).
fn insertion_sort(pairs: &mut [SelfPair]) {
    for i in 1..pairs.len() {
        let mut j = i;
        while j > 0 && pairs[j - 1].particle > pairs[j].particle {
            pairs.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// Makes room for twice the list's length, so that a step whose pairs
/// grow by less than that allocates nothing (a warmed-up step allocates
/// only when the contacts more than double).
/// The box (m) around the motions `x − at` of every particle; none where
/// one is not finite. Where the CPU has AVX2, eight particles' 24
/// coordinates at a time, each register's lanes of fixed axes (the due
/// test, run every substep, was 3% of the `fold`'s instructions).
fn motion_box(x: &[Vector], at: &[Vector]) -> Option<(Vector, Vector)> {
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
unsafe fn motion_box_avx2(x: &[Vector], at: &[Vector]) -> Option<(usize, Vector, Vector)> {
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

fn headroom<T>(list: &mut Vec<T>) {
    if list.capacity() < 2 * list.len() {
        list.reserve(list.len());
    }
}

/// True for a number > 0 (false for NaN).
#[inline]
pub(crate) fn is_positive(x: f32) -> bool {
    x > 0.0
}

/// The side (±1) of a pair found at signed distance `d` (m), when the
/// look does not know where it lay a substep before (or it lay in the
/// plane): the distance's, +1 at zero.
#[inline]
fn side_at(d: f32) -> f32 {
    if d >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// +1 or −1 by the sign of `x`; none for zero or not a number.
#[inline]
fn sign(x: f32) -> Option<f32> {
    if x > 0.0 {
        Some(1.0)
    } else if x < 0.0 {
        Some(-1.0)
    } else {
        None
    }
}

/// Barycentric coordinates `[u, v, w]` (weights of the corners a, b, c) of
/// the point `a + q` in the plane of the triangle with edges `e1 = b − a`
/// and `e2 = c − a`; a degenerate triangle gives a point outside (−1).
#[inline]
pub(crate) fn barycentric(q: Vector, e1: Vector, e2: Vector) -> [f32; 3] {
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dq1, dq2) = (q.dot(e1), q.dot(e2));
    let denom = d11 * d22 - d12 * d12;
    if !is_positive(denom) {
        return [-1.0; 3];
    }
    let vb = (d22 * dq1 - d12 * dq2) / denom;
    let w = (d11 * dq2 - d12 * dq1) / denom;
    [1.0 - vb - w, vb, w]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    impl SelfContacts {
        /// Every pair of the last look, in triangle order.
        fn all_pairs(&self) -> Vec<SelfPair> {
            let blocks = &self.blocks[..self.used_blocks];
            let pairs: Vec<SelfPair> = blocks.iter().flat_map(|b| b.0.clone()).collect();
            assert_eq!(pairs.len(), self.pairs);
            pairs
        }
    }

    /// The box around 21 motions (two vector steps and a tail) is the
    /// least and greatest of each coordinate; a motion that is not finite,
    /// in a vector step or in the tail, gives none.
    #[test]
    fn the_box_around_the_motions_holds_each_and_none_for_a_lost_particle() {
        let f = |s: f32| -> Vec<Vector> {
            (0..21)
                .map(|i| {
                    let t = (i as f32 + s) * 0.731;
                    Vector::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin() * 3.0)
                })
                .collect()
        };
        let (x, at) = (f(0.0), f(5.0));
        let d: Vec<Vector> = x.iter().zip(&at).map(|(&x, &at)| x - at).collect();
        let lo = d.iter().fold(Vector::INFINITY, |l, &d| l.min(d));
        let hi = d.iter().fold(Vector::NEG_INFINITY, |h, &d| h.max(d));
        assert_eq!(motion_box(&x, &at), Some((lo, hi)));
        // Each coordinate's extremes where they are, in the steps or the tail.
        for (k, a) in [(2, 0), (12, 1), (19, 2), (7, 2)] {
            let mut y = x.clone();
            y[k][a] += 100.0;
            let (_, high) = motion_box(&y, &at).unwrap();
            assert_eq!(high[a], d[k][a] + 100.0, "particle {k}, axis {a}");
            y[k][a] -= 200.0;
            let (low, _) = motion_box(&y, &at).unwrap();
            assert_eq!(low[a], d[k][a] - 100.0, "particle {k}, axis {a}");
        }
        for (k, bad) in [
            (3, f32::NAN),
            (18, f32::NAN),
            (9, f32::INFINITY),
            (20, f32::NEG_INFINITY),
        ] {
            let mut y = x.clone();
            y[k].y = bad;
            assert_eq!(motion_box(&y, &at), None, "particle {k} at {bad}");
        }
    }

    #[test]
    fn a_look_is_due_once_two_particles_may_have_closed_in_by_the_margin() {
        let cloth = ClothBuilder::new(4, 4).build().unwrap();
        let topology = &*cloth.topology;
        let x = cloth.positions().to_vec();
        let basis = |thickness: f32| LookBasis {
            topology,
            particles: x.len(),
            revision: cloth.mass_revision,
            thickness,
            margin: 0.01,
        };
        let mut contacts = SelfContacts::default();
        let mut look = None;
        contacts.begin_step(&mut look, &basis(0.002), Team::ALONE);
        assert!(contacts.due(&look, &x), "no look yet");
        contacts.find(&mut look, (&x, &[], 0.0), &basis(0.002), Team::ALONE);
        assert!(!contacts.due(&look, &x));
        // The whole cloth falling: no two particles closed in.
        let fell: Vec<Vector> = x.iter().map(|&p| p - Vector::Y * 0.3).collect();
        assert!(!contacts.due(&look, &fell));
        // One particle of 16 moved: it closed in on the others by its
        // motion, which may reach the margin (1 cm).
        let moved = |dy: f32| {
            let mut y = x.clone();
            y[5].y += dy;
            y
        };
        assert!(!contacts.due(&look, &moved(0.0099)), "9.9 mm");
        assert!(contacts.due(&look, &moved(0.0101)), "10.1 mm");
        assert!(contacts.due(&look, &moved(f32::NAN)), "lost: look again");
        // Two neighbours moved 4 mm apart along x and y each (5.7 mm
        // each, 11.3 mm from each other): due, though each moved less
        // than the margin.
        let apart = |pair, d| moved_apart(&x, pair, d);
        assert!(contacts.due(&look, &apart((5, 6), 0.004)));
        assert!(!contacts.due(&look, &apart((5, 6), 0.0034)), "9.6 mm apart");
        // Four particles moved out along ±x and ±z: the box around the
        // motions is 2√2 times one motion wide, but no two particles closed
        // in by more than twice one motion, which the mean tells.
        let cross = |d: f32| {
            let mut y = x.clone();
            y[1].x += d;
            y[2].x -= d;
            y[4].z += d;
            y[8].z -= d;
            y
        };
        assert!(!contacts.due(&look, &cross(0.0045)), "9 mm at most");
        assert!(contacts.due(&look, &cross(0.0051)), "10.2 mm");
        // The look carries over to the next step, unless the thickness
        // (or the margin, or the particles) changed.
        contacts.begin_step(&mut look, &basis(0.002), Team::ALONE);
        assert!(!contacts.due(&look, &x));
        contacts.begin_step(&mut look, &basis(0.003), Team::ALONE);
        assert!(look.is_none() && contacts.due(&look, &x));
    }

    /// Positions `x` with particle `i` moved by `d` metres along x and y
    /// and particle `j` by as much the other way.
    fn moved_apart(x: &[Vector], (i, j): (usize, usize), d: f32) -> Vec<Vector> {
        let mut y = x.to_vec();
        y[i] += Vector::new(d, d, 0.0);
        y[j] -= Vector::new(d, d, 0.0);
        y
    }

    /// Two particles inside a cloth, further apart than a triangle reaches
    /// from either, moved apart by more than the margin: no triangle of one
    /// closed in on the other, and no look is due; two neighbours moved
    /// alike, or the far two moved far enough for the edges between them
    /// to have stretched as far, and one is.
    #[test]
    fn far_particles_moved_apart_need_no_look() {
        let cloth = ClothBuilder::new(8, 8).build().unwrap();
        let topology = &*cloth.topology;
        let x = cloth.positions().to_vec();
        let basis = LookBasis {
            topology,
            particles: x.len(),
            revision: cloth.mass_revision,
            thickness: 0.002,
            margin: 0.01,
        };
        let mut contacts = SelfContacts::default();
        let mut look = None;
        contacts.begin_step(&mut look, &basis, Team::ALONE);
        contacts.find(&mut look, (&x, &[], 0.0), &basis, Team::ALONE);
        // 4 mm along x and y each: 11.3 mm from each other. Particles 9
        // and 54 lie five cells apart along the diagonal, off the border.
        let apart = |pair, d| moved_apart(&x, pair, d);
        assert!(!contacts.due(&look, &apart((9, 54), 0.004)), "far apart");
        assert!(contacts.due(&look, &apart((9, 10), 0.004)), "neighbours");
        assert!(contacts.due(&look, &apart((9, 54), 0.2)), "20 cm each");
    }

    /// Fresh scratch finds the pairs of the last look again, at the
    /// positions of that look (not the current ones), to the same list.
    #[test]
    fn fresh_scratch_finds_the_last_looks_pairs_again() {
        let cloth = ClothBuilder::new(6, 6).build().unwrap();
        let topology = &*cloth.topology;
        // Folded in two along a column, the halves 2 mm apart.
        let folded: Vec<Vector> = cloth
            .positions()
            .iter()
            .map(|&p| {
                if p.x > 0.0 {
                    Vector::new(-p.x, p.y + 0.002, p.z)
                } else {
                    p
                }
            })
            .collect();
        let basis = LookBasis {
            topology,
            particles: folded.len(),
            revision: cloth.mass_revision,
            thickness: 0.004,
            margin: 0.004,
        };
        let (mut contacts, mut look) = (SelfContacts::default(), None);
        contacts.begin_step(&mut look, &basis, Team::ALONE);
        contacts.find(&mut look, (&folded, &[], 0.0), &basis, Team::ALONE);
        assert!(
            !contacts.all_pairs().is_empty(),
            "the halves are within reach"
        );
        let mut fresh = SelfContacts::default();
        fresh.begin_step(&mut look, &basis, Team::ALONE);
        assert_eq!(fresh.all_pairs(), contacts.all_pairs());
        assert_eq!(fresh.edge_pairs, contacts.edge_pairs);
    }

    /// Three 14 × 14 sheets joined, crumpled and laid 4 mm apart, 5 mm
    /// layers: pairs within reach everywhere, some closer than the
    /// thickness.
    fn crumpled_layers() -> (crate::cloth::Cloth, Vec<Vector>) {
        joined_sheets((14, 0.35), 3, |i, p| {
            let layer = (i / (14 * 14)) as f32;
            let bump = 0.004 * ((p.x * 23.0).sin() + (p.z * 17.0 + layer).cos());
            Vector::new(p.x + 0.003 * layer, 0.004 * layer + bump, p.z)
        })
    }

    /// `copies` square sheets of `side` particles a side and `size`
    /// metres joined into one cloth, particle `i` of rest position `p`
    /// placed at `place(i, p)`.
    fn joined_sheets(
        (side, size): (usize, f32),
        copies: usize,
        place: impl Fn(usize, Vector) -> Vector,
    ) -> (crate::cloth::Cloth, Vec<Vector>) {
        let sheet = ClothBuilder::new(side, side)
            .size(size, size)
            .build()
            .unwrap();
        let cloth = crate::cloth::Cloth::join(vec![sheet; copies]).unwrap();
        let x = (cloth.positions().iter().enumerate())
            .map(|(i, &p)| place(i, p))
            .collect();
        (cloth, x)
    }

    /// The layers' thickness and the margin of [`looked_at`] (m).
    const LAYERS: f32 = 0.005;

    /// The pass's parameters for layers [`LAYERS`] thick, with `friction`
    /// and a substep of `h` seconds.
    fn layer_params(friction: f32, h: f32) -> SelfContactParams {
        SelfContactParams {
            thickness: LAYERS,
            friction,
            h,
        }
    }

    /// Self-collision of `cloth` after a look at `x` (with the AVX2
    /// kernels unless `portable`).
    fn looked_at(cloth: &crate::cloth::Cloth, x: &[Vector], portable: bool) -> SelfContacts {
        let basis = LookBasis {
            topology: &cloth.topology,
            particles: x.len(),
            revision: cloth.mass_revision,
            thickness: LAYERS,
            margin: LAYERS,
        };
        let mut contacts = SelfContacts {
            portable,
            ..SelfContacts::default()
        };
        let mut look = None;
        contacts.begin_step(&mut look, &basis, Team::ALONE);
        contacts.find(&mut look, (x, &[], 0.0), &basis, Team::ALONE);
        contacts
    }

    /// A look by runs of triangles, with its vector test and without,
    /// finds the pairs of each triangle tested against every particle in
    /// turn (the look's definition: inside the triangle's box, and a
    /// pair), in triangle order, each triangle's in particle order.
    #[test]
    fn a_look_by_runs_finds_the_pairs_of_every_particle_against_every_triangle() {
        let (cloth, x) = crumpled_layers();
        let topology = &*cloth.topology;
        for portable in [false, true] {
            let contacts = looked_at(&cloth, &x, portable);
            let reference = Look {
                x: &x,
                from: &[],
                topology,
                thickness: LAYERS,
                reach: LAYERS + contacts.margin,
                margin: contacts.margin,
                simd: false,
            };
            let mut want = Vec::new();
            for t in 0..topology.triangles.len() {
                if contacts.patches.quiet_triangle(t) {
                    continue;
                }
                if let Some(f) = reference.facing(t, &contacts.neighbours) {
                    for (p, &xp) in x.iter().enumerate() {
                        reference.candidate(&f, (p as u32, xp), &contacts.neighbours, &mut want);
                    }
                }
            }
            assert!(want.len() > 1000, "only {} pairs", want.len());
            assert_eq!(contacts.all_pairs(), want, "portable: {portable}");
        }
    }

    /// The border edges' look finds the same pairs with the AVX2 test of
    /// a ring's edges as with the plain one.
    #[test]
    fn the_border_edges_pairs_are_the_same_either_way() {
        let (cloth, x) = crumpled_layers();
        let (simd, portable) = (looked_at(&cloth, &x, false), looked_at(&cloth, &x, true));
        assert!(
            portable.edge_pairs.len() > 100,
            "only {} edge pairs",
            portable.edge_pairs.len()
        );
        assert_eq!(simd.edge_pairs, portable.edge_pairs);
    }

    /// Two sheets' creases crossing: a 5 × 5 sheet of 30 mm cells folded
    /// down along its middle row (53° between its halves), `crease_gap`
    /// (m) above another folded up along its middle column, offset by half
    /// a cell so that the creases' edges cross between particles, which
    /// lie 7.5 mm plus the gap above or below the other's crease.
    fn crossing_creases(crease_gap: f32) -> (crate::cloth::Cloth, Vec<Vector>) {
        let sheet = ClothBuilder::new(5, 5).size(0.12, 0.12).build().unwrap();
        let centre = sheet.centroid();
        let cloth = crate::cloth::Cloth::join(vec![sheet; 2]).unwrap();
        let slope = 0.5;
        let x = cloth
            .positions()
            .iter()
            .enumerate()
            .map(|(i, &p)| {
                let d = p - centre;
                if i < 25 {
                    // Lowest along its middle row, `crease_gap` above the other's ridge.
                    Vector::new(d.x, crease_gap + slope * d.z.abs(), d.z)
                } else {
                    let (dx, dz) = (d.x + 0.015, d.z + 0.015);
                    Vector::new(dx, -slope * d.x.abs(), dz)
                }
            })
            .collect();
        (cloth, x)
    }

    /// The creases' crossing edges (the upper sheet's along its middle
    /// row, the lower's along its middle column) at positions `x`: the
    /// upper one's height over the lower one's where they cross (m).
    fn crease_gap(x: &[Vector]) -> f32 {
        let (a, b) = (x[12], x[13]);
        let (p, q) = (x[25 + 7], x[25 + 12]);
        let (s, t, _) = closest(a, b - a, p, q - p).expect("the creases cross");
        (a + (b - a) * s).y - (p + (q - p) * t).y
    }

    /// A sharp fold's edge is paired with another layer's fold edge near
    /// it, and the pass keeps the creases from passing through each other
    /// where no particle comes near the other sheet; a flat sheet has no
    /// fold edges.
    #[test]
    fn sharp_folds_keep_crossing_creases_apart() {
        let (cloth, x) = crossing_creases(0.003);
        let contacts = looked_at(&cloth, &x, false);
        let crease = ([12, 13], [25 + 7, 25 + 12]);
        assert!(
            contacts
                .edge_pairs
                .iter()
                .any(|e| (e.edge, e.other) == crease),
            "{:?}",
            contacts.edge_pairs
        );
        let params = layer_params(0.0, 1.0e-3);
        // The upper sheet sinks 4 mm, through the lower one's crease, each
        // particle still over 5 mm from the other sheet's triangles.
        let topology = &*cloth.topology;
        let sunk = |contacts: &SelfContacts| {
            let mut particles = cloth.particles.clone();
            particles.x.copy_from_slice(&x);
            for p in &mut particles.x[..25] {
                p.y -= 0.004;
            }
            assert!(crease_gap(&particles.x) < -0.0009);
            for _ in 0..6 {
                contacts.resolve(&mut particles, topology, &params, Team::ALONE);
            }
            crease_gap(&particles.x)
        };
        let gap = sunk(&contacts);
        assert!(gap > 0.5 * LAYERS, "the creases {gap} m apart");
        // Without the edge pairs the face pairs leave them crossed.
        let mut faces_only = contacts.clone();
        faces_only.edge_pairs.clear();
        assert!(sunk(&faces_only) < 0.0);
        // A flat sheet folds nowhere.
        let flat = ClothBuilder::new(5, 5).build().unwrap();
        let x = flat.positions().to_vec();
        let contacts = looked_at(&flat, &x, false);
        assert!(contacts.folds.is_empty());
    }

    /// Two 5 × 5 sheets of 10 mm cells joined into one cloth (no sheet
    /// shortcut: a grid's one-ring is paired), flat, the second 8 mm over
    /// the first (within reach, beyond the thickness: the first is looked
    /// at, and no pair between them acts).
    fn joined_fine_sheets() -> (crate::cloth::Cloth, Vec<Vector>) {
        joined_sheets((5, 0.04), 2, |i, p| {
            Vector::new(p.x, if i < 25 { 0.0 } else { 0.008 }, p.z)
        })
    }

    /// A border folded over at a particle is paired with the triangles of
    /// that particle it lies over, though it is their corner's neighbour,
    /// and the pass keeps it on its side; a flat grid's one-ring pairs
    /// (within the look's slack at 10 mm cells) never act.
    #[test]
    fn a_border_folded_over_at_a_corner_keeps_to_its_side() {
        let (cloth, flat) = joined_fine_sheets();
        let topology = &*cloth.topology;
        let params = layer_params(0.0, 1.0e-3);
        // Flat: pairs of a corner's one-ring exist, and the pass moves
        // nothing.
        let contacts = looked_at(&cloth, &flat, false);
        let one_ring = contacts
            .all_pairs()
            .iter()
            .filter(|p| {
                let tri = topology.triangles[p.triangle as usize];
                contacts.neighbours.adjacent(p.particle, tri)
            })
            .count();
        assert!(one_ring > 0, "no one-ring pairs");
        let mut particles = cloth.particles.clone();
        particles.x.copy_from_slice(&flat);
        let touching = contacts.resolve(&mut particles, topology, &params, Team::ALONE);
        assert_eq!((touching, &particles.x[..]), (0, &flat[..]));
        // The last row's particle 22 folded back over a triangle at its
        // neighbour 21 (and not at 22), 3 mm above its centre.
        let t = topology
            .triangles
            .iter()
            .position(|t| t.contains(&21) && !t.contains(&22) && t.iter().all(|&c| c < 25))
            .expect("a triangle at 21");
        let tri = topology.triangles[t];
        let centre = tri.iter().map(|&c| flat[c as usize]).sum::<Vector>() / 3.0;
        let mut x = flat.clone();
        x[22] = centre + Vector::new(0.0, 0.003, 0.0);
        let contacts = looked_at(&cloth, &x, false);
        assert!(contacts.all_pairs().contains(&SelfPair {
            particle: 22,
            triangle: t as u32,
            side: 1.0
        }));
        // Pulled 1 mm through it, it is pushed back out over a few passes.
        let mut particles = cloth.particles.clone();
        particles.x.copy_from_slice(&x);
        particles.x[22].y = -0.001;
        for _ in 0..4 {
            contacts.resolve(&mut particles, topology, &params, Team::ALONE);
        }
        let height = particles.x[22].y - particles.x[21].y;
        assert!(height > 0.5 * LAYERS, "{height} m above the triangle");
    }

    /// A particle that crossed a layer within the substep that asked for
    /// the look keeps the side it came from: the look takes the sides from
    /// where the particles were a substep before, and the pass pushes it
    /// back out; taken from where it is, the side would keep it through.
    #[test]
    fn a_layer_crossed_within_the_substep_before_a_look_is_pushed_back() {
        let (cloth, mut x) = joined_fine_sheets();
        let topology = &*cloth.topology;
        // The upper sheet's middle particle 1 mm under the lower sheet,
        // having come down at 6 m/s over a substep of 1.5 ms (from 8 mm
        // over it).
        let (q, h) = (25 + 12, 1.5e-3);
        x[q].y = -0.001;
        let mut v = vec![Vector::ZERO; x.len()];
        v[q] = Vector::new(0.0, -6.0, 0.0);
        let basis = LookBasis {
            topology,
            particles: x.len(),
            revision: cloth.mass_revision,
            thickness: LAYERS,
            margin: LAYERS,
        };
        let params = layer_params(0.0, h);
        let pushed = |v: &[Vector]| {
            let mut contacts = SelfContacts::default();
            let mut look = None;
            contacts.begin_step(&mut look, &basis, Team::ALONE);
            contacts.find(&mut look, (&x, v, h), &basis, Team::ALONE);
            let sides: Vec<f32> = contacts
                .all_pairs()
                .iter()
                .filter(|p| p.particle == q as u32)
                .map(|p| p.side)
                .collect();
            let mut particles = cloth.particles.clone();
            particles.x.copy_from_slice(&x);
            for _ in 0..4 {
                contacts.resolve(&mut particles, topology, &params, Team::ALONE);
            }
            // Over the lower sheet's particle under it.
            (sides, particles.x[q].y - particles.x[12].y)
        };
        let (sides, y) = pushed(&v);
        assert!(
            !sides.is_empty() && sides.iter().all(|&s| s == 1.0),
            "{sides:?}"
        );
        assert!(y > 0.5 * LAYERS, "{y} m");
        // At rest (no velocity) the look takes the side it is on now.
        let (sides, y) = pushed(&vec![Vector::ZERO; x.len()]);
        assert!(
            !sides.is_empty() && sides.iter().all(|&s| s == -1.0),
            "{sides:?}"
        );
        assert!(y < 0.0, "{y} m");
    }

    /// The pass eight pairs at a time (a vector test passing over the
    /// idle ones) gives the bits of the pass one pair at a time, pass
    /// after pass, and as many pairs closer than the thickness; its two
    /// parts on two threads too.
    #[test]
    fn the_pass_by_eights_gives_the_bits_of_one_pair_at_a_time() {
        let (cloth, x) = crumpled_layers();
        let topology = &*cloth.topology;
        let params = layer_params(0.3, 1.0e-3);
        let run = |portable: bool| {
            let contacts = looked_at(&cloth, &x, portable);
            let parts: Vec<Vec<&PartPairs>> =
                (0..3).map(|k| contacts.part_blocks(k).collect()).collect();
            let usable = parts
                .iter()
                .flatten()
                .all(|p| p.pairs.is_empty() || p.lanes.usable(p.pairs.len(), x.len()));
            assert_eq!(usable, !portable && simd_available());
            // Two parts apart, a few pairs across; every pair in one.
            let sizes: Vec<usize> = parts
                .iter()
                .map(|part| part.iter().map(|p| p.pairs.len()).sum())
                .collect();
            assert!(
                sizes[0] > 500 && sizes[1] > 500 && sizes[2] < sizes[0],
                "{sizes:?}"
            );
            assert_eq!(sizes.iter().sum::<usize>(), contacts.pairs);
            let mut particles = cloth.particles.clone();
            particles.x.copy_from_slice(&x);
            for (i, v) in particles.v.iter_mut().enumerate() {
                *v = Vector::new(0.0, -0.3 * ((i % 7) as f32 - 3.0), 0.1);
            }
            let bits = |v: &[Vector]| -> Vec<[u32; 3]> {
                v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            let pass = |team: Team| {
                let mut particles = particles.clone();
                let touching: Vec<u32> = (0..4)
                    .map(|_| contacts.resolve(&mut particles, topology, &params, team))
                    .collect();
                (touching, bits(&particles.x), bits(&particles.v))
            };
            let alone = pass(Team::ALONE);
            assert!(
                contacts.pairs >= PARALLEL_MIN_PAIRS,
                "{} pairs",
                contacts.pairs
            );
            // The two parts on two threads: the same bits.
            #[cfg(feature = "parallel")]
            assert_eq!(crate::parallel::on_threads(2, pass), alone);
            alone
        };
        let (batched, one) = (run(false), run(true));
        assert!(one.0[0] > 50, "only {:?} pairs touching", one.0);
        assert_eq!(batched, one);
    }
}
