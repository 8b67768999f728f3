//! The lanes' contact kernels without AVX2: the same floats, eight lanes a step
//! in plain arrays.

use super::chunk::{Chunk, Law};
use super::lanes::{near_ball, whole, W};
use super::shape::StillShape;
use super::still_cuboid::StillCuboid;
use crate::solver::lane_convex::StillConvex;
use crate::solver::lane_mesh::StillMesh;

/// Eight lanes of a chunk, copied into registers: positions now and at
/// the substep's start (m), inverse masses, pushes (m) and marks.
#[derive(Clone, Copy)]
pub(super) struct Eight {
    /// The index of the first among all lanes, and how many are lanes
    /// (the rest pad a short last step).
    pub(super) at: usize,
    pub(super) count: usize,
    pub(super) p: [[f32; W]; 3],
    pub(super) start: [[f32; W]; 3],
    pub(super) w: [f32; W],
    pub(super) depth: [f32; W],
    pub(super) touch: [u32; W],
}

impl Eight {
    /// The half-space (unit normal, offset: `normal · x ≥ offset`) that
    /// `shape` holds lane `k` of these eight in: a plane's own, a
    /// cuboid's plane for the lane; none (an offset of −∞) for a ball.
    #[inline(always)]
    pub(super) fn half_space(&self, law: &Law, shape: StillShape, k: usize) -> ([f32; 3], f32) {
        match shape {
            StillShape::Plane { normal, offset } => ([normal.x, normal.y, normal.z], offset),
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => self.plane(law, slot, k),
            StillShape::Ball { .. } | StillShape::Capsule { .. } => ([0.0; 3], f32::NEG_INFINITY),
        }
    }

    /// The plane (normal, offset) of lane `k` of these eight in the
    /// cuboid's `slot` (none for padding).
    #[inline(always)]
    pub(super) fn plane(&self, law: &Law, slot: usize, k: usize) -> ([f32; 3], f32) {
        if k < self.count {
            law.plane(slot, self.at + k)
        } else {
            ([0.0; 3], f32::NEG_INFINITY)
        }
    }
}

/// The pass of `law` over the lanes of `c`, eight at a time on copies in
/// registers, written back whole (as one loop over lanes, or through
/// references the compiler could not prove apart, it stayed scalar: a
/// quarter of the frame at N = 64). The last, short step runs on copies
/// padded with pinned lanes. Returns the farthest push (m).
#[inline(always)]
pub(super) fn run_lanes(c: Chunk, law: &Law) -> f32 {
    let n = c.len();
    let mut farthest = [0.0f32; W];
    let mut k = 0;
    while k < n {
        let m = W.min(n - k);
        let mut e = Eight {
            at: c.first + k,
            count: m,
            p: [[0.0; W]; 3],
            start: [[0.0; W]; 3],
            w: [0.0; W],
            depth: [0.0; W],
            touch: [0; W],
        };
        if m == W {
            e.p = [
                c.x[k..k + W].try_into().expect("eight"),
                c.y[k..k + W].try_into().expect("eight"),
                c.z[k..k + W].try_into().expect("eight"),
            ];
            // Eight lanes clear of every shape and (for friction) pushed by
            // none this substep: the pass would leave every bit as it is.
            let touched = || c.touch[k..k + W].iter().any(|&t| t != 0);
            if !maybe_inside(&e, law) && (law.friction.is_none() || !touched()) {
                k += W;
                continue;
            }
            if law.friction.is_some() {
                for a in 0..3 {
                    e.start[a] = c.start[a][k..k + W].try_into().expect("eight");
                }
            }
            e.w = c.w[k..k + W].try_into().expect("eight");
            e.depth = c.depth[k..k + W].try_into().expect("eight");
            e.touch = c.touch[k..k + W].try_into().expect("eight");
        } else {
            e.p[0][..m].copy_from_slice(&c.x[k..n]);
            e.p[1][..m].copy_from_slice(&c.y[k..n]);
            e.p[2][..m].copy_from_slice(&c.z[k..n]);
            for a in 0..3 {
                e.start[a][..m].copy_from_slice(&c.start[a][k..n]);
            }
            e.w[..m].copy_from_slice(&c.w[k..n]);
            e.depth[..m].copy_from_slice(&c.depth[k..n]);
            e.touch[..m].copy_from_slice(&c.touch[k..n]);
        }
        eight(&mut e, law, &mut farthest);
        let out = &e;
        if m == W {
            // Stores of a known length, in registers (`copy_from_slice`
            // of a run of unknown length calls `memmove`: 14% of the
            // frame at N = 64).
            *whole(&mut c.x[k..k + W]) = out.p[0];
            *whole(&mut c.y[k..k + W]) = out.p[1];
            *whole(&mut c.z[k..k + W]) = out.p[2];
            *whole(&mut c.depth[k..k + W]) = out.depth;
            let touch: &mut [u32; W] = (&mut c.touch[k..k + W]).try_into().expect("eight");
            *touch = out.touch;
        } else {
            c.x[k..n].copy_from_slice(&out.p[0][..m]);
            c.y[k..n].copy_from_slice(&out.p[1][..m]);
            c.z[k..n].copy_from_slice(&out.p[2][..m]);
            c.depth[k..n].copy_from_slice(&out.depth[..m]);
            c.touch[k..n].copy_from_slice(&out.touch[..m]);
        }
        k += m;
    }
    farthest.into_iter().fold(0.0, f32::max)
}

/// Whether a lane of `e` may lie inside one of the shapes of `law` (the
/// test of [`eight`], with a margin for the rounding of a squared
/// distance: never false where that test is true).
#[inline(always)]
pub(super) fn maybe_inside(e: &Eight, law: &Law) -> bool {
    let p = &e.p;
    let mut any = false;
    for &shape in law.shapes {
        match shape {
            StillShape::Ball { reach, .. } | StillShape::Capsule { reach, .. } => {
                let near = near_ball(reach);
                for k in 0..W {
                    let c = shape.centre_for([p[0][k], p[1][k], p[2][k]]);
                    let d = [p[0][k] - c[0], p[1][k] - c[1], p[2][k] - c[2]];
                    any |= d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < near;
                }
            }
            StillShape::Plane { normal: m, offset } => {
                for k in 0..W {
                    any |= offset - (m.x * p[0][k] + m.y * p[1][k] + m.z * p[2][k]) > 0.0;
                }
            }
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => {
                for k in 0..W {
                    let (m, offset) = e.plane(law, slot, k);
                    any |= offset - (m[0] * e.p[0][k] + m[1] * e.p[1][k] + m[2] * e.p[2][k]) > 0.0;
                }
            }
        }
    }
    any
}

/// [`run_lanes`] on eight lanes, without branches (in place: moving the
/// lanes in and out by value was a `memmove` call); keeps in `farthest`
/// the farthest push of each.
#[inline(always)]
pub(super) fn eight(e: &mut Eight, law: &Law, farthest: &mut [f32; W]) {
    // Each lane's normal and friction coefficient: those of the shape
    // that last pushed it (zero for none).
    let mut normal = [[0.0f32; W]; 3];
    let mut mu = [0.0f32; W];
    let mut shift = [[0.0f32; W]; 3];
    for (o, &shape) in law.shapes.iter().enumerate() {
        let mark = o as u32 + 1;
        let mut to = [[0.0f32; W]; 3];
        let mut n = [[0.0f32; W]; 3];
        let mut push = [0.0f32; W];
        let mut inside = [false; W];
        match shape {
            StillShape::Ball { reach, .. } | StillShape::Capsule { reach, .. } => {
                let (up, tiny) = shape.way_out();
                for k in 0..W {
                    let c = shape.centre_for([e.p[0][k], e.p[1][k], e.p[2][k]]);
                    let d = [e.p[0][k] - c[0], e.p[1][k] - c[1], e.p[2][k] - c[2]];
                    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let length = d2.sqrt();
                    let recip = 1.0 / length;
                    // At the centre itself: out along `up`.
                    let at_centre = d2 <= tiny;
                    for a in 0..3 {
                        let up = [up.x, up.y, up.z][a];
                        n[a][k] = if at_centre { up } else { d[a] * recip };
                        to[a][k] = c[a] + n[a][k] * reach;
                    }
                    inside[k] = (length < reach) & (e.w[k] != 0.0);
                    push[k] = if inside[k] { reach - length } else { 0.0 };
                }
            }
            StillShape::Plane { .. }
            | StillShape::Cuboid(_)
            | StillShape::Convex(_)
            | StillShape::Mesh(_) => {
                for k in 0..W {
                    let (m, offset) = e.half_space(law, shape, k);
                    let gap = offset - (m[0] * e.p[0][k] + m[1] * e.p[1][k] + m[2] * e.p[2][k]);
                    for a in 0..3 {
                        n[a][k] = m[a];
                        to[a][k] = e.p[a][k] + m[a] * gap;
                    }
                    inside[k] = (gap > 0.0) & (e.w[k] != 0.0);
                    push[k] = if inside[k] { gap } else { 0.0 };
                }
            }
        }
        let coefficient = law.friction.map_or(0.0, |f| f[o]);
        let moves = law.shifts.map_or([0.0; 3], |s| [s[o].x, s[o].y, s[o].z]);
        for k in 0..W {
            for a in 0..3 {
                e.p[a][k] = if inside[k] { to[a][k] } else { e.p[a][k] };
            }
            e.depth[k] += push[k];
            e.touch[k] = if inside[k] { mark } else { e.touch[k] };
            farthest[k] = farthest[k].max(push[k]);
            let this = e.touch[k] == mark;
            for a in 0..3 {
                normal[a][k] = if this { n[a][k] } else { normal[a][k] };
            }
            mu[k] = if this { coefficient } else { mu[k] };
            for a in 0..3 {
                shift[a][k] = if this { moves[a] } else { shift[a][k] };
            }
        }
    }
    if law.friction.is_none() {
        return;
    }
    for k in 0..W {
        let mut slide = [
            e.p[0][k] - e.start[0][k],
            e.p[1][k] - e.start[1][k],
            e.p[2][k] - e.start[2][k],
        ];
        if law.shifts.is_some() {
            // Relative to the surface, which moved too.
            for a in 0..3 {
                slide[a] -= shift[a][k];
            }
        }
        let n = [normal[0][k], normal[1][k], normal[2][k]];
        let along = n[0] * slide[0] + n[1] * slide[1] + n[2] * slide[2];
        let tangent = [
            slide[0] - n[0] * along,
            slide[1] - n[1] * along,
            slide[2] - n[2] * along,
        ];
        let length =
            (tangent[0] * tangent[0] + tangent[1] * tangent[1] + tangent[2] * tangent[2]).sqrt();
        let allowed = mu[k] * e.depth[k];
        let whole = length <= allowed;
        let scale = allowed / length;
        let touched = e.touch[k] != 0;
        for a in 0..3 {
            let undone = if whole {
                tangent[a]
            } else {
                tangent[a] * scale
            };
            e.p[a][k] = if touched {
                e.p[a][k] - undone
            } else {
                e.p[a][k]
            };
        }
    }
}
