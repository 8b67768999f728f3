//! The still convex shapes other than balls, capsules, half-spaces and
//! cuboids (cylinders, cones, convex hulls) as the small-steps solver's
//! lanes hold them (`lane_contacts`): as a cuboid, each takes a slot of
//! the lanes' plane records, and each lane, once a substep, the tangent
//! plane of the shape at the point nearest where the lane starts the
//! substep, moved out by the thickness. A convex shape lies behind each of
//! its tangent planes, so a lane put back onto its plane is outside it.
//! A cylinder's planes are its own (single precision), a hull's its
//! faces' where the nearest point is on one, any other's (and a hull's
//! near its edges) the collision stage's contact. Before the lanes held
//! them, a round table (two cylinders) sent the collision stage after
//! each of the edge rule's 32 substeps: 25–29 ms a frame at 64², 4.3–5.3
//! since (thirty-ninth session, BENCHMARKS.md).

use parry3d::shape::{ConvexPolyhedron, Shape};

use crate::collision::contact::{contact_prepared, Analytic, PoseF64};
use crate::collision::Obstacle;
use crate::math::{Pose, Vector};

/// A still convex shape other than a ball, capsule, half-space or cuboid
/// as the lanes take it (`StillShape::Convex`): as a cuboid, a lane is
/// held by the tangent plane of the shape (rounded by the thickness) at
/// the point nearest to where it started the substep, when it started
/// within `reach` (m) of the shape. The plane is found once a substep by
/// the collision stage's contact ([`crate::collision::contact()`]), for the lanes
/// that start inside the box (m) around the shape and its reach only. A
/// cylinder (a round table, a pole) or a cone went to the collision
/// stage after every substep before: 70% of a frame of 32 substeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StillConvex {
    /// The obstacle's index among the substep's, and the shape's among
    /// its compound's parts (none for the obstacle's whole shape).
    pub(super) obstacle: usize,
    pub(super) part: Option<usize>,
    /// The box (m) a lane that starts within reach of the shape lies in.
    lo: Vector,
    hi: Vector,
    thickness: f32,
    reach: f32,
    /// How far (m) within the thickness a lane may start and still be
    /// put out to it (as a cuboid's, `lane_contacts::SETTLE_SHARE`).
    settle: f32,
    /// Which of the lanes' plane records is this shape's.
    pub(super) slot: usize,
    /// A cylinder's own, found without the stage's contact.
    pub(super) cylinder: Option<StillCylinder>,
    /// A convex hull's faces in [`HullFaces`] (a range of them).
    pub(super) hull: Option<(u32, u32)>,
}

/// No plane: an offset of −∞ (every point in front of it).
pub(super) const NONE: ([f32; 3], f32) = ([0.0; 3], f32::NEG_INFINITY);

impl StillConvex {
    /// How far (m) from the shape a lane may start and be held.
    #[inline(always)]
    pub(super) fn reach(&self) -> f32 {
        self.reach
    }

    /// Whether `s` (m) is in the box a lane within reach of the shape
    /// starts in.
    #[inline(always)]
    pub(super) fn boxes(&self, s: Vector) -> bool {
        s.cmpge(self.lo).all() && s.cmple(self.hi).all()
    }

    /// The plane that holds a lane starting at `s` (m) whose nearest point
    /// of the shape lies on the plane `normal · x = surface` (unit normal,
    /// m), `signed` (m, negative inside) from it: that plane moved out by
    /// the thickness when `s` is within reach, held where `s` is along the
    /// normal when it starts deep within the thickness (as a cuboid's,
    /// `lane_contacts::cuboid_plane`), none beyond reach.
    #[inline(always)]
    pub(super) fn plane(
        &self,
        s: Vector,
        (normal, surface, signed): (Vector, f32, f32),
    ) -> ([f32; 3], f32) {
        if signed.is_nan() || signed >= self.reach {
            return NONE;
        }
        let offset = surface + self.thickness;
        let from = normal.dot(s);
        let offset = if from < offset - self.settle {
            from
        } else {
            offset
        };
        (normal.to_array(), offset)
    }

    /// The still convex `shape` at `pose` (obstacle `index` of the
    /// substep's, or its compound's `part`; its planes in record `slot`)
    /// for lanes within `thickness` (m) of it, moving at most `motion` (m)
    /// in the substep, held to the thickness from `settle` (m) within it;
    /// a hull's faces go to `hulls`.
    pub(super) fn new(
        (shape, pose): (&dyn Shape, &Pose),
        (index, part, slot): (usize, Option<usize>, usize),
        (thickness, motion, settle): (f32, f32, f32),
        hulls: &mut HullFaces,
    ) -> StillConvex {
        // As the cuboid's: within twice the thickness and twice the
        // substep's motion.
        let reach = 2.0 * (thickness + motion);
        let pad = Vector::splat(reach);
        let aabb = shape.compute_aabb(pose);
        let cylinder = shape.as_cylinder().map(|c| StillCylinder {
            centre: pose.translation,
            axis: (pose.rotation * Vector::Y).normalize(),
            half_height: c.half_height,
            radius: c.radius,
        });
        let hull = shape
            .as_convex_polyhedron()
            .and_then(|hull| hulls.add(hull, pose));
        StillConvex {
            obstacle: index,
            part,
            lo: aabb.mins - pad,
            hi: aabb.maxs + pad,
            thickness,
            reach,
            settle,
            slot,
            cylinder,
            hull,
        }
    }
}

/// The faces of the still convex hulls the lanes hold, in the world, found at
/// [`LaneContacts::begin_holding`](super::lane_contacts::LaneContacts::begin_holding):
/// a lane whose start projects onto the face it is farthest beyond (or is
/// inside the hull) takes that face's plane, without parry's projection on a
/// support map (iterative, and inside the hull by its expanding polytope): a
/// cloth on a hull's faces took 5 times a cuboid's time a frame so.
#[derive(Debug, Default)]
pub(super) struct HullFaces {
    /// Per face: outward unit normal and offset (m; the face lies in
    /// `normal · x = offset`).
    normal: Vec<Vector>,
    offset: Vec<f32>,
    /// Per face: the range of its edges.
    edges: Vec<(u32, u32)>,
    /// Per edge of a face: the unit vector in the face's plane square to
    /// the edge, into the face, and its offset (m): a point of the plane
    /// lies in the face where `edge_normal · x ≥ edge_offset` for all its
    /// edges.
    edge_normal: Vec<Vector>,
    edge_offset: Vec<f32>,
}

impl HullFaces {
    /// Forgets every hull.
    pub(super) fn clear(&mut self) {
        self.normal.clear();
        self.offset.clear();
        self.edges.clear();
        self.edge_normal.clear();
        self.edge_offset.clear();
    }

    /// Adds the faces of `hull` placed at `pose`; returns their range, or
    /// none for a hull with a face of fewer than three corners or of no
    /// area (its lanes' planes then all come from the stage's contact).
    fn add(&mut self, hull: &ConvexPolyhedron, pose: &Pose) -> Option<(u32, u32)> {
        let (first, first_edge) = (self.normal.len(), self.edge_normal.len());
        let points = hull.points();
        let adjacent = hull.vertices_adj_to_face();
        for face in hull.faces() {
            let range = face.first_vertex_or_edge as usize
                ..(face.first_vertex_or_edge + face.num_vertices_or_edges) as usize;
            let Some(corners) = adjacent.get(range) else {
                self.truncate(first, first_edge);
                return None;
            };
            let corner =
                |k: usize| pose.transform_point(points[corners[k % corners.len()] as usize]);
            let normal = (pose.rotation * face.normal).normalize();
            if corners.len() < 3 || !normal.is_finite() {
                self.truncate(first, first_edge);
                return None;
            }
            // Which way the corners turn about the normal.
            let turn = (0..corners.len())
                .map(|k| {
                    (corner(k + 1) - corner(k))
                        .cross(corner(k + 2) - corner(k + 1))
                        .dot(normal)
                })
                .sum::<f32>()
                .signum();
            let edges = self.edge_normal.len() as u32;
            for k in 0..corners.len() {
                let (a, b) = (corner(k), corner(k + 1));
                let inward = (normal.cross(b - a) * turn).normalize();
                if !inward.is_finite() || turn == 0.0 {
                    self.truncate(first, first_edge);
                    return None;
                }
                self.edge_normal.push(inward);
                self.edge_offset.push(inward.dot(a));
            }
            self.normal.push(normal);
            self.offset.push(normal.dot(corner(0)));
            self.edges.push((edges, self.edge_normal.len() as u32));
        }
        Some((first as u32, self.normal.len() as u32))
    }

    /// Back to `faces` faces and `edges` edges.
    fn truncate(&mut self, faces: usize, edges: usize) {
        self.normal.truncate(faces);
        self.offset.truncate(faces);
        self.edges.truncate(faces);
        self.edge_normal.truncate(edges);
        self.edge_offset.truncate(edges);
    }

    /// For a point `s` (m): the face of `faces` it is farthest beyond
    /// (least far inside), as its outward normal, its offset and how far
    /// beyond it `s` is (m, negative inside), when that face's plane holds
    /// the point of the hull nearest `s`: `s` inside the hull, or its
    /// projection onto the face within the face. Otherwise none (`s`
    /// nearest an edge or a corner).
    #[inline]
    pub(super) fn nearest_face(
        &self,
        (first, end): (u32, u32),
        s: Vector,
    ) -> Option<(Vector, f32, f32)> {
        let (mut best, mut beyond) = (first as usize, f32::NEG_INFINITY);
        for f in first as usize..end as usize {
            let d = self.normal[f].dot(s) - self.offset[f];
            if d > beyond {
                (best, beyond) = (f, d);
            }
        }
        if beyond > 0.0 {
            let q = s - self.normal[best] * beyond;
            let (a, b) = self.edges[best];
            for e in a as usize..b as usize {
                if self.edge_normal[e].dot(q) < self.edge_offset[e] - 1.0e-6 {
                    return None;
                }
            }
        }
        Some((self.normal[best], self.offset[best], beyond))
    }
}

/// A still cylinder as [`cylinder_plane`] takes it: centre (m), the unit
/// vector along its axis, half height and radius (m). Its planes in single
/// precision, without a rotation there and back: the round table's planes
/// through the stage's contact (double precision) were 40% of its frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StillCylinder {
    centre: Vector,
    axis: Vector,
    half_height: f32,
    radius: f32,
}

/// The plane (unit normal, offset in m) that holds a lane starting the
/// substep at `start` (m) against the convex shape of `obstacle`, as
/// `lane_contacts::cuboid_plane` takes a cuboid's: the tangent plane of the shape
/// rounded by the thickness at the point nearest to `start` (the
/// collision stage's contact: a cylinder's analytic, any other shape's
/// through parry's projection), when `start` is within the shape's reach; otherwise none
/// (an offset of −∞). The shape is convex: a lane on its plane's side is
/// outside it.
#[inline(always)]
pub(super) fn convex_plane(
    convex: &StillConvex,
    (shape, analytic, pose): (&dyn Shape, Analytic, &PoseF64),
    start: [f32; 3],
) -> ([f32; 3], f32) {
    let s = Vector::from(start);
    if !convex.boxes(s) {
        return NONE;
    }
    let Some(hit) = contact_prepared(shape, analytic, pose, s) else {
        return NONE;
    };
    convex.plane(
        s,
        (hit.normal, hit.normal.dot(hit.point), hit.signed_distance),
    )
}

/// [`convex_plane`] of a cylinder, in single precision: the tangent plane
/// at the nearest point of its side, of a cap or of a rim (inside, of the
/// nearer of side and caps, as the stage's contact takes it), moved out
/// by the thickness. A lane on the axis nearer the side than the caps
/// (deep inside: held where it starts) goes out along any direction
/// across the axis.
#[inline(always)]
pub(super) fn cylinder_plane(
    convex: &StillConvex,
    c: &StillCylinder,
    start: [f32; 3],
) -> ([f32; 3], f32) {
    let s = Vector::from(start);
    if !convex.boxes(s) {
        return NONE;
    }
    let d = s - c.centre;
    let along = d.dot(c.axis);
    let radial = d - c.axis * along;
    let rho = radial.length();
    let across = if rho > 1.0e-6 {
        radial / rho
    } else {
        c.axis.any_orthonormal_vector()
    };
    let up = if along >= 0.0 { c.axis } else { -c.axis };
    let (beyond_side, beyond_cap) = (rho - c.radius, along.abs() - c.half_height);
    let (normal, surface, signed) = if beyond_side > 0.0 && beyond_cap > 0.0 {
        let rim = c.centre + across * c.radius + up * c.half_height;
        let offset = s - rim;
        let dist = offset.length();
        (offset / dist, rim, dist)
    } else if beyond_cap >= beyond_side {
        (up, c.centre + up * c.half_height, beyond_cap)
    } else {
        (across, c.centre + across * c.radius, beyond_side)
    };
    if !normal.is_finite() {
        return NONE;
    }
    convex.plane(s, (normal, normal.dot(surface), signed))
}

/// [`convex_plane`] of a convex hull from its faces ([`HullFaces`]): the
/// plane of the face that holds the point nearest `start`, moved out by
/// the thickness; `None` for a start nearest an edge or a corner (the
/// stage's contact then finds it).
#[inline(always)]
pub(super) fn hull_plane(
    convex: &StillConvex,
    (hulls, faces): (&HullFaces, (u32, u32)),
    start: [f32; 3],
) -> Option<([f32; 3], f32)> {
    let s = Vector::from(start);
    if !convex.boxes(s) {
        return Some(NONE);
    }
    Some(convex.plane(s, hulls.nearest_face(faces, s)?))
}

/// The planes of the convex shape of `obstacle` ([`convex_plane`]) for
/// lanes starting at `start`, into `out` (normal x, y, z, offset).
pub(super) fn convex_planes_of(
    convex: &StillConvex,
    (obstacle, hulls): (&Obstacle, &HullFaces),
    start: [&[f32]; 3],
    out: &mut [&mut [f32]; 4],
) {
    let n = start[0].len();
    assert!(start.iter().all(|s| s.len() == n) && out.iter().all(|o| o.len() == n));
    // The shape's kind and pose read once (a downcast through `dyn Shape`):
    // the obstacle's, or its compound's part's.
    let part = convex
        .part
        .and_then(|k| obstacle.shape.as_compound()?.shapes().get(k));
    let (shape, placed): (&dyn Shape, Pose) = match part {
        Some((pose, part)) => (&**part, obstacle.pose * *pose),
        None => (&*obstacle.shape, obstacle.pose),
    };
    let analytic = Analytic::of(shape);
    let pose = PoseF64::placing(&placed, analytic);
    for k in 0..n {
        let start = [start[0][k], start[1][k], start[2][k]];
        let face = || {
            convex
                .hull
                .and_then(|faces| hull_plane(convex, (hulls, faces), start))
        };
        let (normal, offset) = match &convex.cylinder {
            Some(cylinder) => cylinder_plane(convex, cylinder, start),
            None => face().unwrap_or_else(|| convex_plane(convex, (shape, analytic, &pose), start)),
        };
        for a in 0..3 {
            out[a][k] = normal[a];
        }
        out[3][k] = offset;
    }
}
