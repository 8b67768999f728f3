//! How the implicit solvers treat a contact during a substep: free, stuck
//! (static friction) or sliding (kinetic friction), decided from the state at
//! the start of the substep.
//!
//! Friction decided inside the solve lets the cloth around a held particle
//! answer in the same substep. Applied afterwards, as a position correction
//! of the touching particles alone, it stretches the springs to their free
//! neighbours by up to `μ v h` per substep, which at a 1/60 s frame step is
//! more than a fine cloth's spacing.

use crate::math::Vector;

/// Who decides Coulomb friction in a substep: the collision stage after
/// the solver's step, or the solver inside its solve. The solver hands it
/// back with its substep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionPolicy {
    /// The collision stage applies friction to the touching particles.
    Apply,
    /// The solver decided friction inside its solve; the collision stage only
    /// puts particles back on the surfaces.
    AlreadySolved,
}

/// A contact's role in one substep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Response {
    /// Not pressed against the surface: no constraint.
    Free,
    /// Held by static friction: ends the substep with this velocity relative
    /// to the surface (m/s), along the normal only.
    Stick {
        /// Relative velocity at the end of the substep (m/s).
        velocity: Vector,
    },
    /// Sliding: the normal part of the relative velocity is set, the
    /// tangential part is free and slowed by kinetic friction.
    Slide {
        /// Normal relative velocity at the end of the substep (m/s).
        normal_velocity: f32,
        /// Velocity change by kinetic friction over the substep (m/s).
        friction: Vector,
    },
}

/// Classifies a contact with unit normal `normal`, a `gap` (m) still to close
/// to the thickness layer (zero when touching) and friction coefficient `mu`:
/// `rel` is the particle's velocity relative to the surface now, `predicted`
/// what it would be at the end of the substep of `h` seconds under the
/// current forces, unconstrained.
pub fn respond(
    rel: Vector,
    predicted: Vector,
    normal: Vector,
    gap: f32,
    mu: f32,
    h: f32,
) -> Response {
    // A speculative contact may approach as fast as closes the gap, and acts
    // only if the particle would otherwise move faster; a touching one may
    // not approach at all, and holds until the particle moves away.
    let allowed = -gap / h;
    let pressing = (allowed - predicted.dot(normal)).max(0.0);
    let holding = gap <= 0.0 && rel.dot(normal) <= 0.0;
    if pressing <= 0.0 && !holding {
        return Response::Free;
    }
    let slide = predicted - normal * predicted.dot(normal);
    let speed = slide.length();
    let grip = mu * pressing;
    if grip > 0.0 && speed <= grip {
        Response::Stick {
            velocity: normal * allowed,
        }
    } else {
        Response::Slide {
            normal_velocity: allowed,
            friction: -slide * (grip / speed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UP: Vector = Vector::Y;

    #[test]
    fn resting_particle_sticks_and_a_pushed_one_slides() {
        let h = 0.01;
        // Resting, pulled down by gravity: stuck.
        let r = respond(Vector::ZERO, Vector::new(0.0, -0.1, 0.0), UP, 0.0, 0.5, h);
        assert_eq!(
            r,
            Response::Stick {
                velocity: Vector::ZERO
            }
        );
        // Pulled sideways harder than μ times down: slides, slowed by μ·0.1.
        let r = respond(Vector::ZERO, Vector::new(1.0, -0.1, 0.0), UP, 0.0, 0.5, h);
        let Response::Slide {
            normal_velocity,
            friction,
        } = r
        else {
            panic!("{r:?}")
        };
        assert_eq!(normal_velocity, 0.0);
        assert!((friction - Vector::new(-0.05, 0.0, 0.0)).length() < 1e-6);
        // Leaving the surface: free.
        let r = respond(
            Vector::new(0.0, 1.0, 0.0),
            Vector::new(0.0, 0.9, 0.0),
            UP,
            0.0,
            0.5,
            h,
        );
        assert_eq!(r, Response::Free);
    }

    #[test]
    fn speculative_contact_closes_its_gap_exactly() {
        let h = 0.01;
        // 1 cm away, arriving at 2 m/s: may approach at 1 m/s only.
        let r = respond(
            Vector::new(0.0, -2.0, 0.0),
            Vector::new(0.0, -2.0, 0.0),
            UP,
            0.01,
            0.0,
            h,
        );
        let Response::Slide {
            normal_velocity, ..
        } = r
        else {
            panic!("{r:?}")
        };
        assert!((normal_velocity + 1.0).abs() < 1e-6);
        // Arriving too slowly to reach it: free.
        let r = respond(
            Vector::new(0.0, -0.5, 0.0),
            Vector::new(0.0, -0.5, 0.0),
            UP,
            0.01,
            0.0,
            h,
        );
        assert_eq!(r, Response::Free);
    }
}
