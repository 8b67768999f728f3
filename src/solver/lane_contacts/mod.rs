//! Contacts with still balls, capsules, half-spaces and cuboids (a ball on
//! a stand, a bar, a floor, a table), and with sliding ones, held inside
//! the small-steps solver's substeps, in its grid lanes. The
//! collision stage after a substep visits every particle near an obstacle
//! through its general pass (candidates, exact contact, tracing, friction,
//! impulses): at N = 128 on the `drape`'s ball that was a third of the
//! frame, paid every substep. A still ball's or plane's contact is a few
//! vector operations a lane, so xpbd puts every particle back out of them
//! itself after the chains and after the last sweep, there with Coulomb
//! friction by how far it pushed (and at the step's last substep once
//! more after the stretch limit); the collision stage then runs only at
//! the step's last substep (the schedule skips it before, see
//! [`LaneContacts::holds`]), where its exact pass, edge pass and stretch
//! hold leave the frame as every other integrator's. While the contacts
//! are held, the cloth's state stays in the lanes from one substep to the
//! next (`xpbd.rs`).
//!
//! Every lane is looked at, not a list of candidates: a branchless vector pass
//! over the lanes is cheaper than gathering candidates, and misses no particle
//! whatever its speed. A particle is put back through the nearest point of the
//! surface: against a still shape over a substep's motion (a few millimetres)
//! that is the side it came in by; a ball must be several times larger than the
//! substep's fastest motion ([`BALL_MOTIONS`](contacts::BALL_MOTIONS)), or the
//! collision stage, which traces paths, keeps it. A cuboid holds each lane on
//! the tangent plane of the cuboid (rounded by the thickness) at the point
//! nearest to where the lane started the substep, found once a substep
//! ([`LaneContacts::take_planes`]), as the collision stage's contact planes
//! did: a lane pulled over an edge stays on the face it was on. The `box` went
//! from 9.0 to 5.9 ms a frame so, its peak stretch from 5.20% to 4.78%. A
//! spring between two particles held out may still cut a cuboid's edge: the
//! lanes keep the springs off the edges too, every second substep, as the
//! collision stage's edge pass does
//! ([`LaneContacts::keep_springs_off_cuboids`], `xpbd::CUBOID_EDGES_EVERY`);
//! the stage ran every second substep for that before, and the state left the
//! lanes for it (`box` 6.4 → 4.4 ms, bench, one thread).
//!
//! A body that moves without turning and is not dynamic (a kinematic bar, ball
//! or platform on its path) is held too, if made of balls, capsules,
//! half-spaces and cuboids: where it is at the substep's end, as the collision
//! stage takes it, with a lane's slide for friction taken relative to the
//! surface's move and a cuboid's plane from where the lane started relative to
//! it ([`lane_held`](contacts::lane_held)). The state then stays in the lanes
//! among such bodies too: the `tear`, whose sheet hangs from two sliding bars,
//! ran the collision stage after each of its 43 substeps: its instructions a
//! frame fell by a third, its frame from 6.7–8.0 to 3.3–5.5 ms on a slow host;
//! the `curtain`'s by two fifths.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod chunk;
mod contacts;
mod lanes;
mod portable;
mod shape;
mod still_cuboid;

pub(crate) use self::contacts::{Holding, LaneContacts};

#[cfg(test)]
mod tests;
