//! One point against one shape: closest surface point, outward normal, signed distance.

use parry3d::shape::Shape;

use crate::math::{Pose, Vector};

/// The closest point of a shape's surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Closest surface point, in world coordinates.
    pub point: Vector,
    /// Unit outward normal at that point (from the surface towards the outside).
    pub normal: Vector,
    /// Distance from the surface, negative inside, in metres.
    pub signed_distance: f32,
}

/// Below this distance (m) a point is taken to lie on the surface and the
/// normal comes from the surface feature instead of the point's offset.
const ON_SURFACE: f32 = 1.0e-6;

/// The contact of `point` with `shape` at `pose`; `None` only if the shape
/// cannot answer (non-finite data).
///
/// Degenerate cases get a sensible normal, never NaN: a point at a ball's
/// centre is pushed out along `+y`; a point exactly on an edge or corner gets
/// the feature's normal (or the direction from the shape's centre).
pub fn contact(shape: &dyn Shape, pose: &Pose, point: Vector) -> Option<Contact> {
    let local = pose.inverse_transform_point(point);
    let proj = shape.project_local_point(local, false);
    let (surface, normal, signed) = if proj.point.is_finite() {
        let offset = local - proj.point;
        let len = offset.length();
        if len > ON_SURFACE {
            let n = offset / len;
            if proj.is_inside {
                (proj.point, -n, -len)
            } else {
                (proj.point, n, len)
            }
        } else {
            (proj.point, surface_normal(shape, local)?, 0.0)
        }
    } else {
        // A point at a ball's centre projects to NaN: push it out along the world's up.
        let up = pose.inverse_transform_vector(Vector::Y);
        let nudged = shape.project_local_point(local + up * 1.0e-3, false);
        if !nudged.point.is_finite() {
            return None;
        }
        let depth = (nudged.point - local).length();
        (nudged.point, up, -depth)
    };
    Some(Contact {
        point: pose.transform_point(surface),
        normal: pose.transform_vector(normal),
        signed_distance: signed,
    })
}

/// Outward normal at a local point lying on the surface.
fn surface_normal(shape: &dyn Shape, local: Vector) -> Option<Vector> {
    let (proj, feature) = shape.project_local_point_and_get_feature(local);
    if let Some(n) = shape.feature_normal_at_point(0, feature, proj.point) {
        if let Some(n) = n.try_normalize() {
            return Some(n);
        }
    }
    let center = shape.compute_local_aabb().center();
    Some((local - center).try_normalize().unwrap_or(Vector::Y))
}

/// How deep `point` lies inside `shape` at `pose`, in metres (0 outside).
pub fn penetration_depth(shape: &dyn Shape, pose: &Pose, point: Vector) -> f32 {
    let local = pose.inverse_transform_point(point);
    let proj = shape.project_local_point(local, false);
    if !proj.is_inside {
        return 0.0;
    }
    if proj.point.is_finite() {
        (proj.point - local).length()
    } else {
        // At a ball's centre: as deep as the radius (any surface point is as far).
        shape.compute_local_aabb().half_extents().min_element()
    }
}
