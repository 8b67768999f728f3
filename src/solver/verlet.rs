//! Störmer–Verlet in velocity form.

use super::workspace::ExplicitScratch;
use crate::forces::ForceModel;
use crate::math::Vector;

/// `x += h v + ½ h² a₀; v += ½ h (a₀ + a₁)` with `a₁` evaluated at the new
/// positions and the predicted velocity `v + h a₀` (for the damping terms).
pub(crate) fn step(
    model: &ForceModel,
    x: &mut [Vector],
    v: &mut [Vector],
    ws: &mut ExplicitScratch,
    h: f32,
) {
    model.accelerations(x, v, &mut ws.a);
    for i in 0..x.len() {
        x[i] += v[i] * h + ws.a[i] * (0.5 * h * h);
        ws.vt[i] = v[i] + ws.a[i] * h;
    }
    model.accelerations(x, &ws.vt, &mut ws.a2);
    for i in 0..x.len() {
        v[i] += (ws.a[i] + ws.a2[i]) * (0.5 * h);
    }
}
