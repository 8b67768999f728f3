//! A still cuboid as the lanes take it: its frame, its faces, its tangent
//! planes, one lane at a time or eight in AVX2.

use super::lanes::W;
use crate::collision::EDGE_SAMPLES;
use crate::math::Vector;

/// A still cuboid as the lanes take it
/// ([`StillShape::Cuboid`](super::shape::StillShape::Cuboid)): a lane is held
/// by the tangent plane of the rounded cuboid at the point nearest to where it
/// started the substep, as the collision stage's contact planes hold it, when
/// it started within `reach` (m) of the cuboid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StillCuboid {
    pub(super) centre: Vector,
    pub(super) axes: [Vector; 3],
    pub(super) half: Vector,
    pub(super) thickness: f32,
    pub(super) reach: f32,
    /// How far (m) within the thickness a lane may start and still be
    /// put out to it ([`cuboid_plane`]).
    pub(super) settle: f32,
    /// Which of the lanes' plane records is this cuboid's.
    pub(super) slot: usize,
}

impl StillCuboid {
    /// How far (m) out along one of its axes a lane must start to be
    /// surely beyond its reach ([`far_from_cuboid`]): the reach and a
    /// margin over the rounding of the distance to it.
    #[inline(always)]
    pub(super) fn far(&self) -> f32 {
        self.reach * (1.0 + 1.0e-4)
    }

    /// Whether the cuboid's bounding box grown by `margin` (m), and a hair
    /// for rounding, meets the box `(lo, hi)` (m).
    pub(super) fn box_meets(&self, (lo, hi): (Vector, Vector), margin: f32) -> bool {
        let extent = self.axes[0].abs() * self.half.x
            + self.axes[1].abs() * self.half.y
            + self.axes[2].abs() * self.half.z;
        let grown = extent + Vector::splat(margin * (1.0 + 1.0e-3) + 1.0e-6);
        let (min, max) = (self.centre - grown, self.centre + grown);
        min.cmple(hi).all() && lo.cmple(max).all()
    }

    /// Where `p` (m) is in the cuboid's frame: per axis, the coordinate
    /// and how far beyond the face on that side it is (m, negative inside).
    #[inline(always)]
    pub(super) fn local(&self, p: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let d = [
            p[0] - self.centre.x,
            p[1] - self.centre.y,
            p[2] - self.centre.z,
        ];
        let half = [self.half.x, self.half.y, self.half.z];
        let mut local = [0.0f32; 3];
        let mut beyond = [0.0f32; 3];
        for a in 0..3 {
            let axis = self.axes[a];
            local[a] = axis.x * d[0] + axis.y * d[1] + axis.z * d[2];
            beyond[a] = local[a].abs() - half[a];
        }
        (local, beyond)
    }
}

impl StillCuboid {
    /// The faces `p` (m) is at least `margin` (m) beyond or over: bit `2a`
    /// for the face on the positive side of axis `a`, bit `2a + 1` for the
    /// negative; over a face is on its side of the centre and within the
    /// face's rectangle along the other two axes. A segment whose two ends
    /// share a bit comes no nearer the cuboid than its nearer end (a face's
    /// plane has the cuboid behind it, and over the face the distance is
    /// the height above its plane, which changes linearly along the
    /// segment): nothing to keep off an edge there, and the ends are the
    /// lanes' contacts' (the collision stage's edge pass passes over such
    /// springs too: both ends on one smooth stretch of surface). A sheet
    /// laid within the thickness of a ramp's face is so left to the
    /// contacts, which put it out gently, not thrown out by the springs.
    /// Without a branch.
    #[inline(always)]
    pub(super) fn faces_beyond(&self, p: [f32; 3], margin: f32) -> u8 {
        let (local, beyond) = self.local(p);
        let half = [self.half.x, self.half.y, self.half.z];
        let within = beyond.map(|b| b <= 0.0);
        let mut bits = 0u8;
        for a in 0..3 {
            let out = half[a] + margin;
            let over = within[(a + 1) % 3] & within[(a + 2) % 3];
            bits |= u8::from((local[a] >= out) | (over & (local[a] >= 0.0))) << (2 * a);
            bits |= u8::from((local[a] <= -out) | (over & (local[a] < 0.0))) << (2 * a + 1);
        }
        bits
    }

    /// [`Self::faces_beyond`] for every lane at `p` (m), into `faces`
    /// (without a branch: with them, the loop was 7% of the `box`'s
    /// frame, 4% so).
    pub(super) fn mark_faces_beyond(&self, p: [&[f32]; 3], margin: f32, faces: &mut [u8]) {
        let n = faces.len();
        let [x, y, z] = p.map(|a| &a[..n]);
        for k in 0..n {
            faces[k] = self.faces_beyond([x[k], y[k], z[k]], margin);
        }
    }

    /// Whether `p` (m) is surely at least `margin` (m) out of the cuboid
    /// (outside it by the square of its distance: no root).
    #[inline(always)]
    pub(super) fn surely_beyond(&self, p: [f32; 3], margin: f32) -> bool {
        let (_, beyond) = self.local(p);
        let over = beyond.map(|b| b.max(0.0));
        over[0] * over[0] + over[1] * over[1] + over[2] * over[2] >= margin * margin
    }

    /// The signed distance (m, negative inside) of `p` (m) from the
    /// cuboid itself (not rounded), and the outward unit normal there:
    /// outside, from the nearest point of the surface; inside, of the
    /// nearest face (the first of equals).
    pub(super) fn signed_distance(&self, p: [f32; 3]) -> (f32, [f32; 3]) {
        let (local, beyond) = self.local(p);
        let over = beyond.map(|b| b.max(0.0));
        let dist2 = over[0] * over[0] + over[1] * over[1] + over[2] * over[2];
        let mut normal_local = [0.0f32; 3];
        let distance = if dist2 > 0.0 {
            let dist = dist2.sqrt();
            for a in 0..3 {
                normal_local[a] = (over[a] / dist).copysign(local[a]);
            }
            dist
        } else {
            let face = if beyond[0] >= beyond[1] && beyond[0] >= beyond[2] {
                0
            } else if beyond[1] >= beyond[2] {
                1
            } else {
                2
            };
            normal_local[face] = 1.0f32.copysign(local[face]);
            beyond[face]
        };
        let [u, v, w] = self.axes;
        let normal = u * normal_local[0] + v * normal_local[1] + w * normal_local[2];
        (distance, [normal.x, normal.y, normal.z])
    }

    /// The collision stage's edge pass on one spring against this cuboid
    /// (`CollisionStage::resolve_spring`): its ends at `pa` and `pb` (m,
    /// inverse masses `wa`, `wb`) moved so that its samples lie at least
    /// `margin` (m) out of it. Returns the farthest it moved an end (m).
    pub(super) fn keep_spring_off(
        &self,
        (pa, wa): (&mut [f32; 3], f32),
        (pb, wb): (&mut [f32; 3], f32),
        margin: f32,
    ) -> f32 {
        if wa == 0.0 && wb == 0.0 {
            return 0.0;
        }
        // A pinned end held inside cannot be moved out: pushing the free
        // end would only shove it about.
        let pinned_inside = |p: [f32; 3], w: f32| w == 0.0 && self.signed_distance(p).0 < 0.0;
        if pinned_inside(*pa, wa) || pinned_inside(*pb, wb) {
            return 0.0;
        }
        let mut farthest = 0.0f32;
        for t in EDGE_SAMPLES {
            let sample: [f32; 3] = std::array::from_fn(|c| pa[c] * (1.0 - t) + pb[c] * t);
            if self.surely_beyond(sample, margin) {
                continue;
            }
            let (distance, normal) = self.signed_distance(sample);
            // Not a number: nothing known to push by.
            if distance >= margin || distance.is_nan() {
                continue;
            }
            let (ca, cb) = ((1.0 - t) * wa, t * wb);
            let denom = (1.0 - t) * ca + t * cb;
            if denom <= 0.0 {
                continue;
            }
            let push = (margin - distance) / denom;
            for c in 0..3 {
                pa[c] += normal[c] * (push * ca);
                pb[c] += normal[c] * (push * cb);
            }
            farthest = farthest.max(push * ca.max(cb));
        }
        farthest
    }
}

/// Bit `i` set for each `i < count` (at most 32) where `fa[i]` and `fb[i]`
/// share no face (the spring between them may come near the cuboid): on
/// x86-64 sixteen at a time in SSE2 (which every such CPU has).
#[inline(always)]
pub(super) fn apart_from_faces(fa: &[u8], fb: &[u8], count: usize) -> u32 {
    let (fa, fb) = (&fa[..count], &fb[..count]);
    let mut due = 0u32;
    let mut i = 0;
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        while i + 16 <= count {
            // SAFETY: bytes `i..i + 16` are within both (checked above);
            // SSE2 is part of x86-64.
            let shared = unsafe {
                let a = _mm_loadu_si128(fa.as_ptr().add(i) as *const __m128i);
                let b = _mm_loadu_si128(fb.as_ptr().add(i) as *const __m128i);
                _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_and_si128(a, b), _mm_setzero_si128()))
            };
            due |= (shared as u32) << i;
            i += 16;
        }
    }
    while i < count {
        due |= u32::from(fa[i] & fb[i] == 0) << i;
        i += 1;
    }
    due
}

/// The point of `cuboid` rounded by its thickness nearest to `p` (m), and
/// the outward normal there: outside the cuboid, through the nearest point
/// of its surface; in it, out through the nearest face (the lanes hold a
/// cuboid only while a substep's motion is small beside it, so that is
/// the face the lane came in by). Also whether `p` is outside the cuboid
/// itself, and how far (m) from it. Branch-free, as the AVX2 pass runs it
/// (the same operations in the same order).
#[inline(always)]
pub(super) fn cuboid_nearest(cuboid: &StillCuboid, p: [f32; 3]) -> ([f32; 3], [f32; 3], bool, f32) {
    let (local, beyond) = cuboid.local(p);
    let half = [cuboid.half.x, cuboid.half.y, cuboid.half.z];
    let t = cuboid.thickness;
    let over = beyond.map(|b| if b > 0.0 { b } else { 0.0 });
    let dist2 = over[0] * over[0] + over[1] * over[1] + over[2] * over[2];
    let outside = dist2 > 0.0;
    let dist = dist2.sqrt();
    let recip = 1.0 / dist;
    let scale = t * recip;
    // In the cuboid: the face it is least far in from (the first of equals).
    let x_face = (beyond[0] >= beyond[1]) & (beyond[0] >= beyond[2]);
    let y_face = !x_face & (beyond[1] >= beyond[2]);
    let face = [x_face, y_face, !x_face & !y_face];
    let mut delta = [0.0f32; 3];
    let mut normal_local = [0.0f32; 3];
    for a in 0..3 {
        let sign = 1.0f32.copysign(local[a]);
        let abs = local[a].abs();
        let out_delta = if beyond[a] > 0.0 {
            (half[a] + over[a] * scale) - abs
        } else {
            0.0
        };
        let face_delta = if face[a] { (half[a] + t) - abs } else { 0.0 };
        delta[a] = (if outside { out_delta } else { face_delta }) * sign;
        let face_normal = if face[a] { 1.0 } else { 0.0 };
        normal_local[a] = (if outside {
            over[a] * recip
        } else {
            face_normal
        }) * sign;
    }
    let [u, v, w] = cuboid.axes;
    let (u, v, w) = ([u.x, u.y, u.z], [v.x, v.y, v.z], [w.x, w.y, w.z]);
    let mut to = [0.0f32; 3];
    let mut normal = [0.0f32; 3];
    for c in 0..3 {
        to[c] = p[c] + (u[c] * delta[0] + v[c] * delta[1] + w[c] * delta[2]);
        normal[c] = u[c] * normal_local[0] + v[c] * normal_local[1] + w[c] * normal_local[2];
    }
    (to, normal, outside, dist)
}

/// The plane (unit normal, offset in m) that holds a lane starting the
/// substep at `start` against `cuboid`: the tangent plane of the rounded
/// cuboid at the point nearest to `start`, when `start` is within the
/// cuboid's reach; otherwise none (an offset of −∞). A plane from where
/// the lane started, not the nearest point where it is, as the collision
/// stage's contact planes take it: a lane the springs pull over an edge
/// is held by the face it was on (the stage's edge pass takes the springs
/// round the edge). The rounded cuboid is convex: a lane on its plane's
/// side is outside it.
#[inline(always)]
pub(super) fn cuboid_plane(cuboid: &StillCuboid, start: [f32; 3]) -> ([f32; 3], f32) {
    if far_from_cuboid(cuboid, start) {
        return ([0.0; 3], f32::NEG_INFINITY);
    }
    let (on, normal, outside, dist) = cuboid_nearest(cuboid, start);
    let applies = if outside { dist < cuboid.reach } else { true };
    let offset = normal[0] * on[0] + normal[1] * on[1] + normal[2] * on[2];
    let from = normal[0] * start[0] + normal[1] * start[1] + normal[2] * start[2];
    // A lane that starts deep within the thickness (a cloth laid on the
    // cuboid by hand) is held where it starts along the normal: put out
    // to the thickness in one substep it would leave at the push over the
    // substep (a sheet laid 1 cm into a ramp took off at 38 m/s); the
    // collision stage's pass takes it out.
    let deep = from < offset - cuboid.settle;
    let offset = if deep { from } else { offset };
    (normal, if applies { offset } else { f32::NEG_INFINITY })
}

/// Whether a lane starting at `start` is surely beyond the reach of
/// `cuboid`: further out along one of its axes than [`StillCuboid::far`].
/// Its plane is then none, with a zero normal, told without the root and
/// division of the nearest point (the plane found so would be none too).
#[inline(always)]
pub(super) fn far_from_cuboid(cuboid: &StillCuboid, start: [f32; 3]) -> bool {
    let (_, beyond) = cuboid.local(start);
    beyond[0].max(beyond[1]).max(beyond[2]) > cuboid.far()
}

/// The planes of `cuboid` ([`cuboid_plane`]) for lanes starting at
/// `start` with inverse masses `w`, into `out` (normal x, y, z, offset),
/// eight at a time in AVX2 when `simd`. A pinned lane's is none: no pass
/// moves it (the bars the `tear` hangs from hold its edges' particles
/// within their reach).
pub(super) fn planes_of(
    cuboid: &StillCuboid,
    (start, w): ([&[f32]; 3], &[f32]),
    out: &mut [&mut [f32]; 4],
    simd: bool,
) {
    let n = start[0].len();
    assert!(start.iter().all(|s| s.len() == n) && out.iter().all(|o| o.len() == n));
    assert!(w.len() == n);
    let mut k = 0;
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        k = unsafe { planes_avx2(cuboid, (start, w), out) };
    }
    let _ = simd;
    for k in k..n {
        let (normal, offset) = if w[k] == 0.0 {
            ([0.0; 3], f32::NEG_INFINITY)
        } else {
            cuboid_plane(cuboid, [start[0][k], start[1][k], start[2][k]])
        };
        for a in 0..3 {
            out[a][k] = normal[a];
        }
        out[3][k] = offset;
    }
}

/// The planes of `cuboid` ([`planes_of`]) for lanes starting at `start`
/// with inverse masses `w` when it moves by `shift` (m) over the substep,
/// `cuboid` being where it is at the substep's end: each taken from where
/// its lane started relative to the cuboid (at the cuboid where it was at
/// the substep's start), then moved with it. A still cuboid's are
/// [`planes_of`]'s own.
pub(super) fn moved_planes_of(
    (cuboid, shift): (&StillCuboid, Vector),
    (start, w): ([&[f32]; 3], &[f32]),
    out: &mut [&mut [f32]; 4],
    simd: bool,
) {
    if shift == Vector::ZERO {
        planes_of(cuboid, (start, w), out, simd);
        return;
    }
    let before = StillCuboid {
        centre: cuboid.centre - shift,
        ..*cuboid
    };
    planes_of(&before, (start, w), out, simd);
    let [nx, ny, nz, offset] = out;
    let n = offset.len();
    assert!([nx.len(), ny.len(), nz.len()] == [n; 3]);
    for k in 0..n {
        // No plane (−∞) stays none.
        offset[k] += nx[k] * shift.x + ny[k] * shift.y + nz[k] * shift.z;
    }
}

/// [`planes_of`] for every whole eight lanes, in AVX2; returns how many
/// lanes it took (the rest are left to the portable pass).
#[target_feature(enable = "avx2")]
pub(super) unsafe fn planes_avx2(
    cuboid: &StillCuboid,
    (start, w): ([&[f32]; 3], &[f32]),
    out: &mut [&mut [f32]; 4],
) -> usize {
    crate::math::align_frame();
    use std::arch::x86_64::*;
    let n = start[0].len();
    assert!(start.iter().all(|s| s.len() == n) && out.iter().all(|o| o.len() == n));
    assert!(w.len() == n);
    let mut k = 0;
    while k + W <= n {
        // SAFETY: lanes `k..k + 8` are within every array (asserted).
        let s = [
            _mm256_loadu_ps(start[0].as_ptr().add(k)),
            _mm256_loadu_ps(start[1].as_ptr().add(k)),
            _mm256_loadu_ps(start[2].as_ptr().add(k)),
        ];
        let pinned =
            _mm256_cmp_ps::<_CMP_EQ_OQ>(_mm256_loadu_ps(w.as_ptr().add(k)), _mm256_setzero_ps());
        let local = cuboid_local_avx2(cuboid, s);
        let far = _mm256_or_ps(far_from_cuboid_avx2(cuboid, local), pinned);
        let (normal, offset) = if _mm256_movemask_ps(far) == 0xff {
            // All eight far or pinned: the kernel's sqrt and division for
            // nothing (the `tear`'s two bars over its sheet, planes a
            // seventh of the frame before).
            ([_mm256_setzero_ps(); 3], _mm256_set1_ps(f32::NEG_INFINITY))
        } else {
            let (normal, offset) = cuboid_plane_avx2(cuboid, (s, local));
            (
                normal.map(|n| _mm256_andnot_ps(far, n)),
                _mm256_blendv_ps(offset, _mm256_set1_ps(f32::NEG_INFINITY), far),
            )
        };
        for a in 0..3 {
            _mm256_storeu_ps(out[a].as_mut_ptr().add(k), normal[a]);
        }
        _mm256_storeu_ps(out[3].as_mut_ptr().add(k), offset);
        k += W;
    }
    k
}

/// Where eight lanes at `p` (m) are in the frame of `cuboid` (m along
/// each of its axes from its centre), as [`StillCuboid::local`] finds
/// them, in AVX2 registers: the same operations in the same order. Found
/// once for both [`far_from_cuboid_avx2`] and [`cuboid_plane_avx2`].
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn cuboid_local_avx2(
    cuboid: &StillCuboid,
    p: [std::arch::x86_64::__m256; 3],
) -> [std::arch::x86_64::__m256; 3] {
    // Loops over the axes, not closures ([`cuboid_plane_avx2`] says why).
    use std::arch::x86_64::*;
    let centre = [cuboid.centre.x, cuboid.centre.y, cuboid.centre.z];
    let mut d = [_mm256_setzero_ps(); 3];
    for a in 0..3 {
        d[a] = _mm256_sub_ps(p[a], _mm256_set1_ps(centre[a]));
    }
    let mut local = [_mm256_setzero_ps(); 3];
    for a in 0..3 {
        let axis = cuboid.axes[a];
        local[a] = _mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(_mm256_set1_ps(axis.x), d[0]),
                _mm256_mul_ps(_mm256_set1_ps(axis.y), d[1]),
            ),
            _mm256_mul_ps(_mm256_set1_ps(axis.z), d[2]),
        );
    }
    local
}

/// Which of eight lanes at `local` in the frame of `cuboid`
/// ([`cuboid_local_avx2`]) are surely beyond its reach
/// ([`far_from_cuboid`]), in AVX2 registers: the same operations in the
/// same order.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn far_from_cuboid_avx2(
    cuboid: &StillCuboid,
    local: [std::arch::x86_64::__m256; 3],
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let sign_bit = _mm256_set1_ps(-0.0);
    let half = [cuboid.half.x, cuboid.half.y, cuboid.half.z];
    let mut most = _mm256_set1_ps(f32::NEG_INFINITY);
    for a in 0..3 {
        let beyond = _mm256_sub_ps(
            _mm256_andnot_ps(sign_bit, local[a]),
            _mm256_set1_ps(half[a]),
        );
        most = _mm256_max_ps(most, beyond);
    }
    _mm256_cmp_ps::<_CMP_GT_OQ>(most, _mm256_set1_ps(cuboid.far()))
}

/// [`cuboid_plane`] for eight lanes that start at `start`, in AVX2
/// registers: the same operations in the same order, without fused
/// multiply-add, so the same bits.
#[target_feature(enable = "avx2")]
#[inline]
pub(super) unsafe fn cuboid_plane_avx2(
    cuboid: &StillCuboid,
    (start, local): (
        [std::arch::x86_64::__m256; 3],
        [std::arch::x86_64::__m256; 3],
    ),
) -> ([std::arch::x86_64::__m256; 3], std::arch::x86_64::__m256) {
    // Written with loops over the three axes, not closures: a closure
    // does not take the function's AVX2 and was called with its vectors
    // in memory (planes a ninth of the `box`'s frame so).
    use std::arch::x86_64::*;
    let zero = _mm256_setzero_ps();
    let one = _mm256_set1_ps(1.0);
    let all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    let sign_bit = _mm256_set1_ps(-0.0);
    let t = _mm256_set1_ps(cuboid.thickness);
    let half = [cuboid.half.x, cuboid.half.y, cuboid.half.z];
    let mut axes = [[zero; 3]; 3];
    for a in 0..3 {
        let axis = cuboid.axes[a];
        axes[a] = [
            _mm256_set1_ps(axis.x),
            _mm256_set1_ps(axis.y),
            _mm256_set1_ps(axis.z),
        ];
    }
    let (mut abs, mut sign, mut beyond) = ([zero; 3], [zero; 3], [zero; 3]);
    let (mut positive, mut over) = ([zero; 3], [zero; 3]);
    for a in 0..3 {
        let local = local[a];
        abs[a] = _mm256_andnot_ps(sign_bit, local);
        sign[a] = _mm256_or_ps(_mm256_and_ps(local, sign_bit), one);
        beyond[a] = _mm256_sub_ps(abs[a], _mm256_set1_ps(half[a]));
        positive[a] = _mm256_cmp_ps::<_CMP_GT_OQ>(beyond[a], zero);
        over[a] = _mm256_and_ps(positive[a], beyond[a]);
    }
    let dist2 = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(over[0], over[0]),
            _mm256_mul_ps(over[1], over[1]),
        ),
        _mm256_mul_ps(over[2], over[2]),
    );
    let outside = _mm256_cmp_ps::<_CMP_GT_OQ>(dist2, zero);
    let dist = _mm256_sqrt_ps(dist2);
    let recip = _mm256_div_ps(one, dist);
    let scale = _mm256_mul_ps(t, recip);
    let x_face = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GE_OQ>(beyond[0], beyond[1]),
        _mm256_cmp_ps::<_CMP_GE_OQ>(beyond[0], beyond[2]),
    );
    let y_face = _mm256_andnot_ps(x_face, _mm256_cmp_ps::<_CMP_GE_OQ>(beyond[1], beyond[2]));
    let z_face = _mm256_andnot_ps(_mm256_or_ps(x_face, y_face), all);
    let face = [x_face, y_face, z_face];
    let mut delta = [zero; 3];
    let mut normal_local = [zero; 3];
    for a in 0..3 {
        let h = _mm256_set1_ps(half[a]);
        let out_delta = _mm256_and_ps(
            positive[a],
            _mm256_sub_ps(_mm256_add_ps(h, _mm256_mul_ps(over[a], scale)), abs[a]),
        );
        let face_delta = _mm256_and_ps(face[a], _mm256_sub_ps(_mm256_add_ps(h, t), abs[a]));
        delta[a] = _mm256_mul_ps(_mm256_blendv_ps(face_delta, out_delta, outside), sign[a]);
        let face_normal = _mm256_and_ps(face[a], one);
        normal_local[a] = _mm256_mul_ps(
            _mm256_blendv_ps(face_normal, _mm256_mul_ps(over[a], recip), outside),
            sign[a],
        );
    }
    let [u, v, w] = axes;
    let (mut on, mut normal) = ([zero; 3], [zero; 3]);
    for c in 0..3 {
        let moved = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(u[c], delta[0]), _mm256_mul_ps(v[c], delta[1])),
            _mm256_mul_ps(w[c], delta[2]),
        );
        on[c] = _mm256_add_ps(start[c], moved);
        normal[c] = _mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(u[c], normal_local[0]),
                _mm256_mul_ps(v[c], normal_local[1]),
            ),
            _mm256_mul_ps(w[c], normal_local[2]),
        );
    }
    let applies = _mm256_or_ps(
        _mm256_andnot_ps(outside, all),
        _mm256_cmp_ps::<_CMP_LT_OQ>(dist, _mm256_set1_ps(cuboid.reach)),
    );
    let offset = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(normal[0], on[0]),
            _mm256_mul_ps(normal[1], on[1]),
        ),
        _mm256_mul_ps(normal[2], on[2]),
    );
    let from = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(normal[0], start[0]),
            _mm256_mul_ps(normal[1], start[1]),
        ),
        _mm256_mul_ps(normal[2], start[2]),
    );
    let deep = _mm256_sub_ps(offset, _mm256_set1_ps(cuboid.settle));
    let offset = _mm256_blendv_ps(offset, from, _mm256_cmp_ps::<_CMP_LT_OQ>(from, deep));
    let none = _mm256_set1_ps(f32::NEG_INFINITY);
    (normal, _mm256_blendv_ps(none, offset, applies))
}
