//! A still cuboid as the lanes take it: its frame, its faces and its tangent
//! planes.

#[cfg(target_arch = "x86_64")]
use super::avx2::planes_avx2;
use crate::collision::EDGE_SAMPLES;
use crate::math::Vector;

/// A still cuboid as the lanes take it
/// ([`StillShape::Cuboid`](super::StillShape::Cuboid)): a lane is held by the
/// tangent plane of the rounded cuboid at the point nearest to where it started
/// the substep, as the collision stage's contact planes hold it, when it
/// started within `reach` (m) of the cuboid.
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
