//! The stage: which obstacles the lanes hold, their planes a substep, and the
//! passes that push the lanes out of them.

#[cfg(target_arch = "x86_64")]
use super::avx2::run_avx2;
use super::chunk::{Chunk, Law};
use super::lanes::W;
use super::portable::run_lanes;
use super::shape::StillShape;
use super::still_cuboid::{apart_from_faces, moved_planes_of, StillCuboid};
use crate::collision::{chords_clear_ball, Obstacle};
use crate::math::{simd_available, Pose, Vector};
use crate::parallel::{Disjoint, Team};
use crate::solver::grid_sweep::{GridPlan, LanePlanes, Lanes};
use crate::solver::lane_convex::{convex_planes_of, HullFaces, StillConvex};
use crate::solver::lane_mesh::{is_held_mesh, mesh_planes_of, MeshLists, StillMesh, Surface};
use parry3d::shape::Shape;

/// Lanes per chunk of a pass, a chunk to a thread.
pub(super) const CHUNK: usize = 2048;

/// A ball's radius must be over this many times the farthest a particle
/// moves in the substep for the lanes to hold it: a particle is put back
/// through the nearest point of the surface, which is the side it came in
/// by only while it has not come near the centre (the collision stage
/// traces a particle's path back instead). A particle can also be moved
/// by the sweeps beyond its own motion, hence a wide margin.
pub(crate) const BALL_MOTIONS: f32 = 4.0;

/// Within this share of a capsule's reach from its axis, a lane goes out
/// along the capsule's `across` ([`StillShape::Capsule`]).
pub(super) const ON_AXIS: f32 = 1.0e-3;

/// How far within the thickness, as a share of it, a lane may start a substep
/// and still be put out to the thickness by a cuboid's plane
/// ([`cuboid_plane`](super::still_cuboid::cuboid_plane)); one deeper is held
/// where it starts along the normal. The passes after the lanes' last push (the
/// stretch limit) leave lanes a hair inside, and held there they sank with each
/// substep's limit: the `box` peaked at 5.03% so with none, 4.78% with a tenth
/// (a quarter, a half and the whole thickness the same).
pub(super) const SETTLE_SHARE: f32 = 0.1;

/// The still smooth obstacles of a substep and what the lanes passes
/// record of them: per lane, how far (m) the passes pushed it this substep
/// and which obstacle last did (its index plus one, 0 for none).
#[derive(Debug, Default)]
pub(crate) struct LaneContacts {
    pub(super) shapes: Vec<StillShape>,
    pub(super) friction: Vec<f32>,
    /// Per shape, how far (m) its surface moves over the substep (zero
    /// for a still one).
    pub(super) shifts: Vec<Vector>,
    pub(super) depth: Vec<f32>,
    pub(super) touch: Vec<u32>,
    /// Per cuboid or other convex shape, per lane: the plane that holds
    /// the lane this substep (unit normal x, y, z and offset, m; an offset
    /// of −∞ for none), in the shape's slot of `lanes` entries
    /// ([`Self::take_planes`]).
    pub(super) planes: [Vec<f32>; 4],
    /// Lanes of the substep.
    pub(super) lanes: usize,
    /// Per lane, for the cuboid [`Self::keep_springs_off_cuboids`] is at:
    /// the faces it is beyond by the margin or over
    /// ([`StillCuboid::faces_beyond`]).
    pub(super) faces: Vec<u8>,
    /// The faces of the convex hulls held this substep.
    pub(super) hulls: HullFaces,
    /// Per mesh held, per lane: the triangles near it, kept from substep
    /// to substep.
    pub(super) meshes: MeshLists,
}

/// Whether the lanes may hold obstacle `o`'s shape, still: convex (parry
/// knows balls, capsules, half-spaces and cuboids convex too), a mesh
/// without an inside or a heightfield, or a compound of such parts.
pub(super) fn held_shape(o: &Obstacle) -> bool {
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
pub(super) fn lane_held(o: &Obstacle) -> bool {
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
pub(super) fn pieces(shape: &dyn Shape) -> impl Iterator<Item = (Option<usize>, Pose, &dyn Shape)> {
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
    pub(super) fn holds_each<'a>(
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
    pub(super) fn moving(&self) -> bool {
        self.shifts.iter().any(|&s| s != Vector::ZERO)
    }

    /// The still `shape` at `pose` (piece `part` of a compound, or the
    /// whole) of obstacle `index`, as the lanes hold it, its surface moved
    /// out by `thickness` (m), for a substep of `lanes` lanes in which no
    /// particle moves further than `motion` (m); one [`Self::holds`] took.
    pub(super) fn still_shape(
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
    /// the tangent plane of the rounded shape at the point nearest to the start
    /// ([`cuboid_plane`](super::still_cuboid::cuboid_plane),
    /// [`convex_plane`](crate::solver::lane_convex::convex_plane)). Once a
    /// substep, after [`Self::begin_holding`] with the same `obstacles` and
    /// before the passes.
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
    pub(super) fn slots(&self) -> usize {
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
    pub(super) fn pass(&mut self, lanes: &mut Lanes, team: Team, friction: bool) -> f32 {
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

/// [`run_lanes`], vectorised for AVX2 when `simd` (the same operations
/// lane by lane, no fused multiply-add: the same bits).
pub(super) fn run(chunk: Chunk, law: &Law, simd: bool) -> f32 {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        return unsafe { run_avx2(chunk, law) };
    }
    let _ = simd;
    run_lanes(chunk, law)
}

/// The bounding box (least and greatest corner, m) of the lanes at `p`;
/// of none, an empty one (least above greatest). Eight running extremes,
/// not one: a chain of dependent `min`s stalls.
pub(super) fn lanes_box(p: [&[f32]; 3]) -> (Vector, Vector) {
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
