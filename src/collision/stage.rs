//! The collision stage of a step: it owns where the obstacles are
//! ([`ObstacleTracks`]) and the particles' contacts ([`ContactSet`]), finds
//! contacts ahead of a substep for the solvers that take them into their
//! solve, and resolves them after the substep.

use parry3d::bounding_volume::Aabb;
use parry3d::query::Ray;

use super::contact::Contact;
use super::contact_set::{ContactSet, ParticleContact, NONE};
use super::obstacle::{Obstacle, ObstacleImpulse};
use super::response::FrictionPolicy;
use super::tracks::ObstacleTracks;
use crate::cloth::{Particles, SpringKind, Springs};
use crate::context::StepContext;
use crate::math::Vector;

/// Distance (m) beyond the thickness within which a particle still counts as touching.
const CONTACT_SLACK: f32 = 1.0e-5;

/// Two contact normals closer than this (cosine) lie on one smooth stretch of
/// surface, where a spring between two particles outside it stays outside.
const SMOOTH_COS: f32 = 0.995;

/// Collision state and scratch of a cloth's solver.
#[derive(Debug, Default)]
pub struct CollisionStage {
    pub(super) tracks: ObstacleTracks,
    contacts: ContactSet,
    /// Per particle: the obstacle nearest to it this substep (`NONE` for none)
    /// and the outward normal there.
    pub(super) nearest: Vec<u32>,
    pub(super) normal: Vec<Vector>,
    /// Per particle: distance to that obstacle after resolution (m).
    pub(super) distance: Vec<f32>,
    /// Per particle: moved by the edge pass in this substep.
    pub(super) edge_moved: Vec<bool>,
}

impl CollisionStage {
    /// Prepares a step of `dt` seconds for `particles` particles: bounds
    /// swept over the step, grown by `reach` metres (the thickness plus the
    /// longest sampled spring).
    pub fn begin_step(&mut self, obstacles: &[Obstacle], dt: f32, reach: f32, particles: usize) {
        self.tracks.begin_step(obstacles, dt, reach);
        self.nearest.resize(particles, NONE);
        self.normal.resize(particles, Vector::ZERO);
        self.distance.resize(particles, f32::INFINITY);
        self.edge_moved.resize(particles, false);
        self.contacts.begin_step(particles, obstacles.len());
    }

    /// Finds once for the step which obstacles each particle at `x` may meet
    /// while it stays within `margin` metres of there (further, it is looked
    /// up afresh: the cache changes no result, only the cost).
    pub fn cache_candidates(&mut self, x: &[Vector], margin: f32) {
        self.tracks.cache_candidates(x, margin);
    }

    /// Moves the obstacles to where they are at the end of the context's substep.
    pub fn advance(&mut self, ctx: &StepContext, obstacles: &[Obstacle]) {
        self.tracks.advance_to(obstacles, ctx.substep_end(), ctx.h);
    }

    /// The particles' contacts.
    pub fn contacts(&self) -> &ContactSet {
        &self.contacts
    }

    /// Momentum handed to each obstacle during the current step.
    pub fn impulses(&self) -> &[ObstacleImpulse] {
        self.tracks.impulses()
    }

    /// Records momentum `j` (N·s) handed to obstacle `o` at `point` by a solver.
    pub fn add_impulse(&mut self, o: usize, point: Vector, j: Vector) {
        self.tracks.add_impulse(o, point, j);
    }

    /// The contact of particle `i` with obstacle `o`. A particle that ended the
    /// substep inside but started it outside (relative to the moving
    /// obstacle) is traced along its relative path, so it is pushed back out
    /// through the face it entered rather than through the nearest one: fast
    /// obstacles do not pass through the cloth.
    fn particle_contact(
        &self,
        p: &Particles,
        i: usize,
        obstacles: &[Obstacle],
        o: usize,
    ) -> Option<Contact> {
        let (obstacle, pose) = (&obstacles[o], &self.tracks.poses[o]);
        let c = self.tracks.contact(obstacles, o, p.x[i])?;
        if c.signed_distance >= 0.0 {
            return Some(c);
        }
        let prev = &self.tracks.prev_poses[o];
        let from = prev.inverse_transform_point(p.x_prev[i]);
        if obstacle.shape.contains_local_point(from) {
            return Some(c);
        }
        let to = pose.inverse_transform_point(p.x[i]);
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

    /// Finds which free particles touch an obstacle now (within the thickness
    /// and a hair) or will reach its thickness layer within the substep
    /// (speculative contacts: moving at `v` plus gravity times `h` relative
    /// to the surface), without moving anything. Solvers that treat contacts
    /// as constraints have it run at the start of a substep, so their result
    /// depends only on the current state.
    pub fn detect_contacts(&mut self, ctx: &StepContext, p: &Particles, obstacles: &[Obstacle]) {
        let (h, thickness) = (ctx.h, ctx.thickness);
        for i in 0..p.x.len() {
            self.contacts.clear(i);
            if obstacles.is_empty() || p.inv_mass[i] == 0.0 {
                continue;
            }
            let x = p.x[i];
            let predicted = p.v[i] + ctx.gravity * h;
            let reach = Vector::splat(thickness + CONTACT_SLACK + predicted.length() * h);
            self.tracks.gather_box(Aabb::new(x - reach, x + reach));
            // The earliest arrival wins: the smallest gap left after the motion.
            let mut best = thickness + CONTACT_SLACK;
            for c in 0..self.tracks.candidates.len() {
                let o = self.tracks.candidates[c] as usize;
                let Some(hit) = self.tracks.contact(obstacles, o, x) else {
                    continue;
                };
                let surface_v = self.tracks.surface_velocity_of(obstacles, o, hit.point);
                let approach = (predicted - surface_v).dot(hit.normal).min(0.0) * h;
                let after = hit.signed_distance + approach;
                if after < best {
                    best = after;
                    self.contacts.detect(
                        i,
                        &ParticleContact {
                            obstacle: o as u32,
                            normal: hit.normal,
                            surface_velocity: surface_v,
                            immovable: obstacles[o].body.is_none(),
                            gap: (hit.signed_distance - thickness).max(0.0),
                            friction: obstacles[o].friction,
                        },
                    );
                }
            }
        }
    }

    /// Pushes free particles out to the thickness, positions only. Used
    /// inside iterative solvers so that they converge to a state outside the
    /// obstacles; such solvers apply friction themselves.
    pub fn project_positions(
        &mut self,
        x: &mut [Vector],
        inv_mass: &[f32],
        obstacles: &[Obstacle],
        thickness: f32,
    ) {
        if obstacles.is_empty() {
            return;
        }
        for i in 0..x.len() {
            if inv_mass[i] == 0.0 {
                continue;
            }
            self.move_out(&mut x[i], None, obstacles, thickness);
        }
    }

    /// The deepest obstacle the point `x` is closer than `thickness` to:
    /// its index, the surface normal and how far `x` must move along it, in
    /// metres. Used by solvers that add contacts found during their solve.
    pub fn penetration(
        &mut self,
        x: Vector,
        obstacles: &[Obstacle],
        thickness: f32,
    ) -> Option<(usize, Vector, f32)> {
        self.tracks.gather(x);
        let mut deepest = None;
        for c in 0..self.tracks.candidates.len() {
            let o = self.tracks.candidates[c] as usize;
            let Some(hit) = self.tracks.contact(obstacles, o, x) else {
                continue;
            };
            let depth = thickness - hit.signed_distance;
            if depth > 0.0 && deepest.is_none_or(|(_, _, d)| depth > d) {
                deepest = Some((o, hit.normal, depth));
            }
        }
        deepest
    }

    /// Resolves every contact after a substep, with the obstacles where
    /// [`CollisionStage::advance`] put them; with `edges`, stretch and shear
    /// springs too. The solver's `friction` policy says whether Coulomb
    /// friction acts on the touching particles here or was already decided
    /// inside its solve (then they are only put back on the surface).
    /// Returns the particle contacts resolved.
    pub fn resolve(
        &mut self,
        ctx: &StepContext,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        friction: FrictionPolicy,
        edges: bool,
    ) -> u32 {
        if obstacles.is_empty() {
            return 0;
        }
        let thickness = ctx.thickness;
        let far = self.tracks.reach.max(thickness + CONTACT_SLACK);
        let mut contacts = 0;
        for i in 0..particles.len() {
            self.nearest[i] = NONE;
            self.contacts.clear(i);
            self.tracks.gather_particle(i, particles.x[i]);
            let mut nearest_distance = f32::INFINITY;
            for c in 0..self.tracks.candidates.len() {
                let o = self.tracks.candidates[c] as usize;
                // Beyond the reach of the contact and the edge pass: as if
                // it were not a candidate (the edge pass then takes the
                // particle's distance to be the reach, less than it is).
                if self.tracks.surely_beyond(o, particles.x[i], far) {
                    continue;
                }
                let Some(hit) = self.particle_contact(particles, i, obstacles, o) else {
                    continue;
                };
                if hit.signed_distance < nearest_distance {
                    nearest_distance = hit.signed_distance;
                    self.nearest[i] = o as u32;
                    self.normal[i] = hit.normal;
                    // Resolution below leaves a particle at least the thickness out.
                    self.distance[i] = if particles.inv_mass[i] != 0.0 {
                        hit.signed_distance.max(thickness)
                    } else {
                        hit.signed_distance
                    };
                }
                // A hair of slack keeps particles a solver left exactly at the
                // thickness in contact, so friction still acts on them.
                if particles.inv_mass[i] != 0.0 && hit.signed_distance < thickness + CONTACT_SLACK {
                    self.resolve_particle(ctx, particles, i, obstacles, (o, hit), friction);
                    contacts += 1;
                }
            }
        }
        if edges {
            self.resolve_edges(particles, springs, obstacles, thickness);
        }
        contacts
    }

    /// The edge pass: stretch and shear springs whose ends lie near an
    /// obstacle are kept out of it, then every particle it moved is pushed
    /// back out of every obstacle.
    fn resolve_edges(
        &mut self,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        thickness: f32,
    ) {
        for kind in [SpringKind::Stretch, SpringKind::Shear] {
            for s in springs.range(kind) {
                let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
                let (oa, ob) = (self.nearest[a], self.nearest[b]);
                if oa == NONE && ob == NONE {
                    continue;
                }
                // Both ends on one smooth stretch of the same surface: nothing to cut.
                if oa == ob && self.normal[a].dot(self.normal[b]) > SMOOTH_COS {
                    continue;
                }
                // Distance to a surface changes no faster than along the
                // spring, so no point of it comes closer than
                // (d_a + d_b - length) / 2.
                let da = if oa == NONE {
                    self.tracks.reach
                } else {
                    self.distance[a]
                };
                let db = if ob == NONE {
                    self.tracks.reach
                } else {
                    self.distance[b]
                };
                let length = (particles.x[b] - particles.x[a]).length();
                if 0.5 * (da + db - length) >= 0.5 * thickness {
                    continue;
                }
                self.resolve_spring(particles, a, b, obstacles, 0.5 * thickness);
            }
        }
        // Particles come first: whatever the springs did, every particle
        // the edge pass moved ends the substep outside the obstacles.
        for i in 0..particles.len() {
            if std::mem::take(&mut self.edge_moved[i]) && particles.inv_mass[i] != 0.0 {
                self.move_out(
                    &mut particles.x[i],
                    Some(&mut particles.v[i]),
                    obstacles,
                    thickness,
                );
            }
        }
    }

    /// Moves the point `x` out to the thickness of every obstacle it is
    /// inside; with a velocity, also takes away its part into each surface.
    /// Returns how far it moved along the normals, in metres.
    fn move_out(
        &mut self,
        x: &mut Vector,
        mut v: Option<&mut Vector>,
        obstacles: &[Obstacle],
        thickness: f32,
    ) -> f32 {
        let mut moved = 0.0;
        self.tracks.gather(*x);
        for c in 0..self.tracks.candidates.len() {
            let o = self.tracks.candidates[c] as usize;
            let Some(hit) = self.tracks.contact(obstacles, o, *x) else {
                continue;
            };
            if hit.signed_distance < thickness {
                let (n, depth) = (hit.normal, thickness - hit.signed_distance);
                *x += n * depth;
                moved += depth;
                if let Some(v) = v.as_deref_mut() {
                    let vn = (*v - self.tracks.surface_velocity_of(obstacles, o, *x)).dot(n);
                    if vn < 0.0 {
                        *v -= n * vn;
                    }
                }
            }
        }
        moved
    }

    /// Pushes particle `i` out of obstacle `o` (the `hit` with it) and, by
    /// the solver's policy, applies friction.
    fn resolve_particle(
        &mut self,
        ctx: &StepContext,
        p: &mut Particles,
        i: usize,
        obstacles: &[Obstacle],
        (o, hit): (usize, Contact),
        friction: FrictionPolicy,
    ) {
        let obstacle = &obstacles[o];
        let n = hit.normal;
        let new_x = p.x[i] + n * (ctx.thickness - hit.signed_distance).max(0.0);
        let surface_v = self.tracks.surface_velocity_of(obstacles, o, new_x);
        let v_old = p.v[i];
        let rel = v_old - surface_v;
        let vn = rel.dot(n);
        // The normal velocity taken away bounds what friction may take away.
        let removed = (-vn).max(0.0);
        let rel_t = rel - n * vn;
        let slip = rel_t.length();
        let limit = obstacle.friction * removed;
        let rel_t_new = match friction {
            FrictionPolicy::AlreadySolved => rel_t,
            FrictionPolicy::Apply if slip <= limit => Vector::ZERO,
            FrictionPolicy::Apply => rel_t * (1.0 - limit / slip),
        };
        let v_new = surface_v + n * vn.max(0.0) + rel_t_new;
        // Undo the slip friction forbade during this substep.
        p.x[i] = new_x + (rel_t_new - rel_t) * ctx.h;
        p.v[i] = v_new;
        self.contacts.touch(
            i,
            &ParticleContact {
                obstacle: o as u32,
                normal: n,
                surface_velocity: surface_v,
                immovable: obstacle.body.is_none(),
                gap: 0.0,
                friction: obstacle.friction,
            },
        );
        let j = (v_old - v_new) * p.mass[i];
        let imp = &mut self.tracks.impulses[o];
        imp.linear += j;
        imp.angular_about_origin += new_x.cross(j);
        imp.contacts += 1;
    }
}
