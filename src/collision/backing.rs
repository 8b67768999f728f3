//! Bodies held up by the cloth they press against immovable obstacles: a
//! ball resting on a tablecloth on a table. The particle pass pushes each
//! particle out of every obstacle in turn, and hands the body the momentum
//! the particle lost; a particle between a ball and a table cannot make
//! room, and the little momentum it has cannot hold a body a thousand
//! times heavier. The ball sank into the cloth, squeezing it out sideways:
//! a 1 kg ball on a 64² cotton tablecloth on a table left it 9% stretched,
//! and the stage's stretch hold and the rounds after it
//! (`solver/contact_follow.rs`) fought the squeeze every substep, 200 ms a
//! frame.
//!
//! So the pass records each particle a dynamic body presses against an
//! immovable obstacle ([`Backed`]: their contact normals more than 120°
//! apart), and the body then meets those particles as it would meet the
//! obstacle itself: sequential impulses over them, along the immovable
//! obstacle's normal (the only way it can push back), stop the body
//! coming closer and lift it by a share of the layers' overlap
//! ([`SUPPORT_LIFT`]). Dynamic bodies pressing each other through the
//! cloth are left as they were.

use super::obstacle::Obstacle;
use super::tracks::ObstacleTracks;
use crate::math::Vector;

/// A particle caught between a dynamic body and an immovable obstacle:
/// their thickness layers overlap where it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Backed {
    /// The dynamic body (index into the step's obstacles).
    pub obstacle: u32,
    /// The particle's position (m), where the body is pushed.
    pub point: Vector,
    /// The direction (unit) the body presses the particle in: into the
    /// immovable obstacle, against its normal, which is the only way it
    /// can push back (along the body's own normal, a ball landing off
    /// centre on its first few backed particles was kicked sideways at
    /// 0.35 m/s and rolled off the table).
    pub normal: Vector,
    /// How far (m) the two thickness layers overlap.
    pub depth: f32,
    /// The velocity (m/s) of the immovable obstacle's surface there, which
    /// the particle cannot leave along the normal.
    pub velocity: Vector,
}

/// Gauss–Seidel rounds over a body's backed particles.
const SUPPORT_ROUNDS: usize = 8;

/// The share of the layers' overlap a body pressing backed particles is
/// lifted by over a step: the overlap is taken back over a few frames, as
/// a velocity the body keeps. (Measured the other way: with the
/// particle's own velocity in place of the immovable surface's, the
/// overlap alone pushed back, as a spring, and the ball bounced back to
/// nearly the height it fell from.)
const SUPPORT_LIFT: f32 = 0.2;

/// Holds up each dynamic body by the particles it presses against
/// immovable obstacles (`backed`, in block and particle order: the same
/// bits on any number of threads), from the velocities it will have over
/// the next substep of `h` seconds, lifting it by [`SUPPORT_LIFT`] of the
/// overlap per step of `dt` seconds. The momentum goes to the body (and to
/// rapier) as any particle's push does; the obstacle behind the particle
/// gives it. `support` is scratch.
pub(super) fn support_backed(
    tracks: &mut ObstacleTracks,
    obstacles: &[Obstacle],
    backed: &[Backed],
    (h, dt): (f32, f32),
    support: &mut Vec<f32>,
) {
    for (o, obstacle) in obstacles.iter().enumerate() {
        let Some(body) = &obstacle.body else {
            continue;
        };
        let pressing = |b: &&Backed| b.obstacle as usize == o;
        if !backed.iter().any(|b| pressing(&b)) {
            continue;
        }
        let (mut v, mut w, com) = tracks.next_velocities(o, body, h);
        support.clear();
        support.resize(backed.len(), 0.0);
        for _ in 0..SUPPORT_ROUNDS {
            let each = backed.iter().zip(support.iter_mut());
            for (c, lambda) in each.filter(|(b, _)| pressing(b)) {
                let (r, n) = (c.point - com, c.normal);
                let rn = r.cross(n);
                let k = n.dot(body.inverse_mass * n) + rn.dot(body.inverse_inertia * rn);
                if !(k > 0.0 && k.is_finite()) {
                    continue;
                }
                // How fast the body comes closer along n, and how fast it
                // should leave.
                let closing = (v + w.cross(r) - c.velocity).dot(n);
                let lift = SUPPORT_LIFT * c.depth / dt;
                let total = (*lambda + (closing + lift) / k).max(0.0);
                let change = total - *lambda;
                *lambda = total;
                v -= body.inverse_mass * n * change;
                w -= body.inverse_inertia * (rn * change);
            }
        }
        for (k, c) in backed.iter().enumerate().filter(|(_, b)| pressing(b)) {
            if support[k] > 0.0 {
                tracks.add_impulse(o, c.point, -c.normal * support[k]);
            }
        }
    }
}
