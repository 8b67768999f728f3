//! Co-simulation with a rapier3d world: its colliders are obstacles, dynamic
//! bodies are pushed back, particles can be attached to bodies.
//!
//! # Stepping order
//!
//! Each frame, call [`RapierCoupling::step`] first and then rapier's own step,
//! with the same `dt`. The cloth step moves every collider from its current
//! pose across the substeps, so fast obstacles do not tunnel: a kinematic body
//! towards its next kinematic pose; a dynamic body with its velocity and
//! gravity, its velocity changed substep by substep by the impulses the cloth
//! gives it (with its mass and inertia), so the cloth stops a falling box
//! within the frame. The sum of those impulses is then applied to the rapier
//! body (`apply_impulse`/`apply_torque_impulse`), and rapier's step right
//! after integrates it in the same frame. (Stepping rapier first would apply
//! the cloth's push one frame late, and that delay feeds energy into bouncing
//! bodies.)
//!
//! Rapier's step may then put a dynamic body elsewhere than the cloth's
//! substeps did: its own contacts (a crate landing on the floor, a ball
//! stopped by a wall) change its motion within the frame, and its one step
//! over the cloth's summed push differs from the substeps' path. The body
//! moves into cloth the step left outside it (a cloth lying on a falling
//! crate, slowed by the air, was 4.4 cm inside it at the landing; flaps of
//! a torn sheet falling on a ball that had just landed, 8 mm). So
//! [`RapierCoupling::push_out_of_bodies`], right after rapier's step (or
//! else first thing in the next cloth step), moves each particle such a
//! body swept into back out, to its place on the body as the cloth's step
//! left it. Use one coupling per
//! cloth: it remembers where the last step left the bodies its cloth met.
//!
//! ```
//! use cloth3d::prelude::*;
//! use cloth3d::rapier::RapierCoupling;
//! use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder};
//!
//! let mut world = PhysicsWorld::new();
//! // A user's world: a ball falling onto a hammock.
//! world.insert(
//!     RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.0, 0.0)),
//!     ColliderBuilder::ball(0.1).density(500.0),
//! );
//! let cloth = ClothBuilder::new(16, 16)
//!     .horizontal(Vector::new(0.0, 0.5, 0.0))
//!     .pins(PinPreset::FourCorners)
//!     .build()?;
//! let mut cloth = Simulation::new(cloth);
//! let mut coupling = RapierCoupling::new();
//! for _ in 0..60 {
//!     coupling.step_world(&mut cloth, &mut world)?;
//!     world.step();
//!     coupling.push_out_of_world(&mut cloth, &world);
//! }
//! assert!(cloth.is_finite());
//! # Ok::<(), cloth3d::ClothError>(())
//! ```

use glam::Mat3;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::prelude::{
    BroadPhaseBvh, ColliderHandle, ColliderSet, InteractionGroups, NarrowPhase, PhysicsWorld,
    QueryFilter, RigidBody, RigidBodyHandle, RigidBodySet, RigidBodyType, SharedShape,
};

use crate::cloth::{Cloth, SpringKind};
use crate::collision::LIMIT_SLACK;
use crate::collision::{DynamicBody, Obstacle};
use crate::error::ClothError;
use crate::math::{Pose, Vector};
use crate::simulation::Simulation;
use crate::solver::{ClothSolver, StepReport};

/// The parts of a rapier world a cloth step reads (and the bodies it pushes),
/// borrowed for one step, as rapier's own `step` takes its sets.
pub struct RapierSets<'a> {
    /// The frame step, in seconds (rapier's `integration_parameters.dt`).
    pub dt: f32,
    /// Gravity, in m/s², to predict where dynamic bodies go.
    pub gravity: Vector,
    /// The bodies; dynamic ones receive the cloth's impulses.
    pub bodies: &'a mut RigidBodySet,
    /// The colliders, every one a potential obstacle.
    pub colliders: &'a ColliderSet,
    /// The broad phase that finds the colliders near the cloth.
    pub broad_phase: &'a BroadPhaseBvh,
    /// The narrow phase (its query dispatcher).
    pub narrow_phase: &'a NarrowPhase,
}

impl<'a> RapierSets<'a> {
    /// The sets of a [`PhysicsWorld`], with its `dt` and gravity.
    pub fn of(world: &'a mut PhysicsWorld) -> Self {
        RapierSets {
            dt: world.integration_parameters.dt,
            gravity: world.gravity,
            bodies: &mut world.bodies,
            colliders: &world.colliders,
            broad_phase: &world.broad_phase,
            narrow_phase: &world.narrow_phase,
        }
    }
}

/// A particle held at a point fixed on a rigid body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attachment {
    /// The particle index.
    pub particle: usize,
    /// The body.
    pub body: RigidBodyHandle,
    /// The point, in the body's local frame (metres).
    pub local_point: Vector,
}

/// What the cloth and the rapier world exchanged during the last step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CouplingReport {
    /// The cloth step's own report.
    pub step: StepReport,
    /// Colliders the cloth was tested against.
    pub colliders: usize,
    /// Linear impulse given to dynamic bodies in total, in N·s.
    pub impulse_to_bodies: Vector,
}

/// Couples a cloth with a rapier world. Holds the coupling options, scratch
/// memory, and where the last step left the dynamic bodies the cloth
/// touched (module docs); the bodies and colliders stay in the user's sets.
#[derive(Debug, Clone)]
pub struct RapierCoupling {
    /// Which colliders the cloth sees: tested against each collider's collision groups.
    pub groups: InteractionGroups,
    /// When false, the cloth collides with dynamic bodies but never pushes them
    /// (cloth that must not move gameplay objects).
    pub two_way: bool,
    /// Coulomb friction between cloth and colliders (rapier's own friction
    /// coefficient is for body–body contacts).
    pub friction: f32,
    /// Sensors are ignored unless this is true.
    pub include_sensors: bool,
    /// The fastest a collider may move (m/s) and still be found before it
    /// reaches the cloth; faster ones may pass through it for a frame.
    pub max_obstacle_speed: f32,
    attachments: Vec<Attachment>,
    obstacles: Vec<Obstacle>,
    handles: Vec<(ColliderHandle, Option<RigidBodyHandle>)>,
    /// The dynamic bodies' colliders the last step's cloth met, with where
    /// that step left them.
    met: Vec<MetBody>,
    /// The bodies that pushed particles out this time, where they are
    /// (scratch).
    pushing: Vec<(SharedShape, Pose)>,
    /// Per particle: its inverse mass, or 0 once pushed out of a body
    /// (held in the stretch limit that follows, and not pushed again) or
    /// pinned (scratch).
    weight: Vec<f32>,
    /// The particles' positions and previous positions before a push, to
    /// go back to (scratch).
    before: (Vec<Vector>, Vec<Vector>),
}

/// A dynamic body's collider the cloth met during a step, with the pose (m,
/// rad) the step's substeps left it in
/// ([`RapierCoupling::push_out_of_bodies`]).
#[derive(Debug, Clone)]
struct MetBody {
    collider: ColliderHandle,
    shape: SharedShape,
    left_at: Pose,
}

/// How far (m) and how much (rad) rapier's step may put a dynamic body from
/// where the cloth's step left it before the cloth is looked at: rounding
/// stays under it.
const PUSH_OUT_BEYOND: f32 = 1.0e-4;

/// Rounds at most of the stretch limit and the pushing bodies after a push
/// out of them ([`RapierCoupling::push_out_of_bodies`]); they stop once
/// neither moves a particle.
const PUSH_OUT_ROUNDS: usize = 16;

impl Default for RapierCoupling {
    fn default() -> Self {
        Self::new()
    }
}

impl RapierCoupling {
    /// Two-way coupling with every collider, friction 0.5.
    pub fn new() -> Self {
        Self {
            groups: InteractionGroups::all(),
            two_way: true,
            friction: 0.5,
            include_sensors: false,
            max_obstacle_speed: 30.0,
            attachments: Vec::new(),
            obstacles: Vec::new(),
            handles: Vec::new(),
            met: Vec::new(),
            pushing: Vec::new(),
            weight: Vec::new(),
            before: (Vec::new(), Vec::new()),
        }
    }

    /// Attaches particle `particle` of the cloth to the point `local_point`
    /// (body frame, metres) of `body`. The particle follows the body exactly;
    /// with two-way coupling the cloth's pull acts back on a dynamic body.
    pub fn attach(
        &mut self,
        particle: usize,
        body: RigidBodyHandle,
        local_point: Vector,
    ) -> Result<(), ClothError> {
        crate::error::finite_vec("attachment point", local_point)?;
        self.attachments.retain(|a| a.particle != particle);
        self.attachments.push(Attachment {
            particle,
            body,
            local_point,
        });
        Ok(())
    }

    /// Attaches particle `particle` to `body` where the particle is now.
    pub fn attach_here(
        &mut self,
        cloth: &Cloth,
        particle: usize,
        body: RigidBodyHandle,
        bodies: &RigidBodySet,
    ) -> Result<(), ClothError> {
        let p = *cloth
            .positions()
            .get(particle)
            .ok_or(ClothError::ParticleOutOfRange {
                index: particle,
                count: cloth.particle_count(),
            })?;
        let rb = bodies.get(body).ok_or_else(|| stale_body(body))?;
        self.attach(particle, body, rb.position().inverse_transform_point(p))
    }

    /// Releases an attached particle (it stays pinned where it is; unpin it to free it).
    pub fn detach(&mut self, particle: usize) {
        self.attachments.retain(|a| a.particle != particle);
    }

    /// The attachments.
    pub fn attachments(&self) -> &[Attachment] {
        &self.attachments
    }

    /// The obstacles built from colliders during the last step, with the
    /// collider each came from.
    pub fn last_obstacles(&self) -> impl Iterator<Item = (&Obstacle, ColliderHandle)> {
        self.obstacles.iter().zip(self.handles.iter().map(|h| h.0))
    }

    /// Steps `cloth` with `solver` by the sets' `dt` against the colliders
    /// of a rapier world given as its parts; call right before rapier's own step.
    pub fn step(
        &mut self,
        cloth: &mut Cloth,
        solver: &mut ClothSolver,
        sets: RapierSets,
    ) -> Result<CouplingReport, ClothError> {
        let (dt, gravity) = (sets.dt, sets.gravity);
        crate::error::positive("dt", dt)?;
        crate::error::finite_vec("gravity", gravity)?;
        crate::error::non_negative("friction", self.friction)?;
        crate::error::non_negative("max obstacle speed", self.max_obstacle_speed)?;
        self.refuse_unsafe_integrator(solver, &sets)?;
        self.push_out_of_bodies(cloth, solver, sets.colliders);
        self.drive_attachments(cloth, dt, gravity, sets.bodies)?;
        self.gather(cloth, &sets);
        let step = solver.step(cloth, dt, &self.obstacles)?;
        let mut report = CouplingReport {
            step,
            colliders: self.obstacles.len(),
            ..Default::default()
        };
        if self.two_way {
            report.impulse_to_bodies = self.push_bodies(cloth, solver, dt, sets.bodies);
        }
        self.remember_met_bodies(solver);
        Ok(report)
    }

    /// [`RapierCoupling::step`] for a [`Simulation`], with the sets of a
    /// [`PhysicsWorld`] and its `dt`.
    pub fn step_world(
        &mut self,
        sim: &mut Simulation,
        world: &mut PhysicsWorld,
    ) -> Result<CouplingReport, ClothError> {
        self.step(&mut sim.cloth, &mut sim.solver, RapierSets::of(world))
    }

    /// Refuses an integrator that cannot carry dynamic bodies while the world
    /// has one the cloth would meet, at the first step rather than when a
    /// body first comes near the cloth.
    fn refuse_unsafe_integrator(
        &self,
        solver: &ClothSolver,
        sets: &RapierSets,
    ) -> Result<(), ClothError> {
        let integrator = solver.settings.integrator;
        if integrator.carries_dynamic_bodies() {
            return Ok(());
        }
        let dynamic = sets.colliders.iter().find(|(_, c)| {
            c.is_enabled()
                && (self.include_sensors || !c.is_sensor())
                && self.groups.test(c.collision_groups())
                && c.parent()
                    .and_then(|h| sets.bodies.get(h))
                    .is_some_and(|b| b.is_dynamic())
        });
        match dynamic {
            Some((handle, _)) => Err(ClothError::CannotCarryBodies {
                integrator: integrator.name(),
                body: format!("the rapier collider {handle:?}"),
            }),
            None => Ok(()),
        }
    }

    /// Pushes the cloth out of the dynamic bodies rapier's step moved into
    /// it (module docs): for each body the cloth met in its last step that
    /// rapier put elsewhere than that step left it, every particle inside
    /// it now and not then goes back to its place on the body as the step
    /// left it (as far outside it, on the same side: swept layers keep
    /// their order), and the cloth around follows within its stretch
    /// limit. Where it cannot (the cloth held by pins beyond the
    /// pushed particles, or pressed under a stack of bodies), and the push
    /// would leave the cloth stretched past its limit and past its stretch
    /// before, every particle goes back to where it was: the next step
    /// pushes the body instead. Positions only; the velocities meet the
    /// body in the next step. A particle the body moved away from stays:
    /// cloth does not stick.
    ///
    /// Call it right after rapier's step, to draw the frame with the cloth
    /// outside the bodies; otherwise the next [`RapierCoupling::step`]
    /// does it first. Once done, it does nothing until the next step.
    pub fn push_out_of_bodies(
        &mut self,
        cloth: &mut Cloth,
        solver: &mut ClothSolver,
        colliders: &ColliderSet,
    ) {
        let particles = &mut cloth.particles;
        let (mut any, mut saved) = (false, false);
        self.pushing.clear();
        for c in &self.met {
            let Some(collider) = colliders.get(c.collider) else {
                continue;
            };
            let now = *collider.position();
            // Where rapier's step put the body against where the cloth's
            // left it: its own contacts, joints or forces, or its one step
            // over a push the substeps spread through the frame.
            let by = now * c.left_at.inverse();
            let (moved, turned) = (
                by.translation.length(),
                by.rotation.to_scaled_axis().length(),
            );
            if !(moved > PUSH_OUT_BEYOND || turned > PUSH_OUT_BEYOND)
                || !moved.is_finite()
                || !turned.is_finite()
            {
                continue;
            }
            if !any {
                self.weight.clear();
                self.weight.extend_from_slice(&particles.inv_mass);
                any = true;
            }
            let near = c.shape.compute_aabb(&now);
            let mut pushes = false;
            for i in 0..particles.x.len() {
                let p = particles.x[i];
                if self.weight[i] == 0.0 || !near.contains_local_point(p) {
                    continue;
                }
                // Inside the body now, and not as the step left it: the
                // body's difference swept into the particle.
                let (then, inside) = (
                    c.left_at.inverse_transform_point(p),
                    now.inverse_transform_point(p),
                );
                if !c.shape.contains_local_point(inside) || c.shape.contains_local_point(then) {
                    continue;
                }
                // Back to its place on the body as the step left it: as
                // far outside it, on the same side, so layers of cloth
                // the body swept keep their order.
                let to = now.transform_point(then);
                if !saved {
                    let (x, x_prev) = &mut self.before;
                    x.clear();
                    x.extend_from_slice(&particles.x);
                    x_prev.clear();
                    x_prev.extend_from_slice(&particles.x_prev);
                    saved = true;
                }
                particles.x_prev[i] += to - p;
                particles.x[i] = to;
                self.weight[i] = 0.0;
                pushes = true;
            }
            if pushes {
                self.pushing.push((c.shape.clone(), now));
            }
        }
        self.met.clear();
        if self.pushing.is_empty() {
            return;
        }
        solver.wake();
        // The cloth around follows what was pushed: rounds of the stretch
        // limit and of the pushing bodies' surfaces, as the cloth follows
        // its contacts within a step (a cloth over a crate the floor
        // stopped, its top pushed up 7 cm and its sides not, was 97%
        // stretched at the crate's edges; 11.6% when the limit could pull
        // the pushed particles back in, to be pushed out again).
        // Held where pushed (weight 0): the limit moves the cloth around
        // towards them rather than them back in.
        for _ in 0..PUSH_OUT_ROUNDS {
            let shortened = solver.limit_stretch_between_steps(cloth, &self.weight);
            let particles = &mut cloth.particles;
            let mut pushed = 0;
            for (shape, now) in &self.pushing {
                let near = shape.compute_aabb(now);
                for i in 0..particles.x.len() {
                    let p = particles.x[i];
                    if self.weight[i] == 0.0 || !near.contains_local_point(p) {
                        continue;
                    }
                    let surface = shape.project_point(now, p, false);
                    if surface.is_inside && surface.point.is_finite() {
                        particles.x_prev[i] += surface.point - p;
                        particles.x[i] = surface.point;
                        self.weight[i] = 0.0;
                        pushed += 1;
                    }
                }
            }
            if shortened == 0 && pushed == 0 {
                break;
            }
        }
        // No worse than before: where the cloth cannot follow within its
        // limit (held by pins beyond the pushed particles, as a hammock's
        // side under a box rapier shoved into it at 20 Hz: 17% stretched),
        // the push goes back, and the next step pushes the body instead.
        let limit = cloth.material.stretch_limit_factor() - 1.0;
        let (x, x_prev) = &self.before;
        let stretch = cloth.max_strain(SpringKind::Stretch);
        let was = cloth.max_strain_at(SpringKind::Stretch, x);
        let same = x.len() == cloth.particles.x.len() && x_prev.len() == x.len();
        if same && stretch > was.max(limit * (1.0 + LIMIT_SLACK) + LIMIT_SLACK) {
            cloth.particles.x.copy_from_slice(x);
            cloth.particles.x_prev.copy_from_slice(x_prev);
        }
    }

    /// [`RapierCoupling::push_out_of_bodies`] for a [`Simulation`] in a
    /// [`PhysicsWorld`]: call it right after the world's step.
    pub fn push_out_of_world(&mut self, sim: &mut Simulation, world: &PhysicsWorld) {
        self.push_out_of_bodies(&mut sim.cloth, &mut sim.solver, &world.colliders);
    }

    /// Remembers the dynamic bodies' colliders the step's cloth met and
    /// where the step left them (none while the cloth sleeps: its step
    /// moved nothing).
    fn remember_met_bodies(&mut self, solver: &ClothSolver) {
        self.met.clear();
        let ends = solver.obstacle_end_poses();
        if solver.is_asleep() || ends.len() != self.obstacles.len() {
            return;
        }
        // Every dynamic body the cloth met, pushing it or not: a cloth
        // lying on a falling crate falls with it and pushes it nowhere.
        for ((obstacle, &(collider, _)), end) in self.obstacles.iter().zip(&self.handles).zip(ends)
        {
            if obstacle.body.is_some() {
                self.met.push(MetBody {
                    collider,
                    shape: obstacle.shape.clone(),
                    left_at: *end,
                });
            }
        }
    }

    /// Pins every attached particle and gives it the velocity that takes it
    /// to its body point by the end of the step (where rapier's step will put
    /// the body).
    fn drive_attachments(
        &mut self,
        cloth: &mut Cloth,
        dt: f32,
        gravity: Vector,
        bodies: &RigidBodySet,
    ) -> Result<(), ClothError> {
        for a in &self.attachments {
            let body = bodies.get(a.body).ok_or_else(|| stale_body(a.body))?;
            let mut next = predicted_pose(body, dt);
            if body.is_dynamic() {
                next = next.append_translation(gravity * (body.gravity_scale() * dt * dt));
            }
            let target = next.transform_point(a.local_point);
            let now = *cloth
                .positions()
                .get(a.particle)
                .ok_or(ClothError::ParticleOutOfRange {
                    index: a.particle,
                    count: cloth.particle_count(),
                })?;
            cloth.pin(a.particle)?;
            cloth.set_velocity(a.particle, (target - now) / dt)?;
        }
        Ok(())
    }

    /// Builds the obstacles from the colliders near the cloth, found through
    /// rapier's broad phase.
    fn gather(&mut self, cloth: &Cloth, sets: &RapierSets) {
        let (dt, gravity, bodies) = (sets.dt, sets.gravity, &*sets.bodies);
        self.obstacles.clear();
        self.handles.clear();
        let Some(region) = cloth_region(cloth, dt) else {
            return;
        };
        let mut filter = QueryFilter::default().groups(self.groups);
        if !self.include_sensors {
            filter = filter.exclude_sensors();
        }
        let query = sets.broad_phase.as_query_pipeline(
            sets.narrow_phase.query_dispatcher(),
            bodies,
            sets.colliders,
            filter,
        );
        // Candidates from the broad phase, within reach of a collider moving
        // at up to `max_obstacle_speed`; then only those whose path this step
        // really crosses the cloth.
        let reach = region.loosened(self.max_obstacle_speed * dt);
        // The broad phase holds the colliders of rapier's last step: before
        // the first, or with colliders inserted or enabled since, it misses
        // some, and every enabled collider is looked at instead (a cloth
        // stepped before the world's first step fell through a rising slab
        // for that frame).
        let enabled = sets.colliders.iter_enabled().count();
        let stale = (query.bvh.leaf_count() as usize) < enabled;
        let from_broad_phase = (!stale).then(|| query.intersect_aabb_conservative(reach));
        let every = stale.then(|| {
            sets.colliders
                .iter_enabled()
                .filter(move |(handle, c)| filter.test(bodies, *handle, c))
                .filter(move |(_, c)| c.compute_aabb().intersects(&reach))
        });
        let candidates = from_broad_phase
            .into_iter()
            .flatten()
            .chain(every.into_iter().flatten());
        for (handle, collider) in candidates {
            if !collider.is_enabled() {
                continue;
            }
            let start = *collider.position();
            let parent = collider.parent();
            let mut obstacle =
                Obstacle::new(collider.shared_shape().clone(), start).with_friction(self.friction);
            match parent.and_then(|h| bodies.get(h)) {
                Some(body) if body.is_dynamic() => {
                    // Its velocity responds to the cloth substep by substep.
                    let mp = body.mass_properties();
                    let i = &mp.effective_world_inv_inertia;
                    obstacle.linvel = body.velocity_at_point(start.translation);
                    obstacle.angvel = body.angvel();
                    obstacle.body = Some(DynamicBody {
                        inverse_mass: if self.two_way {
                            mp.effective_inv_mass
                        } else {
                            Vector::ZERO
                        },
                        inverse_inertia: if self.two_way {
                            Mat3::from_cols_array(&[
                                i.m11, i.m12, i.m13, i.m12, i.m22, i.m23, i.m13, i.m23, i.m33,
                            ])
                        } else {
                            Mat3::ZERO
                        },
                        center_of_mass: body.center_of_mass(),
                        acceleration: gravity * body.gravity_scale(),
                    });
                }
                Some(body) if body.is_kinematic() => {
                    // Where rapier will put it: the body's next kinematic pose.
                    let end = predicted_pose(body, dt) * body.position().inv_mul(&start);
                    let linvel = (end.translation - start.translation) / dt;
                    let angvel = (end.rotation * start.rotation.inverse()).to_scaled_axis() / dt;
                    if linvel.is_finite() && angvel.is_finite() {
                        obstacle.linvel = linvel;
                        obstacle.angvel = angvel;
                    }
                }
                _ => {}
            }
            if !obstacle.swept_aabb(dt).intersects(&region) {
                continue;
            }
            self.obstacles.push(obstacle);
            self.handles.push((handle, parent));
        }
    }

    /// Hands the cloth's contact impulses, and the pull of attached particles,
    /// to the dynamic bodies.
    fn push_bodies(
        &self,
        cloth: &Cloth,
        solver: &ClothSolver,
        dt: f32,
        bodies: &mut RigidBodySet,
    ) -> Vector {
        let mut total = Vector::ZERO;
        for (impulse, &(_, parent)) in solver.obstacle_impulses().iter().zip(&self.handles) {
            if impulse.contacts == 0 && impulse.linear == Vector::ZERO {
                continue;
            }
            let Some(body) = parent.and_then(|h| bodies.get_mut(h)) else {
                continue;
            };
            if !body.is_dynamic() {
                continue;
            }
            let com = body.center_of_mass();
            body.apply_impulse(impulse.linear, true);
            body.apply_torque_impulse(impulse.angular_about(com), true);
            total += impulse.linear;
        }
        if self.attachments.is_empty() {
            return total;
        }
        // The attached particles' share of the cloth: the internal force on them.
        let forces = cloth.forces();
        for a in &self.attachments {
            let Some(body) = bodies.get_mut(a.body) else {
                continue;
            };
            if !body.is_dynamic() {
                continue;
            }
            let p = cloth.positions()[a.particle];
            // The spring pull and the particle's own weight hang on the body.
            let j = forces[a.particle] * dt;
            let com = body.center_of_mass();
            body.apply_impulse(j, true);
            body.apply_torque_impulse((p - com).cross(j), true);
            total += j;
        }
        total
    }
}

/// The cloth's bounding box grown by how far it can travel in a step and by
/// its thickness; `None` for an empty or non-finite cloth.
fn cloth_region(cloth: &Cloth, dt: f32) -> Option<Aabb> {
    let x = cloth.positions();
    let first = *x.first()?;
    let (mut lo, mut hi) = (first, first);
    for &p in x {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let speed = cloth
        .velocities()
        .iter()
        .map(|v| v.length())
        .fold(0.0, f32::max);
    let margin = cloth.params.thickness + speed * dt + 1.0e-3;
    let region = Aabb::new(lo - Vector::splat(margin), hi + Vector::splat(margin));
    (region.mins.is_finite() && region.maxs.is_finite()).then_some(region)
}

/// Where rapier's next step puts a body, from what is known before it: the
/// target of a position-based kinematic body, otherwise its velocity.
fn predicted_pose(body: &RigidBody, dt: f32) -> Pose {
    match body.body_type() {
        RigidBodyType::KinematicPositionBased => *body.next_position(),
        RigidBodyType::Fixed => *body.position(),
        _ => body.predict_position_using_velocity(dt),
    }
}

fn stale_body(handle: RigidBodyHandle) -> ClothError {
    ClothError::StaleHandle {
        what: "rigid body",
        handle: format!("{:?}", handle.into_raw_parts()),
    }
}
