//! Contacts with still balls, capsules, half-spaces and cuboids (a ball on
//! a stand, a bar, a floor, a table), and with sliding ones, held inside
//! the small-steps solver's substeps, in its grid lanes. The
//! collision stage after a substep visits every particle near an obstacle
//! through its general pass (candidates, exact contact, tracing, friction,
//! impulses): at N = 128 on the `drape`'s ball that was a third of the
//! frame, paid every substep. A still ball's or plane's contact is a few
//! vector operations a lane, so xpbd puts every particle back out of them
//! itself after the chains and after the last sweep, there with Coulomb
//! friction by how far it pushed (and at the step's last substep once
//! more after the stretch limit); the collision stage then runs only at
//! the step's last substep (the schedule skips it before, see
//! [`LaneContacts::holds`]), where its exact pass, edge pass and stretch
//! hold leave the frame as every other integrator's. While the contacts
//! are held, the cloth's state stays in the lanes from one substep to the
//! next (`xpbd.rs`).
//!
//! Every lane is looked at, not a list of candidates: a branchless vector
//! pass over the lanes is cheaper than gathering candidates, and misses no
//! particle whatever its speed. A particle is put back through the nearest
//! point of the surface: against a still shape over a substep's motion (a
//! few millimetres) that is the side it came in by; a ball must be several
//! times larger than the substep's fastest motion ([`BALL_MOTIONS`]), or
//! the collision stage, which traces paths, keeps it. A cuboid holds each
//! lane on the tangent plane of the cuboid (rounded by the thickness) at
//! the point nearest to where the lane started the substep, found once a
//! substep ([`LaneContacts::take_planes`]), as the collision stage's
//! contact planes did: a lane pulled over an edge stays on the face it was
//! on. The `box` went from 9.0 to 5.9 ms a frame so, its peak stretch
//! from 5.20% to 4.78%. A spring between two particles held out may still
//! cut a cuboid's edge: the lanes keep the springs off the edges too,
//! every second substep, as the collision stage's edge pass does
//! ([`LaneContacts::keep_springs_off_cuboids`], `xpbd::CUBOID_EDGES_EVERY`);
//! the stage ran every second substep for that before, and the state left
//! the lanes for it (`box` 6.4 → 4.4 ms, bench, one thread).
//!
//! A body that moves without turning and is not dynamic (a kinematic bar,
//! ball or platform on its path) is held too, if made of balls, capsules,
//! half-spaces and cuboids: where it is at the substep's end, as the
//! collision stage takes it, with a lane's slide for friction taken
//! relative to the surface's move and a cuboid's plane from where the lane
//! started relative to it ([`lane_held`]). The state then stays in the
//! lanes among such bodies too: the `tear`, whose sheet hangs from two
//! sliding bars, ran the collision stage after each of its 43 substeps:
//! its instructions a frame fell by a third, its frame from 6.7–8.0 to
//! 3.3–5.5 ms on a slow host; the `curtain`'s by two fifths.

use crate::collision::{chords_clear_ball, Obstacle, EDGE_SAMPLES};
use crate::math::{simd_available, Pose, Vector};
use crate::parallel::{Disjoint, Team};
use parry3d::shape::Shape;

use super::grid_sweep::{GridPlan, LanePlanes, Lanes};
use super::lane_convex::{convex_planes_of, HullFaces, StillConvex};
use super::lane_mesh::{is_held_mesh, mesh_planes_of, MeshLists, StillMesh, Surface};

/// Lanes per chunk of a pass, a chunk to a thread.
const CHUNK: usize = 2048;

/// A ball's radius must be over this many times the farthest a particle
/// moves in the substep for the lanes to hold it: a particle is put back
/// through the nearest point of the surface, which is the side it came in
/// by only while it has not come near the centre (the collision stage
/// traces a particle's path back instead). A particle can also be moved
/// by the sweeps beyond its own motion, hence a wide margin.
pub(crate) const BALL_MOTIONS: f32 = 4.0;

/// One still shape, as its lanes pass takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
enum StillShape {
    /// A ball: centre (m) and radius plus the thickness (m).
    Ball { centre: Vector, reach: f32 },
    /// A capsule (a bar, a rod): the ball of radius plus thickness `reach`
    /// (m) around the point of its axis nearest the lane; the axis from
    /// `from` (m) along the unit vector `axis` for `length` (m). A lane on
    /// the axis (within [`ON_AXIS`] of the reach) goes out along `across`,
    /// a unit vector square to the axis (the rounding of its nearest
    /// point gives it no direction, or one along the axis, which does not
    /// lead out).
    Capsule {
        from: Vector,
        axis: Vector,
        across: Vector,
        length: f32,
        reach: f32,
        /// The square (m²) of [`ON_AXIS`] of the reach, worked out here
        /// rather than in each pass: the pass's code reads it (and did
        /// the product) before it knows the shape is a capsule, and the
        /// bytes there for a ball are whatever was left, often a subnormal
        /// float, whose product stalled the drape's lane pass for a
        /// hundred cycles a chunk (43% of its frame in `perf`).
        on_axis2: f32,
    },
    /// A half-space: outward unit normal, and the offset (m) of its
    /// boundary moved out by the thickness (`n · x = offset` on it).
    Plane { normal: Vector, offset: f32 },
    /// A cuboid (a table, a box), rounded by the thickness: centre (m),
    /// its local axes in the world (unit vectors), half extents (m) and
    /// the thickness (m).
    Cuboid(StillCuboid),
    /// Any other convex shape (a cylinder, a cone, a convex hull), held
    /// as a cuboid is, by a plane a lane (`lane_convex.rs`).
    Convex(StillConvex),
    /// A triangle mesh or a heightfield, held by a plane a lane through
    /// its nearest point (`lane_mesh.rs`).
    Mesh(StillMesh),
}

/// Within this share of a capsule's reach from its axis, a lane goes out
/// along the capsule's `across` ([`StillShape::Capsule`]).
const ON_AXIS: f32 = 1.0e-3;

/// How far within the thickness, as a share of it, a lane may start a
/// substep and still be put out to the thickness by a cuboid's plane
/// ([`cuboid_plane`]); one deeper is held where it starts along the normal.
/// The passes after the lanes' last push (the stretch limit) leave lanes a
/// hair inside, and held there they sank with each substep's limit: the
/// `box` peaked at 5.03% so with none, 4.78% with a tenth (a quarter, a
/// half and the whole thickness the same).
const SETTLE_SHARE: f32 = 0.1;

/// A still cuboid as the lanes take it ([`StillShape::Cuboid`]): a lane
/// is held by the tangent plane of the rounded cuboid at the point nearest
/// to where it started the substep, as the collision stage's contact
/// planes hold it, when it started within `reach` (m) of the cuboid.
#[derive(Debug, Clone, Copy, PartialEq)]
struct StillCuboid {
    centre: Vector,
    axes: [Vector; 3],
    half: Vector,
    thickness: f32,
    reach: f32,
    /// How far (m) within the thickness a lane may start and still be
    /// put out to it ([`cuboid_plane`]).
    settle: f32,
    /// Which of the lanes' plane records is this cuboid's.
    slot: usize,
}

/// The still smooth obstacles of a substep and what the lanes passes
/// record of them: per lane, how far (m) the passes pushed it this substep
/// and which obstacle last did (its index plus one, 0 for none).
#[derive(Debug, Default)]
pub(crate) struct LaneContacts {
    shapes: Vec<StillShape>,
    friction: Vec<f32>,
    /// Per shape, how far (m) its surface moves over the substep (zero
    /// for a still one).
    shifts: Vec<Vector>,
    depth: Vec<f32>,
    touch: Vec<u32>,
    /// Per cuboid or other convex shape, per lane: the plane that holds
    /// the lane this substep (unit normal x, y, z and offset, m; an offset
    /// of −∞ for none), in the shape's slot of `lanes` entries
    /// ([`Self::take_planes`]).
    planes: [Vec<f32>; 4],
    /// Lanes of the substep.
    lanes: usize,
    /// Per lane, for the cuboid [`Self::keep_springs_off_cuboids`] is at:
    /// the faces it is beyond by the margin or over
    /// ([`StillCuboid::faces_beyond`]).
    faces: Vec<u8>,
    /// The faces of the convex hulls held this substep.
    hulls: HullFaces,
    /// Per mesh held, per lane: the triangles near it, kept from substep
    /// to substep.
    meshes: MeshLists,
}

/// Whether the lanes may hold obstacle `o`'s shape, still: convex (parry
/// knows balls, capsules, half-spaces and cuboids convex too), a mesh
/// without an inside or a heightfield, or a compound of such parts.
fn held_shape(o: &Obstacle) -> bool {
    pieces(&*o.shape).all(|(_, _, shape)| shape.is_convex() || is_held_mesh(shape))
}

/// Whether the lanes may hold obstacle `o` over a substep: a still one of
/// a shape they take ([`held_shape`]), or one that moves without turning
/// and is not a dynamic body (a kinematic bar, ball or platform sliding
/// along its path) made of balls, capsules, half-spaces and cuboids, held
/// where it is at the substep's end. Friction then takes a lane's slide
/// relative to the surface's move over the substep, and a cuboid's plane
/// for a lane is taken from where the lane started relative to it.
/// (A turning body moves each point of its surface differently, and a
/// convex hull's or mesh's planes come from lists made for one pose: the
/// collision stage keeps those.)
fn lane_held(o: &Obstacle) -> bool {
    if o.is_still() {
        return held_shape(o);
    }
    o.body.is_none()
        && o.angvel == Vector::ZERO
        && pieces(&*o.shape).all(|(_, _, shape)| {
            shape.as_ball().is_some()
                || shape.as_capsule().is_some()
                || shape.as_halfspace().is_some()
                || shape.as_cuboid().is_some()
        })
}

/// Which obstacles the lanes hold in a substep ([`LaneContacts::begin_holding`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Holding {
    /// None: the collision stage answers for every contact after the substep.
    None,
    /// Every obstacle: the collision stage may wait for the step's last substep.
    All,
    /// The still ones; the collision stage answers for the moving and
    /// dynamic bodies after each substep, and for all at the last.
    Still,
}

/// The pieces of an obstacle's `shape` the lanes take one by one, each
/// with its pose in the obstacle's frame and its index among a compound's
/// parts: a compound's parts (parry's compounds do not nest), or the
/// shape itself.
fn pieces(shape: &dyn Shape) -> impl Iterator<Item = (Option<usize>, Pose, &dyn Shape)> {
    let compound = shape.as_compound();
    let parts = compound.map_or(&[][..], |c| c.shapes());
    let whole = compound.is_none().then_some((None, Pose::IDENTITY, shape));
    whole.into_iter().chain(
        parts
            .iter()
            .enumerate()
            .map(|(k, (pose, part))| (Some(k), *pose, &**part)),
    )
}

impl LaneContacts {
    /// Whether every obstacle is one the lanes may hold, whatever the
    /// motion (none counts: nothing to hold) ([`lane_held`]): still (no
    /// rapier body, no velocity), and a ball, a capsule, a half-space, a
    /// cuboid or another shape parry knows to be convex (a cylinder, a
    /// cone, a convex hull), a triangle mesh without an inside or a
    /// heightfield (`lane_mesh.rs`), or a compound of such parts (a table
    /// built of a top and legs, a convex decomposition), not an oriented
    /// mesh; or moving without turning, not a dynamic body, and made of
    /// balls, capsules, half-spaces and cuboids.
    pub fn may_hold(obstacles: &[Obstacle]) -> bool {
        obstacles.iter().all(lane_held)
    }

    /// Whether the lanes hold the contacts of every one of `obstacles`
    /// (and there is one) for a substep of `h` seconds in which no
    /// particle moves further than `motion` (m): each is one they may hold
    /// ([`Self::may_hold`]) and a half-space, or a ball or capsule of a
    /// radius or a cuboid of half extents over [`BALL_MOTIONS`] times
    /// `motion` and the obstacle's own move in the substep (a particle is
    /// put back through the nearest face, which must be the one it came
    /// in by), or another convex shape whose own box's half extents are
    /// (a triangle, flat, is not held), or a mesh or heightfield whatever
    /// its size; a compound when each of its parts is. The collision
    /// stage then need not run after a substep but the last.
    pub fn holds(obstacles: &[Obstacle], motion: f32, h: f32) -> bool {
        Self::holds_each(obstacles.iter(), motion, h)
    }

    /// [`Self::holds`] over `obstacles` as an iterator.
    fn holds_each<'a>(
        obstacles: impl Iterator<Item = &'a Obstacle> + Clone,
        motion: f32,
        h: f32,
    ) -> bool {
        obstacles.clone().next().is_some()
            && obstacles.clone().all(lane_held)
            && obstacles.into_iter().all(|o| {
                // Relative to the obstacle: its own move adds to the particle's.
                let deep = BALL_MOTIONS * (motion + o.linvel.length() * h);
                pieces(&*o.shape).all(|(_, _, shape)| {
                    match (shape.as_ball(), shape.as_capsule(), shape.as_cuboid()) {
                        (Some(ball), _, _) => ball.radius > deep,
                        (_, Some(capsule), _) => capsule.radius > deep,
                        (_, _, Some(cuboid)) => cuboid.half_extents.min_element() > deep,
                        // A mesh has no inside to come out of the wrong
                        // way: its planes face the side a lane starts on.
                        _ => {
                            shape.as_halfspace().is_some()
                                || is_held_mesh(shape)
                                || shape.compute_local_aabb().half_extents().min_element() > deep
                        }
                    }
                })
            })
    }

    /// Whether the lanes may hold the still ones among `obstacles` while
    /// the collision stage answers for the others, moving or dynamic
    /// ([`Holding::Still`]): there are both, and every still one is a
    /// shape [`Self::may_hold`] takes.
    pub fn may_hold_still(obstacles: &[Obstacle]) -> bool {
        let still = obstacles.iter().filter(|o| o.is_still());
        still.clone().next().is_some()
            && obstacles.iter().any(|o| !o.is_still())
            && still.into_iter().all(held_shape)
    }

    /// [`Self::begin_holding`] of every obstacle or none, for a substep of
    /// 1 ms at the step's start: whether it holds them all.
    #[cfg(test)]
    pub fn begin(
        &mut self,
        obstacles: &[Obstacle],
        (thickness, motion): (f32, f32),
        n: usize,
    ) -> bool {
        let (end, h) = (1.0e-3, 1.0e-3);
        self.begin_holding(obstacles, (thickness, motion), (end, h), n) == Holding::All
    }

    /// Takes `obstacles` for a substep of `n` lanes, `h` seconds long and
    /// ending `end` seconds into the step, in which no particle moves
    /// further than `motion` (m), their surfaces moved out by `thickness`
    /// (m); clears every lane's record. A moving obstacle is taken where
    /// it is at the substep's end, as the collision stage takes it.
    /// Returns which it holds: all ([`Self::holds`]), or the still ones
    /// among others (moving or dynamic), when [`Self::holds`] would hold
    /// those; else none.
    pub fn begin_holding(
        &mut self,
        obstacles: &[Obstacle],
        (thickness, motion): (f32, f32),
        (end, h): (f32, f32),
        n: usize,
    ) -> Holding {
        self.shapes.clear();
        self.friction.clear();
        self.shifts.clear();
        self.hulls.clear();
        self.meshes.begin();
        let holding = if Self::holds(obstacles, motion, h) {
            Holding::All
        } else if obstacles.iter().any(|o| !o.is_still())
            && Self::holds_each(obstacles.iter().filter(|o| o.is_still()), motion, h)
        {
            Holding::Still
        } else {
            return Holding::None;
        };
        for (index, o) in obstacles.iter().enumerate() {
            let still = o.is_still();
            if holding == Holding::Still && !still {
                continue;
            }
            // A still obstacle's own pose (the bits of its translation as
            // given, −0 among them); a moving one's at the substep's end.
            let (at, shift) = if still {
                (o.pose, Vector::ZERO)
            } else {
                (o.pose_at(end), o.linvel * h)
            };
            for (part, placed, shape) in pieces(&*o.shape) {
                let pose = at * placed;
                let held = self.still_shape((shape, &pose), (index, part), (thickness, motion), n);
                self.shapes.push(held);
                self.friction.push(o.friction);
                self.shifts.push(shift);
            }
        }
        self.depth.clear();
        self.depth.resize(n, 0.0);
        self.touch.clear();
        self.touch.resize(n, 0);
        self.lanes = n;
        let slots = self.slots();
        // Not cleared: `take_planes` writes every slot's plane of every
        // lane before a pass reads one (a fill of the records, 128 kB a
        // substep for a 64² cloth around two shapes, was a tenth of a
        // round table's frame between its loops).
        for record in &mut self.planes {
            record.resize(slots * n, f32::NEG_INFINITY);
        }
        holding
    }

    /// Whether a shape held this substep moves.
    fn moving(&self) -> bool {
        self.shifts.iter().any(|&s| s != Vector::ZERO)
    }

    /// The still `shape` at `pose` (piece `part` of a compound, or the
    /// whole) of obstacle `index`, as the lanes hold it, its surface moved
    /// out by `thickness` (m), for a substep of `lanes` lanes in which no
    /// particle moves further than `motion` (m); one [`Self::holds`] took.
    fn still_shape(
        &mut self,
        (shape, pose): (&dyn Shape, &Pose),
        (index, part): (usize, Option<usize>),
        (thickness, motion): (f32, f32),
        lanes: usize,
    ) -> StillShape {
        if let Some(surface) = Surface::of(shape) {
            let (slot, settle) = (self.slots(), SETTLE_SHARE * thickness);
            let list = self.meshes.take((surface, pose), (index, part), lanes);
            return StillShape::Mesh(StillMesh::new(
                (shape, pose),
                (index, part, slot, list),
                (thickness, motion, settle),
            ));
        }
        match (shape.as_ball(), shape.as_halfspace(), shape.as_cuboid()) {
            (Some(ball), _, _) => StillShape::Ball {
                centre: pose.translation,
                reach: ball.radius + thickness,
            },
            (None, Some(half), _) => {
                let normal = (pose.rotation * half.normal).normalize();
                StillShape::Plane {
                    normal,
                    offset: normal.dot(pose.translation) + thickness,
                }
            }
            (None, None, Some(cuboid)) => StillShape::Cuboid(StillCuboid {
                slot: self.slots(),
                centre: pose.translation,
                axes: [Vector::X, Vector::Y, Vector::Z]
                    .map(|axis| (pose.rotation * axis).normalize()),
                half: cuboid.half_extents,
                thickness,
                // As the collision stage's contact planes: within twice
                // the thickness and twice the substep's motion.
                reach: 2.0 * (thickness + motion),
                settle: SETTLE_SHARE * thickness,
            }),
            (None, None, None) => match shape.as_capsule() {
                Some(capsule) => {
                    let [a, b] =
                        [capsule.segment.a, capsule.segment.b].map(|end| pose.transform_point(end));
                    let length = (b - a).length();
                    // A capsule of no length is a ball at `from`.
                    let axis = if length > 0.0 {
                        (b - a) / length
                    } else {
                        Vector::Y
                    };
                    let reach = capsule.radius + thickness;
                    let tiny = ON_AXIS * reach;
                    StillShape::Capsule {
                        from: a,
                        axis,
                        across: axis.any_orthonormal_vector(),
                        length,
                        reach,
                        on_axis2: tiny * tiny,
                    }
                }
                // Another convex shape (`holds` took no other).
                None => {
                    let (slot, settle) = (self.slots(), SETTLE_SHARE * thickness);
                    StillShape::Convex(StillConvex::new(
                        (shape, pose),
                        (index, part, slot),
                        (thickness, motion, settle),
                        &mut self.hulls,
                    ))
                }
            },
        }
    }

    /// Each cuboid's and other convex shape's plane for every lane, from
    /// where the lanes start the substep (`lanes`' start positions, m):
    /// the tangent plane of the rounded shape at the point nearest to the
    /// start ([`cuboid_plane`],
    /// [`convex_plane`](super::lane_convex::convex_plane)). Once a substep,
    /// after [`Self::begin_holding`] with the same `obstacles` and before the
    /// passes.
    pub fn take_planes(&mut self, obstacles: &[Obstacle], lanes: &mut Lanes, team: Team) {
        let n = self.lanes;
        let [_, _, _, sx, sy, sz, lw] = lanes.disjoint();
        if sx.len() != n {
            // No lanes to take planes for: none holds one.
            self.planes[3].fill(f32::NEG_INFINITY);
            return;
        }
        let simd = simd_available();
        for (shape, &shift) in self.shapes.iter().zip(&self.shifts) {
            let Some(slot) = shape.slot() else {
                continue;
            };
            let slot = slot * n..(slot + 1) * n;
            let lists = match shape {
                StillShape::Mesh(mesh) => Some(self.meshes.shared(mesh.list)),
                _ => None,
            };
            let [nx, ny, nz, offset] = self
                .planes
                .each_mut()
                .map(|r| Disjoint::new(&mut r[slot.clone()]));
            team.largest_over_chunks((n, CHUNK), |range| {
                // SAFETY: chunks are disjoint ranges of lanes; the start
                // positions and inverse masses are only read.
                let (start, w, mut out) = unsafe {
                    (
                        [sx, sy, sz].map(|a| &*a.range(range.clone())),
                        &*lw.range(range.clone()),
                        [nx, ny, nz, offset].map(|a| a.range(range.clone())),
                    )
                };
                match *shape {
                    StillShape::Cuboid(cuboid) => {
                        moved_planes_of((&cuboid, shift), (start, w), &mut out, simd);
                    }
                    StillShape::Convex(convex) => convex_planes_of(
                        &convex,
                        (&obstacles[convex.obstacle], &self.hulls),
                        start,
                        &mut out,
                    ),
                    StillShape::Mesh(mesh) => {
                        if let Some(lists) = &lists {
                            // SAFETY: as the planes: this chunk's lanes alone.
                            let lists = unsafe { lists.lanes(range.clone()) };
                            let obstacle = &obstacles[mesh.held.obstacle];
                            mesh_planes_of(&mesh, obstacle, lists, start, &mut out);
                        }
                    }
                    _ => {}
                }
                0.0
            });
        }
    }

    /// Keeps the stretch and shear springs of `plan` at least half the
    /// thickness out of every cuboid the lanes hold, as the collision
    /// stage's edge pass does (`collision/edges.rs`): the lanes hold each
    /// particle out of a cuboid, but a spring between two of them may
    /// still cut one of its edges or corners. A spring whose two ends are
    /// beyond one face (by that margin) or over it comes no nearer than
    /// its ends ([`StillCuboid::faces_beyond`]), and is
    /// passed over by one test of two lanes' marks (almost all of them:
    /// a sheet on a cube cuts only where it wraps its edges); the others
    /// are sampled at a quarter, a half and three quarters, and each
    /// sample within the margin is pushed out along the cuboid's normal
    /// there, the ends by their share and inverse masses, one spring after
    /// another. A spring with a pinned end inside the cuboid is left (it
    /// cannot be put out). One thread: the springs it samples are few.
    /// Returns the farthest it moved a lane (m).
    pub fn keep_springs_off_cuboids(&mut self, plan: &GridPlan, lanes: &mut Lanes) -> f32 {
        let n = self.lanes;
        let [x, y, z, _, _, _, w] = lanes.arrays_mut();
        if [x.len(), y.len(), z.len(), w.len()] != [n; 4] {
            return 0.0;
        }
        let mut farthest = 0.0f32;
        // Every spring lies within the lanes' box (the box is convex): a
        // cuboid whose own box, grown by the margin, is clear of it is
        // clear of every spring (the `tear`'s bars above its sheet: the
        // marks and runs were a ninth of its frame).
        let lanes = lanes_box([&x[..], &y[..], &z[..]]);
        for shape in &self.shapes {
            let StillShape::Cuboid(cuboid) = *shape else {
                continue;
            };
            let margin = 0.5 * cuboid.thickness;
            if !cuboid.box_meets(lanes, margin) {
                continue;
            }
            let faces = &mut self.faces;
            faces.clear();
            faces.resize(n, 0);
            cuboid.mark_faces_beyond([&x[..], &y[..], &z[..]], margin, faces);
            plan.for_each_edge_run(|(a, b, len)| {
                // Once a run, for the loops' indexing.
                if a.max(b) + len > n {
                    return;
                }
                // The springs to sample, found 32 at a time without a
                // branch (a spring at a time, the test was 7% of the
                // `box`'s frame, 3% so). A run's springs share no lane, so what
                // one spring's push changes cannot make another of the
                // same run due.
                for first in (0..len).step_by(32) {
                    let count = (len - first).min(32);
                    let mut due = apart_from_faces(&faces[a + first..], &faces[b + first..], count);
                    while due != 0 {
                        let i = due.trailing_zeros() as usize;
                        due &= due - 1;
                        let (a, b) = (a + first + i, b + first + i);
                        let (mut pa, mut pb) = ([x[a], y[a], z[a]], [x[b], y[b], z[b]]);
                        let moved =
                            cuboid.keep_spring_off((&mut pa, w[a]), (&mut pb, w[b]), margin);
                        if moved > 0.0 {
                            farthest = farthest.max(moved);
                            (x[a], y[a], z[a]) = (pa[0], pa[1], pa[2]);
                            (x[b], y[b], z[b]) = (pb[0], pb[1], pb[2]);
                            faces[a] = cuboid.faces_beyond(pa, margin);
                            faces[b] = cuboid.faces_beyond(pb, margin);
                        }
                    }
                }
            });
        }
        farthest
    }

    /// The planes of the lanes' cuboids and other convex shapes
    /// ([`Self::take_planes`]), when they hold one or more this substep.
    pub fn held_planes(&self) -> Option<LanePlanes<'_>> {
        (self.slots() > 0).then(|| LanePlanes {
            arrays: self.planes.each_ref().map(|r| &r[..]),
            slots: self.slots(),
            lanes: self.lanes,
        })
    }

    /// Whether the lanes hold a cuboid this substep.
    pub fn holds_cuboid(&self) -> bool {
        self.shapes
            .iter()
            .any(|s| matches!(s, StillShape::Cuboid(_)))
    }

    /// How many cuboids and other convex shapes the lanes hold (each its
    /// slot of plane records).
    fn slots(&self) -> usize {
        self.shapes.iter().filter(|s| s.slot().is_some()).count()
    }

    /// Whether there is anything to hold this substep.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// The lanes a pass pushed out of a shape this substep: the particles
    /// in contact, as the collision stage would count them.
    pub fn touching(&self) -> u32 {
        if self.is_empty() {
            return 0;
        }
        self.touch.iter().map(|&t| u32::from(t != 0)).sum()
    }

    /// Whether no stretch or shear spring shorter than `longest` (m)
    /// between two particles the lanes left outside `obstacles` (their
    /// surfaces moved out by `thickness`, m) can come within half the
    /// thickness of one: then the collision stage's edge pass has nothing
    /// to do. A segment between two points outside a half-space stays
    /// outside it (the outside is convex). Between two points at least
    /// `R = r + t` from a ball's centre, a segment of length `l` comes no
    /// closer than `√(R² − l²/4)`, which must be at least `r + t/2`: the
    /// edge pass's own test of one ball ([`chords_clear_ball`]); so too
    /// for a capsule, whose every axis point is such a centre. A ball
    /// beside another shape: not known (a spring may rest across both).
    pub fn springs_stay_out(obstacles: &[Obstacle], longest: f32, thickness: f32) -> bool {
        let halfspaces = obstacles.iter().all(|o| o.shape.as_halfspace().is_some());
        if halfspaces {
            return true;
        }
        let [one] = obstacles else {
            return false;
        };
        let radius = match (one.shape.as_ball(), one.shape.as_capsule()) {
            (Some(ball), _) => ball.radius,
            (None, Some(capsule)) => capsule.radius,
            (None, None) => return false,
        };
        chords_clear_ball(radius, thickness, longest)
    }

    /// Puts every free lane (inverse mass not zero) back out of every
    /// shape, through its nearest point, and records the push. Returns the
    /// farthest it pushed a lane (m).
    pub fn project(&mut self, lanes: &mut Lanes, team: Team) -> f32 {
        self.pass(lanes, team, false)
    }

    /// [`Self::project`], then Coulomb friction on every lane a pass
    /// pushed this substep: its slide over the substep along the surface
    /// (the shapes are still) is undone up to the coefficient times how
    /// far the passes pushed it. One pass: the push's normals are the
    /// friction's. Returns the farthest it pushed a lane (m).
    pub fn project_with_friction(&mut self, lanes: &mut Lanes, team: Team) -> f32 {
        self.pass(lanes, team, true)
    }

    /// [`Self::project`], with friction when `friction`.
    fn pass(&mut self, lanes: &mut Lanes, team: Team, friction: bool) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let moving = self.moving();
        let [lx, ly, lz, sx, sy, sz, lw] = lanes.disjoint();
        let (depth, touch) = (
            Disjoint::new(&mut self.depth[..]),
            Disjoint::new(&mut self.touch[..]),
        );
        let law = Law {
            shapes: &self.shapes,
            friction: friction.then_some(&self.friction[..]),
            shifts: (friction && moving).then_some(&self.shifts[..]),
            planes: self.planes.each_ref().map(|r| &r[..]),
            lanes: self.lanes,
        };
        let simd = simd_available();
        team.largest_over_chunks((lx.len(), CHUNK), |range| {
            // SAFETY: chunks are disjoint ranges of lanes; the start
            // positions and inverse masses are only read.
            let chunk = unsafe {
                let [x, y, z, sx, sy, sz, w] =
                    [lx, ly, lz, sx, sy, sz, lw].map(|a| a.range(range.clone()));
                Chunk {
                    first: range.start,
                    x,
                    y,
                    z,
                    start: [&*sx, &*sy, &*sz],
                    w: &*w,
                    depth: depth.range(range.clone()),
                    touch: touch.range(range.clone()),
                }
            };
            run(chunk, &law, simd)
        })
    }
}

/// What a pass applies: the shapes, and the friction coefficient of each
/// when it applies friction.
struct Law<'a> {
    shapes: &'a [StillShape],
    friction: Option<&'a [f32]>,
    /// With friction, when a shape moves: how far (m) each shape's
    /// surface moves over the substep ([`LaneContacts::shifts`]); a slide
    /// is taken relative to it.
    shifts: Option<&'a [Vector]>,
    /// The cuboids' planes ([`LaneContacts::planes`]) and the lanes of a slot.
    planes: [&'a [f32]; 4],
    lanes: usize,
}

impl Law<'_> {
    /// Checks that every cuboid's planes hold lanes `0..end` (the plane
    /// arrays all one length, each slot's `end` lanes within it): then a
    /// step of lanes below `end` may load them unchecked.
    #[inline]
    fn check_planes(&self, end: usize) {
        let [px, py, pz, po] = self.planes;
        let len = po.len();
        assert!([px.len(), py.len(), pz.len()] == [len; 3]);
        for shape in self.shapes {
            if let Some(slot) = shape.slot() {
                assert!(
                    slot * self.lanes + end <= len,
                    "a held shape's planes for its lanes"
                );
            }
        }
    }

    /// The plane (normal, offset) of lane `i` in `slot`.
    #[inline(always)]
    fn plane(&self, slot: usize, i: usize) -> ([f32; 3], f32) {
        let at = slot * self.lanes + i;
        let [x, y, z, offset] = self.planes;
        ([x[at], y[at], z[at]], offset[at])
    }
}

/// A chunk of lanes: positions now and at the substep's start (m),
/// inverse masses (1/kg), and the record of the pushes.
struct Chunk<'a> {
    /// The index of its first lane among all.
    first: usize,
    x: &'a mut [f32],
    y: &'a mut [f32],
    z: &'a mut [f32],
    start: [&'a [f32]; 3],
    w: &'a [f32],
    depth: &'a mut [f32],
    touch: &'a mut [u32],
}

impl<'a> Chunk<'a> {
    /// The lanes in the chunk, every array checked to hold them all (once
    /// a pass, so that the steps' indexing needs no more checks).
    #[inline(always)]
    fn len(&self) -> usize {
        let n = self.x.len();
        let lens = [self.y.len(), self.z.len(), self.w.len()];
        assert!(lens == [n; 3] && [self.depth.len(), self.touch.len()] == [n; 2]);
        assert!(self.start.iter().all(|s| s.len() == n));
        n
    }

    /// The lanes of this chunk from `start` on.
    #[cfg(target_arch = "x86_64")]
    fn from(self, start: usize) -> Chunk<'a> {
        Chunk {
            first: self.first + start,
            x: &mut self.x[start..],
            y: &mut self.y[start..],
            z: &mut self.z[start..],
            start: self.start.map(|s| &s[start..]),
            w: &self.w[start..],
            depth: &mut self.depth[start..],
            touch: &mut self.touch[start..],
        }
    }
}

/// [`run_lanes`], vectorised for AVX2 when `simd` (the same operations
/// lane by lane, no fused multiply-add: the same bits).
fn run(chunk: Chunk, law: &Law, simd: bool) -> f32 {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        return unsafe { run_avx2(chunk, law) };
    }
    let _ = simd;
    run_lanes(chunk, law)
}

/// [`run_lanes`] with AVX2 intrinsics for every whole step of eight lanes,
/// straight from the chunk's arrays and back (written as arrays selected
/// lane by lane, the whole steps compiled to masked stores whose reloads
/// could not be forwarded: a sixth of the drape's frame at N = 128); the
/// short last step as the portable pass runs it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn run_avx2(mut chunk: Chunk, law: &Law) -> f32 {
    crate::math::align_frame();
    use std::arch::x86_64::*;
    let n = chunk.len();
    let whole = n - n % W;
    // Once a chunk, for the steps' unchecked loads of the cuboids' planes
    // (checked in every step, the comparison of the arrays' lengths went
    // through the stack and stalled on store forwarding: half of this
    // pass on the `box`).
    law.check_planes(chunk.first + whole);
    let mut far = _mm256_setzero_ps();
    // Whether a shape moves, once a chunk: the relative slide's three
    // more vectors in every step cost the still scenes a tenth of the pass.
    if law.shifts.is_some() {
        for k in (0..whole).step_by(W) {
            eight_avx2::<true>(&mut chunk, k, law, &mut far);
        }
    } else {
        for k in (0..whole).step_by(W) {
            eight_avx2::<false>(&mut chunk, k, law, &mut far);
        }
    }
    let rest = run_lanes(chunk.from(whole), law);
    let mut lanes = [0.0f32; W];
    _mm256_storeu_ps(lanes.as_mut_ptr(), far);
    lanes.into_iter().fold(rest, f32::max)
}

/// [`eight`] on lanes `k..k + 8` of `c` (all in it), in AVX2 registers:
/// the same operations in the same order, without fused multiply-add,
/// so the same bits; keeps in `far` the farthest push of each lane.
/// Writes nothing where no lane is inside a shape nor (with friction)
/// was pushed this substep: the pass would leave every bit as it is.
///
/// # Safety
/// The CPU has AVX2, and [`Law::check_planes`] held for lanes up to
/// `c.first + k + 8`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn eight_avx2<const MOVING: bool>(
    c: &mut Chunk,
    k: usize,
    law: &Law,
    far: &mut std::arch::x86_64::__m256,
) {
    use std::arch::x86_64::*;
    let at = k..k + W;
    let (x, y, z) = (
        c.x[at.clone()].as_mut_ptr(),
        c.y[at.clone()].as_mut_ptr(),
        c.z[at.clone()].as_mut_ptr(),
    );
    let depth_at = c.depth[at.clone()].as_mut_ptr();
    let touch_at = c.touch[at.clone()].as_mut_ptr() as *mut __m256i;
    let mut p = [_mm256_loadu_ps(x), _mm256_loadu_ps(y), _mm256_loadu_ps(z)];
    let zero = _mm256_setzero_ps();
    let free = _mm256_cmp_ps::<_CMP_NEQ_UQ>(_mm256_loadu_ps(c.w[at.clone()].as_ptr()), zero);
    let mut depth = _mm256_loadu_ps(depth_at);
    let mut touch = _mm256_castsi256_ps(_mm256_loadu_si256(touch_at));
    let mut normal = [zero; 3];
    let mut mu = zero;
    let mut shift = [zero; 3];
    let mut any_inside = zero;
    for (o, &shape) in law.shapes.iter().enumerate() {
        let mark = _mm256_castsi256_ps(_mm256_set1_epi32(o as i32 + 1));
        // The lanes this shape pushed last (a lane it pushed goes on
        // taking its normal and friction even when now clear of it).
        let its = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_castps_si256(touch),
            _mm256_castps_si256(mark),
        ));
        let (to, n, inside, push);
        match shape {
            StillShape::Ball { centre, reach } => {
                let centre = [centre.x, centre.y, centre.z].map(|v| _mm256_set1_ps(v));
                let Some(out) = round_avx2(p, (centre, reach, shape.way_out()), (its, free)) else {
                    continue;
                };
                (to, n, inside, push) = out;
            }
            StillShape::Capsule {
                from,
                axis,
                length,
                reach,
                ..
            } => {
                let from = [from.x, from.y, from.z].map(|v| _mm256_set1_ps(v));
                let u = [axis.x, axis.y, axis.z].map(|v| _mm256_set1_ps(v));
                let d = [0, 1, 2].map(|a| _mm256_sub_ps(p[a], from[a]));
                let along = _mm256_add_ps(
                    _mm256_add_ps(_mm256_mul_ps(d[0], u[0]), _mm256_mul_ps(d[1], u[1])),
                    _mm256_mul_ps(d[2], u[2]),
                );
                let t = _mm256_min_ps(_mm256_max_ps(along, zero), _mm256_set1_ps(length));
                let centre = [0, 1, 2].map(|a| _mm256_add_ps(from[a], _mm256_mul_ps(u[a], t)));
                let Some(out) = round_avx2(p, (centre, reach, shape.way_out()), (its, free)) else {
                    continue;
                };
                (to, n, inside, push) = out;
            }
            StillShape::Plane { normal: m, offset } => {
                let m = [m.x, m.y, m.z].map(|v| _mm256_set1_ps(v));
                let (gap, on) = behind_plane_avx2(m, _mm256_set1_ps(offset), p);
                n = m;
                to = on;
                inside = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(gap, zero), free);
                push = _mm256_and_ps(inside, gap);
            }
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => {
                // This lane's plane, taken at the substep's start.
                // SAFETY: within every plane array, checked once a chunk
                // (`Law::check_planes`).
                let at = slot * law.lanes + c.first + k;
                let [px, py, pz, po] = law.planes;
                debug_assert!(
                    at + W <= po.len() && [px.len(), py.len(), pz.len()] == [po.len(); 3]
                );
                let m = [
                    _mm256_loadu_ps(px.as_ptr().add(at)),
                    _mm256_loadu_ps(py.as_ptr().add(at)),
                    _mm256_loadu_ps(pz.as_ptr().add(at)),
                ];
                let offset = _mm256_loadu_ps(po.as_ptr().add(at));
                let (gap, on) = behind_plane_avx2(m, offset, p);
                let behind = _mm256_cmp_ps::<_CMP_GT_OQ>(gap, zero);
                // No lane behind its plane nor last pushed by it: as for
                // the ball.
                if _mm256_movemask_ps(_mm256_or_ps(behind, its)) == 0 {
                    continue;
                }
                n = m;
                to = on;
                inside = _mm256_and_ps(behind, free);
                push = _mm256_and_ps(inside, gap);
            }
        }
        let coefficient = _mm256_set1_ps(law.friction.map_or(0.0, |f| f[o]));
        p = [0, 1, 2].map(|a| _mm256_blendv_ps(p[a], to[a], inside));
        depth = _mm256_add_ps(depth, push);
        touch = _mm256_blendv_ps(touch, mark, inside);
        // No push is NaN or −0: `max` as `f32::max` takes it.
        *far = _mm256_max_ps(*far, push);
        any_inside = _mm256_or_ps(any_inside, inside);
        let this = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_castps_si256(touch),
            _mm256_castps_si256(mark),
        ));
        normal = [0, 1, 2].map(|a| _mm256_blendv_ps(normal[a], n[a], this));
        mu = _mm256_blendv_ps(mu, coefficient, this);
        if let (true, Some(shifts)) = (MOVING, law.shifts) {
            let s = shifts[o];
            let s = [s.x, s.y, s.z].map(|v| _mm256_set1_ps(v));
            shift = [0, 1, 2].map(|a| _mm256_blendv_ps(shift[a], s[a], this));
        }
    }
    let touched = _mm256_xor_ps(
        _mm256_castsi256_ps(_mm256_cmpeq_epi32(
            _mm256_castps_si256(touch),
            _mm256_setzero_si256(),
        )),
        _mm256_castsi256_ps(_mm256_set1_epi32(-1)),
    );
    let slides = law.friction.is_some() && _mm256_movemask_ps(touched) != 0;
    if _mm256_movemask_ps(any_inside) == 0 && !slides {
        return;
    }
    if slides {
        let start = c.start.map(|s| _mm256_loadu_ps(s[at.clone()].as_ptr()));
        let mut slide = [0, 1, 2].map(|a| _mm256_sub_ps(p[a], start[a]));
        if MOVING {
            // Relative to the surface, which moved too.
            slide = [0, 1, 2].map(|a| _mm256_sub_ps(slide[a], shift[a]));
        }
        let along = _mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(normal[0], slide[0]),
                _mm256_mul_ps(normal[1], slide[1]),
            ),
            _mm256_mul_ps(normal[2], slide[2]),
        );
        let tangent = [0, 1, 2].map(|a| _mm256_sub_ps(slide[a], _mm256_mul_ps(normal[a], along)));
        let length = _mm256_sqrt_ps(_mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(tangent[0], tangent[0]),
                _mm256_mul_ps(tangent[1], tangent[1]),
            ),
            _mm256_mul_ps(tangent[2], tangent[2]),
        ));
        let allowed = _mm256_mul_ps(mu, depth);
        let whole = _mm256_cmp_ps::<_CMP_LE_OQ>(length, allowed);
        let scale = _mm256_div_ps(allowed, length);
        p = [0, 1, 2].map(|a| {
            let undone = _mm256_blendv_ps(_mm256_mul_ps(tangent[a], scale), tangent[a], whole);
            _mm256_blendv_ps(p[a], _mm256_sub_ps(p[a], undone), touched)
        });
    }
    _mm256_storeu_ps(x, p[0]);
    _mm256_storeu_ps(y, p[1]);
    _mm256_storeu_ps(z, p[2]);
    _mm256_storeu_ps(depth_at, depth);
    _mm256_storeu_si256(touch_at, _mm256_castps_si256(touch));
}

/// Eight lanes at `p` (m) against balls of radius `reach` (m) at `centre`
/// (m, one a lane), a lane at a squared distance up to `tiny` (m²) from
/// its centre put out along `up` ([`StillShape::way_out`]): the point each
/// is put back to, the outward normal, which lanes are inside (and free:
/// `free`) and how far they are pushed (m), as the portable pass computes
/// them; `None` when no lane is near its ball nor last pushed by this
/// shape (`its`): the shape would change no bit, and its square root and
/// division are the pass's dearest operations.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
#[allow(clippy::type_complexity)]
unsafe fn round_avx2(
    p: [std::arch::x86_64::__m256; 3],
    (centre, reach, (up, tiny)): ([std::arch::x86_64::__m256; 3], f32, (Vector, f32)),
    (its, free): (std::arch::x86_64::__m256, std::arch::x86_64::__m256),
) -> Option<(
    [std::arch::x86_64::__m256; 3],
    [std::arch::x86_64::__m256; 3],
    std::arch::x86_64::__m256,
    std::arch::x86_64::__m256,
)> {
    use std::arch::x86_64::*;
    let d = [0, 1, 2].map(|a| _mm256_sub_ps(p[a], centre[a]));
    let d2 = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(d[0], d[0]), _mm256_mul_ps(d[1], d[1])),
        _mm256_mul_ps(d[2], d[2]),
    );
    // With a margin for the rounding of the square.
    let near = _mm256_cmp_ps::<_CMP_LT_OQ>(d2, _mm256_set1_ps(near_ball(reach)));
    if _mm256_movemask_ps(_mm256_or_ps(near, its)) == 0 {
        return None;
    }
    let reach = _mm256_set1_ps(reach);
    let length = _mm256_sqrt_ps(d2);
    let recip = _mm256_div_ps(_mm256_set1_ps(1.0), length);
    // At the centre itself: out along `up`.
    let at_centre = _mm256_cmp_ps::<_CMP_LE_OQ>(d2, _mm256_set1_ps(tiny));
    let up = [up.x, up.y, up.z];
    let n = [0, 1, 2]
        .map(|a| _mm256_blendv_ps(_mm256_mul_ps(d[a], recip), _mm256_set1_ps(up[a]), at_centre));
    let to = [0, 1, 2].map(|a| _mm256_add_ps(centre[a], _mm256_mul_ps(n[a], reach)));
    let inside = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(length, reach), free);
    let push = _mm256_and_ps(inside, _mm256_sub_ps(reach, length));
    Some((to, n, inside, push))
}

/// Eight lanes at `p` (m) against the half-spaces `m · x ≥ offset` (unit
/// normals `m`, offsets in m): how far behind its plane each is (m,
/// negative in front) and its point on the plane, as the portable pass
/// computes them.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn behind_plane_avx2(
    m: [std::arch::x86_64::__m256; 3],
    offset: std::arch::x86_64::__m256,
    p: [std::arch::x86_64::__m256; 3],
) -> (std::arch::x86_64::__m256, [std::arch::x86_64::__m256; 3]) {
    use std::arch::x86_64::*;
    let gap = _mm256_sub_ps(
        offset,
        _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(m[0], p[0]), _mm256_mul_ps(m[1], p[1])),
            _mm256_mul_ps(m[2], p[2]),
        ),
    );
    let on = [
        _mm256_add_ps(p[0], _mm256_mul_ps(m[0], gap)),
        _mm256_add_ps(p[1], _mm256_mul_ps(m[1], gap)),
        _mm256_add_ps(p[2], _mm256_mul_ps(m[2], gap)),
    ];
    (gap, on)
}

/// [`planes_of`] for every whole eight lanes, in AVX2; returns how many
/// lanes it took (the rest are left to the portable pass).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn planes_avx2(
    cuboid: &StillCuboid,
    (start, w): ([&[f32]; 3], &[f32]),
    out: &mut [&mut [f32]; 4],
) -> usize {
    crate::math::align_frame();
    use std::arch::x86_64::*;
    let n = start[0].len();
    assert!(start.iter().all(|s| s.len() == n) && out.iter().all(|o| o.len() == n));
    assert!(w.len() == n);
    let mut k = 0;
    while k + W <= n {
        // SAFETY: lanes `k..k + 8` are within every array (asserted).
        let s = [
            _mm256_loadu_ps(start[0].as_ptr().add(k)),
            _mm256_loadu_ps(start[1].as_ptr().add(k)),
            _mm256_loadu_ps(start[2].as_ptr().add(k)),
        ];
        let pinned =
            _mm256_cmp_ps::<_CMP_EQ_OQ>(_mm256_loadu_ps(w.as_ptr().add(k)), _mm256_setzero_ps());
        let local = cuboid_local_avx2(cuboid, s);
        let far = _mm256_or_ps(far_from_cuboid_avx2(cuboid, local), pinned);
        let (normal, offset) = if _mm256_movemask_ps(far) == 0xff {
            // All eight far or pinned: the kernel's sqrt and division for
            // nothing (the `tear`'s two bars over its sheet, planes a
            // seventh of the frame before).
            ([_mm256_setzero_ps(); 3], _mm256_set1_ps(f32::NEG_INFINITY))
        } else {
            let (normal, offset) = cuboid_plane_avx2(cuboid, (s, local));
            (
                normal.map(|n| _mm256_andnot_ps(far, n)),
                _mm256_blendv_ps(offset, _mm256_set1_ps(f32::NEG_INFINITY), far),
            )
        };
        for a in 0..3 {
            _mm256_storeu_ps(out[a].as_mut_ptr().add(k), normal[a]);
        }
        _mm256_storeu_ps(out[3].as_mut_ptr().add(k), offset);
        k += W;
    }
    k
}

/// Where eight lanes at `p` (m) are in the frame of `cuboid` (m along
/// each of its axes from its centre), as [`StillCuboid::local`] finds
/// them, in AVX2 registers: the same operations in the same order. Found
/// once for both [`far_from_cuboid_avx2`] and [`cuboid_plane_avx2`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn cuboid_local_avx2(
    cuboid: &StillCuboid,
    p: [std::arch::x86_64::__m256; 3],
) -> [std::arch::x86_64::__m256; 3] {
    // Loops over the axes, not closures ([`cuboid_plane_avx2`] says why).
    use std::arch::x86_64::*;
    let centre = [cuboid.centre.x, cuboid.centre.y, cuboid.centre.z];
    let mut d = [_mm256_setzero_ps(); 3];
    for a in 0..3 {
        d[a] = _mm256_sub_ps(p[a], _mm256_set1_ps(centre[a]));
    }
    let mut local = [_mm256_setzero_ps(); 3];
    for a in 0..3 {
        let axis = cuboid.axes[a];
        local[a] = _mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(_mm256_set1_ps(axis.x), d[0]),
                _mm256_mul_ps(_mm256_set1_ps(axis.y), d[1]),
            ),
            _mm256_mul_ps(_mm256_set1_ps(axis.z), d[2]),
        );
    }
    local
}

/// Which of eight lanes at `local` in the frame of `cuboid`
/// ([`cuboid_local_avx2`]) are surely beyond its reach
/// ([`far_from_cuboid`]), in AVX2 registers: the same operations in the
/// same order.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn far_from_cuboid_avx2(
    cuboid: &StillCuboid,
    local: [std::arch::x86_64::__m256; 3],
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let sign_bit = _mm256_set1_ps(-0.0);
    let half = [cuboid.half.x, cuboid.half.y, cuboid.half.z];
    let mut most = _mm256_set1_ps(f32::NEG_INFINITY);
    for a in 0..3 {
        let beyond = _mm256_sub_ps(
            _mm256_andnot_ps(sign_bit, local[a]),
            _mm256_set1_ps(half[a]),
        );
        most = _mm256_max_ps(most, beyond);
    }
    _mm256_cmp_ps::<_CMP_GT_OQ>(most, _mm256_set1_ps(cuboid.far()))
}

/// [`cuboid_plane`] for eight lanes that start at `start`, in AVX2
/// registers: the same operations in the same order, without fused
/// multiply-add, so the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn cuboid_plane_avx2(
    cuboid: &StillCuboid,
    (start, local): (
        [std::arch::x86_64::__m256; 3],
        [std::arch::x86_64::__m256; 3],
    ),
) -> ([std::arch::x86_64::__m256; 3], std::arch::x86_64::__m256) {
    // Written with loops over the three axes, not closures: a closure
    // does not take the function's AVX2 and was called with its vectors
    // in memory (planes a ninth of the `box`'s frame so).
    use std::arch::x86_64::*;
    let zero = _mm256_setzero_ps();
    let one = _mm256_set1_ps(1.0);
    let all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    let sign_bit = _mm256_set1_ps(-0.0);
    let t = _mm256_set1_ps(cuboid.thickness);
    let half = [cuboid.half.x, cuboid.half.y, cuboid.half.z];
    let mut axes = [[zero; 3]; 3];
    for a in 0..3 {
        let axis = cuboid.axes[a];
        axes[a] = [
            _mm256_set1_ps(axis.x),
            _mm256_set1_ps(axis.y),
            _mm256_set1_ps(axis.z),
        ];
    }
    let (mut abs, mut sign, mut beyond) = ([zero; 3], [zero; 3], [zero; 3]);
    let (mut positive, mut over) = ([zero; 3], [zero; 3]);
    for a in 0..3 {
        let local = local[a];
        abs[a] = _mm256_andnot_ps(sign_bit, local);
        sign[a] = _mm256_or_ps(_mm256_and_ps(local, sign_bit), one);
        beyond[a] = _mm256_sub_ps(abs[a], _mm256_set1_ps(half[a]));
        positive[a] = _mm256_cmp_ps::<_CMP_GT_OQ>(beyond[a], zero);
        over[a] = _mm256_and_ps(positive[a], beyond[a]);
    }
    let dist2 = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(over[0], over[0]),
            _mm256_mul_ps(over[1], over[1]),
        ),
        _mm256_mul_ps(over[2], over[2]),
    );
    let outside = _mm256_cmp_ps::<_CMP_GT_OQ>(dist2, zero);
    let dist = _mm256_sqrt_ps(dist2);
    let recip = _mm256_div_ps(one, dist);
    let scale = _mm256_mul_ps(t, recip);
    let x_face = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GE_OQ>(beyond[0], beyond[1]),
        _mm256_cmp_ps::<_CMP_GE_OQ>(beyond[0], beyond[2]),
    );
    let y_face = _mm256_andnot_ps(x_face, _mm256_cmp_ps::<_CMP_GE_OQ>(beyond[1], beyond[2]));
    let z_face = _mm256_andnot_ps(_mm256_or_ps(x_face, y_face), all);
    let face = [x_face, y_face, z_face];
    let mut delta = [zero; 3];
    let mut normal_local = [zero; 3];
    for a in 0..3 {
        let h = _mm256_set1_ps(half[a]);
        let out_delta = _mm256_and_ps(
            positive[a],
            _mm256_sub_ps(_mm256_add_ps(h, _mm256_mul_ps(over[a], scale)), abs[a]),
        );
        let face_delta = _mm256_and_ps(face[a], _mm256_sub_ps(_mm256_add_ps(h, t), abs[a]));
        delta[a] = _mm256_mul_ps(_mm256_blendv_ps(face_delta, out_delta, outside), sign[a]);
        let face_normal = _mm256_and_ps(face[a], one);
        normal_local[a] = _mm256_mul_ps(
            _mm256_blendv_ps(face_normal, _mm256_mul_ps(over[a], recip), outside),
            sign[a],
        );
    }
    let [u, v, w] = axes;
    let (mut on, mut normal) = ([zero; 3], [zero; 3]);
    for c in 0..3 {
        let moved = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(u[c], delta[0]), _mm256_mul_ps(v[c], delta[1])),
            _mm256_mul_ps(w[c], delta[2]),
        );
        on[c] = _mm256_add_ps(start[c], moved);
        normal[c] = _mm256_add_ps(
            _mm256_add_ps(
                _mm256_mul_ps(u[c], normal_local[0]),
                _mm256_mul_ps(v[c], normal_local[1]),
            ),
            _mm256_mul_ps(w[c], normal_local[2]),
        );
    }
    let applies = _mm256_or_ps(
        _mm256_andnot_ps(outside, all),
        _mm256_cmp_ps::<_CMP_LT_OQ>(dist, _mm256_set1_ps(cuboid.reach)),
    );
    let offset = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(normal[0], on[0]),
            _mm256_mul_ps(normal[1], on[1]),
        ),
        _mm256_mul_ps(normal[2], on[2]),
    );
    let from = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(normal[0], start[0]),
            _mm256_mul_ps(normal[1], start[1]),
        ),
        _mm256_mul_ps(normal[2], start[2]),
    );
    let deep = _mm256_sub_ps(offset, _mm256_set1_ps(cuboid.settle));
    let offset = _mm256_blendv_ps(offset, from, _mm256_cmp_ps::<_CMP_LT_OQ>(from, deep));
    let none = _mm256_set1_ps(f32::NEG_INFINITY);
    (normal, _mm256_blendv_ps(none, offset, applies))
}

/// Lanes of one vector step of [`run_lanes`] (AVX2's eight `f32`).
const W: usize = 8;

/// Eight lanes of a chunk, copied into registers: positions now and at
/// the substep's start (m), inverse masses, pushes (m) and marks.
#[derive(Clone, Copy)]
struct Eight {
    /// The index of the first among all lanes, and how many are lanes
    /// (the rest pad a short last step).
    at: usize,
    count: usize,
    p: [[f32; W]; 3],
    start: [[f32; W]; 3],
    w: [f32; W],
    depth: [f32; W],
    touch: [u32; W],
}

impl Eight {
    /// The half-space (unit normal, offset: `normal · x ≥ offset`) that
    /// `shape` holds lane `k` of these eight in: a plane's own, a
    /// cuboid's plane for the lane; none (an offset of −∞) for a ball.
    #[inline(always)]
    fn half_space(&self, law: &Law, shape: StillShape, k: usize) -> ([f32; 3], f32) {
        match shape {
            StillShape::Plane { normal, offset } => ([normal.x, normal.y, normal.z], offset),
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => self.plane(law, slot, k),
            StillShape::Ball { .. } | StillShape::Capsule { .. } => ([0.0; 3], f32::NEG_INFINITY),
        }
    }

    /// The plane (normal, offset) of lane `k` of these eight in the
    /// cuboid's `slot` (none for padding).
    #[inline(always)]
    fn plane(&self, law: &Law, slot: usize, k: usize) -> ([f32; 3], f32) {
        if k < self.count {
            law.plane(slot, self.at + k)
        } else {
            ([0.0; 3], f32::NEG_INFINITY)
        }
    }
}

/// The pass of `law` over the lanes of `c`, eight at a time on copies in
/// registers, written back whole (as one loop over lanes, or through
/// references the compiler could not prove apart, it stayed scalar: a
/// quarter of the frame at N = 64). The last, short step runs on copies
/// padded with pinned lanes. Returns the farthest push (m).
#[inline(always)]
fn run_lanes(c: Chunk, law: &Law) -> f32 {
    let n = c.len();
    let mut farthest = [0.0f32; W];
    let mut k = 0;
    while k < n {
        let m = W.min(n - k);
        let mut e = Eight {
            at: c.first + k,
            count: m,
            p: [[0.0; W]; 3],
            start: [[0.0; W]; 3],
            w: [0.0; W],
            depth: [0.0; W],
            touch: [0; W],
        };
        if m == W {
            e.p = [
                c.x[k..k + W].try_into().expect("eight"),
                c.y[k..k + W].try_into().expect("eight"),
                c.z[k..k + W].try_into().expect("eight"),
            ];
            // Eight lanes clear of every shape and (for friction) pushed by
            // none this substep: the pass would leave every bit as it is.
            let touched = || c.touch[k..k + W].iter().any(|&t| t != 0);
            if !maybe_inside(&e, law) && (law.friction.is_none() || !touched()) {
                k += W;
                continue;
            }
            if law.friction.is_some() {
                for a in 0..3 {
                    e.start[a] = c.start[a][k..k + W].try_into().expect("eight");
                }
            }
            e.w = c.w[k..k + W].try_into().expect("eight");
            e.depth = c.depth[k..k + W].try_into().expect("eight");
            e.touch = c.touch[k..k + W].try_into().expect("eight");
        } else {
            e.p[0][..m].copy_from_slice(&c.x[k..n]);
            e.p[1][..m].copy_from_slice(&c.y[k..n]);
            e.p[2][..m].copy_from_slice(&c.z[k..n]);
            for a in 0..3 {
                e.start[a][..m].copy_from_slice(&c.start[a][k..n]);
            }
            e.w[..m].copy_from_slice(&c.w[k..n]);
            e.depth[..m].copy_from_slice(&c.depth[k..n]);
            e.touch[..m].copy_from_slice(&c.touch[k..n]);
        }
        eight(&mut e, law, &mut farthest);
        let out = &e;
        if m == W {
            // Stores of a known length, in registers (`copy_from_slice`
            // of a run of unknown length calls `memmove`: 14% of the
            // frame at N = 64).
            *whole(&mut c.x[k..k + W]) = out.p[0];
            *whole(&mut c.y[k..k + W]) = out.p[1];
            *whole(&mut c.z[k..k + W]) = out.p[2];
            *whole(&mut c.depth[k..k + W]) = out.depth;
            let touch: &mut [u32; W] = (&mut c.touch[k..k + W]).try_into().expect("eight");
            *touch = out.touch;
        } else {
            c.x[k..n].copy_from_slice(&out.p[0][..m]);
            c.y[k..n].copy_from_slice(&out.p[1][..m]);
            c.z[k..n].copy_from_slice(&out.p[2][..m]);
            c.depth[k..n].copy_from_slice(&out.depth[..m]);
            c.touch[k..n].copy_from_slice(&out.touch[..m]);
        }
        k += m;
    }
    farthest.into_iter().fold(0.0, f32::max)
}

/// Whether a lane of `e` may lie inside one of the shapes of `law` (the
/// test of [`eight`], with a margin for the rounding of a squared
/// distance: never false where that test is true).
#[inline(always)]
fn maybe_inside(e: &Eight, law: &Law) -> bool {
    let p = &e.p;
    let mut any = false;
    for &shape in law.shapes {
        match shape {
            StillShape::Ball { reach, .. } | StillShape::Capsule { reach, .. } => {
                let near = near_ball(reach);
                for k in 0..W {
                    let c = shape.centre_for([p[0][k], p[1][k], p[2][k]]);
                    let d = [p[0][k] - c[0], p[1][k] - c[1], p[2][k] - c[2]];
                    any |= d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < near;
                }
            }
            StillShape::Plane { normal: m, offset } => {
                for k in 0..W {
                    any |= offset - (m.x * p[0][k] + m.y * p[1][k] + m.z * p[2][k]) > 0.0;
                }
            }
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => {
                for k in 0..W {
                    let (m, offset) = e.plane(law, slot, k);
                    any |= offset - (m[0] * e.p[0][k] + m[1] * e.p[1][k] + m[2] * e.p[2][k]) > 0.0;
                }
            }
        }
    }
    any
}

impl StillShape {
    /// The centre (m) of the ball that holds a lane at `p` (m): a ball's
    /// own, a capsule's axis point nearest `p` (the same operations as the
    /// AVX2 pass); the origin for the other shapes, which take no centre.
    #[inline(always)]
    fn centre_for(&self, p: [f32; 3]) -> [f32; 3] {
        match *self {
            StillShape::Ball { centre, .. } => [centre.x, centre.y, centre.z],
            StillShape::Capsule {
                from, axis, length, ..
            } => {
                let d = [p[0] - from.x, p[1] - from.y, p[2] - from.z];
                let along = d[0] * axis.x + d[1] * axis.y + d[2] * axis.z;
                let t = along.max(0.0).min(length);
                [
                    from.x + axis.x * t,
                    from.y + axis.y * t,
                    from.z + axis.z * t,
                ]
            }
            StillShape::Plane { .. }
            | StillShape::Cuboid(_)
            | StillShape::Convex(_)
            | StillShape::Mesh(_) => [0.0; 3],
        }
    }

    /// The slot of the lanes' plane records of a cuboid or other convex
    /// shape; none for the shapes held without planes.
    #[inline(always)]
    fn slot(&self) -> Option<usize> {
        match *self {
            StillShape::Cuboid(StillCuboid { slot, .. })
            | StillShape::Convex(StillConvex { slot, .. })
            | StillShape::Mesh(StillMesh {
                held: StillConvex { slot, .. },
                ..
            }) => Some(slot),
            _ => None,
        }
    }

    /// Which way (a unit vector) a ball or capsule puts out a lane at its
    /// centre, and within what squared distance (m²) of it a lane is
    /// there: a ball's top, at the centre itself; a capsule's `across`,
    /// within [`ON_AXIS`] of its reach.
    #[inline(always)]
    fn way_out(&self) -> (Vector, f32) {
        match *self {
            StillShape::Capsule {
                across, on_axis2, ..
            } => (across, on_axis2),
            _ => (Vector::Y, 0.0),
        }
    }
}

impl StillCuboid {
    /// How far (m) out along one of its axes a lane must start to be
    /// surely beyond its reach ([`far_from_cuboid`]): the reach and a
    /// margin over the rounding of the distance to it.
    #[inline(always)]
    fn far(&self) -> f32 {
        self.reach * (1.0 + 1.0e-4)
    }

    /// Whether the cuboid's bounding box grown by `margin` (m), and a hair
    /// for rounding, meets the box `(lo, hi)` (m).
    fn box_meets(&self, (lo, hi): (Vector, Vector), margin: f32) -> bool {
        let extent = self.axes[0].abs() * self.half.x
            + self.axes[1].abs() * self.half.y
            + self.axes[2].abs() * self.half.z;
        let grown = extent + Vector::splat(margin * (1.0 + 1.0e-3) + 1.0e-6);
        let (min, max) = (self.centre - grown, self.centre + grown);
        min.cmple(hi).all() && lo.cmple(max).all()
    }

    /// Where `p` (m) is in the cuboid's frame: per axis, the coordinate
    /// and how far beyond the face on that side it is (m, negative inside).
    #[inline(always)]
    fn local(&self, p: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let d = [
            p[0] - self.centre.x,
            p[1] - self.centre.y,
            p[2] - self.centre.z,
        ];
        let half = [self.half.x, self.half.y, self.half.z];
        let mut local = [0.0f32; 3];
        let mut beyond = [0.0f32; 3];
        for a in 0..3 {
            let axis = self.axes[a];
            local[a] = axis.x * d[0] + axis.y * d[1] + axis.z * d[2];
            beyond[a] = local[a].abs() - half[a];
        }
        (local, beyond)
    }
}

/// Bit `i` set for each `i < count` (at most 32) where `fa[i]` and `fb[i]`
/// share no face (the spring between them may come near the cuboid): on
/// x86-64 sixteen at a time in SSE2 (which every such CPU has).
#[inline(always)]
fn apart_from_faces(fa: &[u8], fb: &[u8], count: usize) -> u32 {
    let (fa, fb) = (&fa[..count], &fb[..count]);
    let mut due = 0u32;
    let mut i = 0;
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        while i + 16 <= count {
            // SAFETY: bytes `i..i + 16` are within both (checked above);
            // SSE2 is part of x86-64.
            let shared = unsafe {
                let a = _mm_loadu_si128(fa.as_ptr().add(i) as *const __m128i);
                let b = _mm_loadu_si128(fb.as_ptr().add(i) as *const __m128i);
                _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_and_si128(a, b), _mm_setzero_si128()))
            };
            due |= (shared as u32) << i;
            i += 16;
        }
    }
    while i < count {
        due |= u32::from(fa[i] & fb[i] == 0) << i;
        i += 1;
    }
    due
}

impl StillCuboid {
    /// The faces `p` (m) is at least `margin` (m) beyond or over: bit `2a`
    /// for the face on the positive side of axis `a`, bit `2a + 1` for the
    /// negative; over a face is on its side of the centre and within the
    /// face's rectangle along the other two axes. A segment whose two ends
    /// share a bit comes no nearer the cuboid than its nearer end (a face's
    /// plane has the cuboid behind it, and over the face the distance is
    /// the height above its plane, which changes linearly along the
    /// segment): nothing to keep off an edge there, and the ends are the
    /// lanes' contacts' (the collision stage's edge pass passes over such
    /// springs too: both ends on one smooth stretch of surface). A sheet
    /// laid within the thickness of a ramp's face is so left to the
    /// contacts, which put it out gently, not thrown out by the springs.
    /// Without a branch.
    #[inline(always)]
    fn faces_beyond(&self, p: [f32; 3], margin: f32) -> u8 {
        let (local, beyond) = self.local(p);
        let half = [self.half.x, self.half.y, self.half.z];
        let within = beyond.map(|b| b <= 0.0);
        let mut bits = 0u8;
        for a in 0..3 {
            let out = half[a] + margin;
            let over = within[(a + 1) % 3] & within[(a + 2) % 3];
            bits |= u8::from((local[a] >= out) | (over & (local[a] >= 0.0))) << (2 * a);
            bits |= u8::from((local[a] <= -out) | (over & (local[a] < 0.0))) << (2 * a + 1);
        }
        bits
    }

    /// [`Self::faces_beyond`] for every lane at `p` (m), into `faces`
    /// (without a branch: with them, the loop was 7% of the `box`'s
    /// frame, 4% so).
    fn mark_faces_beyond(&self, p: [&[f32]; 3], margin: f32, faces: &mut [u8]) {
        let n = faces.len();
        let [x, y, z] = p.map(|a| &a[..n]);
        for k in 0..n {
            faces[k] = self.faces_beyond([x[k], y[k], z[k]], margin);
        }
    }

    /// Whether `p` (m) is surely at least `margin` (m) out of the cuboid
    /// (outside it by the square of its distance: no root).
    #[inline(always)]
    fn surely_beyond(&self, p: [f32; 3], margin: f32) -> bool {
        let (_, beyond) = self.local(p);
        let over = beyond.map(|b| b.max(0.0));
        over[0] * over[0] + over[1] * over[1] + over[2] * over[2] >= margin * margin
    }

    /// The signed distance (m, negative inside) of `p` (m) from the
    /// cuboid itself (not rounded), and the outward unit normal there:
    /// outside, from the nearest point of the surface; inside, of the
    /// nearest face (the first of equals).
    fn signed_distance(&self, p: [f32; 3]) -> (f32, [f32; 3]) {
        let (local, beyond) = self.local(p);
        let over = beyond.map(|b| b.max(0.0));
        let dist2 = over[0] * over[0] + over[1] * over[1] + over[2] * over[2];
        let mut normal_local = [0.0f32; 3];
        let distance = if dist2 > 0.0 {
            let dist = dist2.sqrt();
            for a in 0..3 {
                normal_local[a] = (over[a] / dist).copysign(local[a]);
            }
            dist
        } else {
            let face = if beyond[0] >= beyond[1] && beyond[0] >= beyond[2] {
                0
            } else if beyond[1] >= beyond[2] {
                1
            } else {
                2
            };
            normal_local[face] = 1.0f32.copysign(local[face]);
            beyond[face]
        };
        let [u, v, w] = self.axes;
        let normal = u * normal_local[0] + v * normal_local[1] + w * normal_local[2];
        (distance, [normal.x, normal.y, normal.z])
    }

    /// The collision stage's edge pass on one spring against this cuboid
    /// (`CollisionStage::resolve_spring`): its ends at `pa` and `pb` (m,
    /// inverse masses `wa`, `wb`) moved so that its samples lie at least
    /// `margin` (m) out of it. Returns the farthest it moved an end (m).
    fn keep_spring_off(
        &self,
        (pa, wa): (&mut [f32; 3], f32),
        (pb, wb): (&mut [f32; 3], f32),
        margin: f32,
    ) -> f32 {
        if wa == 0.0 && wb == 0.0 {
            return 0.0;
        }
        // A pinned end held inside cannot be moved out: pushing the free
        // end would only shove it about.
        let pinned_inside = |p: [f32; 3], w: f32| w == 0.0 && self.signed_distance(p).0 < 0.0;
        if pinned_inside(*pa, wa) || pinned_inside(*pb, wb) {
            return 0.0;
        }
        let mut farthest = 0.0f32;
        for t in EDGE_SAMPLES {
            let sample: [f32; 3] = std::array::from_fn(|c| pa[c] * (1.0 - t) + pb[c] * t);
            if self.surely_beyond(sample, margin) {
                continue;
            }
            let (distance, normal) = self.signed_distance(sample);
            // Not a number: nothing known to push by.
            if distance >= margin || distance.is_nan() {
                continue;
            }
            let (ca, cb) = ((1.0 - t) * wa, t * wb);
            let denom = (1.0 - t) * ca + t * cb;
            if denom <= 0.0 {
                continue;
            }
            let push = (margin - distance) / denom;
            for c in 0..3 {
                pa[c] += normal[c] * (push * ca);
                pb[c] += normal[c] * (push * cb);
            }
            farthest = farthest.max(push * ca.max(cb));
        }
        farthest
    }
}

/// The point of `cuboid` rounded by its thickness nearest to `p` (m), and
/// the outward normal there: outside the cuboid, through the nearest point
/// of its surface; in it, out through the nearest face (the lanes hold a
/// cuboid only while a substep's motion is small beside it, so that is
/// the face the lane came in by). Also whether `p` is outside the cuboid
/// itself, and how far (m) from it. Branch-free, as the AVX2 pass runs it
/// (the same operations in the same order).
#[inline(always)]
fn cuboid_nearest(cuboid: &StillCuboid, p: [f32; 3]) -> ([f32; 3], [f32; 3], bool, f32) {
    let (local, beyond) = cuboid.local(p);
    let half = [cuboid.half.x, cuboid.half.y, cuboid.half.z];
    let t = cuboid.thickness;
    let over = beyond.map(|b| if b > 0.0 { b } else { 0.0 });
    let dist2 = over[0] * over[0] + over[1] * over[1] + over[2] * over[2];
    let outside = dist2 > 0.0;
    let dist = dist2.sqrt();
    let recip = 1.0 / dist;
    let scale = t * recip;
    // In the cuboid: the face it is least far in from (the first of equals).
    let x_face = (beyond[0] >= beyond[1]) & (beyond[0] >= beyond[2]);
    let y_face = !x_face & (beyond[1] >= beyond[2]);
    let face = [x_face, y_face, !x_face & !y_face];
    let mut delta = [0.0f32; 3];
    let mut normal_local = [0.0f32; 3];
    for a in 0..3 {
        let sign = 1.0f32.copysign(local[a]);
        let abs = local[a].abs();
        let out_delta = if beyond[a] > 0.0 {
            (half[a] + over[a] * scale) - abs
        } else {
            0.0
        };
        let face_delta = if face[a] { (half[a] + t) - abs } else { 0.0 };
        delta[a] = (if outside { out_delta } else { face_delta }) * sign;
        let face_normal = if face[a] { 1.0 } else { 0.0 };
        normal_local[a] = (if outside {
            over[a] * recip
        } else {
            face_normal
        }) * sign;
    }
    let [u, v, w] = cuboid.axes;
    let (u, v, w) = ([u.x, u.y, u.z], [v.x, v.y, v.z], [w.x, w.y, w.z]);
    let mut to = [0.0f32; 3];
    let mut normal = [0.0f32; 3];
    for c in 0..3 {
        to[c] = p[c] + (u[c] * delta[0] + v[c] * delta[1] + w[c] * delta[2]);
        normal[c] = u[c] * normal_local[0] + v[c] * normal_local[1] + w[c] * normal_local[2];
    }
    (to, normal, outside, dist)
}

/// The plane (unit normal, offset in m) that holds a lane starting the
/// substep at `start` against `cuboid`: the tangent plane of the rounded
/// cuboid at the point nearest to `start`, when `start` is within the
/// cuboid's reach; otherwise none (an offset of −∞). A plane from where
/// the lane started, not the nearest point where it is, as the collision
/// stage's contact planes take it: a lane the springs pull over an edge
/// is held by the face it was on (the stage's edge pass takes the springs
/// round the edge). The rounded cuboid is convex: a lane on its plane's
/// side is outside it.
#[inline(always)]
fn cuboid_plane(cuboid: &StillCuboid, start: [f32; 3]) -> ([f32; 3], f32) {
    if far_from_cuboid(cuboid, start) {
        return ([0.0; 3], f32::NEG_INFINITY);
    }
    let (on, normal, outside, dist) = cuboid_nearest(cuboid, start);
    let applies = if outside { dist < cuboid.reach } else { true };
    let offset = normal[0] * on[0] + normal[1] * on[1] + normal[2] * on[2];
    let from = normal[0] * start[0] + normal[1] * start[1] + normal[2] * start[2];
    // A lane that starts deep within the thickness (a cloth laid on the
    // cuboid by hand) is held where it starts along the normal: put out
    // to the thickness in one substep it would leave at the push over the
    // substep (a sheet laid 1 cm into a ramp took off at 38 m/s); the
    // collision stage's pass takes it out.
    let deep = from < offset - cuboid.settle;
    let offset = if deep { from } else { offset };
    (normal, if applies { offset } else { f32::NEG_INFINITY })
}

/// The bounding box (least and greatest corner, m) of the lanes at `p`;
/// of none, an empty one (least above greatest). Eight running extremes,
/// not one: a chain of dependent `min`s stalls.
fn lanes_box(p: [&[f32]; 3]) -> (Vector, Vector) {
    let (mut lo, mut hi) = ([[f32::INFINITY; W]; 3], [[f32::NEG_INFINITY; W]; 3]);
    for a in 0..3 {
        // Comparisons, not `f32::min`, whose care for NaN kept the loop
        // scalar (a NaN lane is left out; the step's check finds it).
        let eights = p[a].chunks_exact(W);
        let rest = eights.remainder();
        for eight in eights {
            for j in 0..W {
                let v = eight[j];
                lo[a][j] = if v < lo[a][j] { v } else { lo[a][j] };
                hi[a][j] = if v > hi[a][j] { v } else { hi[a][j] };
            }
        }
        for (j, &v) in rest.iter().enumerate() {
            lo[a][j] = if v < lo[a][j] { v } else { lo[a][j] };
            hi[a][j] = if v > hi[a][j] { v } else { hi[a][j] };
        }
    }
    let lo = lo.map(|l| l.into_iter().fold(f32::INFINITY, f32::min));
    let hi = hi.map(|h| h.into_iter().fold(f32::NEG_INFINITY, f32::max));
    (Vector::from_array(lo), Vector::from_array(hi))
}

/// Whether a lane starting at `start` is surely beyond the reach of
/// `cuboid`: further out along one of its axes than [`StillCuboid::far`].
/// Its plane is then none, with a zero normal, told without the root and
/// division of the nearest point (the plane found so would be none too).
#[inline(always)]
fn far_from_cuboid(cuboid: &StillCuboid, start: [f32; 3]) -> bool {
    let (_, beyond) = cuboid.local(start);
    beyond[0].max(beyond[1]).max(beyond[2]) > cuboid.far()
}

/// The planes of `cuboid` ([`cuboid_plane`]) for lanes starting at
/// `start` with inverse masses `w`, into `out` (normal x, y, z, offset),
/// eight at a time in AVX2 when `simd`. A pinned lane's is none: no pass
/// moves it (the bars the `tear` hangs from hold its edges' particles
/// within their reach).
fn planes_of(
    cuboid: &StillCuboid,
    (start, w): ([&[f32]; 3], &[f32]),
    out: &mut [&mut [f32]; 4],
    simd: bool,
) {
    let n = start[0].len();
    assert!(start.iter().all(|s| s.len() == n) && out.iter().all(|o| o.len() == n));
    assert!(w.len() == n);
    let mut k = 0;
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        k = unsafe { planes_avx2(cuboid, (start, w), out) };
    }
    let _ = simd;
    for k in k..n {
        let (normal, offset) = if w[k] == 0.0 {
            ([0.0; 3], f32::NEG_INFINITY)
        } else {
            cuboid_plane(cuboid, [start[0][k], start[1][k], start[2][k]])
        };
        for a in 0..3 {
            out[a][k] = normal[a];
        }
        out[3][k] = offset;
    }
}

/// The planes of `cuboid` ([`planes_of`]) for lanes starting at `start`
/// with inverse masses `w` when it moves by `shift` (m) over the substep,
/// `cuboid` being where it is at the substep's end: each taken from where
/// its lane started relative to the cuboid (at the cuboid where it was at
/// the substep's start), then moved with it. A still cuboid's are
/// [`planes_of`]'s own.
fn moved_planes_of(
    (cuboid, shift): (&StillCuboid, Vector),
    (start, w): ([&[f32]; 3], &[f32]),
    out: &mut [&mut [f32]; 4],
    simd: bool,
) {
    if shift == Vector::ZERO {
        planes_of(cuboid, (start, w), out, simd);
        return;
    }
    let before = StillCuboid {
        centre: cuboid.centre - shift,
        ..*cuboid
    };
    planes_of(&before, (start, w), out, simd);
    let [nx, ny, nz, offset] = out;
    let n = offset.len();
    assert!([nx.len(), ny.len(), nz.len()] == [n; 3]);
    for k in 0..n {
        // No plane (−∞) stays none.
        offset[k] += nx[k] * shift.x + ny[k] * shift.y + nz[k] * shift.z;
    }
}

/// A squared distance from a ball's centre under which a lane may be
/// inside it, `reach` (m) out: the square of `reach` with a margin for the
/// rounding of a squared distance (never under it where the exact test,
/// `sqrt(d²) < reach`, holds).
#[inline(always)]
fn near_ball(reach: f32) -> f32 {
    reach * reach * (1.0 + 1.0e-5)
}

/// `run` as an array of eight lanes.
#[inline(always)]
fn whole(run: &mut [f32]) -> &mut [f32; W] {
    run.try_into().expect("eight lanes")
}

/// [`run_lanes`] on eight lanes, without branches (in place: moving the
/// lanes in and out by value was a `memmove` call); keeps in `farthest`
/// the farthest push of each.
#[inline(always)]
fn eight(e: &mut Eight, law: &Law, farthest: &mut [f32; W]) {
    // Each lane's normal and friction coefficient: those of the shape
    // that last pushed it (zero for none).
    let mut normal = [[0.0f32; W]; 3];
    let mut mu = [0.0f32; W];
    let mut shift = [[0.0f32; W]; 3];
    for (o, &shape) in law.shapes.iter().enumerate() {
        let mark = o as u32 + 1;
        let mut to = [[0.0f32; W]; 3];
        let mut n = [[0.0f32; W]; 3];
        let mut push = [0.0f32; W];
        let mut inside = [false; W];
        match shape {
            StillShape::Ball { reach, .. } | StillShape::Capsule { reach, .. } => {
                let (up, tiny) = shape.way_out();
                for k in 0..W {
                    let c = shape.centre_for([e.p[0][k], e.p[1][k], e.p[2][k]]);
                    let d = [e.p[0][k] - c[0], e.p[1][k] - c[1], e.p[2][k] - c[2]];
                    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let length = d2.sqrt();
                    let recip = 1.0 / length;
                    // At the centre itself: out along `up`.
                    let at_centre = d2 <= tiny;
                    for a in 0..3 {
                        let up = [up.x, up.y, up.z][a];
                        n[a][k] = if at_centre { up } else { d[a] * recip };
                        to[a][k] = c[a] + n[a][k] * reach;
                    }
                    inside[k] = (length < reach) & (e.w[k] != 0.0);
                    push[k] = if inside[k] { reach - length } else { 0.0 };
                }
            }
            StillShape::Plane { .. }
            | StillShape::Cuboid(_)
            | StillShape::Convex(_)
            | StillShape::Mesh(_) => {
                for k in 0..W {
                    let (m, offset) = e.half_space(law, shape, k);
                    let gap = offset - (m[0] * e.p[0][k] + m[1] * e.p[1][k] + m[2] * e.p[2][k]);
                    for a in 0..3 {
                        n[a][k] = m[a];
                        to[a][k] = e.p[a][k] + m[a] * gap;
                    }
                    inside[k] = (gap > 0.0) & (e.w[k] != 0.0);
                    push[k] = if inside[k] { gap } else { 0.0 };
                }
            }
        }
        let coefficient = law.friction.map_or(0.0, |f| f[o]);
        let moves = law.shifts.map_or([0.0; 3], |s| [s[o].x, s[o].y, s[o].z]);
        for k in 0..W {
            for a in 0..3 {
                e.p[a][k] = if inside[k] { to[a][k] } else { e.p[a][k] };
            }
            e.depth[k] += push[k];
            e.touch[k] = if inside[k] { mark } else { e.touch[k] };
            farthest[k] = farthest[k].max(push[k]);
            let this = e.touch[k] == mark;
            for a in 0..3 {
                normal[a][k] = if this { n[a][k] } else { normal[a][k] };
            }
            mu[k] = if this { coefficient } else { mu[k] };
            for a in 0..3 {
                shift[a][k] = if this { moves[a] } else { shift[a][k] };
            }
        }
    }
    if law.friction.is_none() {
        return;
    }
    for k in 0..W {
        let mut slide = [
            e.p[0][k] - e.start[0][k],
            e.p[1][k] - e.start[1][k],
            e.p[2][k] - e.start[2][k],
        ];
        if law.shifts.is_some() {
            // Relative to the surface, which moved too.
            for a in 0..3 {
                slide[a] -= shift[a][k];
            }
        }
        let n = [normal[0][k], normal[1][k], normal[2][k]];
        let along = n[0] * slide[0] + n[1] * slide[1] + n[2] * slide[2];
        let tangent = [
            slide[0] - n[0] * along,
            slide[1] - n[1] * along,
            slide[2] - n[2] * along,
        ];
        let length =
            (tangent[0] * tangent[0] + tangent[1] * tangent[1] + tangent[2] * tangent[2]).sqrt();
        let allowed = mu[k] * e.depth[k];
        let whole = length <= allowed;
        let scale = allowed / length;
        let touched = e.touch[k] != 0;
        for a in 0..3 {
            let undone = if whole {
                tangent[a]
            } else {
                tangent[a] * scale
            };
            e.p[a][k] = if touched {
                e.p[a][k] - undone
            } else {
                e.p[a][k]
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::contact::{contact, contact_prepared, Analytic, PoseF64};
    use crate::collision::DynamicBody;
    use crate::math::Pose;
    use crate::solver::lane_convex::{convex_plane, cylinder_plane, hull_plane};
    use parry3d::shape::{SharedShape, TriMeshFlags};

    const THICKNESS: f32 = 0.01;

    /// A ball of radius 0.5 at (0, 1, 0) over a floor at y = 0.
    fn ball_and_floor() -> [Obstacle; 2] {
        let ball = Obstacle::ball(Vector::new(0.0, 1.0, 0.0), 0.5).with_friction(0.4);
        let floor = Obstacle::new(SharedShape::halfspace(Vector::Y), Pose::IDENTITY);
        [ball, floor.with_friction(0.8)]
    }

    /// `n` lanes scattered around the ball and through the floor (some at
    /// the ball's centre, every fifth pinned): positions, then start
    /// positions a little above.
    fn lanes(n: usize) -> Lanes {
        let mut lanes = Lanes::default();
        lanes.resize(n);
        let [x, y, z, sx, sy, sz, w] = lanes.arrays_mut();
        for k in 0..n {
            let s = k as f32;
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin()).normalize();
            let p = Vector::new(0.0, 1.0, 0.0) + dir * (0.2 + 0.5 * ((0.37 * s) % 1.0));
            let p = if k % 9 == 4 {
                Vector::new(0.0, 1.0, 0.0)
            } else {
                p
            };
            let p = if k % 7 == 2 {
                Vector::new(0.1 * s % 1.0, -0.02, 0.3)
            } else {
                p
            };
            (x[k], y[k], z[k]) = (p.x, p.y, p.z);
            (sx[k], sy[k], sz[k]) = (p.x + 0.003, p.y + 0.004, p.z - 0.002);
            w[k] = if k % 5 == 0 { 0.0 } else { 2.0 };
        }
        lanes
    }

    /// A pass of `contacts` over `lanes` lane by lane, without AVX2, with
    /// friction when `friction`; returns the farthest push (m).
    fn portable_pass(contacts: &mut LaneContacts, lanes: &mut Lanes, friction: bool) -> f32 {
        let [x, y, z, sx, sy, sz, w] = lanes.arrays_mut();
        let law = Law {
            shapes: &contacts.shapes,
            friction: friction.then_some(&contacts.friction[..]),
            shifts: (friction && contacts.moving()).then_some(&contacts.shifts[..]),
            planes: contacts.planes.each_ref().map(|r| &r[..]),
            lanes: contacts.lanes,
        };
        let chunk = Chunk {
            first: 0,
            x,
            y,
            z,
            start: [&*sx, &*sy, &*sz],
            w: &*w,
            depth: &mut contacts.depth,
            touch: &mut contacts.touch,
        };
        run(chunk, &law, false)
    }

    fn bits(lanes: &mut Lanes) -> Vec<u32> {
        lanes
            .arrays_mut()
            .iter()
            .flat_map(|a| a.iter().map(|v| v.to_bits()))
            .collect()
    }

    /// Lane `k`'s position in `bits` ([`bits`]) of `n` lanes.
    fn position_in(bits: &[u32], n: usize, k: usize) -> Vector {
        Vector::new(
            f32::from_bits(bits[k]),
            f32::from_bits(bits[n + k]),
            f32::from_bits(bits[2 * n + k]),
        )
    }

    /// `n` lanes, lane `k` at `at(k)`: its position and start (m) and
    /// inverse mass (1/kg).
    fn placed(n: usize, at: impl Fn(usize) -> (Vector, Vector, f32)) -> Lanes {
        let mut l = Lanes::default();
        l.resize(n);
        let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
        for k in 0..n {
            let (p, start, inverse_mass) = at(k);
            (x[k], y[k], z[k]) = (p.x, p.y, p.z);
            (sx[k], sy[k], sz[k]) = (start.x, start.y, start.z);
            w[k] = inverse_mass;
        }
        l
    }

    /// Every free lane ends out of the ball and above the floor by the
    /// thickness, through the nearest point (at the centre: the top);
    /// pinned lanes and lanes already out keep their bits; the records say
    /// how far each was pushed and by which; the portable and the AVX2
    /// passes agree to the bit.
    #[test]
    fn projection_puts_every_free_lane_out_and_records_the_push() {
        // Four chunks and a short vector step at the end.
        let n = 3 * CHUNK + 13;
        let obstacles = ball_and_floor();
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(&obstacles, (THICKNESS, 0.001), n));
        let mut l = lanes(n);
        let before = bits(&mut l);
        let pushed = contacts.project(&mut l, Team::ALONE);
        let [x, y, z, _, _, _, w] = l.arrays_mut();
        let centre = Vector::new(0.0, 1.0, 0.0);
        let (mut moved, mut deepest) = (0, 0.0f32);
        for k in 0..n {
            let p = Vector::new(x[k], y[k], z[k]);
            let old = position_in(&before, n, k);
            if w[k] == 0.0 {
                assert_eq!(p, old, "pinned lane {k} moved");
                assert_eq!(contacts.touch[k], 0);
                continue;
            }
            let d = (p - centre).length();
            assert!(
                d >= 0.51 - 1e-5 && p.y >= THICKNESS - 1e-6,
                "lane {k} at {p:?}"
            );
            let push = (p - old).length();
            if push > 0.0 {
                moved += 1;
                assert!(contacts.touch[k] != 0, "lane {k} pushed, not marked");
                deepest = deepest.max(push);
                // Out through the nearest point: along the radius, or up
                // (a push of a few ulps, from the rounding of a lane just
                // at the surface, has no direction to speak of).
                let dir = (p - old) / push;
                let radial = (old - centre).normalize_or(Vector::Y);
                assert!(
                    push < 1e-5 || dir.dot(radial) > 0.999 || dir.dot(Vector::Y) > 0.999,
                    "lane {k} pushed along {dir:?} from {old:?} to {p:?}"
                );
            } else {
                assert_eq!(contacts.touch[k], 0, "lane {k} marked, not pushed");
                assert_eq!(contacts.depth[k], 0.0);
            }
        }
        assert!(moved > n / 4 && moved < n, "{moved} of {n} pushed");
        assert_eq!(contacts.touching() as usize, moved, "the lanes in contact");
        assert!(
            (pushed - deepest).abs() < 1e-5,
            "{pushed} against {deepest}"
        );
        // The same passes lane by lane, without AVX2: the projection, then
        // the projection with friction.
        let mut portable = LaneContacts::default();
        portable.begin(&obstacles, (THICKNESS, 0.001), n);
        let mut m = lanes(n);
        let again = portable_pass(&mut portable, &mut m, false);
        assert_eq!(again.to_bits(), pushed.to_bits());
        assert_eq!(bits(&mut m), bits(&mut l));
        assert_eq!(portable.depth, contacts.depth);
        assert_eq!(portable.touch, contacts.touch);
        // With friction: the same, and it moves only lanes a pass touched.
        let untouched: Vec<usize> = (0..n).filter(|&k| contacts.touch[k] == 0).collect();
        let before = bits(&mut l);
        contacts.project_with_friction(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, true);
        let after = bits(&mut l);
        assert_eq!(bits(&mut m), after);
        assert!(after != before, "friction moved nothing");
        for k in untouched {
            for a in 0..3 {
                assert_eq!(
                    after[a * n + k],
                    before[a * n + k],
                    "untouched lane {k} moved"
                );
            }
        }
    }

    /// Eight lanes the ball pushed, then carried far from it, still take
    /// the ball's normal and friction in the next pass; eight far from it
    /// and never pushed by it pass it over: the vector and the portable
    /// passes agree to the bit either way.
    #[test]
    fn lanes_far_from_the_ball_pass_it_over_to_the_same_bits() {
        let n = 4 * 8 + 3;
        let obstacles = ball_and_floor();
        let (mut vector, mut portable) = (LaneContacts::default(), LaneContacts::default());
        vector.begin(&obstacles, (THICKNESS, 0.001), n);
        portable.begin(&obstacles, (THICKNESS, 0.001), n);
        let place = || {
            placed(n, |k| {
                let s = k as f32 * 0.01;
                // Into the ball's top; through the floor far from it; above
                // the floor far from it; the rest by the ball.
                let p = match k / 8 {
                    0 => Vector::new(s, 1.49, 0.0),
                    1 => Vector::new(4.0 + s, 0.003, 0.5),
                    2 => Vector::new(-4.0 - s, 0.3, 0.5),
                    _ => Vector::new(0.0, 1.0 + s, 0.48),
                };
                (p, p + Vector::new(-0.002, 0.004, 0.0), 1.0)
            })
        };
        let (mut l, mut m) = (place(), place());
        vector.project(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, false);
        assert_eq!(bits(&mut l), bits(&mut m));
        assert!(
            vector.touch[..8].iter().all(|&t| t == 1),
            "{:?}",
            vector.touch
        );
        assert!(
            vector.touch[8..16].iter().all(|&t| t == 2),
            "{:?}",
            vector.touch
        );
        // The first eight carried 3 m away along x, starts and all.
        for lanes in [&mut l, &mut m] {
            let [x, _, _, sx, ..] = lanes.arrays_mut();
            for k in 0..8 {
                x[k] += 3.0;
                sx[k] += 3.0;
            }
        }
        let before = bits(&mut l);
        vector.project_with_friction(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, true);
        let after = bits(&mut l);
        assert_eq!(after, bits(&mut m));
        assert_eq!(
            (&vector.depth, &vector.touch),
            (&portable.depth, &portable.touch)
        );
        assert!(
            (0..8).any(|k| after[k] != before[k]),
            "friction by the ball's normal moved none of the carried lanes"
        );
        assert!(
            (16..24).all(|k| (0..3).all(|a| after[a * n + k] == before[a * n + k])),
            "lanes clear of both and never pushed moved"
        );
    }

    /// A lane pushed 1 mm out of the floor that slid 10 mm along it keeps
    /// 10 − μ mm of the slide (μ = 0.8 for the floor); with room to stop
    /// (a slide under μ times the push) it stops where it started along
    /// the floor.
    #[test]
    fn friction_undoes_the_slide_up_to_the_coefficient_times_the_push() {
        let obstacles = ball_and_floor();
        let mut contacts = LaneContacts::default();
        let mut l = Lanes::default();
        l.resize(2);
        contacts.begin(&obstacles, (THICKNESS, 0.001), 2);
        {
            let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
            // Started at the thickness, now 1 mm inside it: slid 10 mm, 0.5 mm.
            for (k, slide) in [0.010f32, 0.0005].into_iter().enumerate() {
                (sx[k], sy[k], sz[k]) = (3.0, THICKNESS, 0.0);
                (x[k], y[k], z[k]) = (3.0 + slide, THICKNESS - 0.001, 0.0);
                w[k] = 1.0;
            }
        }
        contacts.project_with_friction(&mut l, Team::ALONE);
        assert_eq!(contacts.touch, [2, 2]);
        let [x, y, ..] = l.arrays_mut();
        assert!(
            (x[0] - (3.0 + 0.010 - 0.8 * 0.001)).abs() < 1e-6,
            "{}",
            x[0]
        );
        assert!((x[1] - 3.0).abs() < 1e-6, "{}", x[1]);
        assert!(y.iter().all(|&y| (y - THICKNESS).abs() < 1e-6));
    }

    /// A cuboid sliding along x without turning (a kinematic platform)
    /// is held where it is at the substep's end: a lane that rested on its
    /// top and sank a little is put back on it and, with friction enough,
    /// carried along by the cuboid's move (its slide taken relative to the
    /// surface), without friction left where it was; a lane that rested
    /// against the face the cuboid moves into is pushed out with that
    /// face. The portable and the AVX2 passes agree to the bit.
    #[test]
    fn a_sliding_cuboid_holds_its_lanes_on_its_moved_faces_and_carries_them_by_friction() {
        let half = Vector::new(0.5, 0.05, 0.5);
        let speed = 0.5;
        let (end, h) = (1.0e-3, 1.0e-3);
        let shift = speed * h;
        let (sink, n) = (0.0004, 19);
        // Even lanes rest on the top (and sank), odd ones against the +x face.
        let place = || {
            placed(n, |k| {
                let s = k as f32 / n as f32 - 0.5;
                if k % 2 == 0 {
                    let start = Vector::new(0.8 * s, half.y + THICKNESS, 0.3 * s);
                    (start - Vector::Y * sink, start, 1.0)
                } else {
                    let start = Vector::new(half.x + THICKNESS, 0.8 * half.y * s, 0.6 * s);
                    (start, start, 1.0)
                }
            })
        };
        for friction in [2.0, 0.0] {
            let table = Obstacle::cuboid(half, Pose::IDENTITY)
                .with_velocity(Vector::X * speed, Vector::ZERO)
                .with_friction(friction);
            let obstacles = std::slice::from_ref(&table);
            let mut contacts = LaneContacts::default();
            let holding = contacts.begin_holding(obstacles, (THICKNESS, 0.001), (end, h), n);
            assert_eq!(holding, Holding::All);
            let mut l = place();
            contacts.take_planes(obstacles, &mut l, Team::ALONE);
            let mut portable = place();
            contacts.project_with_friction(&mut l, Team::ALONE);
            let touch = contacts.touch.clone();
            contacts.depth.fill(0.0);
            contacts.touch.fill(0);
            portable_pass(&mut contacts, &mut portable, true);
            assert_eq!(bits(&mut l), bits(&mut portable), "AVX2 and portable");
            assert_eq!(touch, contacts.touch);
            let [x, y, z, sx, _, sz, _] = l.arrays_mut();
            for k in 0..n {
                if k % 2 == 0 {
                    let carried = if friction > 0.0 { shift } else { 0.0 };
                    assert!(
                        (y[k] - (half.y + THICKNESS)).abs() < 1e-6,
                        "lane {k}: {}",
                        y[k]
                    );
                    assert!(
                        (x[k] - (sx[k] + carried)).abs() < 1e-6,
                        "lane {k}: {}",
                        x[k]
                    );
                } else {
                    let face = shift + half.x + THICKNESS;
                    assert!(
                        (x[k] - face).abs() < 1e-6,
                        "lane {k}: {} not at {face}",
                        x[k]
                    );
                }
                assert!((z[k] - sz[k]).abs() < 1e-6, "lane {k} slid across");
            }
            assert!(touch.iter().all(|&t| t == 1), "{touch:?}");
        }
    }

    /// The lanes hold still convex shapes and meshes without an inside,
    /// and balls, capsules, half-spaces and cuboids moving without
    /// turning; no ball, capsule or cuboid the substep's motion (the
    /// particles' and its own) could carry a particle far into.
    #[test]
    fn the_lanes_hold_still_or_sliding_shapes_the_motion_cannot_cross() {
        let [ball, floor] = ball_and_floor();
        // In substeps of a millisecond.
        let holds = |o: &[Obstacle], motion| LaneContacts::holds(o, motion, 1.0e-3);
        assert!(holds(&[ball.clone(), floor.clone()], 0.01));
        assert!(!holds(&[], 0.01), "nothing to hold");
        assert!(
            !holds(std::slice::from_ref(&ball), 0.2),
            "moves a radius in a few substeps"
        );
        assert!(
            holds(std::slice::from_ref(&floor), 10.0),
            "a floor whatever the motion"
        );
        // A ball moving without turning, by its move and the particles'
        // together (1 m/s: a millimetre a substep); not one that turns.
        let moving = ball.clone().with_velocity(Vector::X, Vector::ZERO);
        assert!(holds(&[moving.clone(), floor.clone()], 0.01));
        assert!(
            !holds(&[moving.clone(), floor.clone()], 0.1245),
            "0.1245 m + 1 mm a substep, four times over, is past its 0.5 m radius"
        );
        assert!(holds(std::slice::from_ref(&ball), 0.1245));
        let turning = ball.clone().with_velocity(Vector::ZERO, Vector::Y);
        assert!(!holds(&[turning, floor.clone()], 0.01));
        // A moving shape the lanes take from lists made for one pose.
        let rolling = Obstacle::new(SharedShape::cylinder(0.5, 0.3), Pose::IDENTITY)
            .with_velocity(Vector::X, Vector::ZERO);
        assert!(!holds(&[rolling, floor.clone()], 0.001));
        let mut dynamic = ball.clone();
        dynamic.body = Some(DynamicBody {
            inverse_mass: Vector::ONE,
            inverse_inertia: glam::Mat3::IDENTITY,
            center_of_mass: Vector::Y,
            acceleration: Vector::ZERO,
        });
        assert!(!holds(&[dynamic], 0.01));
        let table = Obstacle::cuboid(Vector::new(0.5, 0.02, 0.5), Pose::IDENTITY);
        assert!(holds(&[ball.clone(), table.clone()], 0.004));
        assert!(
            !holds(&[ball.clone(), table.clone()], 0.006),
            "a 2 cm top the motion could carry a particle through"
        );
        let capsule = Obstacle::new(SharedShape::capsule_y(0.5, 0.1), Pose::IDENTITY);
        assert!(holds(&[ball.clone(), capsule.clone()], 0.001));
        assert!(
            !holds(&[ball.clone(), capsule], 0.03),
            "a 10 cm bar the motion could carry a particle through"
        );
        // Other convex shapes by their own box's half extents.
        let cylinder = Obstacle::new(SharedShape::cylinder(0.5, 0.1), Pose::IDENTITY);
        assert!(holds(&[ball.clone(), cylinder.clone()], 0.001));
        assert!(
            !holds(&[ball.clone(), cylinder], 0.03),
            "a 10 cm rod the motion could carry a particle through"
        );
        let cone = Obstacle::new(SharedShape::cone(0.2, 0.15), Pose::IDENTITY);
        assert!(holds(std::slice::from_ref(&cone), 0.001));
        let triangle = Obstacle::new(
            SharedShape::triangle(Vector::ZERO, Vector::X, Vector::Z),
            Pose::IDENTITY,
        );
        assert!(
            LaneContacts::may_hold(std::slice::from_ref(&triangle))
                && !holds(std::slice::from_ref(&triangle), 0.001),
            "a triangle is flat"
        );
        // Not convex but held: a mesh of two triangles, whatever its
        // thickness (its planes face the side a lane starts on,
        // `lane_mesh.rs`); not so a mesh with an inside (oriented).
        let mesh = Obstacle::new(
            SharedShape::trimesh(
                vec![
                    Vector::ZERO,
                    Vector::X,
                    Vector::Z,
                    Vector::new(1.0, 0.5, 1.0),
                ],
                vec![[0, 1, 2], [1, 3, 2]],
            )
            .expect("a mesh"),
            Pose::IDENTITY,
        );
        assert!(holds(&[ball.clone(), mesh.clone()], 0.001));
        let tetrahedron = |flags| {
            let corners = vec![Vector::ZERO, Vector::X, Vector::Y, Vector::Z];
            let faces = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
            SharedShape::trimesh_with_flags(corners, faces, flags).expect("a mesh")
        };
        let open = Obstacle::new(tetrahedron(TriMeshFlags::empty()), Pose::IDENTITY);
        assert!(LaneContacts::may_hold(std::slice::from_ref(&open)));
        let oriented = Obstacle::new(tetrahedron(TriMeshFlags::ORIENTED), Pose::IDENTITY);
        assert!(!LaneContacts::may_hold(&[ball, oriented.clone()]));
        // What it holds it holds whole, or nothing.
        let mut contacts = LaneContacts::default();
        assert!(
            contacts.begin(std::slice::from_ref(&floor), (THICKNESS, 0.01), 4)
                && !contacts.is_empty()
        );
        assert!(!contacts.begin(&[floor, oriented], (THICKNESS, 0.01), 4) && contacts.is_empty());
        assert_eq!(contacts.touching(), 0, "nothing held, nothing touching");
    }

    /// A turned capsule (a bar) and lanes around it, on its axis and
    /// beyond its ends: every free lane ends at least its radius and the
    /// thickness from the axis segment, a pushed one moved straight away
    /// from the axis point nearest it (beyond an end, from the end: the
    /// caps are balls); pinned lanes and lanes clear of it keep their
    /// bits; the vector and the portable passes agree to the bit, with
    /// friction too.
    #[test]
    fn a_capsule_puts_the_lanes_out_of_its_axis_by_the_thickness() {
        let turn = glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2)
            * glam::Quat::from_rotation_z(0.4);
        let pose = Pose::from_parts(Vector::new(0.2, 0.4, -0.1), turn);
        let (half_height, radius) = (0.8, 0.05);
        let bar = Obstacle::new(SharedShape::capsule_y(half_height, radius), pose);
        let [a, b] = [-half_height, half_height].map(|y| pose.transform_point(Vector::Y * y));
        let nearest = |p: Vector| {
            let u = b - a;
            a + u * ((p - a).dot(u) / u.length_squared()).clamp(0.0, 1.0)
        };
        let n = CHUNK + 21;
        let place = || {
            placed(n, |k| {
                let s = k as f32;
                // Along the axis and 20% past either end, within 1.5 radii.
                let along = a + (b - a) * (1.4 * ((0.618 * s) % 1.0) - 0.2);
                let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin())
                    .normalize_or(Vector::X);
                let p = along + dir * (1.5 * radius * ((0.37 * s) % 1.0));
                let p = if k % 11 == 3 { nearest(p) } else { p };
                let w = if k % 6 == 0 { 0.0 } else { 1.5 };
                (p, p + Vector::new(0.001, -0.002, 0.001), w)
            })
        };
        let obstacles = [bar.with_friction(0.6)];
        let (mut vector, mut portable) = (LaneContacts::default(), LaneContacts::default());
        assert!(vector.begin(&obstacles, (THICKNESS, 0.002), n));
        assert!(portable.begin(&obstacles, (THICKNESS, 0.002), n));
        let (mut l, mut m) = (place(), place());
        let before = bits(&mut l);
        vector.project(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, false);
        assert_eq!(bits(&mut l), bits(&mut m));
        let reach = radius + THICKNESS;
        let (mut pushed, mut clear) = (0, 0);
        {
            let [x, y, z, _, _, _, w] = l.arrays_mut();
            for k in 0..n {
                let p = Vector::new(x[k], y[k], z[k]);
                let old = position_in(&before, n, k);
                if w[k] == 0.0 || (old - nearest(old)).length() >= reach {
                    assert_eq!(p, old, "lane {k} moved");
                    clear += 1;
                    continue;
                }
                let out = p - nearest(old);
                assert!(
                    (out.length() - reach).abs() < 1e-5
                        && (p - nearest(p)).length() >= reach - 1e-5,
                    "lane {k} at {p:?}, {} from the axis",
                    (p - nearest(p)).length()
                );
                // Straight out from the nearest axis point (on the axis
                // itself: any way out).
                let from = old - nearest(old);
                if from.length() > 1e-4 {
                    assert!(
                        from.normalize().dot(out.normalize()) > 0.999,
                        "lane {k} pushed along {out:?} from {old:?}"
                    );
                }
                pushed += 1;
            }
        }
        assert!(
            pushed > n / 3 && clear > n / 8,
            "{pushed} pushed, {clear} clear"
        );
        assert_eq!(vector.touching() as usize, pushed);
        vector.project_with_friction(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, true);
        assert_eq!(bits(&mut l), bits(&mut m));
        assert_eq!(
            (&vector.depth, &vector.touch),
            (&portable.depth, &portable.touch)
        );
    }

    /// A turned table top (a cuboid) and lanes that start around and in
    /// it and move 3 mm in a substep: each free lane that starts within
    /// the cuboid's reach ends on its plane's side, outside the cuboid by
    /// the thickness (the rounded cuboid is convex), or, having started
    /// within the thickness, no deeper than it started; lanes starting beyond
    /// the reach keep their bits; the planes and the pass are the same
    /// bits in AVX2 and lane by lane.
    #[test]
    fn a_cuboids_planes_put_the_lanes_out_by_the_thickness() {
        let turn = glam::Quat::from_rotation_z(0.3) * glam::Quat::from_rotation_x(-0.2);
        let pose = Pose::from_parts(Vector::new(0.1, 1.0, -0.2), turn);
        let half = Vector::new(0.5, 0.05, 0.4);
        let table = Obstacle::cuboid(half, pose).with_friction(0.5);
        let n = 2 * CHUNK + 11;
        let motion = 0.003;
        let place = || {
            placed(n, |k| {
                let s = k as f32;
                // A point of the cuboid's surface grown by up to 4 cm, in
                // its frame, from a direction that covers faces, edges
                // and corners; every eleventh starts inside it.
                let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin());
                let local = (dir * half * 1.2).clamp(-half, half)
                    + dir.normalize() * (0.04 * ((0.37 * s) % 1.0));
                let local = if k % 11 == 3 { local * 0.5 } else { local };
                let start = pose.transform_point(local);
                let moved = start - pose.rotation * dir.normalize() * motion;
                (moved, start, if k % 5 == 0 { 0.0 } else { 1.0 })
            })
        };
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(std::slice::from_ref(&table), (THICKNESS, motion), n));
        assert!(contacts.holds_cuboid());
        let mut l = place();
        let before = bits(&mut l);
        contacts.take_planes(std::slice::from_ref(&table), &mut l, Team::ALONE);
        contacts.project(&mut l, Team::ALONE);
        let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
        let (mut held, mut far, mut inside) = (0, 0, 0);
        for k in 0..n {
            let p = Vector::new(x[k], y[k], z[k]);
            let start = Vector::new(sx[k], sy[k], sz[k]);
            let old = position_in(&before, n, k);
            let hit = contact_prepared(
                &*table.shape,
                Analytic::of(&*table.shape),
                &PoseF64::of(&table.pose),
                start,
            )
            .expect("a contact");
            let within = hit.signed_distance < 2.0 * (THICKNESS + motion) - 1e-4;
            let beyond = hit.signed_distance > 2.0 * (THICKNESS + motion) + 1e-4;
            if w[k] == 0.0 || beyond {
                assert_eq!(p, old, "lane {k} moved");
                far += usize::from(beyond);
                continue;
            }
            if within {
                held += 1;
                let out = contact_prepared(
                    &*table.shape,
                    Analytic::of(&*table.shape),
                    &PoseF64::of(&table.pose),
                    p,
                )
                .expect("a contact");
                // Out by the thickness; one that started within it no
                // deeper than it started (the stage takes it out).
                let floor = hit.signed_distance.min(THICKNESS);
                assert!(
                    out.signed_distance > floor - 1e-5,
                    "lane {k} from {start:?} ({}) ends {} from the cuboid",
                    hit.signed_distance,
                    out.signed_distance
                );
                inside += usize::from(hit.signed_distance < 0.0);
            }
        }
        assert!(
            held > n / 2 && far > 0 && inside > 0,
            "{held} held, {far} beyond, {inside} started inside"
        );
        // Lane by lane, without AVX2: the same planes and the same pass.
        let mut portable = LaneContacts::default();
        portable.begin(std::slice::from_ref(&table), (THICKNESS, motion), n);
        let mut m = place();
        {
            let [_, _, _, sx, sy, sz, w] = m.arrays_mut();
            let cuboid = cuboid_of(&portable);
            let [a, b, c, d] = &mut portable.planes;
            let mut out = [&mut a[..], &mut b[..], &mut c[..], &mut d[..]];
            planes_of(&cuboid, ([&*sx, &*sy, &*sz], &*w), &mut out, false);
        }
        assert_eq!(portable.planes, contacts.planes, "the planes' bits");
        portable_pass(&mut portable, &mut m, false);
        assert_eq!(bits(&mut m), bits(&mut l));
        contacts.project_with_friction(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, true);
        assert_eq!(bits(&mut m), bits(&mut l));
        assert_eq!(
            (&portable.depth, &portable.touch),
            (&contacts.depth, &contacts.touch)
        );
    }

    /// A turned cylinder and a cone beside it, and lanes that start around
    /// and in them and move 3 mm in a substep: each free lane that starts
    /// within a shape's reach ends outside it by the thickness, or, having
    /// started within the thickness, no deeper than it started (the planes
    /// are tangent planes of convex shapes); lanes starting beyond every
    /// reach and pinned lanes keep their bits; the vector and the portable
    /// passes agree to the bit.
    #[test]
    fn a_convex_shapes_planes_put_the_lanes_out_by_the_thickness() {
        let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
        let obstacles = [
            Obstacle::new(
                SharedShape::cylinder(0.3, 0.25),
                Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn),
            )
            .with_friction(0.5),
            Obstacle::new(
                SharedShape::cone(0.2, 0.15),
                Pose::from_translation(Vector::new(0.8, 1.0, 0.0)),
            ),
        ];
        let n = 2 * CHUNK + 11;
        let motion = 0.003;
        let place = || {
            placed(n, |k| {
                let s = k as f32;
                // Around one shape or the other, from 0.3 m inside its
                // origin out to its surface grown by up to 5 cm.
                let o = &obstacles[k % 2];
                let dir =
                    Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin()).normalize();
                let origin = o.pose.translation;
                let surface = contact(&*o.shape, &o.pose, origin + dir)
                    .expect("a contact")
                    .point;
                let r = 0.7 + 0.45 * ((0.37 * s) % 1.0);
                let start = origin
                    + (surface - origin) * r.min(1.0)
                    + dir * (0.05 * (r - 1.0).max(0.0) / 0.15);
                let moved = start - dir * motion;
                (moved, start, if k % 5 == 0 { 0.0 } else { 1.0 })
            })
        };
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(&obstacles, (THICKNESS, motion), n));
        assert!(!contacts.holds_cuboid() && contacts.held_planes().is_some());
        let mut l = place();
        let before = bits(&mut l);
        contacts.take_planes(&obstacles, &mut l, Team::ALONE);
        contacts.project(&mut l, Team::ALONE);
        let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
        let (mut held, mut far, mut inside) = (0, 0, 0);
        for k in 0..n {
            let p = Vector::new(x[k], y[k], z[k]);
            let start = Vector::new(sx[k], sy[k], sz[k]);
            let old = position_in(&before, n, k);
            let hits = obstacles
                .each_ref()
                .map(|o| contact(&*o.shape, &o.pose, start).expect("a contact"));
            let reach = 2.0 * (THICKNESS + motion);
            let beyond = hits.iter().all(|h| h.signed_distance > reach + 1e-4);
            if w[k] == 0.0 || beyond {
                assert_eq!(p, old, "lane {k} moved");
                far += usize::from(beyond);
                continue;
            }
            for (o, hit) in obstacles.iter().zip(&hits) {
                if hit.signed_distance >= reach - 1e-4 {
                    continue;
                }
                held += 1;
                let out = contact(&*o.shape, &o.pose, p).expect("a contact");
                let floor = hit.signed_distance.min(THICKNESS);
                assert!(
                    out.signed_distance > floor - 1e-4,
                    "lane {k} from {start:?} ({}) ends {} from its shape",
                    hit.signed_distance,
                    out.signed_distance
                );
                inside += usize::from(hit.signed_distance < 0.0);
            }
        }
        assert!(
            held > n / 3 && far > n / 10 && inside > n / 10,
            "{held} held, {far} beyond, {inside} started inside"
        );
        let mut portable = LaneContacts::default();
        portable.begin(&obstacles, (THICKNESS, motion), n);
        let mut m = place();
        portable.take_planes(&obstacles, &mut m, Team::ALONE);
        portable_pass(&mut portable, &mut m, false);
        assert_eq!(bits(&mut m), bits(&mut l));
        contacts.project_with_friction(&mut l, Team::ALONE);
        portable_pass(&mut portable, &mut m, true);
        assert_eq!(bits(&mut m), bits(&mut l));
        assert_eq!(
            (&portable.depth, &portable.touch),
            (&contacts.depth, &contacts.touch)
        );
    }

    /// A table built as one compound collider (a turned cuboid top on a
    /// cylinder leg) is held piece by piece, to the same bits as the same
    /// pieces as two obstacles: the planes, the pass with friction and its
    /// records; a compound with a flat part is not held.
    #[test]
    fn a_compound_is_held_as_its_parts_are() {
        let turn = glam::Quat::from_rotation_y(0.3) * glam::Quat::from_rotation_x(0.1);
        let place = Pose::from_parts(Vector::new(0.2, 0.5, -0.1), turn);
        let (top_at, leg_at) = (
            Pose::from_translation(Vector::new(0.0, 0.25, 0.0)),
            Pose::from_translation(Vector::new(0.0, 0.0, 0.0)),
        );
        let (top, leg) = (
            SharedShape::cuboid(0.4, 0.02, 0.3),
            SharedShape::cylinder(0.25, 0.05),
        );
        let table = Obstacle::new(
            SharedShape::compound(vec![(top_at, top.clone()), (leg_at, leg.clone())]),
            place,
        )
        .with_friction(0.4);
        let apart = [
            Obstacle::new(top, place * top_at).with_friction(0.4),
            Obstacle::new(leg, place * leg_at).with_friction(0.4),
        ];
        let n = 2 * CHUNK + 11;
        let motion = 0.003;
        let at = |k: usize| {
            let s = k as f32;
            let (u, v) = ((1.3 * s).sin(), (2.1 * s).sin());
            // Half over the top, up to 2 cm above it, half around the leg,
            // up to 2 cm out; each moved 1 cm in (some of them beside the
            // top or below it, and some of those clear of everything).
            let (start, inward) = if k.is_multiple_of(2) {
                let y = 0.27 + 0.02 * ((0.37 * s) % 1.0);
                (Vector::new(0.45 * u, y, 0.35 * v), Vector::NEG_Y)
            } else {
                let across = Vector::new(u, 0.0, (0.7 * s).cos()).normalize();
                let r = 0.05 + 0.02 * ((0.37 * s) % 1.0);
                (across * r + Vector::Y * (0.22 * v), -across)
            };
            let start = place.transform_point(start);
            let moved = start + place.rotation * inward * 0.01;
            (moved, start, if k.is_multiple_of(5) { 0.0 } else { 1.0 })
        };
        let (mut whole, mut parts) = (LaneContacts::default(), LaneContacts::default());
        assert!(whole.begin(std::slice::from_ref(&table), (THICKNESS, motion), n));
        assert!(parts.begin(&apart, (THICKNESS, motion), n));
        assert_eq!(whole.shapes.len(), 2);
        let (mut l, mut m) = (placed(n, at), placed(n, at));
        let before = bits(&mut l);
        whole.take_planes(std::slice::from_ref(&table), &mut l, Team::ALONE);
        parts.take_planes(&apart, &mut m, Team::ALONE);
        assert_eq!(whole.planes, parts.planes, "the planes' bits");
        whole.project_with_friction(&mut l, Team::ALONE);
        parts.project_with_friction(&mut m, Team::ALONE);
        let after = bits(&mut l);
        assert_eq!(after, bits(&mut m));
        assert_eq!((&whole.depth, &whole.touch), (&parts.depth, &parts.touch));
        let moved = (0..n)
            .filter(|&k| position_in(&before, n, k) != position_in(&after, n, k))
            .count();
        assert!(moved > n / 2, "{moved} of {n} lanes put out");
        // A flat part (a triangle) is held by none (parry allows no mesh
        // in a compound).
        let with_triangle = Obstacle::new(
            SharedShape::compound(vec![
                (top_at, SharedShape::ball(0.1)),
                (
                    leg_at,
                    SharedShape::triangle(Vector::ZERO, Vector::X, Vector::Z),
                ),
            ]),
            place,
        );
        assert!(!LaneContacts::holds(&[with_triangle], motion, 1.0e-3));
    }

    /// A turned cylinder's planes in single precision agree with those
    /// through the stage's contact (double precision) around it, in it
    /// and beyond its rims: the same normals, offsets within 10 µm, none
    /// where the other has none.
    #[test]
    fn a_cylinders_planes_are_those_of_its_contact() {
        let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
        let o = Obstacle::new(
            SharedShape::cylinder(0.3, 0.25),
            Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn),
        );
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(std::slice::from_ref(&o), (THICKNESS, 0.003), 1));
        let [StillShape::Convex(convex)] = contacts.shapes[..] else {
            panic!("{:?}", contacts.shapes);
        };
        let cylinder = convex.cylinder.expect("a cylinder's own planes");
        let shape = &*o.shape;
        let analytic = Analytic::of(shape);
        let pose = PoseF64::placing(&o.pose, analytic);
        let (mut held, mut none) = (0, 0);
        for i in 0..13 {
            for j in 0..13 {
                for k in 0..13 {
                    let local = Vector::new(i as f32 - 6.0, j as f32 - 6.0, k as f32 - 6.0) * 0.055
                        + Vector::new(0.001, 0.002, 0.003);
                    let p = o.pose.transform_point(local).to_array();
                    let ours = cylinder_plane(&convex, &cylinder, p);
                    let stage = convex_plane(&convex, (shape, analytic, &pose), p);
                    if stage.1 == f32::NEG_INFINITY {
                        assert_eq!(ours.1, f32::NEG_INFINITY, "{p:?}: {ours:?}");
                        none += 1;
                        continue;
                    }
                    held += 1;
                    let (a, b) = (Vector::from(ours.0), Vector::from(stage.0));
                    assert!(a.dot(b) > 0.9999, "{p:?}: {ours:?} against {stage:?}");
                    assert!(
                        (ours.1 - stage.1).abs() < 1e-5,
                        "{p:?}: {ours:?} against {stage:?}"
                    );
                }
            }
        }
        assert!(held > 500 && none > 500, "{held} held, {none} none");
    }

    /// A turned convex hull's planes from its faces agree with those
    /// through the stage's contact (parry's projection), around it, in it
    /// and beyond its edges and corners (there from the contact itself):
    /// the same normals (either of two faces as near), offsets within 50
    /// µm (parry's tolerance), none where the other has none.
    #[test]
    fn a_hulls_planes_are_those_of_its_contact() {
        let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
        // A box with a corner cut off and a roof: faces of 3 to 5 corners.
        let points = [
            Vector::new(-0.3, -0.1, -0.2),
            Vector::new(0.3, -0.1, -0.2),
            Vector::new(-0.3, -0.1, 0.2),
            Vector::new(0.3, -0.1, 0.1),
            Vector::new(0.2, -0.1, 0.2),
            Vector::new(-0.3, 0.1, -0.2),
            Vector::new(0.3, 0.1, -0.2),
            Vector::new(-0.3, 0.1, 0.2),
            Vector::new(0.3, 0.1, 0.2),
            Vector::new(0.0, 0.2, 0.0),
        ];
        let o = Obstacle::new(
            SharedShape::convex_hull(&points).expect("a hull"),
            Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn),
        );
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(std::slice::from_ref(&o), (THICKNESS, 0.003), 1));
        let [StillShape::Convex(convex)] = contacts.shapes[..] else {
            panic!("{:?}", contacts.shapes);
        };
        let faces = convex.hull.expect("a hull's faces");
        assert!(faces.1 - faces.0 >= 7, "{faces:?}");
        let shape = &*o.shape;
        let analytic = Analytic::of(shape);
        let pose = PoseF64::placing(&o.pose, analytic);
        let (mut by_face, mut by_contact, mut none) = (0, 0, 0);
        for i in 0..13 {
            for j in 0..13 {
                for k in 0..13 {
                    let local = Vector::new(i as f32 - 6.0, j as f32 - 6.0, k as f32 - 6.0)
                        * Vector::new(0.055, 0.025, 0.04)
                        + Vector::new(0.001, 0.002, 0.003);
                    let p = o.pose.transform_point(local).to_array();
                    let face = hull_plane(&convex, (&contacts.hulls, faces), p);
                    let stage = convex_plane(&convex, (shape, analytic, &pose), p);
                    let Some(ours) = face else {
                        by_contact += 1;
                        continue;
                    };
                    if stage.1 == f32::NEG_INFINITY {
                        assert_eq!(ours.1, f32::NEG_INFINITY, "{p:?}: {ours:?}");
                        none += 1;
                        continue;
                    }
                    by_face += 1;
                    let (a, b) = (Vector::from(ours.0), Vector::from(stage.0));
                    if a.dot(b) < 0.9999 {
                        // Two faces as near: either holds it.
                        let (_, _, beyond) =
                            contacts.hulls.nearest_face(faces, Vector::from(p)).unwrap();
                        let c = contact(shape, &o.pose, Vector::from(p)).unwrap();
                        assert!(
                            (beyond - c.signed_distance).abs() < 5e-5,
                            "{p:?}: {ours:?} against {stage:?}"
                        );
                        continue;
                    }
                    assert!(a.dot(b) > 0.9999, "{p:?}: {ours:?} against {stage:?}");
                    // parry's projection on a support map converges to
                    // within its tolerance: 10 µm off at some points.
                    assert!(
                        (ours.1 - stage.1).abs() < 5e-5,
                        "{p:?}: {ours:?} against {stage:?}"
                    );
                }
            }
        }
        assert!(
            by_face > 300 && by_contact > 100 && none > 300,
            "{by_face} by a face, {by_contact} by the contact, {none} none"
        );
    }

    /// A sheet folded over a turned cuboid's edge, each particle the
    /// thickness out of it: the springs across the edge cut its rounding.
    /// The lanes' edge pass puts every stretch and shear spring's samples
    /// back to half the thickness out (as the collision stage's edge pass
    /// would), moves no lane of a spring beyond a face, no pinned lane, and
    /// leaves a spring whose pinned end is inside the cuboid.
    #[test]
    fn springs_over_a_cuboids_edge_are_put_off_it() {
        use crate::cloth::{ClothBuilder, SpringKind};
        let turn = glam::Quat::from_rotation_z(0.2) * glam::Quat::from_rotation_y(0.4);
        let pose = Pose::from_parts(Vector::new(0.1, 0.7, -0.2), turn);
        let half = Vector::new(0.3, 0.2, 0.25);
        let table = Obstacle::cuboid(half, pose);
        let (cols, rows, spacing) = (12, 8, 0.02);
        let cloth = ClothBuilder::new(cols, rows).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        let n = cols * rows;
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(std::slice::from_ref(&table), (THICKNESS, 0.001), n));
        // Over the +x edge of the top face: columns before the edge lie on
        // the top, those after hang down the side; one particle of the
        // row 2 pinned on the top, one of row 5 pinned inside the cuboid.
        let pinned_top = cloth.index(2, 3).unwrap();
        let pinned_in = cloth.index(5, 6).unwrap();
        let mut l = sheet_lanes(&cloth, &plan, |r, c| {
            let i = cloth.index(r, c).unwrap();
            let u = (c as f32 - 5.5) * spacing;
            let across = (r as f32 - 3.5) * spacing;
            let local = if i == pinned_in {
                Vector::new(half.x - 0.01, half.y - 0.01, across)
            } else if u < 0.0 {
                Vector::new(half.x + u, half.y + THICKNESS, across)
            } else {
                Vector::new(half.x + THICKNESS, half.y - u, across)
            };
            let pinned = i == pinned_top || i == pinned_in;
            (pose.transform_point(local), if pinned { 0.0 } else { 1.0 })
        });
        let springs = cloth.springs();
        let edge_springs = || {
            springs
                .range(SpringKind::Stretch)
                .chain(springs.range(SpringKind::Shear))
                .map(|s| {
                    (
                        plan.lane(springs.a[s] as usize),
                        plan.lane(springs.b[s] as usize),
                    )
                })
        };
        let distance = |p: Vector| {
            contact_prepared(
                &*table.shape,
                Analytic::of(&*table.shape),
                &PoseF64::of(&table.pose),
                p,
            )
            .unwrap()
            .signed_distance
        };
        // The least of a spring's samples' distances to the cuboid (m).
        let least = |l: &mut Lanes, (a, b): (usize, usize)| {
            let [x, y, z, ..] = l.arrays_mut();
            let (pa, pb) = (Vector::new(x[a], y[a], z[a]), Vector::new(x[b], y[b], z[b]));
            EDGE_SAMPLES
                .iter()
                .map(|&t| distance(pa * (1.0 - t) + pb * t))
                .fold(f32::INFINITY, f32::min)
        };
        let margin = 0.5 * THICKNESS;
        let inside = |(a, b): (usize, usize)| [a, b].contains(&plan.lane(pinned_in));
        let cut_before = edge_springs()
            .filter(|&s| !inside(s) && least(&mut l, s) < 0.5 * margin)
            .count();
        assert!(cut_before >= rows, "{cut_before} springs cut the edge");
        let before = bits(&mut l);
        let moved = contacts.keep_springs_off_cuboids(&plan, &mut l);
        assert!(moved > 0.0);
        let after = bits(&mut l);
        let lane_moved = |k: usize| (0..3).any(|a| before[a * n + k] != after[a * n + k]);
        for s in edge_springs() {
            let d = least(&mut l, s);
            if inside(s) {
                // Left: its pinned end cannot be put out.
                assert!(d < 0.0, "spring {s:?} {d} m out");
                continue;
            }
            assert!(d > 0.9 * margin, "spring {s:?} {d} m out");
        }
        for r in 0..rows {
            for c in 0..cols {
                let i = cloth.index(r, c).unwrap();
                let k = plan.lane(i);
                // Pinned lanes stay; so do lanes two columns or more from
                // the edge, whose springs all lie beyond one face.
                if i == pinned_top || i == pinned_in || !(4..=7).contains(&c) {
                    assert!(!lane_moved(k), "lane of ({r}, {c}) moved");
                }
            }
        }
    }

    /// A sheet laid flat on a cuboid's face within the thickness (a cloth
    /// put on a ramp by hand): every spring lies over the face, no nearer
    /// than its ends, and the lanes' edge pass leaves it to the contacts
    /// (pushed out by the springs at once, it was thrown off the ramp).
    #[test]
    fn a_sheet_within_the_thickness_of_a_face_is_left_to_the_contacts() {
        use crate::cloth::ClothBuilder;
        let pose = Pose::from_parts(
            Vector::new(0.0, -0.5, 0.0),
            glam::Quat::from_rotation_z(-0.3),
        );
        let ramp = Obstacle::cuboid(Vector::new(2.0, 0.5, 2.0), pose);
        let (cols, rows) = (10, 10);
        let cloth = ClothBuilder::new(cols, rows).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        let n = cols * rows;
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(std::slice::from_ref(&ramp), (THICKNESS, 0.001), n));
        let mut l = sheet_lanes(&cloth, &plan, |r, c| {
            let local = Vector::new(
                (c as f32 - 4.5) * 0.05,
                0.5 + 0.2 * THICKNESS,
                (r as f32 - 4.5) * 0.05,
            );
            (pose.transform_point(local), 1.0)
        });
        let before = bits(&mut l);
        assert_eq!(contacts.keep_springs_off_cuboids(&plan, &mut l), 0.0);
        assert_eq!(bits(&mut l), before);
    }

    /// The lanes of a grid `cloth` in `plan`'s order, the particle of row
    /// `r` and column `c` at `place(r, c)` (position in m, inverse mass).
    fn sheet_lanes(
        cloth: &crate::cloth::Cloth,
        plan: &GridPlan,
        place: impl Fn(usize, usize) -> (Vector, f32),
    ) -> Lanes {
        let grid = cloth.grid().unwrap();
        let mut l = Lanes::default();
        l.resize(cloth.particle_count());
        let [x, y, z, _, _, _, w] = l.arrays_mut();
        for r in 0..grid.rows {
            for c in 0..grid.cols {
                let (p, inverse_mass) = place(r, c);
                let k = plan.lane(cloth.index(r, c).unwrap());
                (x[k], y[k], z[k], w[k]) = (p.x, p.y, p.z, inverse_mass);
            }
        }
        l
    }

    /// The one cuboid the lanes hold.
    fn cuboid_of(contacts: &LaneContacts) -> StillCuboid {
        match contacts.shapes[..] {
            [StillShape::Cuboid(c)] => c,
            _ => panic!("not one cuboid"),
        }
    }

    /// A turned cuboid's grown box ([`StillCuboid::box_meets`]) holds
    /// every point within the margin of it, so that the springs' pass may
    /// pass over a cuboid whose box is clear of the lanes'; and the far
    /// test of its planes ([`far_from_cuboid`]) holds only for points
    /// beyond its reach, whose plane is none.
    #[test]
    fn a_cuboids_box_and_far_test_leave_out_only_what_is_beyond_it() {
        let turn = glam::Quat::from_rotation_z(2.0)
            * glam::Quat::from_rotation_y(-0.7)
            * glam::Quat::from_rotation_x(0.4);
        let table = Obstacle::cuboid(
            Vector::new(0.3, 0.05, 0.2),
            Pose::from_parts(Vector::new(0.2, 0.9, -0.1), turn),
        );
        let mut contacts = LaneContacts::default();
        assert!(contacts.begin(std::slice::from_ref(&table), (THICKNESS, 0.002), 1));
        let cuboid = cuboid_of(&contacts);
        let margin = 0.5 * THICKNESS;
        let (mut met, mut clear, mut far) = (0, 0, 0);
        for k in 0..20_000 {
            let s = k as f32;
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin());
            let p = table.pose.translation + dir * (0.5 * ((0.37 * s) % 1.0));
            let distance = contact_prepared(
                &*table.shape,
                Analytic::of(&*table.shape),
                &PoseF64::of(&table.pose),
                p,
            )
            .expect("a contact")
            .signed_distance;
            if cuboid.box_meets((p, p), margin) {
                met += 1;
            } else {
                clear += 1;
                assert!(distance > margin, "{p:?} {distance} m from it, box clear");
            }
            let plane = cuboid_plane(&cuboid, [p.x, p.y, p.z]);
            if far_from_cuboid(&cuboid, [p.x, p.y, p.z]) {
                far += 1;
                assert!(distance > cuboid.reach, "{p:?} {distance} m from it, far");
                assert_eq!(plane, ([0.0; 3], f32::NEG_INFINITY));
            } else if distance < cuboid.reach * 0.999 {
                assert!(plane.1.is_finite(), "{p:?} {distance} m from it, no plane");
            }
        }
        assert!(
            met > 1000 && clear > 1000 && far > 1000,
            "{met} {clear} {far}"
        );
        // Points of its surface, corners and edges among them, moved out
        // by nine tenths of the margin: in the box, each of them.
        let half = Vector::new(0.3, 0.05, 0.2);
        for k in 0..2000 {
            let s = k as f32;
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin());
            let local = (dir * half * 3.0).clamp(-half, half) + dir.normalize() * 0.9 * margin;
            let p = table.pose.transform_point(local);
            assert!(cuboid.box_meets((p, p), margin), "{local:?} out of the box");
        }
    }

    /// Springs between points the lanes left outside: never into a floor;
    /// into a lone ball only when long enough that a chord between two
    /// points on the surface moved out by the thickness dips within half
    /// the thickness of it; not known for a ball beside another shape.
    #[test]
    fn short_springs_stay_out_of_a_lone_ball_and_any_spring_out_of_floors() {
        let [ball, floor] = ball_and_floor();
        let stays = |o: &[Obstacle], l: f32| LaneContacts::springs_stay_out(o, l, THICKNESS);
        assert!(stays(std::slice::from_ref(&floor), 1.0e3));
        assert!(!stays(&[ball.clone(), floor.clone()], 1.0e-3));
        let table = Obstacle::cuboid(Vector::splat(0.5), Pose::IDENTITY);
        assert!(!stays(&[table], 1.0e-3), "edges: the stage's edge pass");
        assert!(!stays(std::slice::from_ref(&ball), f32::NAN));
        // Chords of the ball (radius 0.5 at (0, 1, 0)) moved out by the
        // thickness, through a tilted plane, sampled along their length.
        let centre = Vector::new(0.0, 1.0, 0.0);
        let out = 0.5 + THICKNESS;
        let (mut some_in, mut some_out) = (false, false);
        for k in 1..60 {
            let l = 0.005 * k as f32;
            let half_angle = (0.5 * l / out).asin();
            let tilt = Vector::new(0.3, 1.0, -0.2).normalize();
            let side = tilt.cross(Vector::X).normalize();
            let a = centre + (tilt * half_angle.cos() + side * half_angle.sin()) * out;
            let b = centre + (tilt * half_angle.cos() - side * half_angle.sin()) * out;
            let closest = (0..=64)
                .map(|t| (a + (b - a) * (t as f32 / 64.0) - centre).length())
                .fold(f32::INFINITY, f32::min);
            let clear = closest >= 0.5 + 0.5 * THICKNESS;
            // Within rounding of the border, either answer.
            if (closest - (0.5 + 0.5 * THICKNESS)).abs() > 1.0e-5 {
                assert_eq!(stays(std::slice::from_ref(&ball), l), clear, "l = {l}");
            }
            some_in |= !clear;
            some_out |= clear;
        }
        assert!(some_in && some_out, "chords on both sides of the border");
    }
}
