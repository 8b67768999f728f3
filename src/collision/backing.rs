//! Bodies held up by the cloth they press against other obstacles: a
//! ball resting on a tablecloth on a table, or on a cloth over a crate.
//! The particle pass pushes each particle out of every obstacle in turn,
//! and hands the body the momentum the particle lost; a particle between
//! a ball and a table cannot make room, and the little momentum it has
//! cannot hold a body a thousand times heavier. The ball sank into the cloth, squeezing it out sideways:
//! a 1 kg ball on a 64² cotton tablecloth on a table left it 9% stretched,
//! and the stage's stretch hold and the rounds after it
//! (`solver/contact_follow.rs`) fought the squeeze every substep, 200 ms a
//! frame.
//!
//! So the pass records each particle a dynamic body presses against an
//! immovable obstacle ([`Backed`]), and the body then meets those
//! particles as it would meet the obstacle itself: sequential impulses
//! over them, along the immovable obstacle's normal (the only way it can
//! push back), stop the body coming closer and lift it by a share of the
//! layers' overlap ([`SUPPORT_LIFT`]). A particle pressed between two dynamic bodies
//! (and no immovable obstacle) pushes the two apart the same way, as two
//! bodies in contact: a 1 kg ball on a 32² cotton sheet over a 20 kg
//! crate sank 12 mm into the cloth's two 1 cm layers and left it 12.5%
//! stretched; now 7 mm and 5.7% (the crate, pushed down inside the
//! cloth's step, is held up by its floor only in rapier's step after it).
//! A particle is taken to be pressed when the contacts it was pushed out
//! of last face each other (normals more than 120° apart).
//!
//! Against an immovable backer the same impulses carry Coulomb friction:
//! the body pressing the cloth onto the table cannot slide over it
//! freely, as the particle's own friction (its own weight's worth) let
//! it. A 1 kg box landing at 1 m/s on the laid table slid on at 0.9 m/s
//! and off the table; the cloth slips where it holds least, so the
//! coefficient is the smaller of the body's and the backer's
//! ([`Obstacle::friction`]). And the body turns as if pushed along its own
//! normal ([`Backed::lever`]).

use super::obstacle::Obstacle;
use super::tracks::ObstacleTracks;
use crate::math::Vector;

/// A particle caught between a dynamic body and another obstacle (its
/// backer: immovable, or another dynamic body): their thickness layers
/// overlap where it is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Backed {
    /// The dynamic body (index into the step's obstacles).
    pub obstacle: u32,
    /// The obstacle behind the particle: immovable, or another dynamic
    /// body (index into the step's obstacles).
    pub backer: u32,
    /// The particle's position (m), where the body is pushed.
    pub point: Vector,
    /// The direction (unit) the body presses the particle in: into the
    /// backer, against its normal, which is the only way it can push
    /// back (along the body's own normal, a ball landing off
    /// centre on its first few backed particles was kicked sideways at
    /// 0.35 m/s and rolled off the table).
    pub normal: Vector,
    /// The direction (unit) the body turns as if pushed along: against an
    /// immovable backer, its own outward normal at the particle. A ball is
    /// pushed through its centre and does not turn; pushed along `normal`
    /// at the particles beside its lowest point, one resting on the laid
    /// table spun in place at up to 11 rad/s (and rolled away, once the
    /// support had friction). Against another dynamic body, `normal`
    /// itself ([`support_backed`] says why).
    pub lever: Vector,
    /// How far (m) the two thickness layers overlap.
    pub depth: f32,
    /// The velocity (m/s) of an immovable backer's surface there, which
    /// the particle cannot leave along the normal.
    pub velocity: Vector,
}

/// Gauss–Seidel rounds over the backed particles.
const SUPPORT_ROUNDS: usize = 8;

/// The share of the layers' overlap a body pressing backed particles is
/// lifted by over a step: the overlap is taken back over a few frames, as
/// a velocity the body keeps. (Measured the other way: with the
/// particle's own velocity in place of the immovable surface's, the
/// overlap alone pushed back, as a spring, and the ball bounced back to
/// nearly the height it fell from.)
const SUPPORT_LIFT: f32 = 0.2;

/// The impulses (N·s) a backed particle passes on to the body pressing it
/// ([`support_backed`]'s scratch, one per [`Backed`]).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Support {
    /// Along the backer's normal: how hard the body is held up (≥ 0).
    normal: f32,
    /// Across it, on the body: Coulomb friction, at most the friction
    /// coefficient times `normal` long.
    friction: Vector,
}

/// A body's state through [`support_backed`]: its velocity (m/s), angular
/// velocity (rad/s) and centre of mass (m).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Moving {
    v: Vector,
    w: Vector,
    com: Vector,
}

/// Holds up each dynamic body by the particles it presses against another
/// obstacle (`backed`, in block and particle order: the same bits on any
/// number of threads): against an immovable one, as that obstacle would;
/// against another dynamic body, the two pushed apart as two bodies in
/// contact. Sequential impulses from the velocities each body will have
/// over the next substep of `h` seconds, lifting by [`SUPPORT_LIFT`] of
/// the overlap per step of `dt` seconds, with Coulomb friction against
/// sliding along an immovable backer (module docs). The momentum goes to
/// the bodies (and to rapier) as any particle's push does; an immovable
/// obstacle behind the particle gives it. `support` and `moving` are
/// scratch.
pub(super) fn support_backed(
    tracks: &mut ObstacleTracks,
    obstacles: &[Obstacle],
    backed: &[Backed],
    (h, dt): (f32, f32),
    (support, moving): (&mut Vec<Support>, &mut Vec<Moving>),
) {
    moving.clear();
    moving.extend(obstacles.iter().enumerate().map(|(o, obstacle)| {
        obstacle.body.as_ref().map_or(Moving::default(), |body| {
            let (v, w, com) = tracks.next_velocities(o, body, h);
            Moving { v, w, com }
        })
    }));
    let body = |o: u32| obstacles.get(o as usize).and_then(|b| b.body.as_ref());
    // Between two dynamic bodies, neither the turn along the body's own
    // normal (`Backed::lever` is `normal` there) nor friction: with
    // either a 1 kg ball on cloth over a 20 kg crate (which this step
    // pushes down, its floor only in rapier's step) rolled off its spot
    // and left the cloth 7.5% stretched, not 5.7%. README's known limits
    // say so.
    let friction = |c: &Backed| {
        let of = |o: u32| obstacles.get(o as usize).map_or(0.0, |o| o.friction);
        if body(c.backer).is_some() {
            0.0
        } else {
            of(c.obstacle).min(of(c.backer)).max(0.0)
        }
    };
    support.clear();
    support.resize(backed.len(), Support::default());
    for _ in 0..SUPPORT_ROUNDS {
        for (c, held) in backed.iter().zip(support.iter_mut()) {
            let Some(pressing) = body(c.obstacle) else {
                continue;
            };
            let n = c.normal;
            let a = moving[c.obstacle as usize];
            let ra = c.point - a.com;
            // Along `normal` for the body's motion, along `lever` for its
            // turn.
            let rna = ra.cross(c.lever);
            let mut k = n.dot(pressing.inverse_mass * n) + rna.dot(pressing.inverse_inertia * rna);
            // The backer's surface velocity, and its share of the mass.
            let (backer, mut surface, mut rnb) = (body(c.backer), c.velocity, Vector::ZERO);
            if let Some(backer) = backer {
                let b = moving[c.backer as usize];
                let rb = c.point - b.com;
                (surface, rnb) = (b.v + b.w.cross(rb), rb.cross(n));
                k += n.dot(backer.inverse_mass * n) + rnb.dot(backer.inverse_inertia * rnb);
            }
            if !(k > 0.0 && k.is_finite()) {
                continue;
            }
            // How fast the body comes closer to the backer along n, and
            // how fast it should leave.
            let closing = (a.v - surface).dot(n) + a.w.dot(rna);
            let lift = SUPPORT_LIFT * c.depth / dt;
            let total = (held.normal + (closing + lift) / k).max(0.0);
            let change = total - held.normal;
            held.normal = total;
            let a = &mut moving[c.obstacle as usize];
            a.v -= pressing.inverse_mass * n * change;
            a.w -= pressing.inverse_inertia * (rna * change);
            if let Some(backer) = backer {
                let b = &mut moving[c.backer as usize];
                b.v += backer.inverse_mass * n * change;
                b.w += backer.inverse_inertia * (rnb * change);
            }
            // Friction (against an immovable backer only): the body's
            // slide along it, at the velocities the support left, taken
            // away up to the coefficient times the support so far.
            let limit = friction(c) * held.normal;
            if limit.is_nan() || limit <= 0.0 {
                continue;
            }
            let a = moving[c.obstacle as usize];
            let slide = a.v + a.w.cross(ra) - c.velocity;
            let slide = slide - n * slide.dot(n);
            let speed = slide.length();
            if !(speed > 0.0 && speed.is_finite()) {
                continue;
            }
            let t = slide / speed;
            let rta = ra.cross(t);
            let kt = t.dot(pressing.inverse_mass * t) + rta.dot(pressing.inverse_inertia * rta);
            if !(kt > 0.0 && kt.is_finite()) {
                continue;
            }
            let wanted = held.friction - t * (speed / kt);
            let total = if wanted.length_squared() > limit * limit {
                wanted.normalize_or_zero() * limit
            } else {
                wanted
            };
            let change = total - held.friction;
            held.friction = total;
            let a = &mut moving[c.obstacle as usize];
            a.v += pressing.inverse_mass * change;
            a.w += pressing.inverse_inertia * ra.cross(change);
        }
    }
    // Handed on with the turn the rounds gave: the support's along
    // `lever`, friction's at the particle.
    for (c, held) in backed.iter().zip(support.iter()) {
        if held.normal > 0.0 {
            let com = moving[c.obstacle as usize].com;
            let ra = c.point - com;
            let on_body = held.friction - c.normal * held.normal;
            let spin = ra.cross(held.friction - c.lever * held.normal);
            tracks.add_impulse_and_spin(c.obstacle as usize, com, on_body, spin);
            if body(c.backer).is_some() {
                tracks.add_impulse(c.backer as usize, c.point, -on_body);
            }
        }
    }
}
