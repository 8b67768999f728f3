//! Self-collision: particles kept a layer's thickness
//! ([`crate::cloth::Cloth::self_thickness`]) away from the triangles of
//! their own cloth that are not their neighbours in the rest mesh
//! ([`MeshNeighbours`]), with Coulomb friction between the layers.
//!
//! Found ahead, solved every substep (as the obstacles are): a spatial
//! hash of the particles ([`SpatialHash`]) gives each triangle the
//! particles within reach of it, `thickness + margin`. A look costs a pass
//! over the triangles, so it is taken again only when it may have missed
//! a pair: whenever two particles may have closed in by more than the
//! margin since the last look (a neighbour list with a skin, as in
//! molecular dynamics), by the smaller of two bounds: the diagonal of the
//! box around the particles' motions, and twice the farthest motion from
//! their mean; and when the
//! cloth, its thickness or the margin changed. Every substep for a cloth
//! in violent motion, seldom for one at rest or in free fall: a look
//! carries over from step to step (the `stack` at rest looked once a step
//! before, 5 ms of its frame). Where it looked is solver state
//! ([`SelfLook`], in a snapshot); the pairs are scratch, found again from
//! those positions by a solver with fresh scratch, to the same list. The
//! triangles of quiet patches ([`Patches`]: a bent sheet that cannot touch
//! itself) are skipped. Each pair keeps the side
//! of the triangle the particle was on when found. The cloth's border
//! edges are also paired with the other edges near them, so that two
//! borders cannot slip past each other.
//!
//! A substep's pass, in pair order (Gauss–Seidel, one thread, the same
//! bits on any number): for a particle `p` whose projection falls inside
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

use super::neighbours::{MeshNeighbours, Sheet};
use super::patches::Patches;
use super::spatial_hash::SpatialHash;
use crate::cloth::{Particles, Topology};
use crate::math::Vector;
use crate::parallel::{Disjoint, Team};

/// A particle near a triangle of its own cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SelfPair {
    particle: u32,
    triangle: u32,
    /// +1 when the particle lay on the side the triangle's normal points
    /// to, −1 on the other.
    side: f32,
}

/// An edge of the cloth's border near another edge of the same cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
struct EdgePair {
    /// The border edge.
    border: [u32; 2],
    /// The other edge.
    other: [u32; 2],
    /// +1 when the border edge lay on the side `(b − a) × (q − p)` points
    /// to from the other edge, −1 on the other.
    side: f32,
}

/// Where self-collision last looked for pairs: solver state, since when it
/// looks next depends on it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SelfLook {
    /// The particles' positions (m) at the look.
    at: Vec<Vector>,
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
    neighbours: MeshNeighbours,
    pairs: Vec<SelfPair>,
    /// Border edges near other edges, found by the last look.
    edge_pairs: Vec<EdgePair>,
    /// Which look the pairs are of ([`SelfLook::number`]) and the cloth's
    /// revision then (its masses, pins and topology).
    pairs_of: Option<(u64, u64)>,
    /// How far (m) particles may close in on each other between looks.
    margin: f32,
}

/// Triangles a thread takes at a time in a look for pairs (a quarter of
/// 1024: the `fold`'s look, on two threads, 3.40 → 3.35 ms a frame).
const TRIANGLE_BLOCK: usize = 256;

/// Border edges a thread takes at a time in a look for pairs.
const BORDER_BLOCK: usize = 64;

/// The edge pairs a block of border edges found, alone on its cache lines.
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
struct EdgeList(Vec<EdgePair>);

/// The pairs a block of triangles found, alone on its cache lines (blocks
/// on different threads push at once), and a list for the second of two
/// triangles looked at together ([`Look::two_triangles`]).
#[derive(Debug, Default, Clone)]
#[repr(align(128))]
struct PairList(Vec<SelfPair>, Vec<SelfPair>);

/// One look for pairs: the positions and how far to look.
struct Look<'a> {
    x: &'a [Vector],
    topology: &'a Topology,
    thickness: f32,
    /// Thickness plus margin, in metres.
    reach: f32,
    margin: f32,
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
        let rim = rim(self.thickness, (e1, e2));
        // A particle may slide `margin` towards the triangle before the next
        // look: accept projections that far outside.
        let slack = rim_slack(self.margin + rim, (e1, e2), area2);
        // Particles of the same smooth sheet as the triangle, up to as far as
        // a pair can reach from its corners, are left to the springs.
        let sheet = neighbours.sheet(tri, reach + rim + e1.length().max(e2.length()));
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
    /// lies within reach of it, outside its sheet and not its neighbour.
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
        if u < -slack[0] || v < -slack[1] || w < -slack[2] || neighbours.adjacent(p, f.tri) {
            return None;
        }
        Some(SelfPair {
            particle: p,
            triangle: f.t,
            side: if d >= 0.0 { 1.0 } else { -1.0 },
        })
    }

    /// Pushes the pairs of triangle `t` to `out`, in particle order.
    fn triangle(
        &self,
        t: usize,
        (hash, neighbours): (&SpatialHash, &MeshNeighbours),
        out: &mut Vec<SelfPair>,
    ) {
        if let Some(f) = self.facing(t, neighbours) {
            self.facing_pairs(&f, (hash, neighbours), out);
        }
    }

    /// Pushes the pairs of the triangle `f` to `out`, in particle order.
    fn facing_pairs(
        &self,
        f: &Facing,
        (hash, neighbours): (&SpatialHash, &MeshNeighbours),
        out: &mut Vec<SelfPair>,
    ) {
        let first = out.len();
        hash.for_each_inside(f.lo, f.hi, |p, xp| {
            if let Some(pair) = self.pair(f, (p, xp), neighbours) {
                out.push(pair);
            }
        });
        // The hash hands them out by bucket: particle order, for the same
        // pass whatever the table's size.
        out[first..].sort_unstable_by_key(|q| q.particle);
    }

    /// [`Self::triangle`] on triangles `t` and `t + 1`, from one scan of
    /// the hash over the box around both (each particle in it tested
    /// against the triangles whose own box holds it: the same pairs);
    /// `second` is scratch.
    fn two_triangles(
        &self,
        t: usize,
        (hash, neighbours): (&SpatialHash, &MeshNeighbours),
        (out, second): (&mut Vec<SelfPair>, &mut Vec<SelfPair>),
    ) {
        let both = [self.facing(t, neighbours), self.facing(t + 1, neighbours)];
        let [Some(f), Some(g)] = &both else {
            // One has no area (or neither): the other alone.
            for f in both.iter().flatten() {
                self.facing_pairs(f, (hash, neighbours), out);
            }
            return;
        };
        let inside = |xp: Vector, f: &Facing| xp.cmpge(f.lo).all() && xp.cmple(f.hi).all();
        let first = out.len();
        second.clear();
        hash.for_each_inside(f.lo.min(g.lo), f.hi.max(g.hi), |p, xp| {
            if inside(xp, f) {
                if let Some(pair) = self.pair(f, (p, xp), neighbours) {
                    out.push(pair);
                }
            }
            if inside(xp, g) {
                if let Some(pair) = self.pair(g, (p, xp), neighbours) {
                    second.push(pair);
                }
            }
        });
        out[first..].sort_unstable_by_key(|q| q.particle);
        second.sort_unstable_by_key(|q| q.particle);
        out.extend_from_slice(second);
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
        let length2 = u.length_squared();
        hash.for_each_inside(lo, hi, |e, xe| {
            if sheet.holds(e) || e == ia || e == ib {
                return;
            }
            // How far e lies beyond reach of the border edge: an edge from e
            // with a point within reach of it is at least that long (a hair
            // more spares the rounding: the pairs are those of the look
            // without this test).
            let along = if length2 > 0.0 {
                ((xe - a).dot(u) / length2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let beyond = (xe - a - u * along).length() - self.reach;
            let shortest2 = if beyond > 0.0 {
                beyond * beyond * (1.0 - 1.0e-3)
            } else {
                0.0
            };
            for &f in neighbours.ring(e) {
                let xf = x[f as usize];
                // Each edge once: from its lower end when both ends are
                // in the box.
                if f < e && inside(xf) {
                    continue;
                }
                if f == ia || f == ib || (xf - xe).length_squared() < shortest2 || sheet.holds(f) {
                    continue;
                }
                let (p, q) = (e.min(f), e.max(f));
                // Two border edges meet from both sides: keep the lower one's.
                if [p, q] < [ia, ib] && borders.binary_search(&[p, q]).is_ok() {
                    continue;
                }
                let (xp, xq) = (x[p as usize], x[q as usize]);
                let Some((s, t, n)) = closest(a, u, xp, xq - xp) else {
                    continue;
                };
                let gap = (a + u * s - xp - (xq - xp) * t).dot(n);
                if gap.abs() < self.reach {
                    out.push(EdgePair {
                        border: [ia, ib],
                        other: [p, q],
                        side: if gap >= 0.0 { 1.0 } else { -1.0 },
                    });
                }
            }
        });
        // In edge order, whatever the hash's layout.
        out[first..].sort_unstable_by_key(|e| e.other);
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
        self.neighbours.update(basis.topology, basis.particles);
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
            self.find_pairs(&last.at, basis.topology, basis.thickness, team);
            self.pairs_of = Some((last.number, basis.revision));
        }
    }

    /// True when particles at `x` may have closed in on each other by more
    /// than the margin since the `look` (or there is none), by the module's
    /// two bounds.
    pub(crate) fn due(&self, look: &Option<SelfLook>, x: &[Vector]) -> bool {
        let Some(look) = look else {
            return true;
        };
        if look.at.len() != x.len() {
            return true;
        }
        let n = x.len().max(1) as f32;
        let moved = x.iter().zip(&look.at).map(|(&x, &at)| x - at);
        // Two particles closed in by at most the diagonal of the box
        // around every motion: one of the `stack`'s three cloths falling
        // onto the others has closed in by its fall, where twice its
        // particles' distance from the mean motion counts 4/3 of it.
        let (mut lo, mut hi, mut sum) = (Vector::INFINITY, Vector::NEG_INFINITY, Vector::ZERO);
        for d in moved.clone() {
            if !d.is_finite() {
                return true; // lost: look again
            }
            (lo, hi, sum) = (lo.min(d), hi.max(d), sum + d);
        }
        if (hi - lo).length_squared() <= self.margin * self.margin {
            return false;
        }
        // And by at most twice the farthest motion from the mean (the
        // smaller bound for a cloth that turns).
        let mean = sum / n;
        let half = 0.5 * self.margin;
        moved
            .into_iter()
            .any(|d| (d - mean).length_squared() > half * half)
    }

    /// Looks for pairs at positions `x` (the `basis`'s thickness and
    /// margin) and records the look in `look`.
    pub(crate) fn find(
        &mut self,
        look: &mut Option<SelfLook>,
        x: &[Vector],
        basis: &LookBasis,
        team: Team,
    ) {
        self.find_pairs(x, basis.topology, basis.thickness, team);
        let last = look.get_or_insert_with(SelfLook::default);
        // The positions' buffer is reused: no allocation once warmed up.
        last.at.clear();
        last.at.extend_from_slice(x);
        last.thickness = basis.thickness;
        last.margin = self.margin;
        last.number += 1;
        self.pairs_of = Some((last.number, basis.revision));
    }

    /// Finds the particles within reach of triangles they are not
    /// neighbours of, at positions `x`: blocks of triangles on the `team`,
    /// their pairs then joined in triangle order (the same list on any
    /// number of threads).
    fn find_pairs(&mut self, x: &[Vector], topology: &Topology, thickness: f32, team: Team) {
        self.pairs.clear();
        self.edge_pairs.clear();
        let triangles = &topology.triangles;
        if triangles.is_empty() {
            return;
        }
        let look = Look {
            x,
            topology,
            thickness,
            reach: thickness + self.margin,
            margin: self.margin,
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
        let (hash, neighbours, patches) = (&self.hash, &self.neighbours, &self.patches);
        let lists = Disjoint::new(&mut self.blocks[..blocks]);
        let edge_lists = Disjoint::new(&mut self.border_blocks[..border_blocks]);
        // The triangles' blocks, then the border edges' (serial, they
        // were a tenth of the `fold`'s frame), in one handout.
        team.sum_count_uneven(blocks + border_blocks, |k| {
            if k >= blocks {
                let e = k - blocks;
                // SAFETY: block `e` alone uses edge list `e`.
                let EdgeList(list) = unsafe { &mut edge_lists.range(e..e + 1)[0] };
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
            let PairList(list, second) = unsafe { &mut lists.range(k..k + 1)[0] };
            list.clear();
            let end = ((k + 1) * TRIANGLE_BLOCK).min(triangles.len());
            // Two at a time: a grid's two triangles of a cell (and a
            // mesh's neighbours, mostly) share most of their box, whose
            // scan of the hash is then paid once.
            let mut t = k * TRIANGLE_BLOCK;
            while t < end {
                let pair = [t, t + 1].map(|t| t < end && !patches.quiet_triangle(t));
                match pair {
                    [true, true] => look.two_triangles(t, (hash, neighbours), (list, second)),
                    [true, false] => look.triangle(t, (hash, neighbours), list),
                    [false, true] => look.triangle(t + 1, (hash, neighbours), list),
                    [false, false] => {}
                }
                t += 2;
            }
            0
        });
        for list in &mut self.blocks[..blocks] {
            self.pairs.extend_from_slice(&list.0);
            headroom(&mut list.0);
            headroom(&mut list.1);
        }
        headroom(&mut self.pairs);
        self.edge_pairs.clear();
        for list in &mut self.border_blocks[..border_blocks] {
            self.edge_pairs.extend_from_slice(&list.0);
            headroom(&mut list.0);
        }
        headroom(&mut self.edge_pairs);
    }

    /// One pass over the pairs (module docs); returns how many were
    /// closer than the thickness.
    pub(crate) fn resolve(
        &self,
        particles: &mut Particles,
        topology: &Topology,
        params: &SelfContactParams,
    ) -> u32 {
        let Particles { x, v, inv_mass, .. } = particles;
        let SelfContactParams {
            thickness,
            friction,
            h,
        } = *params;
        let mut touching = 0;
        // The pairs come by triangle (a look's blocks join in triangle
        // order): what depends on the triangle alone is found once for
        // its run of pairs, and found again after any pair moved a
        // particle (it may have moved a corner). The same values as a
        // pair's own: the same expressions of the same positions.
        let mut near: Option<Near> = None;
        for pair in &self.pairs {
            let f = match &mut near {
                Some(f) if f.t == pair.triangle => f,
                _ => {
                    let Some(&tri) = topology.triangles.get(pair.triangle as usize) else {
                        continue;
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
                continue;
            }
            let Some((len, slack)) = f.rim_slack(thickness) else {
                continue;
            };
            let (e1, e2) = (f.e1, f.e2);
            let n = normal * (pair.side / len);
            let d = (xp - a).dot(n);
            if d >= thickness {
                continue;
            }
            // Further on the other side than particles can have moved since
            // the look (the margin): not a crossing but a pair the cloth has
            // turned away from (a fold, a swing).
            if d < -(thickness + self.margin) {
                continue;
            }
            let bary = barycentric(xp - n * d - a, e1, e2);
            if (0..3).any(|k| bary[k] < -slack[k]) {
                continue;
            }
            // Just outside the rim, the nearest point of the edge takes it.
            let [u, vb, w] = clamped(bary);
            let [wp, wa, wb, wc] = [ip, ia, ib, ic].map(|i| inv_mass[i]);
            let weight = wp + wa * u * u + wb * vb * vb + wc * w * w;
            if !is_positive(weight) {
                continue;
            }
            touching += 1;
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
            near = None;
        }
        for pair in &self.edge_pairs {
            let ([ia, ib], [ip, iq]) = (
                pair.border.map(|i| i as usize),
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
            // The border edge's side moves along n, the other edge's against it.
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
    fn of(t: u32, tri: [u32; 3], x: &[Vector]) -> Near {
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
            let edges = (self.e1, self.e2);
            is_positive(len).then(|| (len, rim_slack(rim(thickness, edges), edges, len)))
        })
    }
}

/// How far outside each edge of a triangle a particle is still taken, in
/// barycentric terms (`[u, v, w]` may go that far below 0): `out` metres
/// beyond every edge, over the altitude onto that edge. Where the cloth
/// bends, the projections of a particle near the common edge may fall
/// outside both triangles (a gap a particle slipped through in the `fold`
/// scene); a rim closes it. `len` is `|e1 × e2|`, twice the area.
#[inline]
fn rim_slack(out: f32, (e1, e2): (Vector, Vector), len: f32) -> [f32; 3] {
    // The altitude onto an edge is `len / |edge|`; u belongs to corner a,
    // whose opposite edge is `e2 − e1`.
    [(e2 - e1).length(), e2.length(), e1.length()].map(|edge| out * edge / len)
}

/// The rim of a triangle (m): the thickness, but at most a quarter of its
/// shortest edge, so that the particles beyond the rest-mesh neighbours of
/// a flat cloth never fall within it.
#[inline]
fn rim(thickness: f32, (e1, e2): (Vector, Vector)) -> f32 {
    let shortest = e1
        .length_squared()
        .min(e2.length_squared())
        .min((e2 - e1).length_squared())
        .sqrt();
    thickness.min(0.25 * shortest)
}

/// Barycentric coordinates clamped to the triangle and summing to one.
#[inline]
fn clamped([u, v, w]: [f32; 3]) -> [f32; 3] {
    let [u, v, w] = [u.max(0.0), v.max(0.0), w.max(0.0)];
    let sum = u + v + w;
    [u / sum, v / sum, w / sum]
}

/// Makes room for twice the list's length, so that a step whose pairs
/// grow by less than that allocates nothing (a warmed-up step allocates
/// only when the contacts more than double).
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
        contacts.find(&mut look, &x, &basis(0.002), Team::ALONE);
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
        // Two particles moved 4 mm apart along x and y each (5.7 mm each,
        // 11.3 mm from each other): due, though each moved less than the
        // margin.
        let apart = |d: f32| {
            let mut y = x.clone();
            y[3] += Vector::new(d, d, 0.0);
            y[9] -= Vector::new(d, d, 0.0);
            y
        };
        assert!(contacts.due(&look, &apart(0.004)));
        assert!(!contacts.due(&look, &apart(0.0034)), "9.6 mm apart");
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
        contacts.find(&mut look, &folded, &basis, Team::ALONE);
        assert!(!contacts.pairs.is_empty(), "the halves are within reach");
        let mut fresh = SelfContacts::default();
        fresh.begin_step(&mut look, &basis, Team::ALONE);
        assert_eq!(fresh.pairs, contacts.pairs);
        assert_eq!(fresh.edge_pairs, contacts.edge_pairs);
    }
}
