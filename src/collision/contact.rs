//! One point against one shape: closest surface point, outward normal, signed distance.

use parry3d::bounding_volume::Aabb;
use parry3d::query::PointProjection;
use parry3d::shape::{HeightField, Shape};

use glam::{DMat3, DQuat, DVec3};

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
/// Balls, cuboids, capsules and cylinders are answered analytically (the
/// same surface point as parry's projection, with a normal that stays
/// exact a hair away from the surface; all but balls in double
/// precision); every other shape goes through parry's
/// `project_local_point`.
///
/// Degenerate cases get a sensible normal, never NaN: a point at a ball's
/// centre is pushed out along `+y`; a point exactly on an edge or corner gets
/// the feature's normal (or the direction from the shape's centre).
pub fn contact(shape: &dyn Shape, pose: &Pose, point: Vector) -> Option<Contact> {
    let analytic = Analytic::of(shape);
    match analytic {
        Analytic::Other => general_contact(shape, pose, point),
        _ => contact_prepared(shape, analytic, &PoseF64::placing(pose, analytic), point),
    }
}

/// What the analytic contacts need of a shape, read once per step instead
/// of once per query (a downcast through `dyn Shape`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Analytic {
    /// A ball of this radius (m).
    Ball(f32),
    /// A cuboid of these half extents (m).
    Cuboid(Vector),
    /// A capsule: its segment's ends (m, in its own frame) and radius (m).
    Capsule(Vector, Vector, f32),
    /// A cylinder along its own y axis: half height and radius (m).
    Cylinder(f32, f32),
    /// Any other shape: parry's point projection.
    Other,
}

impl Analytic {
    /// How contacts with `shape` are answered.
    pub fn of(shape: &dyn Shape) -> Self {
        if let Some(ball) = shape.as_ball() {
            Analytic::Ball(ball.radius)
        } else if let Some(cuboid) = shape.as_cuboid() {
            Analytic::Cuboid(cuboid.half_extents)
        } else if let Some(capsule) = shape.as_capsule() {
            Analytic::Capsule(capsule.segment.a, capsule.segment.b, capsule.radius)
        } else if let Some(cylinder) = shape.as_cylinder() {
            Analytic::Cylinder(cylinder.half_height, cylinder.radius)
        } else {
            Analytic::Other
        }
    }
}

/// A pose with its rotation and translation in double precision, prepared
/// once per substep for the analytic contacts: the rotation as a matrix and
/// its transpose (a matrix turns a vector in about half the operations of a
/// quaternion, and a turned cuboid's query turns three: hammock 12% faster
/// a frame, measured).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PoseF64 {
    pose: Pose,
    rotation: DMat3,
    inverse: DMat3,
    t: DVec3,
    /// False when the rotation is the identity: a table or a floor laid
    /// along the axes, whose queries then skip the two rotations (a third
    /// of a frame of the `box` scene, measured).
    turned: bool,
    /// A capsule's segment placed in the world (m): its queries then need
    /// no rotation (zero for other shapes).
    segment: [DVec3; 2],
}

impl PoseF64 {
    /// `pose` in double precision.
    pub fn of(pose: &Pose) -> Self {
        let q = pose.rotation.as_dquat().normalize();
        let rotation = DMat3::from_quat(q);
        PoseF64 {
            pose: *pose,
            rotation,
            inverse: rotation.transpose(),
            t: pose.translation.as_dvec3(),
            turned: q != DQuat::IDENTITY,
            segment: [DVec3::ZERO; 2],
        }
    }

    /// `pose` in double precision, with what the `analytic` shape's
    /// queries need of it placed once.
    pub fn placing(pose: &Pose, analytic: Analytic) -> Self {
        let mut placed = PoseF64::of(pose);
        if let Analytic::Capsule(a, b, _) = analytic {
            placed.segment = [a, b].map(|p| placed.turn(p.as_dvec3()) + placed.t);
        }
        placed
    }

    /// A vector of the shape's frame turned into the world's (the same
    /// vector when the pose is not turned).
    #[inline]
    fn turn(&self, v: DVec3) -> DVec3 {
        if self.turned {
            self.rotation * v
        } else {
            v
        }
    }
}

/// [`contact`] with the shape's kind and the pose in double precision
/// already found: the collision stage's per-particle query. Inlined into
/// the passes (the ball's few operations with it): called out of line, its
/// result went back through memory and the caller's first read of it
/// stalled, a fifth of the particle pass (measured).
#[inline(always)]
pub(crate) fn contact_prepared(
    shape: &dyn Shape,
    analytic: Analytic,
    pose: &PoseF64,
    point: Vector,
) -> Option<Contact> {
    match analytic {
        Analytic::Ball(radius) => ball_contact(radius, pose, point),
        Analytic::Cuboid(half) => cuboid_contact(half, pose, point),
        Analytic::Capsule(_, _, radius) => capsule_contact(radius, pose, point)
            .or_else(|| general_contact(shape, &pose.pose, point)),
        Analytic::Cylinder(half_height, radius) => {
            cylinder_contact((half_height, radius), pose, point)
                .or_else(|| general_contact(shape, &pose.pose, point))
        }
        Analytic::Other => general_contact(shape, &pose.pose, point),
    }
}

/// Any shape through parry's `project_local_point` (a heightfield's
/// through [`field_projection`]).
fn general_contact(shape: &dyn Shape, pose: &Pose, point: Vector) -> Option<Contact> {
    let local = pose.inverse_transform_point(point);
    let proj = match shape.as_heightfield() {
        Some(field) => field_projection(field, local),
        None => shape.project_local_point(local, false),
    };
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

/// The query point in the shape's frame, in double precision, so that the
/// normal stays exact even a hair away from the surface.
#[inline(always)]
fn local_f64(pose: &PoseF64, point: Vector) -> DVec3 {
    let offset = point.as_dvec3() - pose.t;
    if pose.turned {
        pose.inverse * offset
    } else {
        offset
    }
}

/// Back to world coordinates, in single precision.
#[inline(always)]
fn to_world(pose: &PoseF64, point: DVec3, normal: DVec3, signed: f64) -> Option<Contact> {
    finite(Contact {
        point: (pose.turn(point) + pose.t).as_vec3(),
        normal: pose.turn(normal).as_vec3(),
        signed_distance: signed as f32,
    })
}

/// The contact, unless a non-finite input made any of it non-finite.
#[inline(always)]
fn finite(contact: Contact) -> Option<Contact> {
    (contact.point.is_finite() && contact.normal.is_finite() && contact.signed_distance.is_finite())
        .then_some(contact)
}

/// A ball, analytically: `c + r (p - c)/|p - c|`; the centre pushes out
/// along the world's up. A ball looks the same however it is turned, so the
/// query stays in world coordinates, and in single precision: double
/// precision guards the other shapes' rotation there and back, which a
/// ball does not need.
#[inline(always)]
fn ball_contact(radius: f32, pose: &PoseF64, point: Vector) -> Option<Contact> {
    let centre = pose.pose.translation;
    let offset = point - centre;
    let dist = offset.length();
    let normal = if dist > 1e-9 {
        offset / dist
    } else {
        Vector::Y
    };
    finite(Contact {
        point: centre + normal * radius,
        normal,
        signed_distance: dist - radius,
    })
}

/// A cuboid, analytically: the clamp of the point to the box when outside,
/// the nearest face when inside.
#[inline(always)]
fn cuboid_contact(half: Vector, pose: &PoseF64, point: Vector) -> Option<Contact> {
    let local = local_f64(pose, point);
    let h = half.as_dvec3();
    let clamped = local.clamp(-h, h);
    if clamped != local {
        let offset = local - clamped;
        let dist = offset.length();
        return to_world(pose, clamped, offset / dist, dist);
    }
    let gaps = h - local.abs();
    let axis = if gaps.x <= gaps.y && gaps.x <= gaps.z {
        0
    } else if gaps.y <= gaps.z {
        1
    } else {
        2
    };
    let sign = if local[axis] >= 0.0 { 1.0 } else { -1.0 };
    let mut normal = DVec3::ZERO;
    normal[axis] = sign;
    let mut surface = local;
    surface[axis] = h[axis] * sign;
    to_world(pose, surface, normal, -gaps[axis])
}

/// Whether [`cuboid_contact`] of `point` surely gives a signed distance of
/// at least `distance` (m), told without its root and divisions: the
/// point is outside the box, and the squared distance beyond a hair over
/// `distance` squared (the contact's own distance then rounds to at least
/// `distance`).
#[inline(always)]
pub(crate) fn cuboid_beyond(half: Vector, pose: &PoseF64, point: Vector, distance: f32) -> bool {
    let local = local_f64(pose, point);
    let h = half.as_dvec3();
    let offset = local - local.clamp(-h, h);
    let far = f64::from(distance) * (1.0 + 1.0e-6);
    distance > 0.0 && offset.length_squared() > far * far
}

/// [`cuboid_contact`] of a point outside the box, for the particle pass's
/// lanes (the same operations): the normal, the signed distance and
/// whether the contact is finite; and whether the point is inside the box
/// or on it instead, where [`cuboid_contact`] takes the nearest face and
/// the values returned mean nothing.
#[inline(always)]
pub(crate) fn cuboid_outside(
    half: Vector,
    pose: &PoseF64,
    point: Vector,
) -> (Vector, f32, bool, bool) {
    let local = local_f64(pose, point);
    let h = half.as_dvec3();
    let clamped = local.clamp(-h, h);
    let offset = local - clamped;
    let dist = offset.length();
    let inside = clamped == local;
    match to_world(pose, clamped, offset / dist, dist) {
        Some(c) => (c.normal, c.signed_distance, true, inside),
        None => (Vector::ZERO, 0.0, false, inside),
    }
}

/// A capsule, analytically: the nearest point of its segment (placed in
/// the world by [`PoseF64::placing`]: a capsule looks the same however it
/// turns about its segment, so no rotation) pushed out by the radius, in
/// double precision. `None` for a point on the segment itself, whose
/// normal is any direction across it (parry's projection then picks one).
#[inline]
fn capsule_contact(radius: f32, pose: &PoseF64, point: Vector) -> Option<Contact> {
    let p = point.as_dvec3();
    let [a, b] = pose.segment;
    let axis = b - a;
    let length2 = axis.length_squared();
    let t = if length2 > 0.0 {
        ((p - a).dot(axis) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let nearest = a + axis * t;
    let offset = p - nearest;
    let dist = offset.length();
    if dist <= f64::from(ON_SURFACE) {
        return None;
    }
    let normal = offset / dist;
    let radius = f64::from(radius);
    finite(Contact {
        point: (nearest + normal * radius).as_vec3(),
        normal: normal.as_vec3(),
        signed_distance: (dist - radius) as f32,
    })
}

/// A cylinder along its own y axis, analytically, in double precision:
/// outside, the nearest point of its side, of a cap, or of a rim; inside,
/// of the nearer of the side and the caps (the cap of equals). `None` for
/// a point on the axis nearer the side than the caps, whose normal is any
/// direction across the axis (parry's projection then picks one).
#[inline]
fn cylinder_contact(
    (half_height, radius): (f32, f32),
    pose: &PoseF64,
    point: Vector,
) -> Option<Contact> {
    let local = local_f64(pose, point);
    let (h, r) = (f64::from(half_height), f64::from(radius));
    let rho = (local.x * local.x + local.z * local.z).sqrt();
    let (beyond_side, beyond_cap) = (rho - r, local.y.abs() - h);
    let up = DVec3::new(0.0, if local.y >= 0.0 { 1.0 } else { -1.0 }, 0.0);
    // Across the axis towards the point (none on the axis).
    let across =
        (rho > f64::from(ON_SURFACE)).then(|| DVec3::new(local.x / rho, 0.0, local.z / rho));
    let on_side = |across: DVec3| across * r + DVec3::new(0.0, local.y, 0.0);
    let on_cap = DVec3::new(local.x, up.y * h, local.z);
    if beyond_side > 0.0 && beyond_cap > 0.0 {
        // Beyond a rim: its nearest point.
        let rim = across? * r + up * h;
        let offset = local - rim;
        let dist = offset.length();
        return to_world(pose, rim, offset / dist, dist);
    }
    if beyond_cap >= beyond_side {
        to_world(pose, on_cap, up, beyond_cap)
    } else {
        let across = across?;
        to_world(pose, on_side(across), across, beyond_side)
    }
}

/// The point of heightfield `field` nearest `local` (its frame), as
/// parry's projection finds it (a box around the point, from the
/// distance to the field's bounds plus a cell, four times wider until the
/// nearest point in it lies within it; unsigned), each triangle's nearest
/// point found directly ([`Nearest`]): parry's triangle projection, with its features'
/// bookkeeping, was a third of a cloth's frame on terrain (fortieth
/// session, BENCHMARKS.md).
fn field_projection(field: &HeightField, local: Vector) -> PointProjection {
    let root = field.root_aabb();
    let cell = field.cell_width().max(field.cell_height());
    let farthest = (local - root.center()).length() + root.extents().length();
    let to_bounds = (local - local.clamp(root.mins, root.maxs)).length();
    let mut reach = (to_bounds + cell).max(farthest * 1.0e-4);
    loop {
        let wide = reach >= farthest;
        let reach_now = reach.min(farthest);
        let region = Aabb::new(
            local - Vector::splat(reach_now),
            local + Vector::splat(reach_now),
        );
        let mut nearest = Nearest::new();
        field.map_elements_in_local_aabb(&region, &mut |t, tri| {
            nearest.consider(local, t, Some([tri.a, tri.b, tri.c]));
        });
        let best = nearest.best;
        if best.0 <= reach_now * reach_now || (wide && best.0.is_finite()) {
            return PointProjection::new(false, best.1);
        }
        if wide || !reach.is_finite() {
            // No triangle at all (every cell removed), or a point that is
            // not finite: the point itself, as parry answers.
            return PointProjection::new(false, local);
        }
        reach *= 4.0;
    }
}

/// The nearest point to a point among triangles considered one by one
/// (a heightfield's for the stage, a mesh's for the lanes' planes), in
/// any order: of equals, the triangle of least index (the answer does not
/// depend on the order or the number of those considered).
pub(crate) struct Nearest {
    /// Its squared distance (m², infinite before any) and the point (m).
    pub(crate) best: (f32, Vector),
    /// Its triangle.
    triangle: u32,
}

impl Nearest {
    pub(crate) fn new() -> Nearest {
        Nearest {
            best: (f32::INFINITY, Vector::ZERO),
            triangle: u32::MAX,
        }
    }

    /// Considers triangle `t` (its `corners`, none for a removed cell)
    /// for `p` (m, the triangles' frame).
    #[inline(always)]
    pub(crate) fn consider(&mut self, p: Vector, t: u32, corners: Option<[Vector; 3]>) {
        let Some([a, b, c]) = corners else {
            return;
        };
        // The box around the triangle is no farther than the triangle:
        // a triangle whose box is farther than the best is passed over
        // (most of them once the one under the point is found).
        let outside = (a.min(b).min(c) - p).max(p - a.max(b).max(c));
        if outside.max(Vector::ZERO).length_squared() > self.best.0 {
            return;
        }
        let q = nearest_on_triangle(p, (a, b, c));
        let d2 = (p - q).length_squared();
        if d2 < self.best.0 || (d2 == self.best.0 && t < self.triangle) {
            (self.best, self.triangle) = ((d2, q), t);
        }
    }
}

/// The point of triangle `abc` nearest `p` (Ericson, Real-Time Collision
/// Detection, 5.1.5: by the Voronoi regions of its corners, edges and
/// face).
#[inline(always)]
pub(crate) fn nearest_on_triangle(p: Vector, (a, b, c): (Vector, Vector, Vector)) -> Vector {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    if !denom.is_finite() {
        // A triangle of no area: the nearest of its edges' points.
        return [(a, b), (b, c), (c, a)]
            .map(|(u, v)| {
                let e = v - u;
                let t = ((p - u).dot(e) / e.length_squared()).clamp(0.0, 1.0);
                if t.is_finite() {
                    u + e * t
                } else {
                    u
                }
            })
            .into_iter()
            .min_by(|x, y| {
                (p - *x)
                    .length_squared()
                    .total_cmp(&(p - *y).length_squared())
            })
            .unwrap_or(a);
    }
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Outward normal at a local point lying on the surface.
fn surface_normal(shape: &dyn Shape, local: Vector) -> Option<Vector> {
    use parry3d::shape::ShapeType;
    // Some shapes (heightfields, rounded shapes) do not report features.
    let reports_features = matches!(
        shape.shape_type(),
        ShapeType::Capsule
            | ShapeType::Cylinder
            | ShapeType::Cone
            | ShapeType::ConvexPolyhedron
            | ShapeType::Triangle
            | ShapeType::TriMesh
    );
    if reports_features {
        let (proj, feature) = shape.project_local_point_and_get_feature(local);
        if let Some(n) = shape.feature_normal_at_point(0, feature, proj.point) {
            if let Some(n) = n.try_normalize() {
                return Some(n);
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rotation;
    use parry3d::query::PointQuery;
    use parry3d::shape::{Capsule, Cuboid};

    /// `ours` at `p` is parry's contact: the same distance and surface
    /// point within 10 µm, the same normal a millimetre or more from the
    /// surface.
    fn assert_same_contact(p: Vector, ours: &Contact, parry: &Contact) {
        let d = (ours.signed_distance - parry.signed_distance).abs();
        assert!(d < 1e-5, "{p}: {ours:?} against {parry:?}");
        assert!((ours.point - parry.point).length() < 1e-5, "{p}");
        if parry.signed_distance.abs() > 1e-3 {
            assert!(ours.normal.dot(parry.normal) > 0.9999, "{p}");
        }
    }

    #[test]
    fn cuboid_contacts_match_parry_laid_along_the_axes_or_turned() {
        let cuboid = Cuboid::new(Vector::new(0.5, 0.3, 0.4));
        let centre = Vector::new(0.2, -0.1, 0.3);
        let turns = [Rotation::IDENTITY, Rotation::from_rotation_z(0.4)];
        let mut checked = 0;
        for rotation in turns {
            let pose = Pose::from_parts(centre, rotation);
            let prepared = PoseF64::of(&pose);
            assert_eq!(prepared.turned, rotation != Rotation::IDENTITY);
            for i in 0..7 {
                for j in 0..7 {
                    for k in 0..7 {
                        // Points inside, outside, near faces, edges and corners.
                        let local =
                            Vector::new(i as f32 - 3.0, j as f32 - 3.0, k as f32 - 3.0) * 0.21;
                        let p = pose.transform_point(local);
                        let ours = cuboid_contact(cuboid.half_extents, &prepared, p).unwrap();
                        let parry = general_contact(&cuboid, &pose, p).unwrap();
                        assert_same_contact(p, &ours, &parry);
                        checked += 1;
                    }
                }
            }
        }
        assert_eq!(checked, 2 * 343);
    }

    #[test]
    fn cylinder_contacts_match_parry_inside_outside_and_at_the_rims() {
        let cylinder = parry3d::shape::Cylinder::new(0.3, 0.4);
        let pose = Pose::from_parts(Vector::new(0.3, 1.0, -0.2), Rotation::from_rotation_x(0.7));
        let shape: &dyn Shape = &cylinder;
        assert!(matches!(Analytic::of(shape), Analytic::Cylinder(..)));
        let prepared = PoseF64::placing(&pose, Analytic::of(shape));
        let (mut inside, mut outside, mut rims) = (0, 0, 0);
        for i in 0..9 {
            for j in 0..9 {
                for k in 0..9 {
                    let local =
                        Vector::new(i as f32 - 4.0, j as f32 - 4.0, k as f32 - 4.0) * 0.13 + 0.01;
                    let p = pose.transform_point(local);
                    let ours = contact(shape, &pose, p).unwrap();
                    let parry = general_contact(shape, &pose, p).unwrap();
                    assert_same_contact(p, &ours, &parry);
                    let rho = (local.x * local.x + local.z * local.z).sqrt();
                    rims += usize::from(rho > 0.4 && local.y.abs() > 0.3);
                    if parry.signed_distance < 0.0 {
                        inside += 1;
                    } else {
                        outside += 1;
                    }
                }
            }
        }
        assert!(
            inside > 20 && outside > 300 && rims > 100,
            "{inside} inside, {outside} outside, {rims} beyond a rim"
        );
        assert!(cylinder_contact((0.3, 0.4), &prepared, pose.translation).is_some());
        // On the axis of a slender one, nearer the side than the caps:
        // parry's answer.
        let slender = parry3d::shape::Cylinder::new(0.5, 0.2);
        let on_axis = pose.transform_point(Vector::new(0.0, 0.05, 0.0));
        assert!(cylinder_contact((0.5, 0.2), &prepared, on_axis).is_none());
        let hit = contact(&slender, &pose, on_axis).unwrap();
        assert!((hit.signed_distance + 0.2).abs() < 1e-5, "{hit:?}");
    }

    #[test]
    fn capsule_contacts_match_parry_inside_outside_and_at_the_caps() {
        let capsule = Capsule::new(
            Vector::new(-0.1, -0.4, 0.0),
            Vector::new(0.1, 0.5, 0.05),
            0.2,
        );
        let pose = Pose::from_parts(Vector::new(0.3, 1.0, -0.2), Rotation::from_rotation_x(1.2));
        let shape: &dyn Shape = &capsule;
        assert!(matches!(Analytic::of(shape), Analytic::Capsule(..)));
        let prepared = PoseF64::placing(&pose, Analytic::of(shape));
        let (mut inside, mut outside) = (0, 0);
        for i in 0..7 {
            for j in 0..9 {
                for k in 0..7 {
                    let local = Vector::new(i as f32 - 3.0, j as f32 - 4.0, k as f32 - 3.0) * 0.13;
                    let p = pose.transform_point(local);
                    let ours = contact(shape, &pose, p).unwrap();
                    let parry = general_contact(shape, &pose, p).unwrap();
                    assert_same_contact(p, &ours, &parry);
                    if parry.signed_distance < 0.0 {
                        inside += 1;
                    } else {
                        outside += 1;
                    }
                }
            }
        }
        assert!(
            inside > 10 && outside > 100,
            "{inside} inside, {outside} outside"
        );
        // On the segment itself: parry's answer.
        let on_axis = pose.transform_point(Vector::new(0.0, 0.05, 0.025));
        assert!(capsule_contact(0.2, &prepared, on_axis).is_none());
        let hit = contact(shape, &pose, on_axis).unwrap();
        assert!((hit.signed_distance + 0.2).abs() < 1e-5, "{hit:?}");
    }

    /// A heightfield's contact (its projection found by
    /// `field_projection`) is parry's, above it, below it, beyond its
    /// border and far off; and a point that is not finite has none.
    #[test]
    fn heightfield_contacts_match_parry_above_below_and_beyond() {
        let heights: Vec<f32> = (0..9 * 7)
            .map(|k| 0.4 * ((k % 9) as f32 * 1.1).sin() * ((k / 9) as f32 * 0.8).cos())
            .collect();
        let field = HeightField::new(
            parry3d::utils::Array2::new(9, 7, heights),
            Vector::new(1.2, 1.5, 0.8),
        );
        let pose = Pose::from_parts(Vector::new(0.1, 0.5, -0.2), Rotation::from_rotation_z(0.3));
        let mut checked = 0;
        for i in 0..11 {
            for j in 0..9 {
                for k in 0..11 {
                    let local = Vector::new(i as f32 - 5.0, j as f32 - 4.0, k as f32 - 5.0)
                        * Vector::new(0.15, 0.25, 0.1);
                    let p = pose.transform_point(local);
                    let ours = contact(&field, &pose, p).unwrap();
                    let proj = field.project_local_point(pose.inverse_transform_point(p), false);
                    let offset = pose.inverse_transform_point(p) - proj.point;
                    let parry = Contact {
                        point: pose.transform_point(proj.point),
                        normal: pose.transform_vector(offset.normalize()),
                        signed_distance: offset.length(),
                    };
                    assert_same_contact(p, &ours, &parry);
                    checked += 1;
                }
            }
        }
        // Far off: found by the widened search.
        let far = Vector::new(30.0, 20.0, -10.0);
        let ours = contact(&field, &pose, far).unwrap();
        let proj = field.project_local_point(pose.inverse_transform_point(far), false);
        assert!((ours.point - pose.transform_point(proj.point)).length() < 1e-4);
        assert!(checked == 11 * 9 * 11);
        assert!(contact(&field, &pose, Vector::NAN).is_none());
    }
}
