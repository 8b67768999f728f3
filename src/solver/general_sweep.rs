//! The spring sweep of the small-steps solver for any cloth (a mesh, joined
//! cloths, a torn sheet: whatever has no grid plan, `grid_sweep.rs`): one
//! Gauss–Seidel pass over the springs in their stored order, kind by kind
//! and colour class by colour class (`Springs::from_list`).
//!
//! The springs of a colour class share no particle, so 8 of them are
//! projected at once with AVX2 where the CPU has it: their ends' positions
//! read one by one into registers (the processor's gather instruction was
//! slower here than the scalar loop: 18 against 24 ns a spring, the loads
//! one by one 8 ns, on this project's Xeon machines), the 8 projections in
//! vector arithmetic, the ends written back one by one. Elsewhere, and for
//! the few springs past a class's last full 8, one spring at a time. Both
//! make the same IEEE operations in the same order for each spring (no
//! fused multiply-add), so the same bits; a unit test compares them.
//!
//! Positions are kept as structure of arrays for the sweep
//! ([`GeneralLanes`]): an 8-spring step reads whole `f32`s.

use crate::cloth::{SpringKind, Springs};
use crate::math::{simd_available, Vector};

use super::grid_sweep::Compliance;

/// The general sweep's positions (m) as structure of arrays: now (x, y, z)
/// and at the substep's start (sx, sy, sz).
#[derive(Debug, Default)]
pub(crate) struct GeneralLanes {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    sx: Vec<f32>,
    sy: Vec<f32>,
    sz: Vec<f32>,
}

impl GeneralLanes {
    /// Copies the positions `x` and the substep's start `start` in.
    pub fn load(&mut self, x: &[Vector], start: &[Vector]) {
        for (dst, src, axis) in [
            (&mut self.x, x, 0),
            (&mut self.y, x, 1),
            (&mut self.z, x, 2),
            (&mut self.sx, start, 0),
            (&mut self.sy, start, 1),
            (&mut self.sz, start, 2),
        ] {
            dst.clear();
            dst.extend(src.iter().map(|p| p[axis]));
        }
    }

    /// Copies the positions back out to `x`.
    pub fn store(&self, x: &mut [Vector]) {
        let xyz = self.x.iter().zip(&self.y).zip(&self.z);
        for (p, ((&px, &py), &pz)) in x.iter_mut().zip(xyz) {
            *p = Vector::new(px, py, pz);
        }
    }
}

/// One Gauss–Seidel sweep over `springs` (the particles' inverse masses
/// `inv_mass`, 1/kg) on the positions `p`, with the multipliers `lambda`
/// (one a spring, N·s², updated) and each kind's compliance terms.
pub(crate) fn sweep(
    springs: &Springs,
    inv_mass: &[f32],
    p: &mut GeneralLanes,
    lambda: &mut [f32],
    compliance: &[Compliance; 3],
) {
    sweep_with(springs, inv_mass, p, lambda, compliance, simd_available());
}

/// [`sweep`], with the AVX2 steps only when `simd`.
fn sweep_with(
    springs: &Springs,
    inv_mass: &[f32],
    p: &mut GeneralLanes,
    lambda: &mut [f32],
    compliance: &[Compliance; 3],
    simd: bool,
) {
    let job = Job {
        a: &springs.a,
        b: &springs.b,
        rest: &springs.rest,
        inv_mass,
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
        let mut s = class.start;
        #[cfg(target_arch = "x86_64")]
        if simd && disjoint {
            // SAFETY: `simd` only when the CPU has AVX2; the class's springs
            // share no particle (`disjoint`).
            s = unsafe { job.eights_avx2(class.clone(), p, lambda, k) };
        }
        let _ = (simd, disjoint);
        while s < class.end {
            job.one(s, p, lambda, k);
            s += 1;
        }
    }
}

/// What the sweep reads of the springs (ends, rest lengths in m) and the
/// particles (inverse masses, 1/kg).
struct Job<'a> {
    a: &'a [u32],
    b: &'a [u32],
    rest: &'a [f32],
    inv_mass: &'a [f32],
}

impl Job<'_> {
    /// Spring `s`: `C = |x_j − x_i| − L`, `Δλ = −(C + αλ + γ n·(Δx_j − Δx_i))
    /// / ((1 + γ)(w_i + w_j) + α)`, the ends moved by `∓w Δλ n`; no change
    /// for two pinned ends or coincident ends.
    #[inline(always)]
    fn one(&self, s: usize, p: &mut GeneralLanes, lambda: &mut [f32], k: Compliance) {
        let Compliance { alpha, gamma } = k;
        let (i, j) = (self.a[s] as usize, self.b[s] as usize);
        let (wi, wj) = (self.inv_mass[i], self.inv_mass[j]);
        let w = wi + wj;
        if w == 0.0 {
            return;
        }
        let d = [p.x[j] - p.x[i], p.y[j] - p.y[i], p.z[j] - p.z[i]];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if len2 <= f32::MIN_POSITIVE {
            return;
        }
        let inv_len = 1.0 / len2.sqrt();
        let n = [d[0] * inv_len, d[1] * inv_len, d[2] * inv_len];
        let c = len2 * inv_len - self.rest[s];
        let m = [
            (p.x[j] - p.sx[j]) - (p.x[i] - p.sx[i]),
            (p.y[j] - p.sy[j]) - (p.y[i] - p.sy[i]),
            (p.z[j] - p.sz[j]) - (p.z[i] - p.sz[i]),
        ];
        let rate = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
        let dl = -(c + alpha * lambda[s] + gamma * rate) / ((1.0 + gamma) * w + alpha);
        lambda[s] += dl;
        let (si, sj) = (wi * dl, wj * dl);
        (p.x[i], p.y[i], p.z[i]) = (p.x[i] - n[0] * si, p.y[i] - n[1] * si, p.z[i] - n[2] * si);
        (p.x[j], p.y[j], p.z[j]) = (p.x[j] + n[0] * sj, p.y[j] + n[1] * sj, p.z[j] + n[2] * sj);
    }

    /// The springs of `class`, 8 at a time, as long as 8 are left; returns
    /// the first spring not projected.
    ///
    /// # Safety
    /// The CPU has AVX2, and no two springs of `class` share a particle.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn eights_avx2(
        &self,
        class: std::ops::Range<usize>,
        p: &mut GeneralLanes,
        lambda: &mut [f32],
        k: Compliance,
    ) -> usize {
        use std::arch::x86_64::*;
        const W: usize = 8;
        let (alpha, gamma) = (_mm256_set1_ps(k.alpha), _mm256_set1_ps(k.gamma));
        let one_gamma = _mm256_set1_ps(1.0 + k.gamma);
        let (zero, tiny) = (_mm256_setzero_ps(), _mm256_set1_ps(f32::MIN_POSITIVE));
        let mut s = class.start;
        while s + W <= class.end {
            let i: [usize; W] = std::array::from_fn(|c| self.a[s + c] as usize);
            let j: [usize; W] = std::array::from_fn(|c| self.b[s + c] as usize);
            // One load per lane (the gather instruction was slower).
            let at = |v: &[f32], e: &[usize; W]| {
                let t: [f32; W] = std::array::from_fn(|c| v[e[c]]);
                _mm256_loadu_ps(t.as_ptr())
            };
            let (xi, yi, zi) = (at(&p.x, &i), at(&p.y, &i), at(&p.z, &i));
            let (xj, yj, zj) = (at(&p.x, &j), at(&p.y, &j), at(&p.z, &j));
            let (sxi, syi, szi) = (at(&p.sx, &i), at(&p.sy, &i), at(&p.sz, &i));
            let (sxj, syj, szj) = (at(&p.sx, &j), at(&p.sy, &j), at(&p.sz, &j));
            let (wi, wj) = (at(self.inv_mass, &i), at(self.inv_mass, &j));
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
            let mut out = [[0.0f32; W]; 6];
            for (o, v) in out.iter_mut().zip(moved) {
                _mm256_storeu_ps(o.as_mut_ptr(), v);
            }
            for c in 0..W {
                (p.x[i[c]], p.y[i[c]], p.z[i[c]]) = (out[0][c], out[1][c], out[2][c]);
                (p.x[j[c]], p.y[j[c]], p.z[j[c]]) = (out[3][c], out[4][c], out[5][c]);
            }
            s += W;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// A 13 × 11 cloth (classes whose sizes are not multiples of 8), its
    /// particles shaken, a pinned corner, and the substep's start elsewhere.
    fn setup() -> (Springs, Vec<f32>, GeneralLanes) {
        let cloth = ClothBuilder::new(13, 11).build().unwrap();
        let springs = cloth.springs().clone();
        let mut w = cloth.inverse_masses().to_vec();
        w[0] = 0.0;
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
        let mut lanes = GeneralLanes::default();
        lanes.load(&x, &start);
        (springs, w, lanes)
    }

    fn bits(lanes: &GeneralLanes, lambda: &[f32]) -> Vec<u32> {
        let all = [&lanes.x, &lanes.y, &lanes.z];
        all.iter()
            .flat_map(|v| v.iter())
            .chain(lambda)
            .map(|f| f.to_bits())
            .collect()
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
        let (springs, w, mut one) = setup();
        let (_, _, mut eight) = setup();
        let (mut l1, mut l8) = (vec![0.0; springs.len()], vec![0.0; springs.len()]);
        for _ in 0..3 {
            sweep_with(&springs, &w, &mut one, &mut l1, &k, false);
            sweep_with(&springs, &w, &mut eight, &mut l8, &k, simd_available());
        }
        assert_eq!(bits(&one, &l1), bits(&eight, &l8));
        // The sweep did something: the springs pulled the shaken sheet.
        let (_, _, untouched) = setup();
        assert_ne!(bits(&one, &l1), bits(&untouched, &vec![0.0; springs.len()]));
        assert!(l1.iter().any(|&l| l != 0.0));
        // Every class of the cloth had 8 springs or more, so the AVX2 steps ran.
        assert!(springs.colour_ranges().iter().any(|r| r.len() >= 8));
    }
}
