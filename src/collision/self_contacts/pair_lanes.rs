//! The vector test of a pass: a look's pairs as lanes, eight at a time.

use super::pairs::SelfPair;
use super::points::Points;
#[cfg(target_arch = "x86_64")]
use crate::math::{cross_lanes, dot_lanes, load_vectors};

/// Lanes of a vector step over the candidates.
pub(super) const LANES: usize = 8;

/// A look's pairs as lanes
/// ([`SelfContacts::resolve`](super::SelfContacts::resolve)'s vector test):
/// each pair's particle, its triangle's corners and its side, padded to whole
/// vector steps.
#[derive(Debug, Default, Clone)]
pub(super) struct PairLanes {
    /// The CPU has AVX2 and the lanes are to be used (else they are left
    /// empty).
    pub(super) simd: bool,
    /// Pairs, before the padding; the particles their indices are below.
    pub(super) len: usize,
    pub(super) particles: usize,
    /// A pair had an index out of range, or no triangle: not to be used.
    pub(super) broken: bool,
    pub(super) p: Vec<i32>,
    pub(super) corners: [Vec<i32>; 3],
    pub(super) side: Vec<f32>,
}

impl PairLanes {
    /// Empties the lanes, for pairs on `particles` particles, to be used
    /// on a CPU with AVX2 (`simd`).
    pub(super) fn clear(&mut self, simd: bool, particles: usize) {
        self.simd = simd;
        self.len = 0;
        self.particles = particles;
        self.broken = false;
        self.p.clear();
        self.corners.iter_mut().for_each(Vec::clear);
        self.side.clear();
    }

    /// Adds `pair`, of the triangle with `corners` (none: no triangle,
    /// and the lanes are not to be used); nothing without AVX2.
    pub(super) fn push(&mut self, pair: &SelfPair, corners: Option<[u32; 3]>) {
        if !self.simd {
            return;
        }
        let particles = self.particles;
        // Within the particles, and an index the lanes hold as an `i32`
        // (a quarter of its range, as when they were gathers' offsets).
        let fits = |i: u32| (i as usize) < particles && i <= i32::MAX as u32 / 4;
        match corners {
            Some(tri) if fits(pair.particle) && tri.into_iter().all(fits) => {
                self.p.push(pair.particle as i32);
                for (corners, c) in self.corners.iter_mut().zip(tri) {
                    corners.push(c as i32);
                }
                self.side.push(pair.side);
                self.len += 1;
            }
            _ => self.broken = true,
        }
    }

    /// Pads the lanes to whole vector steps.
    pub(super) fn pad(&mut self) {
        let padded = self.len.next_multiple_of(LANES);
        self.p.resize(padded, 0);
        self.corners.iter_mut().for_each(|c| c.resize(padded, 0));
        self.side.resize(padded, 0.0);
    }

    /// True when the lanes hold `pairs` pairs on `particles` particles and
    /// the CPU has AVX2.
    pub(super) fn usable(&self, pairs: usize, particles: usize) -> bool {
        self.simd && !self.broken && self.len == pairs && self.particles == particles && pairs > 0
    }

    /// Which of the eight pairs from `k` the pass may act on at positions
    /// `x`, for layers `(thickness, margin)` (m), a bit each (lane `l` bit
    /// `l`): those not idle by
    /// [`SelfContacts::pair_pass`](super::SelfContacts::pair_pass)'s tests up
    /// to the barycentrics and the rim's thinning
    /// ([`rim_taper`](super::geometry::rim_taper)), each made a hair looser;
    /// every pair's bit when the lanes are not usable. None past the last
    /// pair.
    pub(super) fn busy(&self, k: usize, x: &Points, layers: (f32, f32)) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.usable(self.len, x.len) && k < self.len {
            // SAFETY: usable only with AVX2, with every index below
            // `x.len`, and `k` a pair's; the pairs' particles are this
            // part's.
            return unsafe { self.busy_avx2(k, x, layers) };
        }
        let _ = (x, layers);
        (1u32 << self.len.saturating_sub(k).min(LANES)) - 1
    }

    /// [`Self::busy`] in AVX2.
    ///
    /// # Safety
    /// The CPU has AVX2; the lanes' indices are below `x.len`; `k` is
    /// below `self.len`; no other thread writes the particles of these
    /// pairs meanwhile.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn busy_avx2(
        &self,
        k: usize,
        x: &Points,
        (thickness, margin): (f32, f32),
    ) -> u32 {
        use std::arch::x86_64::*;
        assert!(k + LANES <= self.p.len() && self.p.len() == self.side.len());
        assert!(self.corners.iter().all(|c| c.len() == self.p.len()));
        let base = x.ptr as *const f32;
        // SAFETY: `k + LANES` within the lanes (asserted); each index below
        // `x.len()` (the caller's promise) and not negative (`push`), so
        // each masked load reads the three floats of a particle.
        unsafe {
            // Each lane's point by one masked load (`load_vectors`).
            let point = |v: &Vec<i32>| {
                let index = std::array::from_fn(|l| *v.get_unchecked(k + l) as usize);
                load_vectors(base, index)
            };
            let p = point(&self.p);
            let a = point(&self.corners[0]);
            let b = point(&self.corners[1]);
            let c = point(&self.corners[2]);
            let sub = |u: [__m256; 3], v: [__m256; 3]| [0, 1, 2].map(|i| _mm256_sub_ps(u[i], v[i]));
            let (e1, e2, d) = (sub(b, a), sub(c, a), sub(p, a));
            // e1 × e2, as `Vector::cross`.
            let m = _mm256_mul_ps;
            let normal = cross_lanes(e1, e2);
            let dot = |u: [__m256; 3], v: [__m256; 3]| dot_lanes(u, v);
            let len2 = dot(normal, normal);
            let side = _mm256_loadu_ps(self.side.as_ptr().add(k));
            let out = m(dot(d, normal), side);
            let splat = _mm256_set1_ps;
            let (ge, lt) = (
                |u, v| _mm256_cmp_ps::<_CMP_GE_OQ>(u, v),
                |u, v| _mm256_cmp_ps::<_CMP_LT_OQ>(u, v),
            );
            let or = _mm256_or_ps;
            let t2 = thickness * thickness;
            let apart = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(out, _mm256_setzero_ps()),
                _mm256_cmp_ps::<_CMP_GT_OQ>(
                    m(out, out),
                    m(m(splat(t2), len2), splat(1.0 + 2.0e-4)),
                ),
            );
            // The distance along the unit normal on the pair's side: at or
            // past the thickness, or further on the other side than the
            // margin. Approximate inverses and roots (relative error under
            // 3.7e-4) with thresholds looser by more: what the pass itself
            // finds idle, and a few more.
            let tol = 2.0e-3;
            let inv_len = _mm256_rsqrt_ps(len2);
            let scale = m(side, inv_len);
            let n = normal.map(|c| m(c, scale));
            let dist = dot(d, n);
            let far = or(
                ge(dist, splat(thickness * (1.0 + tol))),
                lt(dist, splat(-(thickness + margin) * (1.0 + tol))),
            );
            // The projection's barycentrics beyond the rim's slack
            // (`barycentric`, `rim`, `rim_slack`).
            let q = [0, 1, 2].map(|i| _mm256_sub_ps(d[i], m(n[i], dist)));
            let (d11, d12, d22) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
            let (dq1, dq2) = (dot(q, e1), dot(q, e2));
            let denom = _mm256_sub_ps(m(d11, d22), m(d12, d12));
            let inv_denom = _mm256_rcp_ps(denom);
            let vb = m(_mm256_sub_ps(m(d22, dq1), m(d12, dq2)), inv_denom);
            let w = m(_mm256_sub_ps(m(d11, dq2), m(d12, dq1)), inv_denom);
            let u = _mm256_sub_ps(_mm256_sub_ps(splat(1.0), vb), w);
            let e3 = sub(e2, e1);
            let d33 = dot(e3, e3);
            let shortest = _mm256_sqrt_ps(_mm256_min_ps(_mm256_min_ps(d11, d22), d33));
            let rim = _mm256_min_ps(splat(thickness), m(splat(0.25), shortest));
            let reach = m(m(rim, inv_len), splat(1.0 + tol));
            let slack = |edge2: __m256| {
                let edge = m(edge2, _mm256_rsqrt_ps(edge2));
                _mm256_sub_ps(
                    _mm256_setzero_ps(),
                    _mm256_add_ps(m(reach, edge), splat(tol)),
                )
            };
            let (s1, s2, s3) = (slack(d11), slack(d22), slack(d33));
            let outside = or(lt(u, s3), or(lt(vb, s2), lt(w, s1)));
            // In the rim, at or past the thinned thickness (`rim_taper`),
            // the barycentrics a hair further in and the slack a hair
            // wider: a pair the pass leaves at the thinned thickness is
            // not taken again every substep.
            let zero = _mm256_setzero_ps();
            // Each share by the slack's approximate inverse (squared,
            // within 7.4e-4 of the quotient's), their sum shrunk by 1e-3:
            // never more than the quotients' sum, so the thinned thickness
            // below is never less (no division: its latency held the test
            // up).
            let share = |bary: __m256, slack: __m256| {
                let r = m(
                    _mm256_min_ps(_mm256_add_ps(bary, splat(tol)), zero),
                    _mm256_rcp_ps(slack),
                );
                m(r, r)
            };
            let out2 = m(
                _mm256_add_ps(share(u, s3), _mm256_add_ps(share(vb, s2), share(w, s1))),
                splat(1.0 - 1.0e-3),
            );
            // At or past the kept share of the thickness: `dist - t·tol >=
            // kept·t·(1 + tol)`, squared (no root).
            let kept2 = _mm256_max_ps(_mm256_sub_ps(splat(1.0), out2), zero);
            let past = _mm256_sub_ps(dist, splat(thickness * tol));
            let full = thickness * (1.0 + tol);
            let thin = _mm256_and_ps(
                ge(past, zero),
                ge(m(past, past), m(kept2, splat(full * full))),
            );
            // A degenerate triangle: left to the pass itself.
            let flat = _mm256_cmp_ps::<_CMP_NGT_UQ>(denom, _mm256_setzero_ps());
            let idle = or(apart, _mm256_andnot_ps(flat, or(or(far, thin), outside)));
            // Lanes past the last pair are idle.
            let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
            let left = _mm256_set1_epi32((self.len - k).min(LANES) as i32);
            let real = _mm256_castsi256_ps(_mm256_cmpgt_epi32(left, lane));
            _mm256_movemask_ps(_mm256_andnot_ps(idle, real)) as u32
        }
    }
}
