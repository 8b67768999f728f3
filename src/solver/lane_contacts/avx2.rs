//! The lanes' contact kernels in AVX2, eight lanes a step.

use super::chunk::{Chunk, Law};
use super::lanes::{near_ball, W};
use super::portable::run_lanes;
use super::shape::StillShape;
use super::still_cuboid::StillCuboid;
use crate::math::Vector;
use crate::solver::lane_convex::StillConvex;
use crate::solver::lane_mesh::StillMesh;

/// [`run_lanes`] with AVX2 intrinsics for every whole step of eight lanes,
/// straight from the chunk's arrays and back (written as arrays selected
/// lane by lane, the whole steps compiled to masked stores whose reloads
/// could not be forwarded: a sixth of the drape's frame at N = 128); the
/// short last step as the portable pass runs it.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn run_avx2(mut chunk: Chunk, law: &Law) -> f32 {
    crate::math::align_frame();
    use std::arch::x86_64::*;
    let n = chunk.len();
    let whole = n - n % W;
    // Once a chunk, for the steps' unchecked loads of the cuboids' planes
    // (checked in every step, the comparison of the arrays' lengths went
    // through the stack and stalled on store forwarding: half of this
    // pass on the `box`).
    law.check_planes(chunk.first + whole);
    let mut far = _mm256_setzero_ps();
    // Whether a shape moves, once a chunk: the relative slide's three
    // more vectors in every step cost the still scenes a tenth of the pass.
    if law.shifts.is_some() {
        for k in (0..whole).step_by(W) {
            eight_avx2::<true>(&mut chunk, k, law, &mut far);
        }
    } else {
        for k in (0..whole).step_by(W) {
            eight_avx2::<false>(&mut chunk, k, law, &mut far);
        }
    }
    let rest = run_lanes(chunk.from(whole), law);
    let mut lanes = [0.0f32; W];
    _mm256_storeu_ps(lanes.as_mut_ptr(), far);
    lanes.into_iter().fold(rest, f32::max)
}

/// [`eight`](super::portable::eight) on lanes `k..k + 8` of `c` (all in it), in
/// AVX2 registers: the same operations in the same order, without fused
/// multiply-add, so the same bits; keeps in `far` the farthest push of each
/// lane. Writes nothing where no lane is inside a shape nor (with friction) was
/// pushed this substep: the pass would leave every bit as it is.
///
/// # Safety
/// The CPU has AVX2, and [`Law::check_planes`] held for lanes up to
/// `c.first + k + 8`.
#[target_feature(enable = "avx2")]
pub(super) unsafe fn eight_avx2<const MOVING: bool>(
    c: &mut Chunk,
    k: usize,
    law: &Law,
    far: &mut std::arch::x86_64::__m256,
) {
    use std::arch::x86_64::*;
    let at = k..k + W;
    let (x, y, z) = (
        c.x[at.clone()].as_mut_ptr(),
        c.y[at.clone()].as_mut_ptr(),
        c.z[at.clone()].as_mut_ptr(),
    );
    let depth_at = c.depth[at.clone()].as_mut_ptr();
    let touch_at = c.touch[at.clone()].as_mut_ptr() as *mut __m256i;
    let mut p = [_mm256_loadu_ps(x), _mm256_loadu_ps(y), _mm256_loadu_ps(z)];
    let zero = _mm256_setzero_ps();
    let free = _mm256_cmp_ps::<_CMP_NEQ_UQ>(_mm256_loadu_ps(c.w[at.clone()].as_ptr()), zero);
    let mut depth = _mm256_loadu_ps(depth_at);
    let mut touch = _mm256_castsi256_ps(_mm256_loadu_si256(touch_at));
    let mut normal = [zero; 3];
    let mut mu = zero;
    let mut shift = [zero; 3];
    let mut any_inside = zero;
    for (o, &shape) in law.shapes.iter().enumerate() {
        let mark = _mm256_castsi256_ps(_mm256_set1_epi32(o as i32 + 1));
        // The lanes this shape pushed last (a lane it pushed goes on
        // taking its normal and friction even when now clear of it).
        let its = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_castps_si256(touch),
            _mm256_castps_si256(mark),
        ));
        let (to, n, inside, push);
        match shape {
            StillShape::Ball { centre, reach } => {
                let centre = [centre.x, centre.y, centre.z].map(|v| _mm256_set1_ps(v));
                let Some(out) = round_avx2(p, (centre, reach, shape.way_out()), (its, free)) else {
                    continue;
                };
                (to, n, inside, push) = out;
            }
            StillShape::Capsule {
                from,
                axis,
                length,
                reach,
                ..
            } => {
                let from = [from.x, from.y, from.z].map(|v| _mm256_set1_ps(v));
                let u = [axis.x, axis.y, axis.z].map(|v| _mm256_set1_ps(v));
                let d = [0, 1, 2].map(|a| _mm256_sub_ps(p[a], from[a]));
                let along = _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(d[0], u[0]), _mm256_mul_ps(d[1], u[1])),
                    _mm256_mul_ps(d[2], u[2]),
                );
                let t = _mm256_min_ps(_mm256_max_ps(along, zero), _mm256_set1_ps(length));
                let centre = [0, 1, 2].map(|a| _mm256_add_ps(from[a], _mm256_mul_ps(u[a], t)));
                let Some(out) = round_avx2(p, (centre, reach, shape.way_out()), (its, free)) else {
                    continue;
                };
                (to, n, inside, push) = out;
            }
            StillShape::Plane { normal: m, offset } => {
                let m = [m.x, m.y, m.z].map(|v| _mm256_set1_ps(v));
                let (gap, on) = behind_plane_avx2(m, _mm256_set1_ps(offset), p);
                n = m;
                to = on;
                inside = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(gap, zero), free);
                push = _mm256_and_ps(inside, gap);
            }
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => {
                // This lane's plane, taken at the substep's start.
                // SAFETY: within every plane array, checked once a chunk
                // (`Law::check_planes`).
                let at = slot * law.lanes + c.first + k;
                let [px, py, pz, po] = law.planes;
                debug_assert!(
                    at + W <= po.len() && [px.len(), py.len(), pz.len()] == [po.len(); 3]
                );
                let m = [
                    _mm256_loadu_ps(px.as_ptr().add(at)),
                    _mm256_loadu_ps(py.as_ptr().add(at)),
                    _mm256_loadu_ps(pz.as_ptr().add(at)),
                ];
                let offset = _mm256_loadu_ps(po.as_ptr().add(at));
                let (gap, on) = behind_plane_avx2(m, offset, p);
                let behind = _mm256_cmp_ps::<_CMP_GT_OQ>(gap, zero);
                // No lane behind its plane nor last pushed by it: as for
                // the ball.
                if _mm256_movemask_ps(_mm256_or_ps(behind, its)) == 0 {
                    continue;
                }
                n = m;
                to = on;
                inside = _mm256_and_ps(behind, free);
                push = _mm256_and_ps(inside, gap);
            }
        }
        let coefficient = _mm256_set1_ps(law.friction.map_or(0.0, |f| f[o]));
        p = [0, 1, 2].map(|a| _mm256_blendv_ps(p[a], to[a], inside));
        depth = _mm256_add_ps(depth, push);
        touch = _mm256_blendv_ps(touch, mark, inside);
        // No push is NaN or −0: `max` as `f32::max` takes it.
        *far = _mm256_max_ps(*far, push);
        any_inside = _mm256_or_ps(any_inside, inside);
        let this = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_castps_si256(touch),
            _mm256_castps_si256(mark),
        ));
        normal = [0, 1, 2].map(|a| _mm256_blendv_ps(normal[a], n[a], this));
        mu = _mm256_blendv_ps(mu, coefficient, this);
        if let (true, Some(shifts)) = (MOVING, law.shifts) {
            let s = shifts[o];
            let s = [s.x, s.y, s.z].map(|v| _mm256_set1_ps(v));
            shift = [0, 1, 2].map(|a| _mm256_blendv_ps(shift[a], s[a], this));
        }
    }
    let touched = _mm256_xor_ps(
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_castps_si256(touch),
            _mm256_setzero_si256(),
        )),
        _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
    );
    let slides = law.friction.is_some() && _mm256_movemask_ps(touched) != 0;
    if _mm256_movemask_ps(any_inside) == 0 && !slides {
        return;
    }
    if slides {
        let start = c.start.map(|s| _mm256_loadu_ps(s[at.clone()].as_ptr()));
        let mut slide = [0, 1, 2].map(|a| _mm256_sub_ps(p[a], start[a]));
        if MOVING {
            // Relative to the surface, which moved too.
            slide = [0, 1, 2].map(|a| _mm256_sub_ps(slide[a], shift[a]));
        }
        let along = _mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(normal[0], slide[0]),
                _mm256_mul_ps(normal[1], slide[1]),
            ),
            _mm256_mul_ps(normal[2], slide[2]),
        );
        let tangent = [0, 1, 2].map(|a| _mm256_sub_ps(slide[a], _mm256_mul_ps(normal[a], along)));
        let length = _mm256_sqrt_ps(_mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(tangent[0], tangent[0]),
                _mm256_mul_ps(tangent[1], tangent[1]),
            ),
            _mm256_mul_ps(tangent[2], tangent[2]),
        ));
        let allowed = _mm256_mul_ps(mu, depth);
        let whole = _mm256_cmp_ps::<_CMP_LE_OQ>(length, allowed);
        let scale = _mm256_div_ps(allowed, length);
        p = [0, 1, 2].map(|a| {
            let undone = _mm256_blendv_ps(_mm256_mul_ps(tangent[a], scale), tangent[a], whole);
            _mm256_blendv_ps(p[a], _mm256_sub_ps(p[a], undone), touched)
        });
    }
    _mm256_storeu_ps(x, p[0]);
    _mm256_storeu_ps(y, p[1]);
    _mm256_storeu_ps(z, p[2]);
    _mm256_storeu_ps(depth_at, depth);
    _mm256_storeu_si256(touch_at, _mm256_castps_si256(touch));
}

/// Eight lanes at `p` (m) against balls of radius `reach` (m) at `centre`
/// (m, one a lane), a lane at a squared distance up to `tiny` (m²) from
/// its centre put out along `up` ([`StillShape::way_out`]): the point each
/// is put back to, the outward normal, which lanes are inside (and free:
/// `free`) and how far they are pushed (m), as the portable pass computes
/// them; `None` when no lane is near its ball nor last pushed by this
/// shape (`its`): the shape would change no bit, and its square root and
/// division are the pass's dearest operations.
#[target_feature(enable = "avx2")]
#[inline]
#[allow(clippy::type_complexity)]
pub(super) unsafe fn round_avx2(
    p: [std::arch::x86_64::__m256; 3],
    (centre, reach, (up, tiny)): ([std::arch::x86_64::__m256; 3], f32, (Vector, f32)),
    (its, free): (std::arch::x86_64::__m256, std::arch::x86_64::__m256),
) -> Option<(
    [std::arch::x86_64::__m256; 3],
    [std::arch::x86_64::__m256; 3],
    std::arch::x86_64::__m256,
    std::arch::x86_64::__m256,
)> {
    use std::arch::x86_64::*;
    let d = [0, 1, 2].map(|a| _mm256_sub_ps(p[a], centre[a]));
    let d2 = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(d[0], d[0]), _mm256_mul_ps(d[1], d[1])),
        _mm256_mul_ps(d[2], d[2]),
    );
    // With a margin for the rounding of the square.
    let near = _mm256_cmp_ps::<_CMP_LT_OQ>(d2, _mm256_set1_ps(near_ball(reach)));
    if _mm256_movemask_ps(_mm256_or_ps(near, its)) == 0 {
        return None;
    }
    let reach = _mm256_set1_ps(reach);
    let length = _mm256_sqrt_ps(d2);
    let recip = _mm256_div_ps(_mm256_set1_ps(1.0), length);
    // At the centre itself: out along `up`.
    let at_centre = _mm256_cmp_ps::<_CMP_LE_OQ>(d2, _mm256_set1_ps(tiny));
    let up = [up.x, up.y, up.z];
    let n = [0, 1, 2]
        .map(|a| _mm256_blendv_ps(_mm256_mul_ps(d[a], recip), _mm256_set1_ps(up[a]), at_centre));
    let to = [0, 1, 2].map(|a| _mm256_add_ps(centre[a], _mm256_mul_ps(n[a], reach)));
    let inside = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(length, reach), free);
    let push = _mm256_and_ps(inside, _mm256_sub_ps(reach, length));
    Some((to, n, inside, push))
}

/// Eight lanes at `p` (m) against the half-spaces `m · x ≥ offset` (unit
/// normals `m`, offsets in m): how far behind its plane each is (m,
/// negative in front) and its point on the plane, as the portable pass
/// computes them.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn behind_plane_avx2(
    m: [std::arch::x86_64::__m256; 3],
    offset: std::arch::x86_64::__m256,
    p: [std::arch::x86_64::__m256; 3],
) -> (std::arch::x86_64::__m256, [std::arch::x86_64::__m256; 3]) {
    use std::arch::x86_64::*;
    let gap = _mm256_sub_ps(
        offset,
        _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(m[0], p[0]), _mm256_mul_ps(m[1], p[1])),
            _mm256_mul_ps(m[2], p[2]),
        ),
    );
    let on = [
        _mm256_add_ps(p[0], _mm256_mul_ps(m[0], gap)),
        _mm256_add_ps(p[1], _mm256_mul_ps(m[1], gap)),
        _mm256_add_ps(p[2], _mm256_mul_ps(m[2], gap)),
    ];
    (gap, on)
}
