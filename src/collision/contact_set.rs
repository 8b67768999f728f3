//! The contacts of a cloth's particles with the obstacles: one entry per
//! particle, stored as structure-of-arrays, written only by the collision
//! stage and read by the solvers through [`ContactSet::get`] and
//! [`ContactSet::response`].

use super::response::{respond, Response};
use crate::math::Vector;
use crate::parallel::Disjoint;

/// No obstacle.
pub(super) const NONE: u32 = u32::MAX;

/// One particle's contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleContact {
    /// The obstacle touched (index into the step's obstacles).
    pub obstacle: u32,
    /// Unit outward normal of its surface there.
    pub normal: Vector,
    /// Velocity of the surface there, in m/s.
    pub surface_velocity: Vector,
    /// True when the obstacle is fixed or kinematic (the cloth's push does not move it).
    pub immovable: bool,
    /// Gap (m) between the particle and the surface's thickness layer when
    /// the contact was detected ahead of the substep; 0 when touching.
    pub gap: f32,
    /// Coulomb friction coefficient of the surface.
    pub friction: f32,
}

/// A [`ContactSet`] that threads share, each taking a disjoint range of
/// particles ([`SharedContacts::range`]).
#[derive(Clone, Copy)]
pub(super) struct SharedContacts<'a> {
    touching: Disjoint<'a, bool>,
    obstacle: Disjoint<'a, u32>,
    immovable: Disjoint<'a, bool>,
    normal: Disjoint<'a, Vector>,
    surface_velocity: Disjoint<'a, Vector>,
}

/// The contacts of a range of particles, indexed from its first.
pub(super) struct ContactRange<'a> {
    touching: &'a mut [bool],
    obstacle: &'a mut [u32],
    immovable: &'a mut [bool],
    normal: &'a mut [Vector],
    surface_velocity: &'a mut [Vector],
}

impl<'a> SharedContacts<'a> {
    /// The contacts of particles `range`.
    ///
    /// # Safety
    /// No other range overlapping `range` may be in use meanwhile.
    pub(super) unsafe fn range(self, range: std::ops::Range<usize>) -> ContactRange<'a> {
        // SAFETY: exclusive by the caller's promise.
        unsafe {
            ContactRange {
                touching: self.touching.range(range.clone()),
                obstacle: self.obstacle.range(range.clone()),
                immovable: self.immovable.range(range.clone()),
                normal: self.normal.range(range.clone()),
                surface_velocity: self.surface_velocity.range(range),
            }
        }
    }
}

impl ContactRange<'_> {
    /// Particle `k` of the range no longer touches anything.
    pub(super) fn clear(&mut self, k: usize) {
        self.touching[k] = false;
    }

    /// Particle `k` of the range touches: everything but the gap and the
    /// friction, which only detection ahead of a substep sets.
    pub(super) fn touch(&mut self, k: usize, c: &ParticleContact) {
        self.touching[k] = true;
        self.obstacle[k] = c.obstacle;
        self.immovable[k] = c.immovable;
        self.normal[k] = c.normal;
        self.surface_velocity[k] = c.surface_velocity;
    }
}

/// Per particle: its contact, if it has one.
#[derive(Debug, Default)]
pub struct ContactSet {
    touching: Vec<bool>,
    obstacle: Vec<u32>,
    normal: Vec<Vector>,
    surface_velocity: Vec<Vector>,
    immovable: Vec<bool>,
    gap: Vec<f32>,
    friction: Vec<f32>,
}

impl ContactSet {
    /// Makes room for `particles` particles; contacts carried over from the
    /// last step must name one of this step's `obstacles`.
    pub(super) fn begin_step(&mut self, particles: usize, obstacles: usize) {
        self.touching.resize(particles, false);
        self.obstacle.resize(particles, NONE);
        self.immovable.resize(particles, false);
        self.gap.resize(particles, 0.0);
        self.friction.resize(particles, 0.0);
        for i in 0..particles {
            if self.touching[i] && self.obstacle[i] as usize >= obstacles {
                self.touching[i] = false;
            }
        }
        self.normal.resize(particles, Vector::ZERO);
        self.surface_velocity.resize(particles, Vector::ZERO);
        if obstacles == 0 {
            self.touching.fill(false);
        }
    }

    /// Particle `i`'s contact, if it touches (or is about to reach) an obstacle.
    pub fn get(&self, i: usize) -> Option<ParticleContact> {
        self.touching
            .get(i)
            .copied()
            .unwrap_or(false)
            .then(|| ParticleContact {
                obstacle: self.obstacle[i],
                normal: self.normal[i],
                surface_velocity: self.surface_velocity[i],
                immovable: self.immovable[i],
                gap: self.gap[i],
                friction: self.friction[i],
            })
    }

    /// The obstacle particle `i` last touched (stale when it does not touch one now).
    pub(crate) fn last_obstacle(&self, i: usize) -> u32 {
        self.obstacle[i]
    }

    /// The contact normal of particle `i` (stale when it does not touch).
    pub(crate) fn normal(&self, i: usize) -> Vector {
        self.normal[i]
    }

    /// The surface velocity at particle `i` (stale when it does not touch).
    pub(crate) fn surface_velocity(&self, i: usize) -> Vector {
        self.surface_velocity[i]
    }

    /// The friction coefficient at particle `i` (stale when it does not touch).
    pub(crate) fn friction(&self, i: usize) -> f32 {
        self.friction[i]
    }

    /// Particle `i` no longer touches anything.
    pub(super) fn clear(&mut self, i: usize) {
        self.touching[i] = false;
    }

    /// Particle `i` will reach an obstacle within the substep (or touches it): all of the contact.
    pub(super) fn detect(&mut self, i: usize, c: &ParticleContact) {
        let shared = self.shared();
        // SAFETY: `shared` borrows the whole set, and this is its one range.
        unsafe { shared.range(i..i + 1) }.touch(0, c);
        self.gap[i] = c.gap;
        self.friction[i] = c.friction;
    }

    /// The contacts, for threads that each take a disjoint range of particles.
    pub(super) fn shared(&mut self) -> SharedContacts<'_> {
        SharedContacts {
            touching: Disjoint::new(&mut self.touching),
            obstacle: Disjoint::new(&mut self.obstacle),
            immovable: Disjoint::new(&mut self.immovable),
            normal: Disjoint::new(&mut self.normal),
            surface_velocity: Disjoint::new(&mut self.surface_velocity),
        }
    }

    /// How particle `i`'s contact responds over a substep of `h` seconds,
    /// for a solver that takes contacts into its solve: `v` is its velocity
    /// and `accel` its acceleration under the current forces (m/s²). Free
    /// unless it touches a fixed or kinematic obstacle: a dynamic body would
    /// be treated as infinitely heavy and thrown back.
    pub fn response(&self, i: usize, v: Vector, accel: Vector, h: f32) -> Response {
        if !(self.touching.get(i).copied().unwrap_or(false) && self.immovable[i]) {
            return Response::Free;
        }
        let rel = v - self.surface_velocity[i];
        respond(
            rel,
            rel + accel * h,
            self.normal[i],
            self.gap[i],
            self.friction[i],
            h,
        )
    }
}
