//! The particles' motion in the small-steps solver's lanes while its state
//! stays there between substeps (`xpbd.rs`): the end of one substep (each
//! lane's velocity from its motion) and the prediction of the next (gravity
//! and air drag, no wind), in one pass. Each lane takes the operations
//! `xpbd::predict` and `xpbd::correct_velocity` make on a particle, in the
//! same order, so the bits are those of the particles' own arrays.
//!
//! Eight lanes at a time on copies in registers, written back whole, in
//! AVX2 where the CPU has it: as one loop over lanes the pass stayed scalar
//! (a tenth of the drape's frame at N = 128, perf, one thread).

use crate::math::{simd_available, Vector};

/// Lanes of one vector step (AVX2's eight `f32`).
const W: usize = 8;

/// What moves the lanes over a substep: gravity (m/s²), air drag (1/s)
/// and the substep's length `h` (s).
#[derive(Debug, Clone, Copy)]
pub(super) struct Motion {
    pub gravity: Vector,
    pub drag: f32,
    pub h: f32,
}

/// One band's lanes: positions x, y, z, positions at the substep's start
/// x, y, z, inverse masses (the lanes' order, `grid_sweep::Lanes`), and
/// velocities x, y, z; all of one length.
pub(super) type BandState<'a> = ([&'a mut [f32]; 7], [&'a mut [f32]; 3]);

/// Ends a substep and predicts the next on the lanes of `band`: each free
/// lane's velocity gains its correction (where it is less where it was
/// predicted to be, the start plus `h` times its velocity, over `h`); the
/// start becomes where the lane is; the velocity gains gravity less drag
/// over `h` and the lane moves by it (a pinned lane keeps its velocity and
/// moves by it). Returns the largest squared speed (m²/s²) after it.
pub(super) fn correct_and_predict(band: BandState, motion: Motion) -> f32 {
    #[cfg(target_arch = "x86_64")]
    if simd_available() {
        // SAFETY: only where the CPU has AVX2.
        return unsafe { correct_and_predict_avx2(band, motion) };
    }
    correct_and_predict_eights(band, motion)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn correct_and_predict_avx2(band: BandState, motion: Motion) -> f32 {
    crate::math::align_frame();
    correct_and_predict_eights(band, motion)
}

/// [`correct_and_predict`], eight lanes at a time; the last, short step on
/// copies padded with pinned lanes at rest.
#[inline(always)]
fn correct_and_predict_eights(mut band: BandState, m: Motion) -> f32 {
    let n = band.0[0].len();
    let arrays = band.0.iter().chain(&band.1);
    assert!(
        arrays.map(|a| a.len()).all(|len| len == n),
        "a band's arrays of one length"
    );
    let mut fast2 = [0.0f32; W];
    let mut k = 0;
    while k + W <= n {
        // A constant length: the copies are vector loads and stores.
        step(&mut band, k, W, m, &mut fast2);
        k += W;
    }
    if k < n {
        step(&mut band, k, n - k, m, &mut fast2);
    }
    fast2.into_iter().fold(0.0, f32::max)
}

/// Lanes `k..k + len` (`len` at most [`W`]) of the band, on copies.
#[inline(always)]
fn step(
    ([lx, ly, lz, sx, sy, sz, lw], [vx, vy, vz]): &mut BandState,
    k: usize,
    len: usize,
    m: Motion,
    fast2: &mut [f32; W],
) {
    let mut e = Eight::default();
    let lanes = k..k + len;
    for (to, from) in e.x.iter_mut().zip([&*lx, &*ly, &*lz]) {
        to[..len].copy_from_slice(&from[lanes.clone()]);
    }
    for (to, from) in e.start.iter_mut().zip([&*sx, &*sy, &*sz]) {
        to[..len].copy_from_slice(&from[lanes.clone()]);
    }
    for (to, from) in e.v.iter_mut().zip([&*vx, &*vy, &*vz]) {
        to[..len].copy_from_slice(&from[lanes.clone()]);
    }
    e.w[..len].copy_from_slice(&lw[lanes.clone()]);
    eight(&mut e, m, fast2);
    for (from, to) in e.x.iter().zip([&mut **lx, &mut **ly, &mut **lz]) {
        to[lanes.clone()].copy_from_slice(&from[..len]);
    }
    for (from, to) in e.start.iter().zip([&mut **sx, &mut **sy, &mut **sz]) {
        to[lanes.clone()].copy_from_slice(&from[..len]);
    }
    for (from, to) in e.v.iter().zip([&mut **vx, &mut **vy, &mut **vz]) {
        to[lanes.clone()].copy_from_slice(&from[..len]);
    }
}

/// Eight lanes in registers: positions, starts (m), velocities (m/s) and
/// inverse masses (1/kg); zeros (a pinned lane at rest) by default.
#[derive(Default, Clone, Copy)]
struct Eight {
    x: [[f32; W]; 3],
    start: [[f32; W]; 3],
    v: [[f32; W]; 3],
    w: [f32; W],
}

/// [`correct_and_predict`] on eight lanes, without branches; keeps in
/// `fast2` the largest squared speed of each.
#[inline(always)]
fn eight(e: &mut Eight, m: Motion, fast2: &mut [f32; W]) {
    let (g, h) = (m.gravity.to_array(), m.h);
    // Into new arrays, not over the old: a pinned lane's velocity selected
    // back over itself became a masked store, whose reads right after
    // could not be forwarded (the pass was a seventh of the drape's frame
    // at N = 128, perf, one thread).
    let mut out = Eight {
        w: e.w,
        ..Eight::default()
    };
    for k in 0..W {
        let free = e.w[k] != 0.0;
        let mut speed2 = 0.0;
        for a in 0..3 {
            // The end of the substep (`correct_velocity`).
            let predicted = e.start[a][k] + e.v[a][k] * h;
            let swept = e.x[a][k];
            let v = if free {
                e.v[a][k] + (swept - predicted) / h
            } else {
                e.v[a][k]
            };
            // The next one's prediction (`predict`).
            let v = if free { v + (g[a] - v * m.drag) * h } else { v };
            out.start[a][k] = swept;
            out.x[a][k] = swept + v * h;
            out.v[a][k] = v;
            speed2 += v * v;
        }
        fast2[k] = fast2[k].max(speed2);
    }
    *e = out;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 21 lanes (two steps and a tail), every third pinned: (positions,
    /// starts, inverse masses, velocities), jittered.
    fn band() -> ([Vec<f32>; 7], [Vec<f32>; 3]) {
        let n = 21;
        let f = |s: f32| {
            (0..n)
                .map(|i| ((i as f32 + s) * 0.731).sin())
                .collect::<Vec<f32>>()
        };
        let w = (0..n)
            .map(|i| if i % 3 == 0 { 0.0 } else { 40.0 })
            .collect();
        (
            [f(0.0), f(1.0), f(2.0), f(3.0), f(4.0), f(5.0), w],
            [f(6.0), f(7.0), f(8.0)],
        )
    }

    fn run(simd: bool) -> ([Vec<f32>; 7], [Vec<f32>; 3], f32) {
        let (mut l, mut v) = band();
        let motion = Motion {
            gravity: Vector::new(0.0, -9.81, 0.0),
            drag: 0.3,
            h: 1.0 / 960.0,
        };
        let state = (
            l.each_mut().map(|a| &mut a[..]),
            v.each_mut().map(|a| &mut a[..]),
        );
        let fast2 = if simd {
            correct_and_predict(state, motion)
        } else {
            correct_and_predict_eights(state, motion)
        };
        (l, v, fast2)
    }

    #[test]
    fn each_lane_moves_as_a_particle_does() {
        let (l0, v0) = band();
        let (l, v, fast2) = run(false);
        let h = 1.0 / 960.0;
        let mut fastest = 0.0f32;
        for k in 0..21 {
            let at = |a: &[Vec<f32>], i: usize| Vector::new(a[i][k], a[i + 1][k], a[i + 2][k]);
            let (x, start, mut vel) = (at(&l0, 0), at(&l0, 3), at(&v0, 0));
            let w = l0[6][k];
            // As the particles' path makes them: the end of the substep,
            // then the next prediction.
            let predicted = start + vel * h;
            super::super::xpbd::correct_velocity(&mut vel, x - predicted, w, h);
            if w != 0.0 {
                vel += (Vector::new(0.0, -9.81, 0.0) - vel * 0.3) * h;
            }
            let next = x + vel * h;
            assert_eq!(
                at(&l, 0).to_array().map(f32::to_bits),
                next.to_array().map(f32::to_bits)
            );
            assert_eq!(at(&l, 3), x, "lane {k}: the start is where it was");
            assert_eq!(
                at(&v, 0).to_array().map(f32::to_bits),
                vel.to_array().map(f32::to_bits)
            );
            fastest = fastest.max(vel.length_squared());
            if w == 0.0 {
                assert_eq!(at(&v, 0), at(&v0, 0), "lane {k} is pinned");
            }
        }
        assert_eq!(fast2, fastest);
    }

    #[test]
    fn the_vectorised_pass_gives_the_bits_of_the_portable_one() {
        let bits = |(l, v, f): ([Vec<f32>; 7], [Vec<f32>; 3], f32)| -> Vec<u32> {
            l.iter()
                .chain(&v)
                .flatten()
                .chain([&f])
                .map(|x| x.to_bits())
                .collect()
        };
        assert_eq!(bits(run(true)), bits(run(false)));
    }
}
