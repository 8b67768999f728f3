//! A vector step of lanes: its width, a whole step of a run, and the reach of a
//! ball as the kernels compare it.

/// Lanes of one vector step of [`run_lanes`](super::portable::run_lanes)
/// (AVX2's eight `f32`).
pub(super) const W: usize = 8;

/// `run` as an array of eight lanes.
#[inline(always)]
pub(super) fn whole(run: &mut [f32]) -> &mut [f32; W] {
    run.try_into().expect("eight lanes")
}

/// A squared distance from a ball's centre under which a lane may be
/// inside it, `reach` (m) out: the square of `reach` with a margin for the
/// rounding of a squared distance (never under it where the exact test,
/// `sqrt(d²) < reach`, holds).
#[inline(always)]
pub(super) fn near_ball(reach: f32) -> f32 {
    reach * reach * (1.0 + 1.0e-5)
}
