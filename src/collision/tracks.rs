//! Where the obstacles are during a step: their poses substep by substep,
//! the velocities of the dynamic bodies among them as the cloth pushes them,
//! the broad phase that finds the obstacles near a point, and the momentum
//! handed to each.

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};

use super::contact::{contact_prepared, cuboid_beyond, Analytic, Contact, PoseF64};
use super::obstacle::{DynamicBody, Obstacle, ObstacleImpulse};
use super::one_obstacle::{LaneShape, OneObstacleLaw};
use crate::math::{Pose, Rotation, Vector};

/// Above this many obstacles, candidates come from a bounding-volume tree
/// instead of a linear scan.
const BVH_THRESHOLD: usize = 8;

/// The obstacles' motion over one step, and the momentum the cloth gave them.
#[derive(Debug, Default)]
pub(crate) struct ObstacleTracks {
    aabbs: Vec<Aabb>,
    /// Poses at the current substep.
    pub(super) poses: Vec<Pose>,
    /// Poses at the previous substep.
    pub(super) prev_poses: Vec<Pose>,
    /// Per dynamic obstacle: centre of mass, its velocity, the angular
    /// velocity, and the impulses already turned into velocity.
    com: Vec<Vector>,
    com_velocity: Vec<Vector>,
    angvel: Vec<Vector>,
    applied: Vec<ObstacleImpulse>,
    bvh: Option<Bvh>,
    /// Obstacles found by the last [`ObstacleTracks::gather`].
    pub(super) candidates: Vec<u32>,
    /// How far (m) beyond an obstacle a particle or a sampled spring can still meet it.
    pub(super) reach: f32,
    /// Momentum handed to each obstacle during the current step.
    pub(super) impulses: Vec<ObstacleImpulse>,
    /// Per obstacle: the centre (in its own frame, m) and radius (m) of a
    /// sphere around it, to tell cheaply that a point is far from it.
    bounds: Vec<(Vector, f32)>,
    /// Per obstacle: that sphere's centre where the obstacle is now (m).
    centers: Vec<Vector>,
    /// Per obstacle: how its contacts are answered, and its pose now in
    /// double precision (for the analytic contacts).
    analytic: Vec<Analytic>,
    poses_f64: Vec<PoseF64>,
    /// Per particle, from the start of the step: where it was (m; its
    /// anchor, x, y and z apart), and the obstacles whose bounds come
    /// within `cache_margin` of there, as
    /// `cached[cache_start[i]..cache_start[i + 1]]`, with 1 in `listed`
    /// where that list is not empty. While a particle stays within the
    /// margin of where it was, its candidates are these, no broad phase
    /// needed. Structure-of-arrays so that the particle pass's lanes copy
    /// a batch's at a time (gathering them particle by particle every
    /// substep was a third of the lanes' gather).
    anchors: [Vec<f32>; 3],
    cache_start: Vec<u32>,
    cached: Vec<u32>,
    cache_margin: f32,
    listed: Vec<u32>,
    /// Per obstacle: whether it stays where it is ([`Obstacle::is_still`]).
    still: Vec<bool>,
    /// Per particle: whether its cached list holds an obstacle that is not
    /// still (a moving or dynamic body).
    near_moving: Vec<bool>,
}

/// The step's cache for some particles, as [`ObstacleTracks::cache_for`]
/// gives it to the particle pass's lanes.
pub(super) struct CacheLanes<'a> {
    /// Where each particle was when the cache was made: x, y, z (m).
    pub anchor: [&'a [f32]; 3],
    /// 1 where the particle's list holds an obstacle, else 0.
    pub listed: &'a [u32],
}

impl ObstacleTracks {
    /// Prepares a step of `dt` seconds: bounds swept over the step, grown by
    /// `reach` metres (the thickness plus the longest sampled spring).
    pub fn begin_step(&mut self, obstacles: &[Obstacle], dt: f32, reach: f32) {
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
        self.bounds.clear();
        self.bounds.extend(obstacles.iter().map(|o| {
            let sphere = o.shape.compute_local_bounding_sphere();
            (sphere.center, sphere.radius)
        }));
        self.analytic.clear();
        self.analytic
            .extend(obstacles.iter().map(|o| Analytic::of(&*o.shape)));
        self.still.clear();
        self.still.extend(obstacles.iter().map(Obstacle::is_still));
        self.place_bounds();
        self.anchors.iter_mut().for_each(Vec::clear);
        self.cache_start.clear();
        self.cached.clear();
        self.listed.clear();
        self.near_moving.clear();
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
    }

    /// Obstacle candidates whose bounds contain `point`, into `self.candidates`.
    pub(super) fn gather(&mut self, point: Vector) {
        self.gather_box(Aabb::new(point, point));
    }

    /// Finds, once for the step, the candidates of every particle at `x`
    /// within `margin` metres of where it is now.
    pub(super) fn cache_candidates(&mut self, x: &[Vector], margin: f32) {
        for (a, anchors) in self.anchors.iter_mut().enumerate() {
            anchors.clear();
            anchors.extend(x.iter().map(|p| p[a]));
        }
        self.cache_margin = margin;
        self.cache_start.clear();
        self.cached.clear();
        self.cache_start.push(0);
        let reach = Vector::splat(margin);
        if self.bvh.is_none() {
            // Few obstacles: their bounds tested in place, the same
            // candidates in the same order as `gather_box` (which went
            // through its scratch list, twice the time: 3% of the drape's
            // step at N = 64).
            for &p in x {
                let region = Aabb::new(p - reach, p + reach);
                for (o, bounds) in self.aabbs.iter().enumerate() {
                    if bounds.intersects(&region) {
                        self.cached.push(o as u32);
                    }
                }
                self.cache_start.push(self.cached.len() as u32);
            }
        } else {
            for &p in x {
                self.gather_box(Aabb::new(p - reach, p + reach));
                self.cached.extend_from_slice(&self.candidates);
                self.cache_start.push(self.cached.len() as u32);
            }
        }
        self.listed.clear();
        self.listed
            .extend(self.cache_start.windows(2).map(|w| (w[0] != w[1]) as u32));
        let (cached, still) = (&self.cached, &self.still);
        self.near_moving.clear();
        self.near_moving
            .extend(self.cache_start.windows(2).map(|w| {
                cached[w[0] as usize..w[1] as usize]
                    .iter()
                    .any(|&o| !still[o as usize])
            }));
    }

    /// The candidates of particle `i` at `point`, into `out`: the same
    /// obstacles in the same order as [`ObstacleTracks::gather`], from the
    /// step's cache while the particle is within its margin. Returns false
    /// when they came from the broad phase instead.
    #[inline]
    pub(super) fn gather_particle(&self, i: usize, point: Vector, out: &mut Vec<u32>) -> bool {
        let Some(anchor) = self.anchor(i) else {
            self.gather_box_into(Aabb::new(point, point), out);
            return false;
        };
        if (point - anchor).abs().max_element() > self.cache_margin {
            self.gather_box_into(Aabb::new(point, point), out);
            return false;
        }
        out.clear();
        let (from, to) = (
            self.cache_start[i] as usize,
            self.cache_start[i + 1] as usize,
        );
        if from == to {
            return true;
        }
        let here = Aabb::new(point, point);
        for &o in &self.cached[from..to] {
            if self.aabbs[o as usize].intersects(&here) {
                out.push(o);
            }
        }
        true
    }

    /// True when obstacle `o` is convex (a ball, a cuboid or a capsule):
    /// its signed distance is then a convex function of the point.
    pub(super) fn is_convex(&self, o: usize) -> bool {
        self.analytic
            .get(o)
            .is_some_and(|a| !matches!(a, Analytic::Other))
    }

    /// How far (squared, m²) particle `i`, now at `point`, is from where it
    /// was when the step's cache was made (infinite without one).
    #[inline]
    pub(super) fn drift2(&self, i: usize, point: Vector) -> f32 {
        self.anchor(i)
            .map_or(f32::INFINITY, |anchor| (point - anchor).length_squared())
    }

    /// Where particle `i` was when the step's cache was made (m); `None`
    /// without a cache.
    #[inline]
    fn anchor(&self, i: usize) -> Option<Vector> {
        let [x, y, z] = &self.anchors;
        Some(Vector::new(*x.get(i)?, *y.get(i)?, *z.get(i)?))
    }

    /// The ball's radius (m) when the one obstacle is a ball.
    pub(super) fn one_ball(&self) -> Option<f32> {
        match self.analytic[..] {
            [Analytic::Ball(radius)] => Some(radius),
            _ => None,
        }
    }

    /// The one obstacle as the particle pass's lanes take it, when it is a
    /// ball or a cuboid: where it is now, its bounds, and its surface's
    /// motion.
    pub(super) fn one_obstacle_law(&self, obstacles: &[Obstacle]) -> Option<OneObstacleLaw> {
        let (&[analytic], [obstacle]) = (&self.analytic[..], obstacles) else {
            return None;
        };
        let centre = self.poses[0].translation;
        let shape = match analytic {
            Analytic::Ball(radius) => LaneShape::Ball { centre, radius },
            Analytic::Cuboid(half) => LaneShape::Cuboid {
                half,
                pose: self.poses_f64[0],
            },
            _ => return None,
        };
        // The surface's velocity at p is `linear + angular × (p - about)`,
        // in the terms `surface_velocity_of` uses.
        let (linear, angular, about) = match obstacle.body {
            Some(_) => (self.com_velocity[0], self.angvel[0], self.com[0]),
            None => (obstacle.linvel, obstacle.angvel, centre),
        };
        Some(OneObstacleLaw {
            shape,
            bounds_min: self.aabbs[0].mins,
            bounds_max: self.aabbs[0].maxs,
            cache_margin: self.cache_margin,
            bound_centre: self.centers[0],
            bound_radius: self.bounds[0].1,
            linear,
            angular,
            about,
            friction: obstacle.friction,
            immovable: obstacle.body.is_none(),
        })
    }

    /// For particles `range`: where each was when the step's cache was made
    /// (m), and whether its list is not empty, as structure-of-arrays;
    /// `None` without a cache.
    #[inline]
    pub(super) fn cache_for(&self, range: std::ops::Range<usize>) -> Option<CacheLanes<'_>> {
        let [x, y, z] = &self.anchors;
        Some(CacheLanes {
            anchor: [
                x.get(range.clone())?,
                y.get(range.clone())?,
                z.get(range.clone())?,
            ],
            listed: self.listed.get(range)?,
        })
    }

    /// True when no cache was made this step.
    pub(super) fn cache_is_empty(&self) -> bool {
        self.anchors[0].is_empty()
    }

    /// The candidate obstacles cached for particle `i` this step (none when
    /// the cache does not cover it).
    pub(super) fn cached_of(&self, i: usize) -> &[u32] {
        match self.cache_start.get(i..i + 2) {
            Some(&[from, to]) => &self.cached[from as usize..to as usize],
            _ => &[],
        }
    }

    /// How far (squared, m²) particle `i`, now at `point`, is from its
    /// anchor, when its cached list is empty and it is still within the
    /// margin: it can then touch no obstacle, and the particle pass has
    /// nothing to do for it but note the drift. `None` otherwise (no cache,
    /// candidates cached, or out of the margin).
    #[inline]
    pub(super) fn free_drift2(&self, i: usize, point: Vector) -> Option<f32> {
        let listed = self.cache_start.get(i..i + 2).is_none_or(|c| c[0] != c[1]);
        self.drift2_unless(listed, i, point)
    }

    /// As [`Self::free_drift2`], for a particle whose cached candidates are
    /// all still obstacles (none that moves or is a dynamic body, or none
    /// at all): a pass over the bodies alone passes it by as it does a
    /// free one.
    #[inline]
    pub(super) fn still_only_drift2(&self, i: usize, point: Vector) -> Option<f32> {
        let near_moving = self.near_moving.get(i).is_none_or(|&m| m);
        self.drift2_unless(near_moving, i, point)
    }

    /// Particle `i`'s squared drift (m²) from its anchor to `point`,
    /// unless `near` or it left the margin (or there is no cache).
    #[inline(always)]
    fn drift2_unless(&self, near: bool, i: usize, point: Vector) -> Option<f32> {
        let from_anchor = point - self.anchor(i)?;
        if near || from_anchor.abs().max_element() > self.cache_margin {
            return None;
        }
        Some(from_anchor.length_squared())
    }

    /// True when particle `i` has candidates in the step's cache: while it
    /// stays within the margin, it can come near no obstacle otherwise.
    pub(super) fn has_cached(&self, i: usize) -> bool {
        self.cache_start.get(i..i + 2).is_some_and(|c| c[0] != c[1])
    }

    /// The contact of `point` with obstacle `o` where it is now (inlined
    /// for the reason `contact_prepared` is).
    #[inline(always)]
    pub(super) fn contact(
        &self,
        obstacles: &[Obstacle],
        o: usize,
        point: Vector,
    ) -> Option<Contact> {
        contact_prepared(
            &*obstacles[o].shape,
            self.analytic[o],
            &self.poses_f64[o],
            point,
        )
    }

    /// Whether the contact of `point` with obstacle `o` surely lies at least
    /// `distance` (m) out, told cheaply (a cuboid's, [`cuboid_beyond`]);
    /// false when not sure.
    #[inline(always)]
    pub(super) fn contact_beyond(&self, o: usize, point: Vector, distance: f32) -> bool {
        match self.analytic[o] {
            Analytic::Cuboid(half) => cuboid_beyond(half, &self.poses_f64[o], point, distance),
            _ => false,
        }
    }

    /// Obstacle candidates whose bounds meet `region`, into `self.candidates`.
    pub(super) fn gather_box(&mut self, region: Aabb) {
        let mut out = std::mem::take(&mut self.candidates);
        self.gather_box_into(region, &mut out);
        self.candidates = out;
    }

    /// Obstacle candidates whose bounds meet `region`, into `out`.
    fn gather_box_into(&self, region: Aabb, out: &mut Vec<u32>) {
        out.clear();
        match &self.bvh {
            Some(bvh) => out.extend(bvh.intersect_aabb(&region)),
            None => out.extend(
                self.aabbs
                    .iter()
                    .enumerate()
                    .filter(|(_, b)| b.intersects(&region))
                    .map(|(o, _)| o as u32),
            ),
        }
    }

    /// True when `point` is surely more than `distance` metres from obstacle
    /// `o` where it is now: outside a sphere around it by that much.
    #[inline]
    pub(super) fn surely_beyond(&self, o: usize, point: Vector, distance: f32) -> bool {
        let (center, radius) = (self.centers[o], self.bounds[o].1);
        (point - center).length_squared() > (radius + distance) * (radius + distance)
    }

    /// Dynamic obstacle `o`'s (its `body`'s) velocity and angular
    /// velocity over the next substep of `h` seconds, as
    /// [`Self::advance_to`] will give them (with the momentum handed to it
    /// since the last), and its centre of mass now (m).
    pub(super) fn next_velocities(
        &self,
        o: usize,
        body: &DynamicBody,
        h: f32,
    ) -> (Vector, Vector, Vector) {
        let (now, done) = (self.impulses[o], self.applied[o]);
        let dj = now.linear - done.linear;
        let dtau = (now.angular_about_origin - done.angular_about_origin) - self.com[o].cross(dj);
        (
            self.com_velocity[o] + dj * body.inverse_mass + body.acceleration * h,
            self.angvel[o] + body.inverse_inertia * dtau,
            self.com[o],
        )
    }

    /// Records momentum `j` (N·s) handed to obstacle `o` at `point`.
    pub fn add_impulse(&mut self, o: usize, point: Vector, j: Vector) {
        if let Some(imp) = self.impulses.get_mut(o) {
            imp.linear += j;
            imp.angular_about_origin += point.cross(j);
        }
    }

    /// Records momentum `j` (N·s) handed to obstacle `o` through its
    /// centre of mass `com` (m), with angular momentum `spin` (N·m·s)
    /// about it: a push whose turn is not that of `j` at one point.
    pub fn add_impulse_and_spin(&mut self, o: usize, com: Vector, j: Vector, spin: Vector) {
        if let Some(imp) = self.impulses.get_mut(o) {
            imp.linear += j;
            imp.angular_about_origin += com.cross(j) + spin;
        }
    }

    /// Momentum handed to each obstacle during the current step.
    pub fn impulses(&self) -> &[ObstacleImpulse] {
        &self.impulses
    }

    /// Each obstacle's pose at the current substep (m): at the end of a
    /// step, where the step left it.
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// Moves the obstacles to where they are `t` seconds into the step,
    /// before a substep of `h` seconds.
    pub fn advance_to(&mut self, obstacles: &[Obstacle], t: f32, h: f32) {
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
        self.place_bounds();
    }

    /// The bounding spheres' centres at the obstacles' current poses, once
    /// per substep rather than once per particle.
    fn place_bounds(&mut self) {
        self.centers.clear();
        self.centers.extend(
            self.bounds
                .iter()
                .zip(&self.poses)
                .map(|(&(center, _), pose)| pose.transform_point(center)),
        );
        self.poses_f64.clear();
        self.poses_f64.extend(
            self.poses
                .iter()
                .zip(&self.analytic)
                .map(|(pose, &analytic)| PoseF64::placing(pose, analytic)),
        );
    }

    /// Velocity of the material point of obstacle `o` at `point`, now.
    pub(super) fn surface_velocity_of(
        &self,
        obstacles: &[Obstacle],
        o: usize,
        point: Vector,
    ) -> Vector {
        match obstacles[o].body {
            Some(_) => self.com_velocity[o] + self.angvel[o].cross(point - self.com[o]),
            None => obstacles[o].velocity_at(&self.poses[o], point),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of `count` balls 0.3 m apart, moving, and points near and far.
    fn check(count: usize) {
        let obstacles: Vec<Obstacle> = (0..count)
            .map(|k| {
                Obstacle::ball(Vector::new(0.3 * k as f32, 0.0, 0.0), 0.1)
                    .with_velocity(Vector::new(0.0, 1.0, 0.0), Vector::ZERO)
            })
            .collect();
        let mut tracks = ObstacleTracks::default();
        tracks.begin_step(&obstacles, 0.02, 0.05);
        let anchors: Vec<Vector> = (0..40)
            .map(|i| Vector::new(0.07 * i as f32, 0.12 * (i % 3) as f32, 0.0))
            .collect();
        tracks.cache_candidates(&anchors, 0.1);
        let mut hits = 0;
        for (i, &a) in anchors.iter().enumerate() {
            // Within the margin, on its edge, and beyond it.
            for offset in [0.0, 0.05, 0.1, 0.25] {
                for dir in [Vector::X, -Vector::Y, Vector::new(0.6, 0.6, 0.5)] {
                    let p = a + dir * offset;
                    tracks.gather(p);
                    let fresh = tracks.candidates.clone();
                    let mut cached = Vec::new();
                    tracks.gather_particle(i, p, &mut cached);
                    assert_eq!(cached, fresh, "particle {i} at {p}");
                    hits += fresh.len();
                }
            }
        }
        assert!(
            hits > 0,
            "no point was near an obstacle: the check can fail"
        );
    }

    #[test]
    fn cached_candidates_are_the_broad_phase_s_own() {
        check(3); // a linear scan
        check(20); // a bounding-volume tree
    }
}
