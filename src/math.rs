//! The math types of parry3d and rapier3d (glam-based, `f32`), so a rapier
//! user passes their own values straight in; and whether the CPU has the
//! vector lanes the kernels use.

pub use parry3d::math::{Pose, Real, Rotation, Vector};

/// The `f32`s of a [`Vector`], which lie in a row (glam's `Vec3` is
/// `repr(C)`): the AVX2 kernels that read and write arrays of vectors as
/// arrays of `f32` (the lanes' motion, the self-collision pass and due
/// test) count on it, and the build stops if it ever changes.
pub(crate) const VECTOR_F32S: usize = 3;
const _: () = assert!(std::mem::size_of::<Vector>() == VECTOR_F32S * std::mem::size_of::<f32>());

/// True when the CPU has AVX2: the vectorised kernels (the grid sweep, the
/// wind's lanes) then run their loops in 8-lane registers; without it the
/// same loops run with the baseline's lanes and give the same bits.
pub(crate) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Eight vectors of an array of [`Vector`]s starting at `base` (as
/// `f32`s), those at `index`, as a register of x, one of y and one of z:
/// each one masked load of its three floats (the fourth may lie past the
/// array's end), the eight then turned into coordinates by unpacks and
/// shuffles. Three gathers a register took longer (the self-collision
/// pass's test, where they were: the `stack` at rest 12.5 -> 10.8 ms a
/// frame on one thread).
///
/// # Safety
/// The CPU has AVX2; each index is of a vector in the array.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn load_vectors(
    base: *const f32,
    index: [usize; 8],
) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let xyz = _mm_setr_epi32(-1, -1, -1, 0);
    // SAFETY: each index of a vector in the array (the caller's promise);
    // the masked load reads its three floats alone.
    let at = |l: usize| unsafe { _mm_maskload_ps(base.add(VECTOR_F32S * index[l]), xyz) };
    let pair = |l: usize| _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(at(l)), at(l + 4));
    let (t0, t1, t2, t3) = (pair(0), pair(1), pair(2), pair(3));
    let (u0, u1) = (_mm256_unpacklo_ps(t0, t1), _mm256_unpackhi_ps(t0, t1));
    let (u2, u3) = (_mm256_unpacklo_ps(t2, t3), _mm256_unpackhi_ps(t2, t3));
    [
        _mm256_shuffle_ps::<0x44>(u0, u2),
        _mm256_shuffle_ps::<0xEE>(u0, u2),
        _mm256_shuffle_ps::<0x44>(u1, u3),
    ]
}

/// Eight vectors' dot products with eight others, each given as a
/// register of x, one of y and one of z: `(u.x v.x + u.y v.y) + u.z v.z`,
/// as `Vector::dot` sums them (the same bits lane by lane).
///
/// # Safety
/// The CPU has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn dot_lanes(
    u: [std::arch::x86_64::__m256; 3],
    v: [std::arch::x86_64::__m256; 3],
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let m = |p, q| _mm256_mul_ps(p, q);
    _mm256_add_ps(_mm256_add_ps(m(u[0], v[0]), m(u[1], v[1])), m(u[2], v[2]))
}

/// Eight vectors' cross products `u × v`, coordinates as in
/// [`dot_lanes`], as `Vector::cross` forms them (the same bits).
///
/// # Safety
/// The CPU has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) unsafe fn cross_lanes(
    u: [std::arch::x86_64::__m256; 3],
    v: [std::arch::x86_64::__m256; 3],
) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let m = |p, q| _mm256_mul_ps(p, q);
    [
        _mm256_sub_ps(m(u[1], v[2]), m(v[1], u[2])),
        _mm256_sub_ps(m(u[2], v[0]), m(v[2], u[0])),
        _mm256_sub_ps(m(u[0], v[1]), m(v[0], u[1])),
    ]
}

/// Aligns the stack frame of the function it is inlined into to a cache
/// line: the first statement of each AVX2 kernel that keeps vectors on
/// its stack. Rust keeps the stack 16-byte aligned, and the 32-byte
/// vectors a kernel spills were then split across cache lines or not by
/// how deep its caller's frames happened to be, one build to another: a
/// load after a split spill waited (the drape at N = 128 on two threads,
/// 3.29–3.33 ms a frame in one build of the same source, 3.00–3.09 in
/// another; the sweep's kernel with its frame aligned, 3.00–3.08 in the
/// slow one). A local that needs the alignment makes the compiler align
/// the frame, and its spills with it.
#[inline(always)]
pub(crate) fn align_frame() {
    #[repr(align(64))]
    struct Line(#[allow(dead_code)] [u8; 64]);
    // A local, not `&Line(..)`, which would be promoted to a static.
    let line = Line([0; 64]);
    std::hint::black_box(&line);
}
