//! Semi-implicit (symplectic) Euler.

use super::workspace::ExplicitScratch;
use crate::forces::ForceModel;
use crate::math::Vector;

/// `v += h a(x, v); x += h v`.
pub(crate) fn step(
    model: &ForceModel,
    x: &mut [Vector],
    v: &mut [Vector],
    ws: &mut ExplicitScratch,
    h: f32,
) {
    model.accelerations(x, v, &mut ws.a);
    for i in 0..x.len() {
        v[i] += ws.a[i] * h;
        x[i] += v[i] * h;
    }
}
