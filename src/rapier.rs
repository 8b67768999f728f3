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
//! }
//! assert!(cloth.is_finite());
//! # Ok::<(), cloth3d::ClothError>(())
//! ```

use glam::Mat3;
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use rapier3d::prelude::{
    BroadPhaseBvh, ColliderHandle, ColliderSet, InteractionGroups, NarrowPhase, PhysicsWorld,
    QueryFilter, RigidBody, RigidBodyHandle, RigidBodySet, RigidBodyType,
};

use crate::cloth::Cloth;
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

/// Couples cloths with a rapier world. Holds only scratch memory and the
/// coupling options; the bodies and colliders stay in the user's sets.
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
}

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
