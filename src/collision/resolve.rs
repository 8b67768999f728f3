//! Resolution of particle and spring contacts against a set of obstacles.

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};

use parry3d::query::Ray;

use super::contact::contact;
use super::response::{respond, Response};
use super::{Contact, Obstacle, ObstacleImpulse};
use crate::cloth::{Particles, SpringKind, Springs};
use crate::math::{Pose, Rotation, Vector};

/// Above this many obstacles, candidates come from a bounding-volume tree
/// instead of a linear scan.
const BVH_THRESHOLD: usize = 8;

/// Where along a spring the edge test samples.
const EDGE_SAMPLES: [f32; 3] = [0.25, 0.5, 0.75];

/// Distance (m) beyond the thickness within which a particle still counts as touching.
const CONTACT_SLACK: f32 = 1.0e-5;

/// No obstacle near a particle.
const NONE: u32 = u32::MAX;

/// Two contact normals closer than this (cosine) lie on one smooth stretch of
/// surface, where a spring between two particles outside it stays outside.
const SMOOTH_COS: f32 = 0.995;

/// Collision scratch memory: obstacle bounds, poses at the current substep,
/// per-particle proximity flags, and the impulses given to each obstacle.
#[derive(Debug, Default)]
pub(crate) struct Collider {
    aabbs: Vec<Aabb>,
    poses: Vec<Pose>,
    prev_poses: Vec<Pose>,
    /// Per dynamic obstacle: centre of mass, its velocity, the angular
    /// velocity, and the impulses already turned into velocity.
    com: Vec<Vector>,
    com_velocity: Vec<Vector>,
    angvel: Vec<Vector>,
    applied: Vec<ObstacleImpulse>,
    bvh: Option<Bvh>,
    candidates: Vec<u32>,
    /// Per particle: the obstacle nearest to it this substep (`u32::MAX` for none)
    /// and the outward normal there.
    nearest: Vec<u32>,
    normal: Vec<Vector>,
    /// Per particle: distance to that obstacle after resolution (m).
    distance: Vec<f32>,
    /// Per particle: moved by the edge pass in this substep.
    edge_moved: Vec<bool>,
    reach: f32,
    /// Momentum handed to each obstacle during the current step.
    pub impulses: Vec<ObstacleImpulse>,
    /// Per particle: in contact at the end of the last substep.
    pub touching: Vec<bool>,
    /// Per particle: the contact normal, when touching.
    pub contact_normal: Vec<Vector>,
    /// Per particle: the velocity of the surface it touches, when touching.
    pub surface_velocity: Vec<Vector>,
    /// Per particle: the obstacle it touches, when touching.
    pub contact_obstacle: Vec<u32>,
    /// Per particle: the obstacle it touches is fixed or kinematic (not pushed back).
    pub contact_immovable: Vec<bool>,
    /// Per particle, after [`Collider::detect_contacts`]: the gap (m) between
    /// the particle and the thickness layer of the surface it touches or is
    /// about to reach; zero or negative when it is already in the layer.
    pub contact_gap: Vec<f32>,
    /// Per particle, after [`Collider::detect_contacts`]: the friction
    /// coefficient of the surface it touches.
    pub contact_friction: Vec<f32>,
}

impl Collider {
    /// Prepares a step of `dt` seconds: bounds swept over the step, grown by
    /// `reach` metres (the thickness plus the longest sampled spring).
    pub fn begin_step(&mut self, obstacles: &[Obstacle], dt: f32, reach: f32, particles: usize) {
        self.reach = reach;
        self.aabbs.clear();
        self.aabbs
            .extend(obstacles.iter().map(|o| o.swept_aabb(dt).loosened(reach)));
        self.bvh = (obstacles.len() > BVH_THRESHOLD)
            .then(|| Bvh::from_leaves(BvhBuildStrategy::Binned, &self.aabbs));
        self.impulses.clear();
        self.impulses
            .resize(obstacles.len(), ObstacleImpulse::default());
        self.applied.clear();
        self.applied
            .resize(obstacles.len(), ObstacleImpulse::default());
        self.poses.clear();
        self.poses.extend(obstacles.iter().map(|o| o.pose));
        self.com.clear();
        self.com_velocity.clear();
        self.angvel.clear();
        for o in obstacles {
            let com = o.body.map_or(o.pose.translation, |b| b.center_of_mass);
            self.com.push(com);
            self.com_velocity
                .push(o.linvel + o.angvel.cross(com - o.pose.translation));
            self.angvel.push(o.angvel);
        }
        self.nearest.resize(particles, NONE);
        self.normal.resize(particles, Vector::ZERO);
        self.distance.resize(particles, f32::INFINITY);
        self.edge_moved.resize(particles, false);
        self.touching.resize(particles, false);
        self.contact_obstacle.resize(particles, NONE);
        self.contact_immovable.resize(particles, false);
        self.contact_gap.resize(particles, 0.0);
        self.contact_friction.resize(particles, 0.0);
        // Contacts carried over from the last step must name an obstacle of this one.
        for i in 0..particles {
            if self.touching[i] && self.contact_obstacle[i] as usize >= obstacles.len() {
                self.touching[i] = false;
            }
        }
        self.contact_normal.resize(particles, Vector::ZERO);
        self.surface_velocity.resize(particles, Vector::ZERO);
        if obstacles.is_empty() {
            self.touching.fill(false);
        }
    }

    /// Obstacle candidates whose bounds contain `point`, into `self.candidates`.
    fn gather(&mut self, point: Vector) {
        self.gather_box(Aabb::new(point, point));
    }

    /// Obstacle candidates whose bounds meet `region`, into `self.candidates`.
    fn gather_box(&mut self, region: Aabb) {
        self.candidates.clear();
        match &self.bvh {
            Some(bvh) => self.candidates.extend(bvh.intersect_aabb(&region)),
            None => self.candidates.extend(
                self.aabbs
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| b.intersects(&region))
                    .map(|(o, _)| o as u32),
            ),
        }
    }

    /// Records momentum `j` (N·s) handed to obstacle `o` at `point` by a solver.
    pub fn add_impulse(&mut self, o: usize, point: Vector, j: Vector) {
        if let Some(imp) = self.impulses.get_mut(o) {
            imp.linear += j;
            imp.angular_about_origin += point.cross(j);
        }
    }

    /// Moves the obstacles to where they are `t` seconds into the step; call
    /// before each substep.
    pub fn set_time(&mut self, obstacles: &[Obstacle], t: f32, h: f32) {
        self.prev_poses.clear();
        self.prev_poses.extend_from_slice(&self.poses);
        for (o, obstacle) in obstacles.iter().enumerate() {
            let Some(body) = &obstacle.body else {
                self.poses[o] = obstacle.pose_at(t);
                continue;
            };
            // A dynamic body: the cloth's push since the last substep changes
            // its velocity, then it moves on by one substep.
            let done = self.applied[o];
            let now = self.impulses[o];
            let dj = now.linear - done.linear;
            let dtau =
                (now.angular_about_origin - done.angular_about_origin) - self.com[o].cross(dj);
            self.applied[o] = now;
            self.com_velocity[o] += dj * body.inverse_mass + body.acceleration * h;
            self.angvel[o] += body.inverse_inertia * dtau;
            let spin = Rotation::from_scaled_axis(self.angvel[o] * h);
            let pose = &mut self.poses[o];
            let arm = pose.translation - self.com[o];
            self.com[o] += self.com_velocity[o] * h;
            pose.translation = self.com[o] + spin * arm;
            pose.rotation = (spin * pose.rotation).normalize();
        }
    }

    /// Velocity of the material point of obstacle `o` at `point`, now.
    fn surface_velocity_of(&self, obstacles: &[Obstacle], o: usize, point: Vector) -> Vector {
        match obstacles[o].body {
            Some(_) => self.com_velocity[o] + self.angvel[o].cross(point - self.com[o]),
            None => obstacles[o].velocity_at(&self.poses[o], point),
        }
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
        obstacle: &Obstacle,
        o: usize,
    ) -> Option<Contact> {
        let pose = &self.poses[o];
        let c = contact(&*obstacle.shape, pose, p.x[i])?;
        if c.signed_distance >= 0.0 {
            return Some(c);
        }
        let prev = &self.prev_poses[o];
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
    /// and a hair) or will reach its thickness layer within the substep of
    /// `h` seconds (speculative contacts: moving at `v` plus `accel · h`
    /// relative to the surface), with the contact normal, the gap
    /// ([`Collider::contact_gap`]), the surface velocity and the obstacle,
    /// without moving anything. Solvers that treat contacts as constraints
    /// call it at the start of a substep, so their result depends only on the
    /// current state.
    #[allow(clippy::too_many_arguments)]
    pub fn detect_contacts(
        &mut self,
        x: &[Vector],
        v: &[Vector],
        inv_mass: &[f32],
        obstacles: &[Obstacle],
        thickness: f32,
        h: f32,
        accel: Vector,
    ) {
        for i in 0..x.len() {
            self.touching[i] = false;
            if obstacles.is_empty() || inv_mass[i] == 0.0 {
                continue;
            }
            let predicted = v[i] + accel * h;
            let reach = Vector::splat(thickness + CONTACT_SLACK + predicted.length() * h);
            self.gather_box(Aabb::new(x[i] - reach, x[i] + reach));
            // The earliest arrival wins: the smallest gap left after the motion.
            let mut best = thickness + CONTACT_SLACK;
            for c in 0..self.candidates.len() {
                let o = self.candidates[c] as usize;
                let Some(contact) = contact(&*obstacles[o].shape, &self.poses[o], x[i]) else {
                    continue;
                };
                let surface_v = self.surface_velocity_of(obstacles, o, contact.point);
                let approach = (predicted - surface_v).dot(contact.normal).min(0.0) * h;
                let after = contact.signed_distance + approach;
                if after < best {
                    best = after;
                    self.touching[i] = true;
                    self.contact_obstacle[i] = o as u32;
                    self.contact_immovable[i] = obstacles[o].body.is_none();
                    self.contact_normal[i] = contact.normal;
                    self.contact_gap[i] = (contact.signed_distance - thickness).max(0.0);
                    self.contact_friction[i] = obstacles[o].friction;
                    self.surface_velocity[i] = surface_v;
                }
            }
        }
    }

    /// How particle `i`'s contact from [`Collider::detect_contacts`] responds
    /// over a substep of `h` seconds, for a solver that takes contacts into
    /// its solve: `v` is its velocity and `accel` its acceleration under the
    /// current forces (m/s²). Free unless it touches a fixed or kinematic
    /// obstacle: a dynamic body would be treated as infinitely heavy and
    /// thrown back.
    pub fn response(&self, i: usize, v: Vector, accel: Vector, h: f32) -> Response {
        if !(self.touching.get(i).copied().unwrap_or(false) && self.contact_immovable[i]) {
            return Response::Free;
        }
        let rel = v - self.surface_velocity[i];
        respond(
            rel,
            rel + accel * h,
            self.contact_normal[i],
            self.contact_gap[i],
            self.contact_friction[i],
            h,
        )
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
    pub(crate) fn penetration(
        &mut self,
        x: Vector,
        obstacles: &[Obstacle],
        thickness: f32,
    ) -> Option<(usize, Vector, f32)> {
        self.gather(x);
        let mut deepest = None;
        for c in 0..self.candidates.len() {
            let o = self.candidates[c] as usize;
            let Some(contact) = contact(&*obstacles[o].shape, &self.poses[o], x) else {
                continue;
            };
            let depth = thickness - contact.signed_distance;
            if depth > 0.0 && deepest.is_none_or(|(_, _, d)| depth > d) {
                deepest = Some((o, contact.normal, depth));
            }
        }
        deepest
    }

    /// Resolves every contact after a substep of `h` seconds, with the
    /// obstacles where [`Collider::set_time`] put them. With `friction`,
    /// Coulomb friction acts on the touching particles; without, they are
    /// only put back on the surface, for solvers that decided friction
    /// inside their solve.
    #[allow(clippy::too_many_arguments)]
    pub fn resolve(
        &mut self,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        h: f32,
        thickness: f32,
        edges: bool,
        friction: bool,
    ) -> u32 {
        if obstacles.is_empty() {
            return 0;
        }
        let mut contacts = 0;
        for i in 0..particles.len() {
            self.nearest[i] = NONE;
            self.touching[i] = false;
            self.gather(particles.x[i]);
            let mut nearest_distance = f32::INFINITY;
            for c in 0..self.candidates.len() {
                let o = self.candidates[c] as usize;
                let Some(contact) = self.particle_contact(particles, i, &obstacles[o], o) else {
                    continue;
                };
                if contact.signed_distance < nearest_distance {
                    nearest_distance = contact.signed_distance;
                    self.nearest[i] = o as u32;
                    self.normal[i] = contact.normal;
                    // Resolution below leaves a particle at least the thickness out.
                    self.distance[i] = if particles.inv_mass[i] != 0.0 {
                        contact.signed_distance.max(thickness)
                    } else {
                        contact.signed_distance
                    };
                }
                // A hair of slack keeps particles a solver left exactly at the
                // thickness in contact, so friction still acts on them.
                if particles.inv_mass[i] != 0.0
                    && contact.signed_distance < thickness + CONTACT_SLACK
                {
                    self.resolve_particle(
                        particles, i, obstacles, o, contact, h, thickness, friction,
                    );
                    contacts += 1;
                }
            }
        }
        if edges {
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
                        self.reach
                    } else {
                        self.distance[a]
                    };
                    let db = if ob == NONE {
                        self.reach
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
                    self.push_out(particles, i, obstacles, thickness);
                }
            }
        }
        contacts
    }

    /// Moves particle `i` out to the thickness of every obstacle it is inside
    /// (positions and the inward normal velocity only).
    fn push_out(&mut self, p: &mut Particles, i: usize, obstacles: &[Obstacle], thickness: f32) {
        self.move_out(&mut p.x[i], Some(&mut p.v[i]), obstacles, thickness);
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
        self.gather(*x);
        for c in 0..self.candidates.len() {
            let o = self.candidates[c] as usize;
            let Some(contact) = contact(&*obstacles[o].shape, &self.poses[o], *x) else {
                continue;
            };
            if contact.signed_distance < thickness {
                let (n, depth) = (contact.normal, thickness - contact.signed_distance);
                *x += n * depth;
                moved += depth;
                if let Some(v) = v.as_deref_mut() {
                    let vn = (*v - self.surface_velocity_of(obstacles, o, *x)).dot(n);
                    if vn < 0.0 {
                        *v -= n * vn;
                    }
                }
            }
        }
        moved
    }

    /// Pushes particle `i` out of obstacle `o` and applies friction.
    #[allow(clippy::too_many_arguments)]
    fn resolve_particle(
        &mut self,
        p: &mut Particles,
        i: usize,
        obstacles: &[Obstacle],
        o: usize,
        c: Contact,
        h: f32,
        thickness: f32,
        friction: bool,
    ) {
        let obstacle = &obstacles[o];
        let n = c.normal;
        let new_x = p.x[i] + n * (thickness - c.signed_distance).max(0.0);
        let surface_v = self.surface_velocity_of(obstacles, o, new_x);
        let v_old = p.v[i];
        let rel = v_old - surface_v;
        let vn = rel.dot(n);
        // The normal velocity taken away bounds what friction may take away.
        let removed = (-vn).max(0.0);
        let rel_t = rel - n * vn;
        let slip = rel_t.length();
        let limit = obstacle.friction * removed;
        let rel_t_new = if !friction {
            rel_t
        } else if slip <= limit {
            Vector::ZERO
        } else {
            rel_t * (1.0 - limit / slip)
        };
        let v_new = surface_v + n * vn.max(0.0) + rel_t_new;
        // Undo the slip friction forbade during this substep.
        p.x[i] = new_x + (rel_t_new - rel_t) * h;
        p.v[i] = v_new;
        self.touching[i] = true;
        self.contact_obstacle[i] = o as u32;
        self.contact_immovable[i] = obstacle.body.is_none();
        self.contact_normal[i] = n;
        self.surface_velocity[i] = surface_v;
        let j = (v_old - v_new) * p.mass[i];
        let imp = &mut self.impulses[o];
        imp.linear += j;
        imp.angular_about_origin += new_x.cross(j);
        imp.contacts += 1;
    }

    /// Keeps the samples of the spring `a`–`b` at least `margin` outside every obstacle.
    fn resolve_spring(
        &mut self,
        p: &mut Particles,
        a: usize,
        b: usize,
        obstacles: &[Obstacle],
        margin: f32,
    ) {
        let (wa, wb) = (p.inv_mass[a], p.inv_mass[b]);
        if wa == 0.0 && wb == 0.0 {
            return;
        }
        // Candidates near the whole spring, once.
        let (xa, xb) = (p.x[a], p.x[b]);
        self.gather_box(Aabb::new(xa.min(xb), xa.max(xb)));
        for c in 0..self.candidates.len() {
            let o = self.candidates[c] as usize;
            let obstacle = &obstacles[o];
            let pose = self.poses[o];
            // A ball: the one point of the spring nearest its centre.
            // Other shapes: the samples at 1/4, 1/2 and 3/4.
            let nearest_to_centre;
            let samples: &[f32] = match obstacle.shape.as_ball() {
                Some(_) => {
                    let (ab, ac) = (p.x[b] - p.x[a], pose.translation - p.x[a]);
                    let len2 = ab.length_squared();
                    nearest_to_centre = [if len2 > 0.0 {
                        (ac.dot(ab) / len2).clamp(0.0, 1.0)
                    } else {
                        0.5
                    }];
                    &nearest_to_centre
                }
                None => &EDGE_SAMPLES,
            };
            // A pinned end held inside the obstacle cannot be moved out: the
            // spring cannot be resolved, and pushing its free end would only
            // shove it about.
            let pinned_inside = [(a, wa), (b, wb)].iter().any(|&(i, w)| {
                w == 0.0
                    && contact(&*obstacle.shape, &pose, p.x[i])
                        .is_some_and(|c| c.signed_distance < 0.0)
            });
            if pinned_inside {
                continue;
            }
            for &t in samples {
                let sample = p.x[a] * (1.0 - t) + p.x[b] * t;
                let Some(contact) = contact(&*obstacle.shape, &pose, sample) else {
                    continue;
                };
                if contact.signed_distance >= margin {
                    continue;
                }
                let (ca, cb) = ((1.0 - t) * wa, t * wb);
                let denom = (1.0 - t) * ca + t * cb;
                if denom <= 0.0 {
                    continue;
                }
                let n = contact.normal;
                let push = n * ((margin - contact.signed_distance) / denom);
                for (i, w) in [(a, ca), (b, cb)] {
                    if w == 0.0 {
                        continue;
                    }
                    p.x[i] += push * w;
                    self.edge_moved[i] = true;
                    let surface_v = self.surface_velocity_of(obstacles, o, p.x[i]);
                    let vn = (p.v[i] - surface_v).dot(n);
                    if vn < 0.0 {
                        let dv = -n * vn;
                        p.v[i] += dv;
                        let j = -dv * p.mass[i];
                        let imp = &mut self.impulses[o];
                        imp.linear += j;
                        imp.angular_about_origin += p.x[i].cross(j);
                    }
                }
            }
        }
    }
}
