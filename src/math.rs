//! The math types of parry3d and rapier3d (glam-based, `f32`), so a rapier
//! user passes their own values straight in; and whether the CPU has the
//! vector lanes the kernels use.

pub use parry3d::math::{Pose, Real, Rotation, Vector};

/// True when the CPU has AVX2: the vectorised kernels (the grid sweep, the
/// wind's lanes) then run their loops in 8-lane registers; without it the
/// same loops run with the baseline's lanes and give the same bits.
pub(crate) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    false
}
