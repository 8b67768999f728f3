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
