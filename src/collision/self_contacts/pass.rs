//! A substep's pass over the pairs, and the triangle it works with.

use super::contacts::SelfContacts;
use super::edge_pairs::fold_share;
use super::geometry::{
    barycentric, clamped, closest, edge_lengths, is_positive, rim, rim_slack, rim_taper,
};
use super::lists::PartPairs;
use super::pair_lanes::LANES;
use super::pairs::{SelfPair, NO_FOLDS};
use super::params::SelfContactParams;
use super::pass_plane::PARALLEL_MIN_PAIRS;
use super::points::Points;
use crate::cloth::{Particles, Topology};
use crate::math::Vector;
use crate::parallel::{Disjoint, Team};

impl SelfContacts {
    /// The pairs of the last look's blocks, in the pass's `part`.
    pub(super) fn part_blocks(&self, part: usize) -> impl Iterator<Item = &PartPairs> + '_ {
        self.blocks[..self.used_blocks]
            .iter()
            .map(move |b| &b.2[part])
    }

    /// One pass over the pairs (module docs), its two parts on the `team`
    /// ([`PassPlane`](super::pass_plane::PassPlane)); returns how many were
    /// closer than the thickness.
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
            // Two folds' edges: as far apart as the lesser fold is sharp.
            let thickness = if pair.folds == NO_FOLDS {
                thickness
            } else {
                let share = |faces| fold_share(faces, &topology.triangles, x);
                thickness * share(pair.folds[0]).min(share(pair.folds[1]))
            };
            if gap >= thickness {
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

    /// The pass over part `k` of the pairs
    /// ([`PassPlane`](super::pass_plane::PassPlane)); returns how many were
    /// closer than the thickness.
    pub(super) fn part_pass(
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
    pub(super) fn block_pass(
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
    pub(super) fn pair_pass(
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
        // Out in the rim the layer thins to nothing at its outer edge.
        let thickness = thickness * rim_taper(bary, slack);
        if d >= thickness {
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
pub(super) struct Near {
    pub(super) t: u32,
    pub(super) tri: [usize; 3],
    pub(super) a: Vector,
    pub(super) e1: Vector,
    pub(super) e2: Vector,
    pub(super) normal: Vector,
    pub(super) len2: f32,
    pub(super) slack: Option<Option<(f32, [f32; 3])>>,
}

impl Near {
    /// Triangle `t` with corners `tri` at positions `x`.
    #[inline]
    pub(super) fn of(
        t: u32,
        tri: [u32; 3],
        x: &impl std::ops::Index<usize, Output = Vector>,
    ) -> Near {
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
    pub(super) fn rim_slack(&mut self, thickness: f32) -> Option<(f32, [f32; 3])> {
        *self.slack.get_or_insert_with(|| {
            let len = self.len2.sqrt();
            let edges = edge_lengths((self.e1, self.e2));
            is_positive(len).then(|| (len, rim_slack(rim(thickness, edges), edges, len)))
        })
    }
}
