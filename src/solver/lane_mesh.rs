//! Still triangle meshes (a table imported as a model, a floor of level
//! geometry) and heightfields (terrain) as the small-steps solver's lanes
//! hold them (`lane_contacts`): as a convex shape is held
//! (`lane_convex.rs`), each lane, once a substep, takes the plane through
//! the point of the mesh nearest where it starts the substep, square to
//! the line from there to the start, moved out by the thickness. A mesh
//! is a surface without an inside (parry's projection of a mesh without
//! pseudo-normals, or of a heightfield, says no point is inside): the
//! plane faces the side the lane starts on, and holds it on that side for
//! the substep, as the collision stage's contact does. Before the lanes
//! held meshes, a cloth on a mesh sent the collision stage after each of
//! the edge rule's 32 substeps, where parry searched its tree of the
//! triangles from the root for every particle: a 64² tablecloth on a box
//! of 12 triangles took 59 ms a frame (13 times the same box as a
//! cuboid), on hilly terrain 340 ms.
//!
//! The search is paid once for many substeps: each lane keeps the
//! triangles within a radius of where it was when it last searched (up to
//! [`LISTED`]), and searches again only when it has moved so far that a
//! triangle within reach could lie outside that radius. The nearest point
//! among the listed triangles is then the nearest of the whole mesh
//! whenever one is within reach: the same planes as a search of every
//! triangle. A crowded lane (more than [`LISTED`] triangles near: a
//! finely cut rim) searches the tree within its reach every substep; a
//! lane on the surface takes the collision stage's contact.
//!
//! And most lanes need no triangle at all: a lane whose nearest point was
//! inside a triangle keeps that face's plane while it moves less than
//! what would let its projection leave the face or another triangle come
//! nearer ([`face_hold`]). A 64² tablecloth on that box: 59 → 8–10 ms a
//! frame, 91% of its planes from the face kept (fortieth session,
//! BENCHMARKS.md).
//!
//! The lists and kept faces are scratch, so the planes must not depend on
//! them: the search answers by a rule of the lane's start alone (the face
//! of least index that holds its projection and is as near as the
//! nearest, [`Face`]; else the nearest point, of the triangle of least
//! index among equals, [`Nearest`]), and a kept face gives the same bits
//! while it is kept, a hair inside its guards ([`BOUNDARY`]). A solver
//! restored from a snapshot, with fresh lists, moves the cloth the same.
//!
//! A mesh can be concave, where a tangent plane of one part may cut
//! another: a lane in an inner corner is held by the nearer of the two
//! faces each substep, the farther one holds it as soon as it is the
//! nearer, and the collision stage's exact pass at the step's last
//! substep answers for the rest.

use parry3d::bounding_volume::Aabb;
use parry3d::shape::{HeightField, Shape, TriMesh};

use super::lane_convex::{convex_plane, HullFaces, StillConvex, NONE};
use crate::collision::contact::{nearest_on_triangle, Analytic, Nearest, PoseF64};
use crate::collision::Obstacle;
use crate::math::{Pose, Vector};
use crate::parallel::Disjoint;

/// The most triangles a lane's list holds; a lane with more near it
/// searches the mesh's tree every substep.
pub(super) const LISTED: usize = 24;

/// A lane's count when it has no list yet.
const UNLISTED: u8 = u8::MAX;
/// A lane's count when more than [`LISTED`] triangles were near it.
const CROWDED: u8 = u8::MAX - 1;

/// How far out a lane's list reaches, in the lane's reach: the lane then
/// moves a reach before it searches again (several substeps of motion).
const LIST_REACHES: f32 = 2.0;

/// Below this distance (m) from the mesh a lane is on its surface, where
/// the line to the nearest point gives no normal: the collision stage's
/// contact answers (as for `collision::contact`'s own threshold).
const ON_SURFACE: f32 = 1.0e-6;

/// A still triangle mesh as the lanes hold it ([`super::lane_contacts`]):
/// a lane within reach is held by the plane through the mesh's point
/// nearest where it starts the substep, by the rule of a convex shape's
/// planes (`held`: its box, reach, thickness and plane slot), from the
/// triangles of the lane's list `lists`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StillMesh {
    pub(super) held: StillConvex,
    /// The mesh's pose: the lanes' starts go into its frame.
    pose: Pose,
    /// Which of [`MeshLists`]' lists is this mesh's.
    pub(super) list: usize,
}

impl StillMesh {
    /// The still mesh `shape` at `pose` (obstacle `index`, or its
    /// compound's `part`; its planes in record `slot`) for lanes within
    /// `thickness` (m) of it, moving at most `motion` (m) in the
    /// substep, held to the thickness from `settle` (m) within it; its
    /// lanes' triangles in list `list`.
    pub(super) fn new(
        (shape, pose): (&dyn Shape, &Pose),
        (index, part, slot, list): (usize, Option<usize>, usize, usize),
        (thickness, motion, settle): (f32, f32, f32),
    ) -> StillMesh {
        // No hull among a mesh's pieces: the faces stay empty.
        let mut no_hulls = HullFaces::default();
        StillMesh {
            held: StillConvex::new(
                (shape, pose),
                (index, part, slot),
                (thickness, motion, settle),
                &mut no_hulls,
            ),
            pose: *pose,
            list,
        }
    }
}

/// Whether the lanes may hold `shape` as a mesh ([`Surface::of`]).
pub(super) fn is_held_mesh(shape: &dyn Shape) -> bool {
    Surface::of(shape).is_some()
}

/// The triangles of a shape the lanes hold as a mesh.
#[derive(Clone, Copy)]
pub(super) enum Surface<'a> {
    /// A triangle mesh; its triangles by index.
    Mesh(&'a TriMesh),
    /// A heightfield (terrain); its triangles by parry's id (two a cell,
    /// none in a removed cell).
    Field(&'a HeightField),
}

impl<'a> Surface<'a> {
    /// `shape` as a surface without an inside, whose contact (parry's
    /// projection) is unsigned: a triangle mesh without pseudo-normals
    /// (as `SharedShape::trimesh` and rapier's `ColliderBuilder::trimesh`
    /// make them), or a heightfield. An oriented mesh has an inside,
    /// which a lane's plane from the nearest point would not know.
    pub(super) fn of(shape: &'a dyn Shape) -> Option<Surface<'a>> {
        if let Some(mesh) = shape.as_trimesh() {
            return mesh
                .pseudo_normals_if_oriented()
                .is_none()
                .then_some(Surface::Mesh(mesh));
        }
        shape.as_heightfield().map(Surface::Field)
    }

    /// The corners (m, the shape's frame) of triangle `t`.
    #[inline(always)]
    fn corners(self, t: u32) -> Option<[Vector; 3]> {
        match self {
            Surface::Mesh(mesh) => {
                let vertices = mesh.vertices();
                Some(
                    mesh.indices()
                        .get(t as usize)?
                        .map(|i| vertices[i as usize]),
                )
            }
            Surface::Field(field) => field.triangle_at_id(t).map(|tri| [tri.a, tri.b, tri.c]),
        }
    }

    /// Calls `f` with each triangle whose box meets `region` (the shape's
    /// frame), and perhaps a few more.
    fn each_near(self, region: &Aabb, mut f: impl FnMut(u32)) {
        match self {
            Surface::Mesh(mesh) => mesh.bvh().intersect_aabb(region).for_each(f),
            Surface::Field(field) => field.map_elements_in_local_aabb(region, &mut |t, _| f(t)),
        }
    }

    /// What tells this surface from another: its address and its count
    /// of triangles (or cells).
    fn identity(self) -> (usize, usize) {
        match self {
            Surface::Mesh(mesh) => (mesh as *const TriMesh as usize, mesh.num_triangles()),
            Surface::Field(field) => {
                let (i, j) = field.num_cells_ij();
                (field as *const HeightField as usize, i * j)
            }
        }
    }
}

/// Per still mesh the lanes hold, per lane: the triangles near where the
/// lane was when it last searched the mesh. Kept from substep to substep
/// and step to step while the mesh is the same one in the same place.
#[derive(Debug, Default)]
pub(super) struct MeshLists {
    lists: Vec<MeshList>,
    /// Lists taken this substep.
    used: usize,
}

/// One mesh's lists ([`MeshLists`]).
#[derive(Debug, Default)]
struct MeshList {
    /// What the lists are of: the lists are searched again when it changes.
    of: Option<ListKey>,
    /// Per lane: its search and its face ([`LaneList`]).
    lanes: Vec<LaneList>,
    /// Per lane, [`LISTED`] places: the triangles listed.
    triangles: Vec<u32>,
}

/// A lane's list of triangles and the face that held it. One record a
/// lane (not an array a field): the lane's pass reads all of it, one lane
/// at a time.
#[derive(Debug, Clone, Copy)]
struct LaneList {
    /// Where (m, in the world) the lane searched, and how far (m) from
    /// there every triangle is listed.
    anchor: Vector,
    radius: f32,
    /// Where (m) the lane was when its plane was last found from the
    /// triangles, and how far (m) from there it may move with that plane
    /// still a face's: the face's plane (unit normal, offset of the
    /// surface in m) holds it as long as it moves less ([`face_hold`]).
    at: Vector,
    valid: f32,
    normal: Vector,
    surface: f32,
    /// How many triangles are listed ([`UNLISTED`], [`CROWDED`]).
    count: u8,
}

impl Default for LaneList {
    fn default() -> Self {
        LaneList {
            anchor: Vector::ZERO,
            radius: 0.0,
            at: Vector::ZERO,
            valid: -1.0,
            normal: Vector::ZERO,
            surface: 0.0,
            count: UNLISTED,
        }
    }
}

/// The mesh a list is of: obstacle, part, the shape's address and size,
/// its pose (bits), and the lanes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct ListKey {
    obstacle: usize,
    part: Option<usize>,
    shape: usize,
    triangles: usize,
    pose: [u32; 7],
    lanes: usize,
}

impl MeshLists {
    /// Forgets which lists were taken (at each substep's start); the
    /// lists themselves stay for the next.
    pub(super) fn begin(&mut self) {
        self.used = 0;
    }

    /// The next list, for `mesh` (`shape` at `pose`, obstacle `index`,
    /// part `part`) and `lanes` lanes: the one this place took last
    /// substep, searched again if it was of another mesh.
    pub(super) fn take(
        &mut self,
        (surface, pose): (Surface, &Pose),
        (index, part): (usize, Option<usize>),
        lanes: usize,
    ) -> usize {
        let (shape, triangles) = surface.identity();
        let key = ListKey {
            obstacle: index,
            part,
            shape,
            triangles,
            pose: pose_bits(pose),
            lanes,
        };
        if self.lists.len() <= self.used {
            self.lists.push(MeshList::default());
        }
        let list = &mut self.lists[self.used];
        if list.of != Some(key) {
            list.of = Some(key);
            list.lanes.clear();
            list.lanes.resize(lanes, LaneList::default());
            list.triangles.clear();
            list.triangles.resize(lanes * LISTED, 0);
        }
        self.used += 1;
        self.used - 1
    }

    /// List `list`'s arrays, to be shared among a pass's chunks of lanes.
    pub(super) fn shared(&mut self, list: usize) -> SharedList<'_> {
        let l = &mut self.lists[list];
        SharedList {
            lanes: Disjoint::new(&mut l.lanes[..]),
            triangles: Disjoint::new(&mut l.triangles[..]),
        }
    }
}

/// The bits of a pose, to tell a moved mesh.
fn pose_bits(pose: &Pose) -> [u32; 7] {
    let (t, r) = (pose.translation, pose.rotation);
    [t.x, t.y, t.z, r.x, r.y, r.z, r.w].map(f32::to_bits)
}

/// A mesh's lists as the chunks of a pass share them: each chunk takes
/// the range of its own lanes ([`SharedList::lanes`]).
pub(super) struct SharedList<'a> {
    lanes: Disjoint<'a, LaneList>,
    triangles: Disjoint<'a, u32>,
}

/// One chunk's lanes of a mesh's lists.
pub(super) struct ChunkList<'a> {
    lanes: &'a mut [LaneList],
    triangles: &'a mut [u32],
}

impl<'a> SharedList<'a> {
    /// The lists of lanes `range`.
    ///
    /// # Safety
    /// No two chunks may hold overlapping ranges at once.
    pub(super) unsafe fn lanes(&self, range: std::ops::Range<usize>) -> ChunkList<'a> {
        let listed = range.start * LISTED..range.end * LISTED;
        // SAFETY: the caller's promise, for both arrays alike.
        unsafe {
            ChunkList {
                lanes: self.lanes.range(range),
                triangles: self.triangles.range(listed),
            }
        }
    }
}

/// The planes of the still `mesh` (obstacle `obstacle`) for lanes
/// starting at `start` (m), into `out` (normal x, y, z, offset), from
/// and into the chunk's `lists`.
pub(super) fn mesh_planes_of(
    mesh: &StillMesh,
    obstacle: &Obstacle,
    lists: ChunkList,
    start: [&[f32]; 3],
    out: &mut [&mut [f32]; 4],
) {
    let n = start[0].len();
    assert!(start.iter().all(|s| s.len() == n) && out.iter().all(|o| o.len() == n));
    assert!(lists.lanes.len() == n && lists.triangles.len() == n * LISTED);
    let held = &mesh.held;
    let part = held
        .part
        .and_then(|k| obstacle.shape.as_compound()?.shapes().get(k));
    let shape: &dyn Shape = match part {
        Some((_, part)) => &**part,
        None => &*obstacle.shape,
    };
    let pose64 = PoseF64::placing(&mesh.pose, Analytic::Other);
    let through_stage =
        |s: Vector| convex_plane(held, (shape, Analytic::Other, &pose64), s.to_array());
    let Some(surface) = Surface::of(shape) else {
        // Not a mesh (`StillMesh` is made of meshes only): every lane
        // through the stage's contact.
        for k in 0..n {
            let s = Vector::new(start[0][k], start[1][k], start[2][k]);
            write(out, k, through_stage(s));
        }
        return;
    };
    let reach = held.reach();
    for k in 0..n {
        let s = Vector::new(start[0][k], start[1][k], start[2][k]);
        if !held.boxes(s) {
            write(out, k, NONE);
            continue;
        }
        let lane = &mut lists.lanes[k];
        // The face that held the lane last, while it has not moved so far
        // that another triangle could be nearer: a cloth lying on a mesh's
        // faces takes its planes so, without a triangle's test. The same
        // bits as the search below would give, so that the planes
        // do not depend on the lists (scratch): a solver restored from a
        // snapshot moves the same. A lane within a hair of the reach
        // searches, which decides it.
        if (s - lane.at).length() < lane.valid {
            let d = lane.normal.dot(s) - lane.surface;
            if (d - reach).abs() > BOUNDARY {
                let plane = if d < reach {
                    held.plane(s, (lane.normal, lane.surface, d))
                } else {
                    NONE
                };
                write(out, k, plane);
                continue;
            }
        }
        let local = mesh.pose.inverse_transform_point(s);
        let listed = lane.count != UNLISTED && (s - lane.anchor).length() + reach <= lane.radius;
        if !listed {
            let radius = LIST_REACHES * reach;
            let triangles = &mut lists.triangles[k * LISTED..(k + 1) * LISTED];
            lane.count = list_near(surface, local, radius, triangles);
            (lane.anchor, lane.radius) = (s, radius);
        }
        lane.valid = -1.0;
        let count = lane.count;
        let (nearest, face, triangles) = if count == CROWDED {
            // Too many to list: the triangles within reach, found now.
            let region = Aabb::new(local - Vector::splat(reach), local + Vector::splat(reach));
            let mut nearest = Nearest::new();
            // The triangles found kept for the face's pass (a second
            // search of the tree when there are more).
            let (mut found, mut count) = ([(0, None); 4 * LISTED], 0);
            surface.each_near(&region, |t| {
                let corners = surface.corners(t);
                nearest.consider(local, t, corners);
                if let Some(slot) = found.get_mut(count) {
                    *slot = (t, corners);
                }
                count += 1;
            });
            let mut face = Face::new(&nearest);
            if count <= found.len() {
                found[..count]
                    .iter()
                    .for_each(|&(t, c)| face.consider(local, t, c));
            } else {
                surface.each_near(&region, |t| face.consider(local, t, surface.corners(t)));
            }
            (nearest, face, None)
        } else {
            let triangles = &lists.triangles[k * LISTED..k * LISTED + count as usize];
            // Each triangle's corners once (a heightfield's are worked
            // out from its heights each time they are asked for).
            let mut corners = [None; LISTED];
            for (c, &t) in corners.iter_mut().zip(triangles) {
                *c = surface.corners(t);
            }
            let near = || triangles.iter().copied().zip(corners);
            let mut nearest = Nearest::new();
            near().for_each(|(t, c)| nearest.consider(local, t, c));
            let mut face = Face::new(&nearest);
            near().for_each(|(t, c)| face.consider(local, t, c));
            (nearest, face, Some((triangles, corners)))
        };
        let (d2, q) = nearest.best;
        // None within reach (or a distance that is not a number).
        if d2.is_nan() || d2 >= reach * reach {
            write(out, k, NONE);
            continue;
        }
        if let Some((t, [a, b, c], normal_local, height)) = face.best {
            // Inside a face: the face's plane, from its corners alone.
            let normal = mesh.pose.rotation * normal_local;
            let offset = normal.dot(mesh.pose.transform_point(a));
            let d = normal.dot(s) - offset;
            if let Some((triangles, corners)) = triangles {
                // How far the lane may move with this face still the one:
                // no farther than the list reaches past the face.
                let listed_to = lane.radius - (s - lane.anchor).length();
                let room = 0.5 * (listed_to - height);
                let others = triangles.iter().copied().zip(corners);
                if let Some(valid) = face_hold(local, (t, [a, b, c]), others, room) {
                    (lane.at, lane.valid, lane.normal, lane.surface) = (s, valid, normal, offset);
                }
            }
            let plane = if d < reach {
                held.plane(s, (normal, offset, d))
            } else {
                NONE
            };
            write(out, k, plane);
            continue;
        }
        let d = d2.sqrt();
        if d <= ON_SURFACE {
            // On the surface: no side to face; the stage's contact says.
            write(out, k, through_stage(s));
            continue;
        }
        // Nearest an edge or a corner.
        let normal = mesh.pose.rotation * ((local - q) / d);
        let offset = normal.dot(mesh.pose.transform_point(q));
        write(out, k, held.plane(s, (normal, offset, d)));
    }
}

/// How far (m) a lane at `p` (the mesh's frame) may move with triangle
/// `face` (its corners) still the face its plane is taken from
/// ([`Face`]), at most
/// `room`: less a hair ([`BOUNDARY`], for rounding) than the least of how
/// far `p`'s projection lies inside the face's edges, of its distance to
/// the face, and of half the distance by which each other of `triangles`
/// (and their corners) not in the face's plane is farther. None when there is no room.
fn face_hold(
    p: Vector,
    (face, [a, b, c]): (u32, [Vector; 3]),
    triangles: impl Iterator<Item = (u32, Option<[Vector; 3]>)>,
    room: f32,
) -> Option<f32> {
    let (_, height, inside) = face_of(p, [a, b, c])?;
    let normal = (b - a).cross(c - a).normalize();
    let mut valid = room.min(height).min(inside);
    for (t, corners) in triangles {
        let Some([a2, b2, c2]) = corners else {
            continue;
        };
        // A triangle of the same plane (the face itself among them) is
        // never nearer than the face while the lane's projection is
        // inside it, nor a face the projection is inside.
        let flat = |v: Vector| (normal.dot(v - a)).abs() <= 1.0e-6;
        if t == face || (flat(a2) && flat(b2) && flat(c2)) {
            continue;
        }
        // Exact, not its box's: a tilted neighbour's box reaches over
        // the face (terrain kept no face so).
        let beyond = (nearest_on_triangle(p, (a2, b2, c2)) - p).length();
        valid = valid.min(0.5 * (beyond - height));
    }
    let valid = valid - BOUNDARY;
    (valid > 0.0).then_some(valid)
}

/// Where `p` (m) is against the face of triangle `abc` (the same frame),
/// when its projection onto the face's plane lies inside the triangle:
/// the face's unit normal on `p`'s side, `p`'s height above the face (m),
/// and how far inside the triangle's edges its projection lies (m).
#[inline(always)]
fn face_of(p: Vector, [a, b, c]: [Vector; 3]) -> Option<(Vector, f32, f32)> {
    let normal = (b - a).cross(c - a).normalize();
    if !normal.is_finite() {
        return None;
    }
    let height = normal.dot(p - a);
    let on = p - normal * height;
    let mut inside = f32::INFINITY;
    for (u, v) in [(a, b), (b, c), (c, a)] {
        // Inward across the edge, in the face's plane.
        let inward = normal.cross(v - u).normalize();
        inside = inside.min(inward.dot(on - u));
    }
    let side = if height >= 0.0 { normal } else { -normal };
    (inside > 0.0).then_some((side, height.abs(), inside))
}

/// Within this (m) of a kept face's guards, and of the reach, a lane
/// searches: rounding then cannot make the search's answer differ from the
/// kept face's.
const BOUNDARY: f32 = 1.0e-5;

/// The face a lane's plane is taken from, once [`Nearest`] has found the
/// nearest distance: of the triangles whose face holds the lane's
/// projection and lies no farther than that distance (and a hair), the
/// one of least index. Two coplanar triangles beside each other are as
/// near within rounding where the lane's projection is near their common
/// edge, and the nearest by distance could be either; the one whose face
/// holds the projection is one only.
struct Face {
    /// How far (m) a face may be: the nearest distance and a hair.
    within: f32,
    /// The face: its triangle and corners, unit normal on the lane's
    /// side, and the lane's height above it (m).
    best: Option<(u32, [Vector; 3], Vector, f32)>,
}

impl Face {
    fn new(nearest: &Nearest) -> Face {
        Face {
            within: nearest.best.0.sqrt() + 1.0e-6,
            best: None,
        }
    }

    /// Considers triangle `t` (its `corners`, none for a removed cell)
    /// for `p` (m, the surface's frame).
    #[inline(always)]
    fn consider(&mut self, p: Vector, t: u32, corners: Option<[Vector; 3]>) {
        if self.best.is_some_and(|(b, ..)| b < t) || !self.within.is_finite() {
            return;
        }
        let Some(corners) = corners else {
            return;
        };
        let [a, b, c] = corners;
        let outside = (a.min(b).min(c) - p).max(p - a.max(b).max(c));
        if outside.max(Vector::ZERO).length() > self.within {
            return;
        }
        // Inside the triangle's edges (by signs, without a root: most
        // triangles tested here are the nearest's neighbours, outside).
        let across = (b - a).cross(c - a);
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(u, v)| across.cross(v - u).dot(p - u) > 0.0);
        if !inside {
            return;
        }
        let normal = across.normalize();
        let height = normal.dot(p - a);
        if normal.is_finite() && height.abs() <= self.within {
            let side = if height >= 0.0 { normal } else { -normal };
            self.best = Some((t, corners, side, height.abs()));
        }
    }
}

/// Lane `k`'s plane (unit normal, offset) into `out`.
#[inline(always)]
fn write(out: &mut [&mut [f32]; 4], k: usize, (normal, offset): ([f32; 3], f32)) {
    for a in 0..3 {
        out[a][k] = normal[a];
    }
    out[3][k] = offset;
}

/// Lists into `listed` the triangles of `mesh` within `radius` (m) of
/// `at` (the mesh's frame); returns their count, or [`CROWDED`] when
/// there are more than [`LISTED`].
fn list_near(surface: Surface, at: Vector, radius: f32, listed: &mut [u32]) -> u8 {
    let region = Aabb::new(at - Vector::splat(radius), at + Vector::splat(radius));
    let mut count = 0;
    surface.each_near(&region, |t| {
        // Within the box but beyond the ball: a thin shape's other face,
        // which would crowd the lists of every lane on this one.
        let Some([a, b, c]) = surface.corners(t) else {
            return;
        };
        if (nearest_on_triangle(at, (a, b, c)) - at).length_squared() > radius * radius {
            return;
        }
        if count < LISTED {
            listed[count] = t;
        }
        count += 1;
    });
    if count > LISTED {
        CROWDED
    } else {
        count as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::contact::contact;
    use parry3d::shape::SharedShape;

    /// A box of `2h` (m) as a mesh, each face cut into `k × k` squares.
    fn box_mesh(h: Vector, k: usize) -> SharedShape {
        let (mut vertices, mut indices) = (Vec::new(), Vec::new());
        let mut face = |o: Vector, u: Vector, v: Vector| {
            let base = vertices.len() as u32;
            for j in 0..=k {
                for i in 0..=k {
                    vertices.push(o + u * (i as f32 / k as f32) + v * (j as f32 / k as f32));
                }
            }
            let w = k as u32 + 1;
            for j in 0..k as u32 {
                for i in 0..k as u32 {
                    let a = base + j * w + i;
                    indices.push([a, a + w, a + 1]);
                    indices.push([a + 1, a + w, a + w + 1]);
                }
            }
        };
        let (x, y, z) = (
            Vector::X * 2.0 * h.x,
            Vector::Y * 2.0 * h.y,
            Vector::Z * 2.0 * h.z,
        );
        face(-h, x, z);
        face(-h + y, z, x);
        face(-h, y, x);
        face(-h + z, x, y);
        face(-h, z, y);
        face(-h + x, y, z);
        SharedShape::trimesh(vertices, indices).expect("a mesh")
    }

    /// A plane: unit normal and offset (m).
    type Plane = ([f32; 3], f32);

    /// The planes of lanes at `points` from the mesh's lists, and through
    /// the stage's contact, for the one mesh `o` held.
    fn planes(
        o: &Obstacle,
        mesh: &StillMesh,
        lists: &mut MeshLists,
        points: &[Vector],
    ) -> Vec<[Plane; 2]> {
        let n = points.len();
        let start: [Vec<f32>; 3] = [0, 1, 2].map(|a| points.iter().map(|p| p[a]).collect());
        let mut out: [Vec<f32>; 4] = [(); 4].map(|_| vec![0.0; n]);
        {
            let shared = lists.shared(mesh.list);
            // SAFETY: one chunk, all lanes.
            let chunk = unsafe { shared.lanes(0..n) };
            let [a, b, c, d] = &mut out;
            let mut refs = [&mut a[..], &mut b[..], &mut c[..], &mut d[..]];
            mesh_planes_of(mesh, o, chunk, start.each_ref().map(|s| &s[..]), &mut refs);
        }
        let pose = PoseF64::placing(&o.pose, Analytic::Other);
        points
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let ours = ([out[0][k], out[1][k], out[2][k]], out[3][k]);
                let stage = convex_plane(
                    &mesh.held,
                    (&*o.shape, Analytic::Other, &pose),
                    p.to_array(),
                );
                [ours, stage]
            })
            .collect()
    }

    /// A turned box mesh's planes from the lanes' lists, a flat sheet's
    /// (a mesh with a border) and a heightfield's, agree with those through the
    /// stage's contact (parry's projection on the mesh) around them, in
    /// them and beyond their edges and corners, when the lists are made
    /// and when the lanes have moved on a little (their faces then
    /// reused): the same normals (either of two triangles as near),
    /// planes within 10 µm at the lane, none where the stage has none.
    #[test]
    fn a_meshs_planes_are_those_of_its_contact() {
        let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
        let pose = Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn);
        let closed = box_mesh(Vector::new(0.3, 0.1, 0.2), 3);
        let sheet = SharedShape::trimesh(
            vec![
                Vector::new(-0.3, 0.0, -0.2),
                Vector::new(0.3, 0.0, -0.2),
                Vector::new(-0.3, 0.0, 0.2),
                Vector::new(0.3, 0.0, 0.2),
            ],
            vec![[0, 2, 1], [1, 2, 3]],
        )
        .expect("a mesh");
        // Terrain: a heightfield of 6 × 5 cells, hills and a valley.
        let heights: Vec<f32> = (0..7 * 6)
            .map(|k| 0.4 * ((k % 7) as f32 * 1.3).sin() * ((k / 7) as f32 * 0.9).cos())
            .collect();
        let terrain = SharedShape::heightfield(
            parry3d::utils::Array2::new(7, 6, heights),
            Vector::new(0.6, 0.2, 0.4),
        );
        let lattice = Vector::new(0.055, 0.025, 0.04);
        check_planes(&Obstacle::new(closed, pose), lattice, 500);
        check_planes(&Obstacle::new(sheet, pose), lattice, 500);
        // Nearer its surface: the ground lies within 8 cm of its middle.
        // Few lanes keep a face there: the next triangle is tilted and
        // its box near.
        let low = Vector::new(0.055, 0.01, 0.04);
        check_planes(&Obstacle::new(terrain, pose), low, 100);
    }

    /// [`a_meshs_planes_are_those_of_its_contact`] for the mesh `o`, at
    /// the points of a lattice of `cells` (m) around its middle, of which
    /// at least `least_faces` keep a face over the rounds.
    fn check_planes(o: &Obstacle, cells: Vector, least_faces: usize) {
        let (thickness, motion) = (0.01, 0.003);
        let mut lists = MeshLists::default();
        let points: Vec<Vector> = (0..13 * 13 * 13)
            .map(|i| {
                let (a, b, c) = (i % 13, (i / 13) % 13, i / 169);
                let local = Vector::new(a as f32 - 6.0, b as f32 - 6.0, c as f32 - 6.0) * cells
                    + Vector::new(0.001, 0.002, 0.003);
                o.pose.transform_point(local)
            })
            .collect();
        let list = lists.take(
            (Surface::of(&*o.shape).unwrap(), &o.pose),
            (0, None),
            points.len(),
        );
        let mesh = StillMesh::new(
            (&*o.shape, &o.pose),
            (0, None, 0, list),
            // No lane held where it starts (it would be deep within the
            // thickness): every plane the surface's, moved out.
            (thickness, motion, 2.0 * thickness),
        );
        let (mut held, mut none, mut faces) = (0, 0, 0);
        for round in 0..4 {
            // Each round a little further along, some lanes on their faces.
            let moved: Vec<Vector> = points
                .iter()
                .enumerate()
                .map(|(k, &p)| {
                    p + Vector::new(0.3, -0.5, 0.2) * (0.002 * round as f32 * (k % 3) as f32)
                })
                .collect();
            let warm = planes(o, &mesh, &mut lists, &moved);
            // The same bits from fresh lists (a solver restored from a
            // snapshot): the kept faces give what a search gives.
            let mut fresh = MeshLists::default();
            fresh.take(
                (Surface::of(&*o.shape).unwrap(), &o.pose),
                (0, None),
                points.len(),
            );
            let cold = planes(o, &mesh, &mut fresh, &moved);
            for (k, ([w, _], [c, _])) in warm.iter().zip(&cold).enumerate() {
                let bits = |(n, d): Plane| (n.map(f32::to_bits), d.to_bits());
                assert_eq!(
                    bits(*w),
                    bits(*c),
                    "{round} {k}: kept {w:?}, searched {c:?}"
                );
            }
            for (k, [ours, stage]) in warm.into_iter().enumerate() {
                // At the reach, either may have a plane by a rounding.
                let signed = contact(&*o.shape, &o.pose, moved[k]).map(|c| c.signed_distance);
                if signed.is_some_and(|d| (d - mesh.held.reach()).abs() < 1e-5) {
                    continue;
                }
                if stage.1 == f32::NEG_INFINITY {
                    assert_eq!(ours.1, f32::NEG_INFINITY, "{round} {k}: {ours:?}");
                    none += 1;
                    continue;
                }
                held += 1;
                let (a, b) = (Vector::from(ours.0), Vector::from(stage.0));
                if a.dot(b) < 0.9999 {
                    // Two triangles as near: either holds it.
                    let c = contact(&*o.shape, &o.pose, moved[k]).unwrap();
                    let ours_d = a.dot(moved[k]) - (ours.1 - thickness);
                    assert!(
                        (ours_d - c.signed_distance).abs() < 1e-5,
                        "{round} {k}: {ours:?} against {stage:?}"
                    );
                    continue;
                }
                // Where each plane is at the lane (a normal's rounding
                // moves the offset of a plane far from the origin).
                let gap = |(n, offset): ([f32; 3], f32)| Vector::from(n).dot(moved[k]) - offset;
                assert!(
                    (gap(ours) - gap(stage)).abs() < 1e-5,
                    "{round} {k}: {ours:?} against {stage:?}"
                );
            }
            faces += lists.lists[0]
                .lanes
                .iter()
                .filter(|l| l.valid > 0.0)
                .count();
        }
        assert!(
            held > 1000 && none > 1000 && faces > least_faces,
            "{held} held, {none} none, {faces} on faces"
        );
    }
}
