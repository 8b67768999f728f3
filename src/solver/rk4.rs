//! Classical fourth-order Runge–Kutta.

use super::workspace::ExplicitScratch;
use crate::forces::ForceModel;
use crate::math::Vector;

/// One RK4 step of the first-order system `x' = v, v' = a(x, v)`.
pub(crate) fn step(
    model: &ForceModel,
    x: &mut [Vector],
    v: &mut [Vector],
    ws: &mut ExplicitScratch,
    h: f32,
) {
    let n = x.len();
    let ExplicitScratch {
        a, xt, vt, sx, sv, ..
    } = ws;
    let half = 0.5 * h;
    // k1
    model.accelerations(x, v, a);
    for i in 0..n {
        sx[i] = v[i];
        sv[i] = a[i];
        xt[i] = x[i] + v[i] * half;
        vt[i] = v[i] + a[i] * half;
    }
    // k2 and k3
    for stage in 0..2 {
        model.accelerations(xt, vt, a);
        let scale = if stage == 0 { half } else { h };
        for i in 0..n {
            sx[i] += vt[i] * 2.0;
            sv[i] += a[i] * 2.0;
            xt[i] = x[i] + vt[i] * scale;
            vt[i] = v[i] + a[i] * scale;
        }
    }
    // k4
    model.accelerations(xt, vt, a);
    let sixth = h / 6.0;
    for i in 0..n {
        x[i] += (sx[i] + vt[i]) * sixth;
        v[i] += (sv[i] + a[i]) * sixth;
    }
}
