//! Forward (explicit) Euler.

use super::workspace::ExplicitScratch;
use crate::forces::ForceModel;
use crate::math::Vector;

/// `x += h v; v += h a(x, v)`.
pub(crate) fn step(
    model: &ForceModel,
    x: &mut [Vector],
    v: &mut [Vector],
    ws: &mut ExplicitScratch,
    h: f32,
) {
    model.accelerations(x, v, &mut ws.a);
    for i in 0..x.len() {
        x[i] += v[i] * h;
        v[i] += ws.a[i] * h;
    }
}
