//! The spring sweep of the small-steps solver for any cloth (a mesh, joined
//! cloths, a torn sheet: whatever has no grid plan, `grid_sweep`): one
//! Gauss–Seidel pass over the springs in their stored order, kind by kind
//! and colour class by colour class (`Springs::from_list`).
//!
//! The springs of a colour class share no particle, so 8 of them are
//! projected at once with AVX2 where the CPU has it. Each particle is kept
//! as four floats ([`PackedParticles`]: position and an unused slot, start
//! position and inverse mass), so a spring's ends are four 16-byte loads,
//! turned into a register per coordinate by an 8 × 4 transpose, and two
//! 16-byte stores. Elsewhere, and for the springs past a class's last full
//! 8, one spring at a time. Both make the same IEEE operations in the same
//! order for each spring (no fused multiply-add), so the same bits; a unit
//! test compares them.
//!
//! Measured on the torn sheet (`tear`, one thread, `perf` samples of the
//! sweep; Xeon machine of the eleventh session): one spring at a time over
//! the cloth's 12-byte vectors 3.2 G; 8 at a time from separate x, y, z
//! arrays, loaded one float at a time, 1.65 G; from the packed rows
//! 0.93 G. The processor's gather instruction was slower than one float at
//! a time (18 against 8 ns a spring in a stand-alone loop; 24 ns one spring
//! at a time).

use crate::cloth::{SpringKind, Springs};
use crate::math::{simd_available, Vector};

use super::grid_sweep::Compliance;

/// The general sweep's particles, four floats each so that one 16-byte load
/// reads a particle: positions (m) now (x, y, z, unused) and at the
/// substep's start with the inverse mass (x, y, z in m, w in 1/kg).
#[derive(Debug, Default)]
pub(crate) struct PackedParticles {
    now: Vec<[f32; 4]>,
    start: Vec<[f32; 4]>,
}

impl PackedParticles {
    /// Copies the substep's start positions `start` and the inverse masses
    /// `inv_mass` in (before the prediction moves the particles).
    pub fn load_start(&mut self, start: &[Vector], inv_mass: &[f32]) {
        self.start.clear();
        let start = start.iter().zip(inv_mass);
        self.start.extend(start.map(|(p, &w)| [p.x, p.y, p.z, w]));
    }

    /// Copies the positions `x` in (the prediction, which the sweeps correct).
    pub fn load_now(&mut self, x: &[Vector]) {
        self.now.clear();
        self.now.extend(x.iter().map(|p| [p.x, p.y, p.z, 0.0]));
    }

    /// Copies the positions back out to `x`.
    pub fn store(&self, x: &mut [Vector]) {
        for (p, &[px, py, pz, _]) in x.iter_mut().zip(&self.now) {
            *p = Vector::new(px, py, pz);
        }
    }
}

/// One Gauss–Seidel sweep over `springs` on the particles `p`, with the
/// multipliers `lambda` (one a spring, N·s², updated) and each kind's
/// compliance terms.
pub(crate) fn sweep(
    springs: &Springs,
    p: &mut PackedParticles,
    lambda: &mut [f32],
    compliance: &[Compliance; 3],
) {
    sweep_with(springs, p, lambda, compliance, simd_available());
}

/// [`sweep`], with the AVX2 steps only when `simd`.
fn sweep_with(
    springs: &Springs,
    p: &mut PackedParticles,
    lambda: &mut [f32],
    compliance: &[Compliance; 3],
    simd: bool,
) {
    let job = Job {
        a: &springs.a,
        b: &springs.b,
        rest: &springs.rest,
    };
    let classes = springs.colour_ranges();
    if classes.is_empty() {
        // A snapshot written before the classes were kept: one at a time.
        for kind in SpringKind::ALL {
            let k = compliance[kind.index()];
            for s in springs.range(kind) {
                job.one(s, p, lambda, k);
            }
        }
        return;
    }
    for (class, &disjoint) in classes.iter().zip(&springs.colour_disjoint) {
        let k = compliance[springs.kind(class.start).index()];
        // The springs left after the 8-spring steps.
        #[cfg(target_arch = "x86_64")]
        let left = if simd && disjoint {
            // SAFETY: `simd` only when the CPU has AVX2; the class's springs
            // share no particle (`disjoint`).
            unsafe { job.eights_avx2(class.clone(), p, lambda, k) }
        } else {
            class.start
        };
        #[cfg(not(target_arch = "x86_64"))]
        let left = {
            let _ = (simd, disjoint);
            class.start
        };
        for s in left..class.end {
            job.one(s, p, lambda, k);
        }
    }
}

/// What the sweep reads of the springs: ends, rest lengths (m).
struct Job<'a> {
    a: &'a [u32],
    b: &'a [u32],
    rest: &'a [f32],
}

impl Job<'_> {
    /// Spring `s`: `C = |x_j − x_i| − L`, `Δλ = −(C + αλ + γ n·(Δx_j − Δx_i))
    /// / ((1 + γ)(w_i + w_j) + α)`, the ends moved by `∓w Δλ n`; no change
    /// for two pinned ends or coincident ends.
    #[inline(always)]
    fn one(&self, s: usize, p: &mut PackedParticles, lambda: &mut [f32], k: Compliance) {
        let Compliance { alpha, gamma } = k;
        let (i, j) = (self.a[s] as usize, self.b[s] as usize);
        let ([xi, yi, zi, _], [xj, yj, zj, _]) = (p.now[i], p.now[j]);
        let ([sxi, syi, szi, wi], [sxj, syj, szj, wj]) = (p.start[i], p.start[j]);
        let w = wi + wj;
        if w == 0.0 {
            return;
        }
        let d = [xj - xi, yj - yi, zj - zi];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if len2 <= f32::MIN_POSITIVE {
            return;
        }
        let inv_len = 1.0 / len2.sqrt();
        let n = [d[0] * inv_len, d[1] * inv_len, d[2] * inv_len];
        let c = len2 * inv_len - self.rest[s];
        let m = [
            (xj - sxj) - (xi - sxi),
            (yj - syj) - (yi - syi),
            (zj - szj) - (zi - szi),
        ];
        let rate = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
        let dl = -(c + alpha * lambda[s] + gamma * rate) / ((1.0 + gamma) * w + alpha);
        lambda[s] += dl;
        let (si, sj) = (wi * dl, wj * dl);
        p.now[i] = [xi - n[0] * si, yi - n[1] * si, zi - n[2] * si, 0.0];
        p.now[j] = [xj + n[0] * sj, yj + n[1] * sj, zj + n[2] * sj, 0.0];
    }

    /// The springs of `class`, 8 at a time, as long as 8 are left; returns
    /// the first spring not projected.
    ///
    /// (Solving two groups before storing either, so that their chains of
    /// a square root and two divisions overlap, was slower on the torn
    /// sheet: the registers spilled.)
    ///
    /// # Safety
    /// The CPU has AVX2, and no two springs of `class` share a particle.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn eights_avx2(
        &self,
        class: std::ops::Range<usize>,
        p: &mut PackedParticles,
        lambda: &mut [f32],
        k: Compliance,
    ) -> usize {
        crate::math::align_frame();
        const W: usize = 8;
        // Every end checked once here, so that the loads and stores below
        // need no check each (their checks and branches were a third of
        // the loop's instructions).
        let n = p.now.len().min(p.start.len());
        let below = |ends: &[u32]| (ends.iter().fold(0, |m, &e| m.max(e)) as usize) < n;
        if !(below(&self.a[class.clone()]) && below(&self.b[class.clone()])) {
            // `one`'s checks report the end out of range.
            return class.start;
        }
        let k = Eights::new(k);
        let mut s = class.start;
        while s + W <= class.end {
            self.eight(s, p, lambda, &k);
            s += W;
        }
        s
    }

    /// Springs `s..s + 8` of one colour class projected: their multipliers
    /// updated in `lambda`, their ends moved in `p`.
    ///
    /// # Safety
    /// The CPU has AVX2 (inlined into [`Job::eights_avx2`], which is compiled
    /// for it); the springs' ends are particles of `p` (`now` and `start`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn eight(&self, s: usize, p: &mut PackedParticles, lambda: &mut [f32], k: &Eights) {
        use std::arch::x86_64::*;
        const W: usize = 8;
        let Eights {
            alpha,
            gamma,
            one_gamma,
            zero,
            tiny,
        } = *k;
        let (a, b): (&[u32; W], &[u32; W]) = (
            self.a[s..s + W].try_into().expect("8 ends"),
            self.b[s..s + W].try_into().expect("8 ends"),
        );
        let i: [usize; W] = a.map(|e| e as usize);
        let j: [usize; W] = b.map(|e| e as usize);
        // One 16-byte load per particle and array (the gather
        // instruction was slower), turned into a register per coordinate.
        let [xi, yi, zi, _] = columns(&p.now, &i);
        let [xj, yj, zj, _] = columns(&p.now, &j);
        let [sxi, syi, szi, wi] = columns(&p.start, &i);
        let [sxj, syj, szj, wj] = columns(&p.start, &j);
        let w = _mm256_add_ps(wi, wj);
        let (dx, dy, dz) = (
            _mm256_sub_ps(xj, xi),
            _mm256_sub_ps(yj, yi),
            _mm256_sub_ps(zj, zi),
        );
        let len2 = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
            _mm256_mul_ps(dz, dz),
        );
        // `one`'s tests, negated with unordered compares so that a
        // lane that is not a number goes on as it does there.
        let on = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(w, zero),
            _mm256_cmp_ps::<_CMP_NLE_UQ>(len2, tiny),
        );
        let inv_len = _mm256_div_ps(_mm256_set1_ps(1.0), _mm256_sqrt_ps(len2));
        let (nx, ny, nz) = (
            _mm256_mul_ps(dx, inv_len),
            _mm256_mul_ps(dy, inv_len),
            _mm256_mul_ps(dz, inv_len),
        );
        let rest = _mm256_loadu_ps(self.rest[s..s + W].as_ptr());
        let c = _mm256_sub_ps(_mm256_mul_ps(len2, inv_len), rest);
        let motion = |now_j, start_j, now_i, start_i| {
            _mm256_sub_ps(_mm256_sub_ps(now_j, start_j), _mm256_sub_ps(now_i, start_i))
        };
        let (mx, my, mz) = (
            motion(xj, sxj, xi, sxi),
            motion(yj, syj, yi, syi),
            motion(zj, szj, zi, szi),
        );
        let rate = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(nx, mx), _mm256_mul_ps(ny, my)),
            _mm256_mul_ps(nz, mz),
        );
        let l = _mm256_loadu_ps(lambda[s..s + W].as_ptr());
        let num = _mm256_add_ps(
            _mm256_add_ps(c, _mm256_mul_ps(alpha, l)),
            _mm256_mul_ps(gamma, rate),
        );
        let den = _mm256_add_ps(_mm256_mul_ps(one_gamma, w), alpha);
        let dl = _mm256_div_ps(_mm256_xor_ps(num, _mm256_set1_ps(-0.0)), den);
        // Selected, not added as zero: a zero change can flip a zero's sign.
        let keep = |old, new| _mm256_blendv_ps(old, new, on);
        _mm256_storeu_ps(lambda[s..s + W].as_mut_ptr(), keep(l, _mm256_add_ps(l, dl)));
        let (si, sj) = (_mm256_mul_ps(wi, dl), _mm256_mul_ps(wj, dl));
        let moved = [
            keep(xi, _mm256_sub_ps(xi, _mm256_mul_ps(nx, si))),
            keep(yi, _mm256_sub_ps(yi, _mm256_mul_ps(ny, si))),
            keep(zi, _mm256_sub_ps(zi, _mm256_mul_ps(nz, si))),
            keep(xj, _mm256_add_ps(xj, _mm256_mul_ps(nx, sj))),
            keep(yj, _mm256_add_ps(yj, _mm256_mul_ps(ny, sj))),
            keep(zj, _mm256_add_ps(zj, _mm256_mul_ps(nz, sj))),
        ];
        rows(&mut p.now, &i, [moved[0], moved[1], moved[2], zero]);
        rows(&mut p.now, &j, [moved[3], moved[4], moved[5], zero]);
    }
}

/// A kind's compliance terms and the sweep's constants, 8 lanes each.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Eights {
    alpha: std::arch::x86_64::__m256,
    gamma: std::arch::x86_64::__m256,
    one_gamma: std::arch::x86_64::__m256,
    zero: std::arch::x86_64::__m256,
    tiny: std::arch::x86_64::__m256,
}

#[cfg(target_arch = "x86_64")]
impl Eights {
    /// # Safety
    /// The CPU has AVX2 (inlined into [`Job::eights_avx2`]).
    #[inline(always)]
    unsafe fn new(k: Compliance) -> Self {
        use std::arch::x86_64::*;
        Self {
            alpha: _mm256_set1_ps(k.alpha),
            gamma: _mm256_set1_ps(k.gamma),
            one_gamma: _mm256_set1_ps(1.0 + k.gamma),
            zero: _mm256_setzero_ps(),
            tiny: _mm256_set1_ps(f32::MIN_POSITIVE),
        }
    }
}

/// The 4 columns of the rows `e` of `rows`, one register each (lane `c`
/// from row `e[c]`): an 8 × 4 transpose.
///
/// # Safety
/// The CPU has AVX2 (inlined into [`Job::eights_avx2`], which is compiled
/// for it); every `e[c]` is below `rows.len()`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn columns(rows: &[[f32; 4]], e: &[usize; 8]) -> [std::arch::x86_64::__m256; 4] {
    use std::arch::x86_64::*;
    // Rows c and c + 4 in the two halves of register c.
    let pair = |c: usize| {
        // SAFETY: by the caller's promise.
        let (lo, hi) = unsafe { (rows.get_unchecked(e[c]), rows.get_unchecked(e[c + 4])) };
        _mm256_setr_m128(_mm_loadu_ps(lo.as_ptr()), _mm_loadu_ps(hi.as_ptr()))
    };
    let (r0, r1, r2, r3) = (pair(0), pair(1), pair(2), pair(3));
    let (t0, t1) = (_mm256_unpacklo_ps(r0, r1), _mm256_unpackhi_ps(r0, r1));
    let (t2, t3) = (_mm256_unpacklo_ps(r2, r3), _mm256_unpackhi_ps(r2, r3));
    [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xEE>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
        _mm256_shuffle_ps::<0xEE>(t1, t3),
    ]
}

/// Writes the 4 columns `cols` (lane `c` to row `e[c]`) into `rows`: the
/// inverse of [`columns`].
///
/// # Safety
/// The CPU has AVX2 (inlined into [`Job::eights_avx2`], which is compiled
/// for it); every `e[c]` is below `rows.len()`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn rows(rows: &mut [[f32; 4]], e: &[usize; 8], cols: [std::arch::x86_64::__m256; 4]) {
    use std::arch::x86_64::*;
    let [c0, c1, c2, c3] = cols;
    let (t0, t1) = (_mm256_unpacklo_ps(c0, c1), _mm256_unpackhi_ps(c0, c1));
    let (t2, t3) = (_mm256_unpacklo_ps(c2, c3), _mm256_unpackhi_ps(c2, c3));
    // Register c holds rows c (low half) and c + 4 (high half).
    let r = [
        _mm256_shuffle_ps::<0x44>(t0, t2),
        _mm256_shuffle_ps::<0xEE>(t0, t2),
        _mm256_shuffle_ps::<0x44>(t1, t3),
        _mm256_shuffle_ps::<0xEE>(t1, t3),
    ];
    for (c, r) in r.into_iter().enumerate() {
        // SAFETY: by the caller's promise.
        let (lo, hi) = unsafe {
            (
                rows.get_unchecked_mut(e[c]).as_mut_ptr(),
                rows.get_unchecked_mut(e[c + 4]).as_mut_ptr(),
            )
        };
        _mm_storeu_ps(lo, _mm256_castps256_ps128(r));
        _mm_storeu_ps(hi, _mm256_extractf128_ps::<1>(r));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// A 13 × 11 cloth (classes whose sizes are not multiples of 8), its
    /// particles shaken, two pinned particles with a spring between them
    /// (no change there), and the substep's start elsewhere.
    fn setup() -> (Springs, PackedParticles) {
        let cloth = ClothBuilder::new(13, 11).build().unwrap();
        let springs = cloth.springs().clone();
        let mut w = cloth.inverse_masses().to_vec();
        (w[0], w[1]) = (0.0, 0.0);
        let shake = |i: usize, k: u32| {
            ((i as u32).wrapping_mul(2654435761).rotate_left(k) % 1000) as f32 * 1e-5
        };
        let x: Vec<Vector> = cloth
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| *p + Vector::new(shake(i, 0), shake(i, 7), shake(i, 13)))
            .collect();
        let start: Vec<Vector> = x
            .iter()
            .enumerate()
            .map(|(i, p)| *p - Vector::new(0.0, shake(i, 3), 0.0))
            .collect();
        let mut packed = PackedParticles::default();
        packed.load_start(&start, &w);
        packed.load_now(&x);
        (springs, packed)
    }

    /// The positions and multipliers, bit for bit.
    fn bits(packed: &PackedParticles, lambda: &[f32]) -> Vec<u32> {
        let now = packed.now.iter().flat_map(|p| &p[..3]);
        now.chain(lambda).map(|f| f.to_bits()).collect()
    }

    #[test]
    fn the_vectorised_and_the_one_at_a_time_sweeps_give_the_same_bits() {
        let k = [
            Compliance {
                alpha: 1e-3,
                gamma: 0.02,
            },
            Compliance {
                alpha: 4e-3,
                gamma: 0.01,
            },
            Compliance {
                alpha: 0.5,
                gamma: 0.0,
            },
        ];
        let (springs, mut one) = setup();
        let (_, mut eight) = setup();
        let (mut l1, mut l8) = (vec![0.0; springs.len()], vec![0.0; springs.len()]);
        for _ in 0..3 {
            sweep_with(&springs, &mut one, &mut l1, &k, false);
            sweep_with(&springs, &mut eight, &mut l8, &k, simd_available());
        }
        assert_eq!(bits(&one, &l1), bits(&eight, &l8));
        // The sweep did something: the springs pulled the shaken sheet.
        let (_, untouched) = setup();
        assert_ne!(bits(&one, &l1), bits(&untouched, &vec![0.0; springs.len()]));
        assert!(l1.iter().any(|&l| l != 0.0));
        // Some classes have 8 springs or more, so the AVX2 steps ran (where
        // the CPU has AVX2).
        assert!(springs.colour_ranges().iter().any(|r| r.len() >= 8));
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn a_class_with_an_end_out_of_range_is_left_to_the_checked_path() {
        if !simd_available() {
            return;
        }
        let (mut springs, mut packed) = setup();
        let class = springs
            .colour_ranges()
            .iter()
            .find(|r| r.len() >= 8)
            .cloned()
            .expect("a class of 8 springs or more");
        let before = bits(&packed, &[]);
        // The class's last spring ends past the particles.
        let end = springs.b[class.end - 1];
        springs.b[class.end - 1] = packed.now.len() as u32;
        let job = Job {
            a: &springs.a,
            b: &springs.b,
            rest: &springs.rest,
        };
        let mut lambda = vec![0.0; springs.len()];
        let k = Compliance {
            alpha: 1e-3,
            gamma: 0.02,
        };
        // SAFETY: the test returned above without AVX2; a colour class.
        let left = unsafe { job.eights_avx2(class.clone(), &mut packed, &mut lambda, k) };
        assert_eq!(left, class.start);
        assert_eq!(bits(&packed, &[]), before);
        // With every end in range the same class is projected 8 at a time.
        springs.b[class.end - 1] = end;
        let job = Job {
            a: &springs.a,
            b: &springs.b,
            rest: &springs.rest,
        };
        // SAFETY: as above.
        let left = unsafe { job.eights_avx2(class.clone(), &mut packed, &mut lambda, k) };
        assert!(left > class.start);
    }
}
