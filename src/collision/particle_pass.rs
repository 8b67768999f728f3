//! The particle pass of contact resolution: every particle near an obstacle
//! is pushed out to the thickness and, by the solver's policy, slowed by
//! Coulomb friction. Particles are taken in blocks of [`BLOCK`], which may
//! run on any thread: a block writes only its own particles, and sums the
//! momentum it hands to each obstacle in its scratch, in particle order;
//! the blocks' sums are added in block order afterwards. Blocks are cut by
//! particle count alone, so the bits never depend on the thread count.

use parry3d::query::Ray;

use super::backing::Backed;
use super::contact::Contact;
use super::contact_set::{ContactRange, ParticleContact, NONE};
use super::obstacle::{Obstacle, ObstacleImpulse};
use super::response::FrictionPolicy;
use super::tracks::ObstacleTracks;
use crate::context::StepContext;
use crate::math::Vector;

/// Distance (m) beyond the thickness within which a particle still counts as touching.
pub(super) const CONTACT_SLACK: f32 = 1.0e-5;

/// Particles in a block of the pass: large enough that a block outweighs
/// handing it to a thread, small enough that a cloth of a few thousand
/// particles still has blocks for two threads.
pub(super) const BLOCK: usize = 1024;

/// Scratch of one block: the candidates of its current particle, and the
/// momentum its particles handed to each obstacle. Alone on its cache
/// lines: blocks on different threads write their scratch at once.
#[derive(Debug, Default)]
#[repr(align(128))]
pub(super) struct BlockScratch {
    candidates: Vec<u32>,
    /// Per obstacle: the momentum this block's particles handed it, summed
    /// in particle order.
    pub impulses: Vec<ObstacleImpulse>,
    /// Particles that came near an obstacle from outside their cached
    /// margin ([`super::tracks::ObstacleTracks::has_cached`] missed them).
    pub strays: u32,
    /// The farthest (squared, m²) a particle of the block has moved since
    /// the step's start, after resolution (infinite without a cache).
    pub drift2: f32,
    /// A pinned particle of the block lies within the thickness of an
    /// obstacle (where no pass moves it out).
    pub pinned_close: bool,
    /// The farthest (squared, m²) this pass moved a particle of the block.
    pub shift2: f32,
    /// Particles of the block pressed by a dynamic body against another
    /// obstacle, in particle order ([`Backed`]).
    pub backed: Vec<Backed>,
}

/// Two contact normals at least this opposed (the cosine of the angle
/// between them at most its negative) press a particle between them.
const OPPOSED: f32 = 0.5;

/// What a block of the pass writes, indexed from the block's first particle:
/// positions (m) and velocities (m/s); the nearest obstacle (`NONE` for
/// none), its outward normal, and the distance to it after resolution (m);
/// the offset (m) of the plane tangent to that obstacle at its point
/// nearest to the particle (`n · p` for a point `p` of the plane); the
/// contacts.
pub(super) struct BlockOut<'a> {
    pub x: &'a mut [Vector],
    pub v: &'a mut [Vector],
    pub nearest: &'a mut [u32],
    pub normal: &'a mut [Vector],
    pub distance: &'a mut [f32],
    pub surface: &'a mut [f32],
    pub contacts: ContactRange<'a>,
}

/// What every block of the pass reads.
pub(super) struct ParticlePass<'a> {
    pub ctx: &'a StepContext,
    pub tracks: &'a ObstacleTracks,
    pub obstacles: &'a [Obstacle],
    /// Positions at the start of the substep (m), for tracing.
    pub x_prev: &'a [Vector],
    pub mass: &'a [f32],
    pub inv_mass: &'a [f32],
    pub friction: FrictionPolicy,
    /// Pass over the still obstacles but for a particle a moving or
    /// dynamic body touched ([`super::stage::ResolveOptions::skip_still`]).
    pub skip_still: bool,
    /// Beyond this distance (m) an obstacle is neither touched nor near.
    pub far: f32,
}

impl ParticlePass<'_> {
    /// Resolves the particles `range` (the block's); returns the contacts resolved.
    pub fn block(
        &self,
        range: std::ops::Range<usize>,
        out: &mut BlockOut,
        scratch: &mut BlockScratch,
    ) -> u32 {
        scratch.strays = 0;
        scratch.drift2 = 0.0;
        scratch.pinned_close = false;
        scratch.shift2 = 0.0;
        scratch.backed.clear();
        scratch.impulses.clear();
        scratch
            .impulses
            .resize(self.obstacles.len(), ObstacleImpulse::default());
        if let Some(law) = self.tracks.one_obstacle_law(self.obstacles) {
            return self.lanes_block(&law, range, out, scratch);
        }
        let mut contacts = 0;
        for (k, i) in range.enumerate() {
            // Most particles of a cloth are far from every obstacle: what
            // `particle` does for them, without its call (a third of the
            // torn sheet's pass went to calls finding no candidate).
            // Nor, in a pass over the bodies alone, for a particle near
            // still obstacles only: `particle` passes over those (the laid
            // table's 4096 particles under a box, a body's substeps).
            let free = if self.skip_still {
                self.tracks.still_only_drift2(i, out.x[k])
            } else {
                self.tracks.free_drift2(i, out.x[k])
            };
            if let Some(drift2) = free {
                out.nearest[k] = NONE;
                out.contacts.clear(k);
                scratch.drift2 = scratch.drift2.max(drift2);
            } else {
                contacts += self.particle(k, i, out, scratch);
            }
        }
        contacts
    }

    /// Resolves particle `i`, the block's `k`th, against every candidate
    /// obstacle; returns the contacts resolved.
    pub(super) fn particle(
        &self,
        k: usize,
        i: usize,
        out: &mut BlockOut,
        scratch: &mut BlockScratch,
    ) -> u32 {
        let thickness = self.ctx.thickness;
        let mut contacts = 0;
        let before = out.x[k];
        out.nearest[k] = NONE;
        out.contacts.clear(k);
        let cached = self
            .tracks
            .gather_particle(i, out.x[k], &mut scratch.candidates);
        let mut nearest_distance = f32::INFINITY;
        // The last immovable obstacle and the last two dynamic bodies
        // touched, and whether a moving or dynamic body did.
        let (mut immovable, mut dynamic, mut dynamic_before) = (None, None, None);
        let mut body_touched = false;
        // Round 0 over the candidates the pass answers for; where it
        // passes over the still ones, round 1 over those, for a particle a
        // moving or dynamic body touched.
        for round in 0..2 {
            if round == 1 && !(self.skip_still && body_touched) {
                break;
            }
            for c in 0..scratch.candidates.len() {
                let o = scratch.candidates[c] as usize;
                if self.skip_still && (round == 0) == self.obstacles[o].is_still() {
                    continue;
                }
                // Beyond the reach of the contact and the edge pass: as if
                // it were not a candidate (the edge pass then takes the
                // particle's distance to be the reach, less than it is).
                if self.tracks.surely_beyond(o, out.x[k], self.far) {
                    continue;
                }
                let Some(hit) = self.contact(o, self.x_prev[i], out.x[k]) else {
                    continue;
                };
                if hit.signed_distance < nearest_distance {
                    nearest_distance = hit.signed_distance;
                    out.nearest[k] = o as u32;
                    out.normal[k] = hit.normal;
                    out.surface[k] = hit.normal.dot(hit.point);
                    // Resolution below leaves a particle at least the thickness out.
                    out.distance[k] = if self.inv_mass[i] != 0.0 {
                        hit.signed_distance.max(thickness)
                    } else {
                        hit.signed_distance
                    };
                }
                // A hair of slack keeps particles a solver left exactly at the
                // thickness in contact, so friction still acts on them.
                if self.inv_mass[i] != 0.0 && hit.signed_distance < thickness + CONTACT_SLACK {
                    let (contact, (point, j)) =
                        self.resolve(i, (&mut out.x[k], &mut out.v[k]), (o, hit));
                    out.contacts.touch(k, &contact);
                    body_touched |= !self.obstacles[o].is_still();
                    if contact.immovable {
                        immovable = Some((o, contact.normal, contact.surface_velocity));
                    } else {
                        if dynamic.is_some_and(|(d, _)| d != o) {
                            dynamic_before = dynamic;
                        }
                        dynamic = Some((o, contact.normal));
                    }
                    let sum = &mut scratch.impulses[o];
                    sum.linear += j;
                    sum.angular_about_origin += point.cross(j);
                    sum.contacts += 1;
                    contacts += 1;
                }
            }
        }
        // Pressed against an immovable obstacle, or else between two
        // dynamic bodies (the first of them presses).
        match (immovable, dynamic, dynamic_before) {
            (Some(s), Some(d), _) if s.1.dot(d.1) < -OPPOSED => {
                // Moved by the pass along the obstacle's normal only: the
                // body presses the particle onto it, and cannot squeeze it
                // out sideways (the support holds the body up instead).
                // Pushed out along a box's corner, the particle under it
                // stretched its springs past the limit, which the rounds
                // after the stage (`contact_follow.rs`) then fought every
                // substep: a box landing tilted on the laid table took
                // 117–431 ms in that frame in six drops of ten; 29–37 ms
                // now (BENCHMARKS.md, forty-second session).
                let moved = out.x[k] - before;
                out.x[k] = before + s.1 * moved.dot(s.1);
                self.back(k, (s.0, d.0, s.2), out, scratch);
            }
            (_, Some(d), Some(e)) if e.1.dot(d.1) < -OPPOSED => {
                let (a, b) = (d.0.min(e.0), d.0.max(e.0));
                self.back(k, (b, a, Vector::ZERO), out, scratch);
            }
            _ => {}
        }
        if !cached && out.nearest[k] != NONE {
            scratch.strays += 1;
        }
        if self.inv_mass[i] == 0.0 && nearest_distance < thickness {
            scratch.pinned_close = true;
        }
        scratch.drift2 = scratch.drift2.max(self.tracks.drift2(i, out.x[k]));
        scratch.shift2 = scratch.shift2.max((out.x[k] - before).length_squared());
        contacts
    }

    /// Records the block's `k`th particle as pressed by dynamic body `d`
    /// against obstacle `s` (immovable, or another dynamic body) when
    /// their thickness layers overlap where it ended ([`Backed`]): by how
    /// much, whichever of the two pushed it last; an immovable surface
    /// moves at `held` (m/s) there.
    fn back(
        &self,
        k: usize,
        (s, d, held): (usize, usize, Vector),
        out: &BlockOut,
        scratch: &mut BlockScratch,
    ) {
        let x = out.x[k];
        let (Some(on_s), Some(on_d)) = (
            self.tracks.contact(self.obstacles, s, x),
            self.tracks.contact(self.obstacles, d, x),
        ) else {
            return;
        };
        let depth = 2.0 * self.ctx.thickness - (on_s.signed_distance + on_d.signed_distance);
        if depth > 0.0 && depth.is_finite() {
            // Against another dynamic body, along the push (`Backed::lever`).
            let lever = if self.obstacles[s].body.is_some() {
                -on_s.normal
            } else {
                on_d.normal
            };
            scratch.backed.push(Backed {
                obstacle: d as u32,
                backer: s as u32,
                point: x,
                normal: -on_s.normal,
                lever,
                depth,
                velocity: held,
            });
        }
    }

    /// The contact with obstacle `o` of a particle now at `x` that started
    /// the substep at `x_prev`. A particle that ended the substep inside but
    /// started it outside (relative to the moving obstacle) is traced along
    /// its relative path, so it is pushed back out through the face it
    /// entered rather than through the nearest one: fast obstacles do not
    /// pass through the cloth.
    fn contact(&self, o: usize, x_prev: Vector, x: Vector) -> Option<Contact> {
        let tracks = self.tracks;
        let (obstacle, pose) = (&self.obstacles[o], &tracks.poses[o]);
        let c = tracks.contact(self.obstacles, o, x)?;
        if c.signed_distance >= 0.0 {
            return Some(c);
        }
        let prev = &tracks.prev_poses[o];
        let from = prev.inverse_transform_point(x_prev);
        if obstacle.shape.contains_local_point(from) {
            return Some(c);
        }
        let to = pose.inverse_transform_point(x);
        let ray = Ray::new(from, to - from);
        match obstacle
            .shape
            .cast_local_ray_and_get_normal(&ray, 1.0, true)
        {
            Some(hit) if hit.normal.is_finite() && hit.normal.length_squared() > 0.5 => {
                let entry = ray.point_at(hit.time_of_impact);
                let n = hit.normal.normalize();
                // Depth below the entry face, along its normal.
                let depth = (to - entry).dot(n).min(0.0);
                Some(Contact {
                    point: pose.transform_point(to - n * depth),
                    normal: pose.transform_vector(n),
                    signed_distance: depth,
                })
            }
            _ => Some(c),
        }
    }

    /// Pushes particle `i` (at `x`, moving at `v`) out of obstacle `o` (the
    /// `hit` with it) and, by the solver's policy, applies friction. Returns
    /// the contact, and the momentum (N·s) handed to the obstacle with the
    /// point (m) it was handed at.
    fn resolve(
        &self,
        i: usize,
        (x, v): (&mut Vector, &mut Vector),
        (o, hit): (usize, Contact),
    ) -> (ParticleContact, (Vector, Vector)) {
        let (ctx, obstacle) = (self.ctx, &self.obstacles[o]);
        let n = hit.normal;
        let v_old = *v;
        let pushed = push_out(
            (*x, v_old),
            (n, hit.signed_distance),
            ctx.thickness,
            #[inline(always)]
            |p| self.tracks.surface_velocity_of(self.obstacles, o, p),
            (
                obstacle.friction,
                self.friction == FrictionPolicy::Apply,
                ctx.h,
            ),
        );
        let (new_x, surface_v, v_new) = (pushed.surface, pushed.surface_velocity, pushed.v);
        *x = pushed.x;
        *v = v_new;
        let contact = ParticleContact {
            obstacle: o as u32,
            normal: n,
            surface_velocity: surface_v,
            immovable: obstacle.body.is_none(),
            gap: 0.0,
            friction: obstacle.friction,
        };
        (contact, (new_x, (v_old - v_new) * self.mass[i]))
    }
}

/// What [`push_out`] gives a particle.
pub(super) struct PushOut {
    /// Where it was pushed out to, before friction (m): where its momentum
    /// is handed to the obstacle.
    pub surface: Vector,
    /// The surface's velocity there (m/s).
    pub surface_velocity: Vector,
    /// Its position (m) and velocity (m/s) after the push and friction.
    pub x: Vector,
    pub v: Vector,
}

/// Pushes a particle at `x` moving at `v` out along the unit normal `n` to
/// `thickness` from a surface `signed` metres away (never pulls it in),
/// whose material moves at `surface_velocity(p)` at `p`; takes away the
/// velocity into the surface and, when friction `applies`, Coulomb friction
/// of coefficient `friction` (the normal velocity taken away bounds what it
/// may take away), undoing the slip it forbade over the substep of `h`
/// seconds. Without branches: the particle pass's lanes run it too, so
/// both give the same bits.
#[inline(always)]
pub(super) fn push_out(
    (x, v): (Vector, Vector),
    (n, signed): (Vector, f32),
    thickness: f32,
    surface_velocity: impl Fn(Vector) -> Vector,
    (friction, applies, h): (f32, bool, f32),
) -> PushOut {
    let surface = x + n * (thickness - signed).max(0.0);
    let surface_v = surface_velocity(surface);
    let rel = v - surface_v;
    let vn = rel.dot(n);
    let removed = (-vn).max(0.0);
    let rel_t = rel - n * vn;
    let slip = rel_t.length();
    let limit = friction * removed;
    let slowed = select(slip <= limit, Vector::ZERO, rel_t * (1.0 - limit / slip));
    let rel_t_new = select(applies, slowed, rel_t);
    PushOut {
        surface,
        surface_velocity: surface_v,
        x: surface + (rel_t_new - rel_t) * h,
        v: surface_v + n * vn.max(0.0) + rel_t_new,
    }
}

/// `a` where `pick`, else `b`, coordinate by coordinate.
#[inline(always)]
pub(super) fn select(pick: bool, a: Vector, b: Vector) -> Vector {
    Vector::new(
        if pick { a.x } else { b.x },
        if pick { a.y } else { b.y },
        if pick { a.z } else { b.z },
    )
}
