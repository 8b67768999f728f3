//! Obstacles: a parry shape with a pose, a velocity and a friction coefficient.

use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::shape::SharedShape;

use crate::error::ClothError;
use glam::Mat3;

use crate::math::{Pose, Rotation, Vector};

/// A shape the cloth collides with.
///
/// `pose` is where the shape is at the start of a step; during the step it
/// moves with the constant velocities `linvel` (of the shape's origin, m/s)
/// and `angvel` (about the shape's origin, rad/s, world frame). The same
/// velocities give the surface velocity that friction acts against, so a
/// moving or spinning obstacle drags the cloth.
#[derive(Clone)]
pub struct Obstacle {
    /// The shape; anything parry can project points on (ball, cuboid, capsule,
    /// cylinder, convex polyhedron, triangle mesh, heightfield, compound, ...).
    pub shape: SharedShape,
    /// Pose at the start of the step.
    pub pose: Pose,
    /// Linear velocity of the shape's origin, in m/s.
    pub linvel: Vector,
    /// Angular velocity about the shape's origin, in rad/s.
    pub angvel: Vector,
    /// Coulomb friction coefficient between cloth and this obstacle.
    pub friction: f32,
    /// For a body that the cloth's push moves (a dynamic rapier body): its
    /// mass properties. Its velocity then responds to the cloth's impulses
    /// substep by substep, and solvers do not treat it as immovable.
    pub body: Option<DynamicBody>,
}

/// Mass properties of a dynamic obstacle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicBody {
    /// Inverse mass along each world axis, in 1/kg (0 on a locked axis).
    pub inverse_mass: Vector,
    /// World-space inverse inertia tensor about the centre of mass, in 1/(kg·m²).
    pub inverse_inertia: Mat3,
    /// Centre of mass at the start of the step, world coordinates (m).
    pub center_of_mass: Vector,
    /// Constant acceleration during the step (its gravity), in m/s².
    pub acceleration: Vector,
}

impl std::fmt::Debug for Obstacle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Obstacle")
            .field("shape", &self.shape.shape_type())
            .field("pose", &self.pose)
            .field("linvel", &self.linvel)
            .field("angvel", &self.angvel)
            .field("friction", &self.friction)
            .field("body", &self.body)
            .finish()
    }
}

/// Momentum the cloth gave an obstacle during a step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ObstacleImpulse {
    /// Linear impulse, in N·s.
    pub linear: Vector,
    /// Angular impulse about the world origin, `Σ p × j`, in N·m·s.
    pub angular_about_origin: Vector,
    /// Number of particle contacts that contributed.
    pub contacts: u32,
}

impl ObstacleImpulse {
    /// The angular impulse about `center` (for example a body's centre of mass).
    pub fn angular_about(&self, center: Vector) -> Vector {
        self.angular_about_origin - center.cross(self.linear)
    }
}

impl Obstacle {
    /// A static obstacle with friction 0.5.
    pub fn new(shape: SharedShape, pose: Pose) -> Self {
        Self {
            shape,
            pose,
            linvel: Vector::ZERO,
            angvel: Vector::ZERO,
            friction: 0.5,
            body: None,
        }
    }

    /// A static ball of `radius` metres centred on `center`.
    pub fn ball(center: Vector, radius: f32) -> Self {
        Self::new(SharedShape::ball(radius), Pose::from_translation(center))
    }

    /// A static box with the given half-extents (metres) and pose.
    pub fn cuboid(half_extents: Vector, pose: Pose) -> Self {
        Self::new(
            SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z),
            pose,
        )
    }

    /// Sets the velocities (m/s and rad/s).
    pub fn with_velocity(mut self, linvel: Vector, angvel: Vector) -> Self {
        self.linvel = linvel;
        self.angvel = angvel;
        self
    }

    /// Sets the friction coefficient.
    pub fn with_friction(mut self, friction: f32) -> Self {
        self.friction = friction;
        self
    }

    /// Pose after `t` seconds of the step.
    pub fn pose_at(&self, t: f32) -> Pose {
        let rotation = if self.angvel == Vector::ZERO {
            self.pose.rotation
        } else {
            (Rotation::from_scaled_axis(self.angvel * t) * self.pose.rotation).normalize()
        };
        Pose::from_parts(self.pose.translation + self.linvel * t, rotation)
    }

    /// Velocity of the material point of the obstacle at `point`, when its pose is `pose`.
    pub fn velocity_at(&self, pose: &Pose, point: Vector) -> Vector {
        self.linvel + self.angvel.cross(point - pose.translation)
    }

    /// Whether the shape has edges or corners: anything but a ball, a
    /// capsule or a half-space (a plane). Over an edge a contact pushes the
    /// cloth out along a normal that turns sharply from one particle to the
    /// next, which short substeps must follow.
    pub fn has_edges(&self) -> bool {
        use parry3d::shape::ShapeType;
        !matches!(
            self.shape.shape_type(),
            ShapeType::Ball | ShapeType::Capsule | ShapeType::HalfSpace
        )
    }

    /// Whether an edge or corner of the obstacle, where it stands at the
    /// step's start, may lie inside `region` (a world box): for a cuboid,
    /// whether the box around one of its twelve edges meets it (a cloth
    /// lying on the middle of a large floor meets none); for any other
    /// shape with edges, whether the shape's own box does.
    pub fn edges_may_meet(&self, region: &Aabb) -> bool {
        if !self.has_edges() {
            return false;
        }
        let Some(cuboid) = self.shape.as_cuboid() else {
            return self.shape.compute_aabb(&self.pose).intersects(region);
        };
        let h = cuboid.half_extents;
        let corner = |k: usize| {
            let sign = |bit: usize| if k & bit == 0 { -1.0 } else { 1.0 };
            self.pose
                .transform_point(Vector::new(sign(1) * h.x, sign(2) * h.y, sign(4) * h.z))
        };
        // An edge joins two corners that differ in one axis' sign.
        (0..8).any(|k| {
            [1, 2, 4]
                .into_iter()
                .filter(|&bit| k & bit == 0)
                .any(|bit| {
                    let (a, b) = (corner(k), corner(k | bit));
                    Aabb::new(a.min(b), a.max(b)).intersects(region)
                })
        })
    }

    /// Whether the obstacle stays where it is: no rapier body, no velocity.
    pub fn is_still(&self) -> bool {
        self.body.is_none() && self.linvel == Vector::ZERO && self.angvel == Vector::ZERO
    }

    /// World bounding box of the obstacle over `[0, dt]` of the step.
    pub fn swept_aabb(&self, dt: f32) -> Aabb {
        let swept = self.shape.compute_swept_aabb(&self.pose, &self.pose_at(dt));
        match &self.body {
            // A dynamic body also falls, and is slowed by the cloth.
            Some(b) => swept.loosened(0.5 * b.acceleration.length() * dt * dt),
            None => swept,
        }
    }

    /// Checks that the pose, velocities and friction are finite (friction >= 0).
    pub fn validate(&self, index: usize) -> Result<(), ClothError> {
        let bad = |reason: &str| ClothError::InvalidObstacle {
            index,
            reason: reason.to_string(),
        };
        if !(self.pose.translation.is_finite() && self.pose.rotation.is_finite()) {
            return Err(bad("its pose is not finite"));
        }
        if !(self.linvel.is_finite() && self.angvel.is_finite()) {
            return Err(bad("its velocity is not finite"));
        }
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(bad("its friction must be a finite number >= 0"));
        }
        if let Some(b) = &self.body {
            let finite = b.inverse_mass.is_finite()
                && b.inverse_inertia.is_finite()
                && b.center_of_mass.is_finite()
                && b.acceleration.is_finite();
            if !finite || b.inverse_mass.min_element() < 0.0 {
                return Err(bad(
                    "its body's mass properties must be finite, inverse mass >= 0",
                ));
            }
        }
        let aabb = self.shape.compute_local_aabb();
        if !(aabb.mins.is_finite() && aabb.maxs.is_finite()) {
            return Err(bad("its shape has a non-finite size"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(centre: Vector, half: f32) -> Aabb {
        Aabb::new(centre - Vector::splat(half), centre + Vector::splat(half))
    }

    /// A cloth on the middle of a floor meets none of its edges; one over
    /// its rim or by a corner does; a box in the empty corner of a turned
    /// cuboid's bounding box meets none; a ball has none, and a cylinder's
    /// are wherever its bounding box is.
    #[test]
    fn edges_are_met_near_a_cuboids_rim_only() {
        let floor = Obstacle::cuboid(
            Vector::new(2.0, 0.1, 2.0),
            Pose::from_translation(Vector::new(0.0, -0.1, 0.0)),
        );
        assert!(!floor.edges_may_meet(&region(Vector::new(0.3, 0.2, -0.4), 0.8)));
        assert!(floor.edges_may_meet(&region(Vector::new(1.6, 0.2, 0.0), 0.5)));
        assert!(floor.edges_may_meet(&region(Vector::new(-2.1, -0.3, 2.1), 0.15)));
        // Under the floor, by its bottom's rim.
        assert!(floor.edges_may_meet(&region(Vector::new(0.0, -0.25, -1.9), 0.1)));
        // A cube turned 45° about y: its box's corner at (+1, ·, +1) is empty.
        let turned = Obstacle::cuboid(
            Vector::splat(0.5),
            Pose::from_parts(
                Vector::ZERO,
                Rotation::from_rotation_y(std::f32::consts::FRAC_PI_4),
            ),
        );
        let corner = Vector::new(0.62, 0.0, 0.62);
        assert!(turned
            .shape
            .compute_aabb(&turned.pose)
            .intersects(&region(corner, 0.05)));
        assert!(!turned.edges_may_meet(&region(corner, 0.05)));
        // Its upright edge at x = √2 / 2.
        assert!(turned.edges_may_meet(&region(Vector::new(0.72, 0.0, 0.0), 0.05)));
        let ball = Obstacle::ball(Vector::ZERO, 0.5);
        assert!(!ball.edges_may_meet(&region(Vector::new(0.5, 0.0, 0.0), 0.1)));
        let cylinder = Obstacle::new(SharedShape::cylinder(0.5, 0.2), Pose::IDENTITY);
        assert!(cylinder.edges_may_meet(&region(Vector::new(0.25, 0.45, 0.0), 0.1)));
        assert!(!cylinder.edges_may_meet(&region(Vector::new(0.25, 0.8, 0.0), 0.1)));
    }
}
