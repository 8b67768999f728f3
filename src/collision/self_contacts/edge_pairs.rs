//! The edges a look pairs: the border's and the sharp folds' with the edges
//! near them.

use super::contacts::SelfContacts;
use super::geometry::{closest, side_at};
use super::lists::EdgeList;
use super::look::{Look, FOLD_BLOCK, TRIANGLE_BLOCK};
use super::pair_lanes::LANES;
use super::pairs::{EdgePair, NO_FOLDS};
use crate::collision::neighbours::{MeshNeighbours, Sheet};
use crate::collision::spatial_hash::SpatialHash;
use crate::math::Vector;
#[cfg(target_arch = "x86_64")]
use crate::math::{cross_lanes, dot_lanes, load_vectors};
use crate::parallel::{Disjoint, Team};

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
/// it in 2 (0), at four times the frame. The pass keeps these pairs the
/// whole thickness apart only from [`FULL_FOLD`] (40°), less the less
/// sharp the folds are now; over the same 42 starts it crossed in 3 (5
/// self-intersections in all, none at the end) against 4 (4, none) with
/// the whole thickness from 30°. Pairing from 20° with the whole
/// thickness from 30° crossed in 2 (3, none), at a third more of the
/// `stack`'s frame (the looks' folds); from 25°, in 2 (2, none) at a
/// fifth more (fifty-ninth session).
pub(super) const SHARP_FOLD: f32 = 30.0 * std::f32::consts::PI / 180.0;

/// How sharply (radians) a fold's triangles meet for the pass to keep its
/// edge the whole thickness from the edges it is paired with. Between
/// [`SHARP_FOLD`] and this the thickness grows from none
/// ([`fold_share`]): a fold that a look pairs, or stops pairing, at the
/// threshold does not push a layer by up to half the thickness at once.
/// With the whole thickness from the threshold, a crease of the `stack`
/// at rest about as sharp flickered across it from look to look; the
/// layers closed in while its pairs were left out and were pushed 3.6 mm
/// apart when they came back, a cycle that shook the cloth at rest by up
/// to 9 mm a frame.
pub(super) const FULL_FOLD: f32 = 40.0 * std::f32::consts::PI / 180.0;

/// The share of the thickness an edge between the triangles `faces` of
/// `triangles` keeps from the edges a look paired it with, at positions
/// `x`: 0 up to [`SHARP_FOLD`] between their normals, 1 from
/// [`FULL_FOLD`], linear in the angle's cosine between; 1 for a triangle
/// of no area (as [`SelfContacts::find_folds`] counts it sharp).
#[inline]
pub(super) fn fold_share(faces: [u32; 2], triangles: &[[u32; 3]], x: &[Vector]) -> f32 {
    let normal = |t: u32| {
        triangles.get(t as usize).map_or(Vector::ZERO, |tri| {
            let [a, b, c] = tri.map(|i| x[i as usize]);
            (b - a).cross(c - a)
        })
    };
    let (n0, n1) = (normal(faces[0]), normal(faces[1]));
    let cos = n0.dot(n1) / (n0.length() * n1.length());
    if !cos.is_finite() {
        return 1.0;
    }
    let (start, full) = (SHARP_FOLD.cos(), FULL_FOLD.cos());
    ((start - cos) / (start - full)).clamp(0.0, 1.0)
}

impl Look<'_> {
    /// Pushes the edges within reach of the border edge `[a, b]` that are
    /// neither its neighbours nor of its smooth sheet (each such pair of
    /// border edges once).
    pub(super) fn border_edge(
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
    pub(super) fn border_pair(
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
    pub(super) fn within_reach(
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
            folds: NO_FOLDS,
        })
    }

    /// The pair of a sharp fold's `edge` with another fold's edge `other`,
    /// pushed to `out` (the lower edge first) when their closest points
    /// lie within reach: sharing no particle with the fold's edge, and not
    /// of its smooth `sheet` (as far as a pair reaches plus twice its
    /// length).
    #[inline]
    pub(super) fn fold_pair(
        &self,
        (edge, faces): ([u32; 2], [u32; 2]),
        other: [u32; 2],
        (sheet, neighbours): (&Sheet, &MeshNeighbours),
        out: &mut Vec<EdgePair>,
    ) {
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
        let Some(pair) = self.within_reach((first, a, b - a), (second, p, q - p)) else {
            return;
        };
        // The other fold's triangles, for the pairs within reach alone.
        let (inner, inner_faces) = neighbours.inner_edges();
        let Some(other_faces) = inner.binary_search(&other).ok().map(|k| inner_faces[k]) else {
            return;
        };
        let folds = if edge <= other {
            [faces, other_faces]
        } else {
            [other_faces, faces]
        };
        out.push(EdgePair { folds, ..pair });
    }

    /// Which of the edges from `xe` to the particles `ends` (at most
    /// [`LANES`]) have a box that meets the box `near`, as bits (bit `j`
    /// for `ends[j]`): `min(xe, xf) <= hi` and `max(xe, xf) >= lo`, the
    /// floats of one edge at a time. Where the CPU has AVX2, those too
    /// that [`Self::border_pair`] would find apart from the border edge
    /// from `a` along `u` (m) are left out.
    #[inline(always)]
    pub(super) fn ring_near(
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
    pub(super) unsafe fn ring_near_avx2(
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

impl SelfContacts {
    /// The sharp folds' edges of the look ([`SHARP_FOLD`]), from the
    /// triangles' normals it found: the edges between two triangles whose
    /// normals lie further apart (or one of no area), as indices into
    /// [`MeshNeighbours::inner_edges`], and which edges and which of the
    /// `particles` they are.
    pub(super) fn find_folds(&mut self, particles: usize) {
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
    pub(super) fn pair_folds(&mut self, look: &Look, team: Team) {
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
                let faces = faces[fold as usize];
                for &other in candidates.iter() {
                    look.fold_pair((edge, faces), other, (&sheet, neighbours), list);
                }
            }
            0
        });
    }
}
