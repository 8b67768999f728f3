//! The particles' motion in the small-steps solver's lanes while its state
//! stays there between substeps (`xpbd.rs`): the end of one substep (each
//! lane's velocity from its motion) and the prediction of the next (gravity
//! and air drag, no wind), in one pass. Each lane takes the operations
//! `xpbd::predict` and [`correct_velocity`] make on a particle, in the
//! same order, so the bits are those of the particles' own arrays.
//!
//! Also the prediction of a substep whose state does not stay in the
//! lanes ([`predict_into_lanes`]): on the particles' own arrays, copied
//! into the lanes as it goes.
//!
//! Eight lanes at a time on copies in registers, written back whole, in
//! AVX2 where the CPU has it: as one loop over lanes the pass stayed scalar
//! (a tenth of the drape's frame at N = 128, perf, one thread).

use crate::math::{simd_available, Vector, VECTOR_F32S};

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

/// The velocity at the end of a substep of `h` seconds: the predicted one
/// plus what the sweeps moved the particle, over `h` (pinned particles keep
/// theirs). Here, with the passes that take it lane by lane, so that the
/// integrator (`xpbd.rs`) and they share one definition.
#[inline(always)]
pub(super) fn correct_velocity(v: &mut Vector, correction: Vector, inv_mass: f32, h: f32) {
    if inv_mass != 0.0 {
        *v += correction / h;
    }
}

/// One band's particles as the prediction reads and writes them:
/// positions (m) and velocities (m/s), inverse masses (1/kg), the wind's
/// forces on them (N; none in calm air) and each one's lane (the band's
/// lanes start at `first_lane`); all of one length.
pub(super) struct BandParticles<'a> {
    pub x: &'a mut [Vector],
    pub v: &'a mut [Vector],
    pub w: &'a [f32],
    pub wind: Option<&'a [Vector]>,
    pub lane: &'a [u32],
    pub first_lane: usize,
}

/// Predicts a substep on the particles of a band, as `xpbd::predict` does
/// each (the velocity gains gravity less drag, and the wind's force over
/// the mass, over `h`; the particle moves by it; a pinned one keeps its
/// velocity and moves by it), and copies them into their lanes: positions
/// now and at the substep's start, inverse masses, and velocities when
/// `velocities` are given. Returns the largest squared speed (m²/s²)
/// after it.
pub(super) fn predict_into_lanes(
    mut p: BandParticles,
    mut lanes: [&mut [f32]; 7],
    mut velocities: Option<[&mut [f32]; 3]>,
    motion: Motion,
) -> f32 {
    let n = p.x.len();
    let lengths = [p.v.len(), p.w.len(), p.lane.len()]
        .into_iter()
        .chain(p.wind.map(<[Vector]>::len))
        .chain(lanes.iter().map(|l| l.len()))
        .chain(velocities.iter().flatten().map(|l| l.len()));
    assert!(
        lengths.into_iter().all(|len| len == n),
        "a band's arrays of one length"
    );
    let mut fast2 = [0.0f32; W];
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if simd_available() {
        // SAFETY: only where the CPU has AVX2; every array is `n` long.
        done = unsafe { predict_avx2(&mut p, &mut lanes, &mut velocities, motion, &mut fast2) };
    }
    let particles = &mut (p, lanes, velocities);
    for k in (done..n).step_by(W) {
        predict_eight_portable(particles, k..(k + W).min(n), motion, &mut fast2);
    }
    fast2.into_iter().fold(0.0, f32::max)
}

/// A band's particles with their lanes and velocity lanes, as
/// [`predict_into_lanes`] takes them.
type Prediction<'a, 'b> = (
    BandParticles<'a>,
    [&'b mut [f32]; 7],
    Option<[&'b mut [f32]; 3]>,
);

/// [`predict_into_lanes`] on the whole steps of eight particles: their
/// positions and velocities turned from three `f32` a particle into a
/// register a coordinate by shuffles and back, the lanes' stores one at a
/// time (the autovectorised copies went through the stack and stayed near
/// a hundred instructions a particle, as the scalar loop was). Returns
/// how many particles it did. Needs every array `n` long.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn predict_avx2(
    p: &mut BandParticles,
    lanes: &mut [&mut [f32]; 7],
    velocities: &mut Option<[&mut [f32]; 3]>,
    m: Motion,
    fast2: &mut [f32; W],
) -> usize {
    use std::arch::x86_64::*;
    let n = p.x.len();
    let steps = n / W;
    let g = m.gravity.to_array().map(|c| _mm256_set1_ps(c));
    let (drag, h, zero) = (
        _mm256_set1_ps(m.drag),
        _mm256_set1_ps(m.h),
        _mm256_setzero_ps(),
    );
    let mut fast = _mm256_loadu_ps(fast2.as_ptr());
    let (x, v) = (p.x.as_mut_ptr() as *mut f32, p.v.as_mut_ptr() as *mut f32);
    let wind = p.wind.map(|f| f.as_ptr() as *const f32);
    for step in 0..steps {
        let k = step * W;
        // SAFETY (for the loads and stores): particles k..k + 8 are in
        // every array, three `f32` each (`Vector` is `repr(C)`).
        let x0 = load_three(x.add(VECTOR_F32S * k));
        let v0 = load_three(v.add(VECTOR_F32S * k));
        let w = _mm256_loadu_ps(p.w.as_ptr().add(k));
        // `w != 0.0`, true for NaN as the scalar test is.
        let free = _mm256_cmp_ps::<_CMP_NEQ_UQ>(w, zero);
        let f = wind.map(|f| load_three(f.add(VECTOR_F32S * k)));
        let mut vn = [zero; 3];
        let mut xn = [zero; 3];
        for a in 0..3 {
            let mut acc = _mm256_sub_ps(g[a], _mm256_mul_ps(v0[a], drag));
            if let Some(f) = f {
                acc = _mm256_add_ps(acc, _mm256_mul_ps(f[a], w));
            }
            let moved = _mm256_add_ps(v0[a], _mm256_mul_ps(acc, h));
            vn[a] = _mm256_blendv_ps(v0[a], moved, free);
            xn[a] = _mm256_add_ps(x0[a], _mm256_mul_ps(vn[a], h));
        }
        let speed2 = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(vn[0], vn[0]), _mm256_mul_ps(vn[1], vn[1])),
            _mm256_mul_ps(vn[2], vn[2]),
        );
        // The old maximum where the speed is NaN, as `f32::max` keeps it.
        fast = _mm256_max_ps(speed2, fast);
        store_three(x.add(VECTOR_F32S * k), xn);
        store_three(v.add(VECTOR_F32S * k), vn);
        // Into the lanes, one by one: lanes only reorder a row, so that a
        // lane outside the band is a broken plan, which the check stops.
        let mut out = [[0.0f32; W]; 10];
        for (to, from) in out
            .iter_mut()
            .zip(xn.iter().chain(&x0).chain([&w]).chain(&vn))
        {
            _mm256_storeu_ps(to.as_mut_ptr(), *from);
        }
        let lane: [usize; W] = std::array::from_fn(|j| p.lane[k + j] as usize - p.first_lane);
        assert!(lane.iter().all(|&l| l < n), "a lane outside its band");
        for (j, &l) in lane.iter().enumerate() {
            for (array, values) in lanes.iter_mut().zip(&out) {
                *array.get_unchecked_mut(l) = values[j];
            }
            if let Some(vl) = velocities {
                for (array, values) in vl.iter_mut().zip(&out[7..]) {
                    *array.get_unchecked_mut(l) = values[j];
                }
            }
        }
    }
    _mm256_storeu_ps(fast2.as_mut_ptr(), fast);
    steps * W
}

/// Eight particles' three coordinates from 24 `f32` at `p` (x, y, z of
/// each in turn): a register of x, one of y, one of z.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn load_three(p: *const f32) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let halves = |a: usize, b: usize| {
        _mm256_insertf128_ps::<1>(
            _mm256_castps128_ps256(_mm_loadu_ps(p.add(a))),
            _mm_loadu_ps(p.add(b)),
        )
    };
    // Particles 0–3 in the low halves, 4–7 in the high ones.
    let m03 = halves(0, 12); // x0 y0 z0 x1
    let m14 = halves(4, 16); // y1 z1 x2 y2
    let m25 = halves(8, 20); // z2 x3 y3 z3
    let xy = _mm256_shuffle_ps::<0b10_01_11_10>(m14, m25); // x2 y2 x3 y3
    let yz = _mm256_shuffle_ps::<0b01_00_10_01>(m03, m14); // y0 z0 y1 z1
    [
        _mm256_shuffle_ps::<0b10_00_11_00>(m03, xy),
        _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy),
        _mm256_shuffle_ps::<0b11_00_11_01>(yz, m25),
    ]
}

/// The inverse of [`load_three`]: registers of x, y and z stored as 24
/// `f32` at `p`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn store_three(p: *mut f32, [x, y, z]: [std::arch::x86_64::__m256; 3]) {
    use std::arch::x86_64::*;
    let xy = _mm256_shuffle_ps::<0b10_00_10_00>(x, y); // x0 x2 y0 y2
    let yz = _mm256_shuffle_ps::<0b11_01_11_01>(y, z); // y1 y3 z1 z3
    let zx = _mm256_shuffle_ps::<0b11_01_10_00>(z, x); // z0 z2 x1 x3
    let m03 = _mm256_shuffle_ps::<0b10_00_10_00>(xy, zx); // x0 y0 z0 x1
    let m14 = _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy); // y1 z1 x2 y2
    let m25 = _mm256_shuffle_ps::<0b11_01_11_01>(zx, yz); // z2 x3 y3 z3
    for (at, m) in [(0, m03), (4, m14), (8, m25)] {
        _mm_storeu_ps(p.add(at), _mm256_castps256_ps128(m));
        _mm_storeu_ps(p.add(at + 12), _mm256_extractf128_ps::<1>(m));
    }
}

/// [`predict_into_lanes`] on the particles `range` (at most [`W`]), on
/// copies, portable.
fn predict_eight_portable(
    (p, lanes, velocities): &mut Prediction,
    range: std::ops::Range<usize>,
    m: Motion,
    fast2: &mut [f32; W],
) {
    let len = range.len();
    let k = range.start;
    let mut p8 = Predicted::default();
    for j in 0..len {
        (p8.e.start[0][j], p8.e.start[1][j], p8.e.start[2][j]) = p.x[k + j].into();
        (p8.e.v[0][j], p8.e.v[1][j], p8.e.v[2][j]) = p.v[k + j].into();
        p8.e.w[j] = p.w[k + j];
    }
    match p.wind {
        Some(wind) => {
            for j in 0..len {
                (p8.wind[0][j], p8.wind[1][j], p8.wind[2][j]) = wind[k + j].into();
            }
            predict_eight::<true>(&mut p8, m, fast2);
        }
        None => predict_eight::<false>(&mut p8, m, fast2),
    }
    for j in 0..len {
        let at = |a: &[[f32; W]; 3]| Vector::new(a[0][j], a[1][j], a[2][j]);
        (p.x[k + j], p.v[k + j]) = (at(&p8.e.x), at(&p8.e.v));
        // Lanes only reorder a row, so that a lane past the band is a
        // broken plan: the index check says so.
        let l = p.lane[k + j] as usize - p.first_lane;
        for a in 0..3 {
            lanes[a][l] = p8.e.x[a][j];
            lanes[3 + a][l] = p8.e.start[a][j];
        }
        lanes[6][l] = p8.e.w[j];
        if let Some(v) = velocities {
            for a in 0..3 {
                v[a][l] = p8.e.v[a][j];
            }
        }
    }
}

/// A band's particles as the end of a substep writes them: positions (m),
/// velocities (m/s), positions at the substep's start (m) and inverse
/// masses (1/kg), and each one's lane (the band's lanes start at
/// `first_lane`); all of one length.
pub(super) struct BandEnd<'a> {
    pub x: &'a mut [Vector],
    pub v: &'a mut [Vector],
    pub x_prev: &'a mut [Vector],
    pub w: &'a [f32],
    pub lane: &'a [u32],
    pub first_lane: usize,
}

/// Ends a substep on the particles of a band from their lanes (positions,
/// starts, inverse masses and velocities, as [`BandState`]): each free
/// particle's velocity gains what the sweeps moved it from where it was
/// predicted to be, over `h` ([`correct_velocity`]), and it goes where
/// its lane is. With `resident`, the particles' arrays hold the state of
/// an earlier substep and the lanes this one's: each particle first takes
/// its lane's start and velocity, and the prediction from them.
pub(super) fn lanes_into_particles(mut p: BandEnd, band: BandState, resident: bool, h: f32) {
    let n = p.x.len();
    let ([lx, ly, lz, sx, sy, sz, _], [vx, vy, vz]) = band;
    let lengths = [p.v.len(), p.x_prev.len(), p.w.len(), p.lane.len()]
        .into_iter()
        .chain([lx.len(), ly.len(), lz.len(), sx.len(), sy.len(), sz.len()])
        .chain([vx.len(), vy.len(), vz.len()]);
    assert!(
        lengths.into_iter().all(|len| len == n),
        "a band's arrays of one length"
    );
    let lanes = [&*lx, ly, lz, sx, sy, sz, vx, vy, vz];
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if simd_available() && !resident {
        // SAFETY: only where the CPU has AVX2; every array is `n` long.
        done = unsafe { swept_avx2(&mut p, [lanes[0], lanes[1], lanes[2]], h) };
    }
    for k in done..n {
        let lane = p.lane[k] as usize - p.first_lane;
        let at = |i: usize| Vector::new(lanes[i][lane], lanes[i + 1][lane], lanes[i + 2][lane]);
        let swept = at(0);
        if resident {
            let start = at(3);
            p.v[k] = at(6);
            p.x[k] = start + p.v[k] * h;
            p.x_prev[k] = start;
        }
        correct_velocity(&mut p.v[k], swept - p.x[k], p.w[k], h);
        p.x[k] = swept;
    }
}

/// [`lanes_into_particles`] without `resident`, on the whole steps of
/// eight particles: the lanes gathered, the particles' arrays turned into
/// registers and back as [`predict_avx2`] does. Returns how many particles
/// it did. Needs every array `n` long.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn swept_avx2(p: &mut BandEnd, swept: [&[f32]; 3], h: f32) -> usize {
    use std::arch::x86_64::*;
    let n = p.x.len();
    let steps = n / W;
    let (h, zero) = (_mm256_set1_ps(h), _mm256_setzero_ps());
    let (x, v) = (p.x.as_mut_ptr() as *mut f32, p.v.as_mut_ptr() as *mut f32);
    for step in 0..steps {
        let k = step * W;
        let lane: [i32; W] =
            std::array::from_fn(|j| (p.lane[k + j] as usize - p.first_lane) as i32);
        // Lanes only reorder a row: a lane outside the band is a broken plan.
        assert!(
            lane.iter().all(|&l| (l as usize) < n),
            "a lane outside its band"
        );
        let at = _mm256_loadu_si256(lane.as_ptr() as *const __m256i);
        // SAFETY (for the gathers, loads and stores): the lanes are in
        // the band, and particles k..k + 8 in every array.
        let to = swept.map(|c| _mm256_i32gather_ps::<4>(c.as_ptr(), at));
        let x0 = load_three(x.add(VECTOR_F32S * k));
        let v0 = load_three(v.add(VECTOR_F32S * k));
        let w = _mm256_loadu_ps(p.w.as_ptr().add(k));
        let free = _mm256_cmp_ps::<_CMP_NEQ_UQ>(w, zero);
        let mut vn = [zero; 3];
        for a in 0..3 {
            let corrected = _mm256_add_ps(v0[a], _mm256_div_ps(_mm256_sub_ps(to[a], x0[a]), h));
            vn[a] = _mm256_blendv_ps(v0[a], corrected, free);
        }
        store_three(v.add(VECTOR_F32S * k), vn);
        store_three(x.add(VECTOR_F32S * k), to);
    }
    steps * W
}

/// Eight particles in registers for the prediction: positions (m, after
/// it), starts (m), velocities (m/s) and inverse masses (1/kg) as
/// [`Eight`] holds lanes, and the wind's forces (N); zeros (a pinned
/// particle at rest) by default.
#[derive(Default, Clone, Copy)]
struct Predicted {
    e: Eight,
    wind: [[f32; W]; 3],
}

/// The prediction (`xpbd::predict`) of eight particles, without branches,
/// in its operations' order; keeps in `fast2` the largest squared speed of
/// each.
#[inline(always)]
fn predict_eight<const WIND: bool>(p8: &mut Predicted, m: Motion, fast2: &mut [f32; W]) {
    let (g, h) = (m.gravity.to_array(), m.h);
    for k in 0..W {
        let free = p8.e.w[k] != 0.0;
        let mut speed2 = 0.0;
        for a in 0..3 {
            let v = p8.e.v[a][k];
            let mut acc = g[a] - v * m.drag;
            if WIND {
                acc += p8.wind[a][k] * p8.e.w[k];
            }
            let v = if free { v + acc * h } else { v };
            p8.e.x[a][k] = p8.e.start[a][k] + v * h;
            p8.e.v[a][k] = v;
            speed2 += v * v;
        }
        fast2[k] = fast2[k].max(speed2);
    }
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
            correct_velocity(&mut vel, x - predicted, w, h);
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

    /// `n` vectors of sines and cosines, from phase `s`.
    fn jittered(n: usize, s: f32) -> Vec<Vector> {
        (0..n)
            .map(|i| {
                let t = (i as f32 + s) * 0.731;
                Vector::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin())
            })
            .collect()
    }

    /// `n` inverse masses (1/kg), every third pinned (0).
    fn every_third_pinned(n: usize) -> Vec<f32> {
        (0..n)
            .map(|i| if i % 3 == 0 { 0.0 } else { 40.0 + i as f32 })
            .collect()
    }

    /// Particle k's lane, `5 + (8 k mod n)`, of a band whose lanes start
    /// at 5: another order, as a grid's row takes its particles.
    fn shuffled_lanes(n: usize) -> Vec<u32> {
        (0..n).map(|k| (5 + (k * 8) % n) as u32).collect()
    }

    /// 21 particles (two steps and a tail), every third pinned, with
    /// their lanes in another order (as a grid's row takes them), predicted
    /// with wind or without and with velocity lanes or without: the
    /// particles' arrays and lanes as `xpbd::predict` leaves a particle,
    /// and the same bits with AVX2 as without.
    #[test]
    fn the_prediction_moves_each_particle_as_predict_does_into_its_lane() {
        let n = 21;
        let (f, w) = (|s: f32| jittered(n, s), every_third_pinned(n));
        let lane = shuffled_lanes(n);
        let motion = Motion {
            gravity: Vector::new(0.0, -9.81, 0.0),
            drag: 0.3,
            h: 1.0 / 960.0,
        };
        let wind_forces = f(9.0);
        for (wind, with_velocities, simd) in [
            (false, false, true),
            (true, true, true),
            (false, true, false),
            (true, false, false),
        ] {
            let (x0, v0) = (f(0.0), f(3.0));
            let (mut x, mut v) = (x0.clone(), v0.clone());
            let mut lanes: [Vec<f32>; 10] = std::array::from_fn(|_| vec![f32::NAN; n]);
            let [lx, ly, lz, sx, sy, sz, lw, vx, vy, vz] = lanes.each_mut();
            let particles = BandParticles {
                x: &mut x,
                v: &mut v,
                w: &w,
                wind: wind.then_some(&wind_forces[..]),
                lane: &lane,
                first_lane: 5,
            };
            let state = [&mut lx[..], ly, lz, sx, sy, sz, lw];
            let velocities = with_velocities.then_some([&mut vx[..], vy, vz]);
            let fast2 = if simd {
                predict_into_lanes(particles, state, velocities, motion)
            } else {
                let mut fast2 = [0.0; W];
                let prediction = &mut (particles, state, velocities);
                for k in (0..n).step_by(W) {
                    predict_eight_portable(prediction, k..(k + W).min(n), motion, &mut fast2);
                }
                fast2.into_iter().fold(0.0, f32::max)
            };
            let mut fastest = 0.0f32;
            for k in 0..n {
                // As `xpbd::predict` moves a particle.
                let (mut xk, mut vk) = (x0[k], v0[k]);
                if w[k] != 0.0 {
                    let mut a = motion.gravity - vk * motion.drag;
                    if wind {
                        a += wind_forces[k] * w[k];
                    }
                    vk += a * motion.h;
                }
                xk += vk * motion.h;
                let bits = |p: Vector| p.to_array().map(f32::to_bits);
                assert_eq!(bits(x[k]), bits(xk), "particle {k}'s position");
                assert_eq!(bits(v[k]), bits(vk), "particle {k}'s velocity");
                let l = (k * 8) % n;
                let at = |i: usize| Vector::new(lanes[i][l], lanes[i + 1][l], lanes[i + 2][l]);
                assert_eq!(bits(at(0)), bits(xk), "lane {l}: where it is");
                assert_eq!(at(3), x0[k], "lane {l}: where it started");
                assert_eq!(lanes[6][l], w[k]);
                if with_velocities {
                    assert_eq!(bits(at(7)), bits(vk), "lane {l}: its velocity");
                } else {
                    assert!(lanes[7..].iter().all(|a| a.iter().all(|c| c.is_nan())));
                }
                fastest = fastest.max(vk.length_squared());
                if w[k] == 0.0 {
                    assert_eq!(v[k], v0[k], "particle {k} is pinned");
                }
            }
            assert_eq!(fast2.to_bits(), fastest.to_bits());
        }
    }

    /// 21 particles (two steps and a tail), every third pinned, their
    /// lanes in another order: the end of a substep leaves each particle
    /// where its lane is, with the velocity [`correct_velocity`] gives
    /// it, and with `resident` from the lane's start and velocity first.
    #[test]
    fn the_end_of_a_substep_takes_each_particle_from_its_lane() {
        let n = 21;
        let (f, w) = (|s: f32| jittered(n, s), every_third_pinned(n));
        let lane = shuffled_lanes(n);
        let h = 1.0 / 960.0;
        let (lanes0, velocities0) = band();
        for resident in [false, true] {
            let (x0, v0, prev0) = (f(0.0), f(3.0), f(6.0));
            let (mut x, mut v, mut x_prev) = (x0.clone(), v0.clone(), prev0.clone());
            let (mut lanes, mut velocities) = (lanes0.clone(), velocities0.clone());
            let end = BandEnd {
                x: &mut x,
                v: &mut v,
                x_prev: &mut x_prev,
                w: &w,
                lane: &lane,
                first_lane: 5,
            };
            let state = (
                lanes.each_mut().map(|a| &mut a[..]),
                velocities.each_mut().map(|a| &mut a[..]),
            );
            lanes_into_particles(end, state, resident, h);
            for k in 0..n {
                let l = (k * 8) % n;
                let at = |a: &[Vec<f32>], i: usize| Vector::new(a[i][l], a[i + 1][l], a[i + 2][l]);
                let (mut xk, mut vk, mut prev) = (x0[k], v0[k], prev0[k]);
                if resident {
                    let start = at(&lanes0, 3);
                    vk = at(&velocities0, 0);
                    xk = start + vk * h;
                    prev = start;
                }
                let swept = at(&lanes0, 0);
                correct_velocity(&mut vk, swept - xk, w[k], h);
                let bits = |p: Vector| p.to_array().map(f32::to_bits);
                assert_eq!(bits(x[k]), bits(swept), "particle {k} where its lane is");
                assert_eq!(bits(v[k]), bits(vk), "particle {k}'s velocity");
                assert_eq!(bits(x_prev[k]), bits(prev), "particle {k}'s start");
                if w[k] == 0.0 && !resident {
                    assert_eq!(v[k], v0[k], "particle {k} is pinned");
                }
            }
            assert_eq!((lanes, velocities), (lanes0.clone(), velocities0.clone()));
        }
    }
}
