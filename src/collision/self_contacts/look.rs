//! A look for pairs: the triangles in runs, against the hash of the particles.

use super::contacts::SelfContacts;
use super::geometry::{barycentric, edge_lengths, is_positive, rim, rim_slack, side_at, sign};
use super::lists::{headroom, Candidates, EdgeList, PairList};
use super::pair_lanes::LANES;
use super::pairs::SelfPair;
use crate::cloth::Topology;
use crate::collision::neighbours::{MeshNeighbours, Sheet};
use crate::collision::spatial_hash::SpatialHash;
use crate::math::{simd_available, Vector};
use crate::parallel::{Disjoint, Team};

/// Triangles a thread takes at a time in a look for pairs (a quarter of
/// 1024: the `fold`'s look, on two threads, 3.40 → 3.35 ms a frame).
pub(super) const TRIANGLE_BLOCK: usize = 256;

/// Border edges a thread takes at a time in a look for pairs.
pub(super) const BORDER_BLOCK: usize = 64;

/// Sharp folds' edges a thread takes at a time in a look for pairs.
pub(super) const FOLD_BLOCK: usize = 64;

/// Triangles a look takes together ([`Look::run`]): one scan of the hash
/// over the box around them all.
pub(super) const RUN: usize = 8;

/// One look for pairs: the positions and how far to look.
pub(super) struct Look<'a> {
    pub(super) x: &'a [Vector],
    /// Where the particles were a substep before (m), for the pairs'
    /// sides; empty: from `x`.
    pub(super) from: &'a [Vector],
    pub(super) topology: &'a Topology,
    pub(super) thickness: f32,
    /// Thickness plus margin, in metres.
    pub(super) reach: f32,
    pub(super) margin: f32,
    /// The CPU has AVX2 ([`Look::facing_candidates`]).
    pub(super) simd: bool,
}

/// A triangle as a look tests particles against it: its corners' indices,
/// first corner `a` and edges `e1`, `e2` (m), unit normal, how far outside
/// each edge a projection is still taken (barycentric, [`rim_slack`]), the
/// particles of its smooth sheet, and the box (m) a particle within reach
/// of it lies in.
pub(super) struct Facing<'a> {
    pub(super) t: u32,
    pub(super) tri: [u32; 3],
    pub(super) a: Vector,
    pub(super) e1: Vector,
    pub(super) e2: Vector,
    pub(super) n: Vector,
    pub(super) slack: [f32; 3],
    pub(super) sheet: Sheet<'a>,
    pub(super) lo: Vector,
    pub(super) hi: Vector,
}

impl Look<'_> {
    /// Triangle `t` as the look tests particles against it; none for a
    /// triangle of no area.
    #[inline(always)]
    pub(super) fn facing<'n>(
        &self,
        t: usize,
        neighbours: &'n MeshNeighbours,
    ) -> Option<Facing<'n>> {
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
    pub(super) fn pair(
        &self,
        f: &Facing,
        (p, xp): (u32, Vector),
        neighbours: &MeshNeighbours,
    ) -> Option<SelfPair> {
        let d = (xp - f.a).dot(f.n);
        if d.abs() >= self.reach {
            return None;
        }
        let [u, v, w] = barycentric(xp - f.n * d - f.a, f.e1, f.e2);
        let slack = f.slack;
        if u < -slack[0] || v < -slack[1] || w < -slack[2] {
            return None;
        }
        self.sheet_pair(f, (p, d), neighbours)
    }

    /// The pair of particle `p` with triangle `f`, whose plane it lies `d`
    /// (m) in front of, once it is within reach and over the triangle or its
    /// rim ([`Look::pair`]'s tests of the numbers): none in the triangle's
    /// sheet or left to the springs.
    #[inline(always)]
    pub(super) fn sheet_pair(
        &self,
        f: &Facing,
        (p, d): (u32, f32),
        neighbours: &MeshNeighbours,
    ) -> Option<SelfPair> {
        if f.sheet.holds(p) || neighbours.left_to_springs(p, f.tri) {
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
    pub(super) fn side_before(&self, tri: [u32; 3], p: u32) -> Option<f32> {
        let from = self.from;
        let [a, b, c] = tri.map(|i| from.get(i as usize).copied());
        let (a, b, c, xp) = (a?, b?, c?, from.get(p as usize).copied()?);
        sign((xp - a).dot((b - a).cross(c - a)))
    }

    /// The side (±1) `edge` lay on from `other` a substep before the look (by
    /// the two lines' orientation, [`closest`](super::geometry::closest)'s
    /// normal), if the look knows where and the lines were neither parallel nor
    /// met.
    #[inline]
    pub(super) fn edge_side_before(&self, edge: [u32; 2], other: [u32; 2]) -> Option<f32> {
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
    pub(super) fn run(
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
    pub(super) fn facing_candidates(
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
    pub(super) fn candidate(
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
    /// hair looser than [`Look::pair`]'s; not a corner); a step that lets
    /// any through takes [`Look::pair`]'s tests of the numbers in vector
    /// (the same operations in the same order), and each candidate that
    /// passes them [`Look::sheet_pair`]: the same pairs as one at a time.
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn facing_candidates_avx2(
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
            // The projection's barycentrics, in `Look::pair`'s and
            // `barycentric`'s operations and order: here their numerators,
            // by the inverse for the vector test (looser), and divided
            // below for the steps it lets anything through.
            let (qx, qy, qz) = (
                _mm256_sub_ps(_mm256_sub_ps(x, _mm256_mul_ps(splat(n.x), d)), splat(a.x)),
                _mm256_sub_ps(_mm256_sub_ps(y, _mm256_mul_ps(splat(n.y), d)), splat(a.y)),
                _mm256_sub_ps(_mm256_sub_ps(z, _mm256_mul_ps(splat(n.z), d)), splat(a.z)),
            );
            let dot = |e: Vector| {
                _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(qx, splat(e.x)), _mm256_mul_ps(qy, splat(e.y))),
                    _mm256_mul_ps(qz, splat(e.z)),
                )
            };
            let (dq1, dq2) = (dot(e1), dot(e2));
            let vb_top = _mm256_sub_ps(
                _mm256_mul_ps(splat(d22), dq1),
                _mm256_mul_ps(splat(d12), dq2),
            );
            let w_top = _mm256_sub_ps(
                _mm256_mul_ps(splat(d11), dq2),
                _mm256_mul_ps(splat(d12), dq1),
            );
            let inside = |[u, vb, w]: [__m256; 3], slack: [__m256; 3]| {
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_NLT_UQ>(u, slack[0]),
                    _mm256_and_ps(
                        _mm256_cmp_ps::<_CMP_NLT_UQ>(vb, slack[1]),
                        _mm256_cmp_ps::<_CMP_NLT_UQ>(w, slack[2]),
                    ),
                )
            };
            let bary = |vb, w| [_mm256_sub_ps(_mm256_sub_ps(one, vb), w), vb, w];
            let loose = bary(_mm256_mul_ps(vb_top, inv), _mm256_mul_ps(w_top, inv));
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
                _mm256_and_ps(_mm256_and_ps(boxed, near), inside(loose, slack)),
            );
            if _mm256_movemask_ps(keep) != 0 {
                // Those let through, tested again exactly as `Look::pair`
                // does: the same operations in the same order on the same
                // floats (the box and the distance `d` are already), so
                // the same answers; then what is not a number's work (the
                // sheet, the springs, the side) one at a time. Taking
                // each of them through `Look::candidate` from the start
                // was half of this function's time on the `stack`.
                let denom = splat(denom);
                let exact = bary(_mm256_div_ps(vb_top, denom), _mm256_div_ps(w_top, denom));
                let near = _mm256_cmp_ps::<_CMP_NGE_UQ>(_mm256_and_ps(d, abs), splat(self.reach));
                let inside = inside(exact, f.slack.map(|s| splat(-s)));
                let pair = _mm256_and_ps(keep, _mm256_and_ps(near, inside));
                let mut bits = _mm256_movemask_ps(pair) as u32;
                let mut ds = [0.0f32; LANES];
                _mm256_storeu_ps(ds.as_mut_ptr(), d);
                while bits != 0 {
                    let j = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let p = cand.p[k + j];
                    if let Some(pair) = self.sheet_pair(f, (p, ds[j]), neighbours) {
                        out.push(pair);
                    }
                }
            }
            k += LANES;
        }
    }
}

impl SelfContacts {
    /// Finds the particles within reach of triangles they are not
    /// neighbours of, at positions `x`: blocks of triangles on the `team`,
    /// their pairs then joined in triangle order (the same list on any
    /// number of threads).
    pub(super) fn find_pairs(
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
