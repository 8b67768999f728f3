//! The cloth follows what pushed it: after the collision stage has put the
//! particles out of the obstacles, the stretch limit again, then the
//! obstacles again, with every integrator (an explicit one only within
//! its stability limit: past it, a run must still diverge and say so).
//!
//! Why: the contacts come after the substep's limit so that they win where
//! the two disagree, and they move each particle alone. An obstacle that
//! moves far in one substep (the `curtain`'s ball, 33 mm a frame, with
//! fast mass-spring's and implicit Euler's one substep a frame) pushes a
//! patch of cloth out through the faces its particles entered by, and the
//! springs from that patch to the particles it left behind, or between
//! two particles traced out through different faces, end far over the
//! limit: the curtain peaked at 214% stretch with fast mass-spring and 18%
//! with implicit Euler. The collision stage's own hold (`stretch_hold.rs`)
//! moves only the ends near an obstacle, which here are the ones the
//! obstacle keeps where they are. The small-steps solver holds most
//! contacts in its lanes, but where the stage runs (dynamic and moving
//! bodies, the step's last substep) the same push left the `hammock`
//! 5.14% stretched at its boxes' impacts, the `curtain` 4.93% and the
//! `box` 4.67%; now 4.51% each.
//!
//! So: while a stretch spring is over the limit, up to [`ROUNDS`] times,
//! the relaxed limit (`strain_limit.rs`) moves every free particle by its
//! weight near the pins (`pin_support.rs`), touching or not (holding the
//! touching ones left both ends of a spring across the ball fixed: no
//! change), and the obstacles push out what it moved into them, positions
//! only (the contacts' velocities and friction were settled by the stage).
//! Measured on the curtain, peak stretch over 120 frames with fast
//! mass-spring / implicit Euler: 214% / 18% without, 11.1% / 10.2% with
//! one round, 6.1% / 5.7% with four, 4.9% / 4.8% with eight, 4.54% /
//! 4.52% with sixteen; no penetration in any frame. Most calls find no
//! spring over the limit and take no round (the hammock: 12 197 of 12 391
//! calls in 480 frames, the rest 1–9 rounds).

use super::strain_limit::{limit_stretch_supported, relaxed_passes};
use super::workspace::Workspace;
use crate::cloth::Cloth;
use crate::collision::{any_stretch_over_limit, Obstacle};
use crate::parallel::Team;

/// Rounds of the limit and the obstacles at most; they stop as soon as no
/// stretch spring is over the limit.
const ROUNDS: usize = 16;

/// After the collision stage of a substep of `h` seconds: up to [`ROUNDS`]
/// rounds of the relaxed stretch limit over the whole cloth (its passes by
/// the substep, `relaxed_passes`) and the obstacles' push out to
/// `thickness` (m), while a stretch spring is over the limit (module
/// docs). Returns the rounds taken.
pub(crate) fn follow_contacts(
    cloth: &mut Cloth,
    obstacles: &[Obstacle],
    ws: &mut Workspace,
    (thickness, h, team): (f32, f32, Team),
) -> u32 {
    let factor = cloth.material.stretch_limit_factor();
    if !factor.is_finite() || obstacles.is_empty() {
        return 0;
    }
    let springs = &cloth.topology.springs;
    let revision = cloth.mass_revision();
    let p = &mut cloth.particles;
    for round in 0..ROUNDS {
        if !any_stretch_over_limit(springs, &p.x, factor, team) {
            return round as u32;
        }
        limit_stretch_supported(
            &mut ws.limit_scratch,
            (springs, &p.inv_mass, revision),
            (&mut p.x, Some(&mut p.v)),
            factor,
            // From the last round's passes on: what moved since is noted.
            (relaxed_passes(h), round > 0),
        );
        let limit = &mut ws.limit_scratch;
        ws.collision
            .project_positions(&mut p.x, &p.inv_mass, obstacles, thickness, |i| {
                limit.moved(i)
            });
    }
    ROUNDS as u32
}
