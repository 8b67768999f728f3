//! The geometry the looks and the passes share.

use crate::math::Vector;

/// The lengths (m) of a triangle's edges opposite its corners a, b and c,
/// from its edges `e1 = b − a` and `e2 = c − a`: `|e2 − e1|`, `|e2|`,
/// `|e1|` (three roots a triangle, shared by [`rim`], [`rim_slack`] and a
/// look's sheet).
#[inline]
pub(super) fn edge_lengths((e1, e2): (Vector, Vector)) -> [f32; 3] {
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
pub(super) fn rim_slack(out: f32, edges: [f32; 3], len: f32) -> [f32; 3] {
    // The altitude onto an edge is `len / |edge|`; u belongs to corner a,
    // whose opposite edge is `e2 − e1`.
    edges.map(|edge| out * edge / len)
}

/// The share of the layers' thickness a particle at barycentrics `bary`
/// in a triangle's rim keeps (1 over the triangle): `√(1 − ℓ²)`, with `ℓ`
/// how far it lies outside the triangle's edges as a share of the rim
/// (`slack`, [`rim_slack`]; over two edges, the root of the squares'
/// sum). So the layer ends in a rounded edge, as far out as the rim
/// reaches, and a particle sliding into the rim meets it gradually; with
/// the whole thickness out to the rim's edge it met a step of up to
/// half the thickness, and two cotton sheets at rest on a ball jittered
/// by up to 7 mm a frame, ten times a second, at their borders.
#[inline]
pub(super) fn rim_taper(bary: [f32; 3], slack: [f32; 3]) -> f32 {
    let out: f32 = (0..3)
        .map(|k| {
            // Outside an edge only: the slack is positive there.
            let r = if bary[k] < 0.0 {
                bary[k] / slack[k]
            } else {
                0.0
            };
            r * r
        })
        .sum();
    (1.0 - out).max(0.0).sqrt()
}

/// The rim of a triangle (m): the thickness, but at most a quarter of its
/// shortest edge, so that the particles beyond the rest-mesh neighbours of
/// a flat cloth never fall within it. `edges` are the edges' lengths
/// ([`edge_lengths`]; the least of the roots is the root of the least
/// square, to the bit, roots being rounded correctly).
#[inline]
pub(super) fn rim(thickness: f32, [bc, ac, ab]: [f32; 3]) -> f32 {
    thickness.min(0.25 * ab.min(ac).min(bc))
}

/// Barycentric coordinates clamped to the triangle and summing to one.
#[inline]
pub(super) fn clamped([u, v, w]: [f32; 3]) -> [f32; 3] {
    let [u, v, w] = [u.max(0.0), v.max(0.0), w.max(0.0)];
    let sum = u + v + w;
    [u / sum, v / sum, w / sum]
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
pub(super) fn side_at(d: f32) -> f32 {
    if d >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// +1 or −1 by the sign of `x`; none for zero or not a number.
#[inline]
pub(super) fn sign(x: f32) -> Option<f32> {
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

/// Where two segments `a + s u` and `p + t v` come closest, when that is
/// inside both (`0 < s, t < 1`) and they are not near parallel: `(s, t)`
/// and the unit normal `u × v / |u × v|`.
#[inline]
pub(super) fn closest(a: Vector, u: Vector, p: Vector, v: Vector) -> Option<(f32, f32, Vector)> {
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
