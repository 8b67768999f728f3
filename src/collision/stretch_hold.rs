//! The stretch limit held against the contacts. The solvers shorten every
//! stretch spring to the material's limit before the contacts, and the
//! contacts win where the two disagree. But a contact pushes a particle out
//! along the obstacle's normal, which at a box's corner or edge points away
//! from its neighbours: cloth draped over a table's corner ended 6%
//! stretched under a 4.5% limit (measured), though it could lie
//! within the limit outside the table. This pass shortens the stretch
//! springs with an end near an obstacle once more, moving only the ends
//! near one (an end away from the obstacles has springs this pass does not
//! look at: moving it stretched those, 5.09% on the 128 × 128 drape's
//! landing against 4.81% so), then pushes every particle it moved back out
//! of the obstacles; a few rounds let the neighbours slide round the
//! corner to where both hold.

use super::contact_set::NONE;
use super::obstacle::Obstacle;
use super::stage::CollisionStage;
use crate::cloth::{Particles, SpringKind, Springs};
use crate::math::Vector;

/// Rounds of shortening and pushing out at most; they stop when no spring
/// near an obstacle is over the limit.
const ROUNDS: usize = 4;

/// How far over its limit, as a share of it, a spring may be and count as
/// within it, in every stretch limit (this hold, the solvers' limit after
/// a substep and the grid's): a spring shortened to its limit measures a
/// few parts in 10⁷ either side of it, and without a slack the passes
/// would chase the rounding.
pub(crate) const LIMIT_SLACK: f32 = 1.0e-4;

impl CollisionStage {
    /// Shortens to `factor` times their rest length the stretch `springs`
    /// with an end near an obstacle (the watched ones, when `watched`), each
    /// end near an obstacle moving by its inverse mass (the other held) and
    /// the ends losing the velocity that still stretches the spring; then
    /// moves each particle it moved back out to `thickness` of the
    /// obstacles. Returns the springs shortened.
    pub(super) fn hold_stretch_limit(
        &mut self,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        (factor, thickness, watched): (f32, f32, bool),
    ) -> u32 {
        if !factor.is_finite() {
            return 0;
        }
        let stretch = springs.range(SpringKind::Stretch);
        // The watched springs are in spring order, stretch first.
        let count = if watched {
            self.edge_watch
                .partition_point(|&s| (s as usize) < stretch.end)
        } else {
            stretch.len()
        };
        let mut shortened = 0;
        for round in 0..ROUNDS {
            self.moved.clear();
            for k in 0..count {
                let s = if watched {
                    self.edge_watch[k] as usize
                } else {
                    stretch.start + k
                };
                let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
                // After the first round, a spring can be over the limit only
                // if the last round or this one moved an end: the others
                // kept the length a round found within it. Skipping them
                // is what a full look would do (nothing), at a fraction of
                // the cost: a round shortens a few springs of thousands.
                let touched = |i: usize| self.held_moved[i] || self.edge_moved[i];
                if round > 0 && !touched(a) && !touched(b) {
                    continue;
                }
                if self.nearest[a] == NONE && self.nearest[b] == NONE {
                    continue;
                }
                // Only ends near an obstacle move: an end away from them
                // has other springs, which this pass does not look at and
                // must not stretch (it is held like a pin here).
                let Particles { x, v, inv_mass, .. } = &mut *particles;
                let near = |i: usize| self.nearest[i] != NONE;
                let wa = if near(a) { inv_mass[a] } else { 0.0 };
                let wb = if near(b) { inv_mass[b] } else { 0.0 };
                let w = wa + wb;
                let d = x[b] - x[a];
                let limit = springs.rest[s] * factor;
                let len2 = d.length_squared();
                // Over by more than the slack every limit allows (also
                // false for a length that is not a number).
                let slack = limit * (1.0 + LIMIT_SLACK);
                let over = len2 > slack * slack;
                if !over || w == 0.0 {
                    continue;
                }
                let len = len2.sqrt();
                let n = d / len;
                let step = n * ((len - limit) / w);
                x[a] += step * wa;
                x[b] -= step * wb;
                stop_separating(v, (a, b), n, (wa, wb));
                for (i, wi) in [(a, wa), (b, wb)] {
                    if wi != 0.0 && !self.edge_moved[i] {
                        self.edge_moved[i] = true;
                        self.moved.push(i as u32);
                    }
                }
                shortened += 1;
            }
            // The last round's marks give way to this one's.
            self.forget_held();
            if self.moved.is_empty() {
                break;
            }
            // The contacts still win: every particle moved ends outside.
            let held = std::mem::take(&mut self.moved);
            for &i in &held {
                let i = i as usize;
                self.edge_moved[i] = false;
                self.held_moved[i] = true;
                let (x, v) = (&mut particles.x[i], &mut particles.v[i]);
                self.move_out(x, Some(v), obstacles, thickness);
            }
            // This round's list becomes the last round's; the emptied one
            // collects the next.
            self.moved = std::mem::replace(&mut self.held_before, held);
        }
        self.forget_held();
        shortened
    }

    /// Clears the marks of the particles the stretch hold's last round moved.
    fn forget_held(&mut self) {
        for &i in &self.held_before {
            self.held_moved[i as usize] = false;
        }
        self.held_before.clear();
    }
}

/// Takes away the velocity with which particles `a` and `b` (inverse
/// masses `wa`, `wb`, not both zero) still separate along the unit vector
/// `n` from `a` to `b`, each by its inverse mass: an inelastic stop, which
/// keeps their momentum and never adds energy.
#[inline]
pub(crate) fn stop_separating(
    v: &mut [Vector],
    (a, b): (usize, usize),
    n: Vector,
    (wa, wb): (f32, f32),
) {
    let separating = (v[b] - v[a]).dot(n);
    if separating > 0.0 {
        let dv = n * (separating / (wa + wb));
        v[a] += dv * wa;
        v[b] -= dv * wb;
    }
}
