//! The wind on triangles in moving air, eight at a time: each batch's
//! corners are gathered into structure-of-arrays lanes, the force of every
//! lane worked out by the one-triangle law ([`super::force_in_moving_air`],
//! written branch-free for this), and the forces shared among the corners
//! in triangle order. With AVX2 (detected at run time) the lanes are one
//! vector each; without it the same loop runs lane by lane, with the same
//! bits (no fused multiply-adds either way).

use super::{force_in_moving_air, AirField};
use crate::math::{simd_available, Vector};

/// Triangles in a batch: eight `f32` lanes, one AVX2 register.
const LANES: usize = 8;

/// One batch: per lane, a triangle's corners (m) and its mean velocity
/// (m/s), coordinate by coordinate.
#[derive(Default)]
struct Batch {
    /// `corners[c][axis][lane]`.
    corners: [[[f32; LANES]; 3]; 3],
    velocity: [[f32; LANES]; 3],
    /// Per lane: the force (N) on the whole triangle.
    force: [[f32; LANES]; 3],
}

/// Adds the force of every triangle in `air` at time `t` (s), moving at
/// its corners' mean velocity `v`, a third to each corner, into `f`.
pub(super) fn add_forces(
    triangles: &[[u32; 3]],
    air: &AirField,
    (x, v): (&[Vector], &[Vector]),
    t: f32,
    f: &mut [Vector],
) {
    add_forces_with(triangles, air, (x, v), t, f, simd_available());
}

/// [`add_forces`], with the AVX2 lanes only when `simd`.
fn add_forces_with(
    triangles: &[[u32; 3]],
    air: &AirField,
    (x, v): (&[Vector], &[Vector]),
    t: f32,
    f: &mut [Vector],
    simd: bool,
) {
    let mut batch = Batch::default();
    for chunk in triangles.chunks(LANES) {
        for (lane, tri) in chunk.iter().enumerate() {
            let [i, j, k] = tri.map(|i| i as usize);
            let velocity = (v[i] + v[j] + v[k]) / 3.0;
            for a in 0..3 {
                for (c, p) in [x[i], x[j], x[k]].into_iter().enumerate() {
                    batch.corners[c][a][lane] = p[a];
                }
                batch.velocity[a][lane] = velocity[a];
            }
        }
        solve(&mut batch, air, t, simd);
        for (lane, tri) in chunk.iter().enumerate() {
            let force = Vector::new(
                batch.force[0][lane],
                batch.force[1][lane],
                batch.force[2][lane],
            );
            let share = force / 3.0;
            for i in tri.map(|i| i as usize) {
                f[i] += share;
            }
        }
    }
}

/// Every lane's force (lanes past a short last batch hold the previous
/// batch's triangles, or zeros, and are not read).
fn solve(batch: &mut Batch, air: &AirField, t: f32, simd: bool) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        unsafe { solve_avx2(batch, air, t) };
        return;
    }
    let _ = simd;
    solve_lanes(batch, air, t);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn solve_avx2(batch: &mut Batch, air: &AirField, t: f32) {
    crate::math::align_frame();
    solve_lanes(batch, air, t);
}

#[inline(always)]
fn solve_lanes(batch: &mut Batch, air: &AirField, t: f32) {
    let c = &batch.corners;
    for lane in 0..LANES {
        let corner = |k: usize| Vector::new(c[k][0][lane], c[k][1][lane], c[k][2][lane]);
        let vel = &batch.velocity;
        let velocity = Vector::new(vel[0][lane], vel[1][lane], vel[2][lane]);
        let force = force_in_moving_air([corner(0), corner(1), corner(2)], velocity, air, t);
        batch.force[0][lane] = force.x;
        batch.force[1][lane] = force.y;
        batch.force[2][lane] = force.z;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::Wind;
    use crate::forces::wind_force_on_moving_triangle;

    /// A crumpled strip of triangles (one degenerate, one moving with the
    /// air) in a gusty wind with skin friction.
    fn strip() -> (Vec<[u32; 3]>, Vec<Vector>, Vec<Vector>) {
        let count = 23;
        let x: Vec<Vector> = (0..count)
            .map(|i| {
                let s = i as f32;
                Vector::new(0.1 * s, 0.3 * (0.7 * s).sin(), 0.05 * (s * s % 7.0))
            })
            .collect();
        let mut v: Vec<Vector> = (0..count)
            .map(|i| Vector::new(0.2 * (i % 3) as f32, -0.5, 0.1 * i as f32))
            .collect();
        let mut triangles: Vec<[u32; 3]> =
            (0..count as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        triangles.push([4, 4, 9]);
        v[20] = Vector::new(3.0, 0.0, 1.0);
        (triangles, x, v)
    }

    fn gusty() -> Wind {
        Wind::new(Vector::new(1.0, 0.0, 0.3), 8.0).with_air(3.6, 0.2, 0.4, 7)
    }

    /// The batches give each triangle exactly the force the one-triangle
    /// law gives it, shared in triangle order, with and without AVX2.
    #[test]
    fn lanes_give_the_one_triangle_law_s_bits() {
        let (triangles, x, v) = strip();
        let wind = gusty();
        let air = AirField::of(&wind).unwrap();
        let t = 12.75;
        let mut one_by_one = vec![Vector::ZERO; x.len()];
        for tri in &triangles {
            let [i, j, k] = tri.map(|i| i as usize);
            let velocity = (v[i] + v[j] + v[k]) / 3.0;
            let force = wind_force_on_moving_triangle([x[i], x[j], x[k]], velocity, &wind, t);
            for c in [i, j, k] {
                one_by_one[c] += force / 3.0;
            }
        }
        assert!(
            one_by_one.iter().any(|f| f.length() > 0.01),
            "no force at all"
        );
        for simd in [false, simd_available()] {
            let mut f = vec![Vector::ZERO; x.len()];
            add_forces_with(&triangles, &air, (&x, &v), t, &mut f, simd);
            for (a, b) in f.iter().zip(&one_by_one) {
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits)
                );
            }
        }
    }

    /// The gusts' sine is the sine, to single precision, from well below
    /// to well above a turn, at the phases a long run reaches.
    #[test]
    fn the_gust_sine_is_the_sine() {
        let mut worst = 0.0f64;
        for k in -200_000..=200_000 {
            let x = k as f32 * 0.0031;
            let err = (super::super::gust_sine(x) as f64 - (x as f64).sin()).abs();
            worst = worst.max(err);
        }
        assert!(worst < 5e-7, "worst error {worst}");
    }
}
