//! How badly a cloth passes through itself: pairs of a particle and a
//! triangle that are not neighbours in the rest mesh ([`MeshNeighbours`])
//! and sit closer than half the layers' thickness
//! ([`Cloth::self_thickness`]), inside the triangle; and pairs
//! of a triangle edge and a triangle without a common corner that cross.
//! What every run reports as `self_intersections`.

use super::neighbours::MeshNeighbours;
use super::self_contacts::{barycentric, is_positive};
use super::spatial_hash::SpatialHash;
use crate::cloth::Cloth;
use crate::math::Vector;

/// Counts the cloth's self-intersections (module docs) at its current
/// positions. Allocates its scratch; for measuring, not for a step.
pub fn self_intersections(cloth: &Cloth) -> usize {
    let x = cloth.positions();
    let topology = cloth.topology();
    let mut neighbours = MeshNeighbours::default();
    neighbours.update(topology, x.len());
    let near = 0.5 * cloth.self_thickness();
    // Edges are found through their lower end, which lies within an edge's
    // length of any triangle the edge crosses.
    let longest = (0..x.len() as u32)
        .flat_map(|p| neighbours.edges_from(p).iter().map(move |&q| (p, q)))
        .map(|(p, q)| (x[p as usize] - x[q as usize]).length())
        .filter(|l| l.is_finite())
        .fold(0.0f32, f32::max);
    let mut hash = SpatialHash::default();
    hash.build(x, longest.max(near).max(1.0e-4));
    let mut count = 0;
    for tri in cloth.triangles() {
        let [a, b, c] = tri.map(|i| x[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let normal = e1.cross(e2);
        let len = normal.length();
        if !is_positive(len) {
            continue;
        }
        let n = normal / len;
        let pad = Vector::splat(longest.max(near));
        let (lo, hi) = (a.min(b).min(c) - pad, a.max(b).max(c) + pad);
        hash.for_each_in(lo, hi, |p| {
            let xp = x[p as usize];
            let d = (xp - a).dot(n);
            if d.abs() < near
                && barycentric(xp - n * d - a, e1, e2)
                    .iter()
                    .all(|&w| w >= 0.0)
                && !neighbours.near(p, *tri)
            {
                count += 1;
            }
            for &q in neighbours.edges_from(p) {
                if !tri.contains(&p)
                    && !tri.contains(&q)
                    && crosses((xp, x[q as usize]), (a, e1, e2, n))
                {
                    count += 1;
                }
            }
        });
    }
    count
}

/// True when the segment `p..q` passes through the triangle at `a` with
/// edges `e1`, `e2` and unit normal `n` (its ends strictly on either side).
fn crosses((p, q): (Vector, Vector), (a, e1, e2, n): (Vector, Vector, Vector, Vector)) -> bool {
    let (dp, dq) = ((p - a).dot(n), (q - a).dot(n));
    if !is_positive(-(dp * dq)) {
        return false;
    }
    let hit = p + (q - p) * (dp / (dp - dq));
    barycentric(hit - a, e1, e2).iter().all(|&w| w >= 0.0)
}
