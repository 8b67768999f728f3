//! The collision stage of a step: it owns where the obstacles are
//! ([`ObstacleTracks`]) and the particles' contacts ([`ContactSet`]), finds
//! contacts ahead of a substep for the solvers that take them into their
//! solve, and resolves them after the substep.

use parry3d::bounding_volume::Aabb;

use super::backing::{support_backed, Backed, Moving, Support};
use super::contact_set::{ContactSet, ParticleContact, NONE};
use super::obstacle::{Obstacle, ObstacleImpulse};
use super::particle_pass::{BlockOut, BlockScratch, ParticlePass, BLOCK, CONTACT_SLACK};
use super::response::FrictionPolicy;
use super::stretch_incidence::StretchIncidence;
use super::tracks::ObstacleTracks;
use crate::cloth::{Particles, SpringKind, Springs};
use crate::context::StepContext;
use crate::math::{Pose, Vector};
use crate::parallel::{Disjoint, Team};

/// Springs per block of the edge pass's first look (which springs come
/// near an obstacle), a block to a thread.
const EDGE_BLOCK: usize = 4096;

/// The bit of an edge list's entry that marks its spring far from every
/// obstacle as the edge pass begins (spring indices stay below it).
const FAR: u32 = 1 << 31;

/// What the particle pass found of each particle's distance to the
/// obstacles, for the edge pass's test of a spring.
struct EndDistances<'a> {
    /// Per particle: the nearest obstacle, or `NONE` beyond reach.
    nearest: &'a [u32],
    /// Per particle: its signed distance to that obstacle (m).
    distance: &'a [f32],
    /// The distance (m) taken for a particle beyond reach.
    reach: f32,
}

impl EndDistances<'_> {
    /// Whether the spring from particle `a` to `b` (at `x`) is surely at
    /// least half the `thickness` from every obstacle: distance to a surface
    /// changes no faster than along the spring, so no point of it comes
    /// closer than (d_a + d_b - length) / 2.
    #[inline]
    fn far(&self, x: &[Vector], (a, b): (usize, usize), thickness: f32) -> bool {
        let d = |i: usize| {
            if self.nearest[i] == NONE {
                self.reach
            } else {
                self.distance[i]
            }
        };
        let length = (x[b] - x[a]).length();
        0.5 * (d(a) + d(b) - length) >= 0.5 * thickness
    }
}

/// What the edge pass's first look at a spring reads: its ends, the
/// normals and distances the particle pass found, and where the particles
/// are.
struct EdgeLook<'a> {
    /// Each spring's two particles.
    ends: (&'a [u32], &'a [u32]),
    /// Per particle: the normal of its nearest obstacle.
    normal: &'a [Vector],
    distances: EndDistances<'a>,
    /// Positions (m).
    x: &'a [Vector],
    /// The collision thickness (m).
    thickness: f32,
}

impl EdgeLook<'_> {
    /// Pushes to `list` those of `springs` that may cut an obstacle, each
    /// marked [`FAR`] when it is surely clear of every one as the pass
    /// begins (found here, on the team's threads: the sort's root and
    /// scattered loads were a fifth of the serial pass).
    #[inline(always)]
    fn list(&self, springs: impl Iterator<Item = usize>, list: &mut Vec<u32>) {
        let (ends_a, ends_b) = self.ends;
        let (nearest, normal) = (self.distances.nearest, self.normal);
        for s in springs {
            let (a, b) = (ends_a[s] as usize, ends_b[s] as usize);
            let (oa, ob) = (nearest[a], nearest[b]);
            // No end near an obstacle, or both ends on one smooth stretch
            // of the same surface: nothing to cut.
            if (oa == NONE && ob == NONE) || (oa == ob && normal[a].dot(normal[b]) > SMOOTH_COS) {
                continue;
            }
            let far = self.distances.far(self.x, (a, b), self.thickness);
            list.push(s as u32 | if far { FAR } else { 0 });
        }
    }
}

/// How [`CollisionStage::resolve`] goes about a substep's contacts.
#[derive(Clone, Copy)]
pub(crate) struct ResolveOptions<'a> {
    /// Whether Coulomb friction acts here or was decided in the solve.
    pub friction: FrictionPolicy,
    /// The integrator held the still obstacles' contacts: pass over them,
    /// but for a particle a moving or dynamic body touched (it may have
    /// pushed it into one, or pressed it against one: `backing.rs`).
    pub skip_still: bool,
    /// Keep stretch and shear springs out of the obstacles too.
    pub edges: bool,
    /// The material's stretch limit (times the rest length; infinite for
    /// none), held once more against the contacts.
    pub stretch_limit: f32,
    /// When the integrator left every stretch spring within the limit: how
    /// much (m) any of them may still lengthen before it reaches it. The
    /// stretch limit is then not held again unless the contacts moved a
    /// particle far enough to use that room up.
    pub stretch_room: Option<f32>,
    /// The threads that resolve blocks of particles.
    pub team: Team<'a>,
}

/// Room (m) below the stretch limit taken to be none: the limit measures
/// a spring by its length, the hold by its square, and the two may round
/// apart.
const ROOM_EPSILON: f32 = 1.0e-6;

/// Two contact normals closer than this (cosine) lie on one smooth stretch of
/// surface, where a spring between two particles outside it stays outside.
const SMOOTH_COS: f32 = 0.995;

/// Collision state and scratch of a cloth's solver.
#[derive(Debug, Default)]
pub struct CollisionStage {
    pub(super) tracks: ObstacleTracks,
    contacts: ContactSet,
    /// Per particle: the obstacle nearest to it this substep (`NONE` for none)
    /// and the outward normal there.
    pub(super) nearest: Vec<u32>,
    pub(super) normal: Vec<Vector>,
    /// Per particle: distance to that obstacle after resolution (m).
    pub(super) distance: Vec<f32>,
    /// Per particle: the offset (m) of that obstacle's tangent plane at its
    /// point nearest to the particle, along `normal` (`contact_planes.rs`).
    pub(super) surface: Vec<f32>,
    /// Per particle: listed in `moved`.
    pub(super) edge_moved: Vec<bool>,
    /// The particles the edge pass moved, or the stretch limit in a round
    /// (`stretch_hold.rs`), each once: those `edge_moved` marks.
    pub(super) moved: Vec<u32>,
    /// Per particle: moved by the stretch hold's last round
    /// (`stretch_hold.rs`), listed in `held_before`.
    pub(super) held_moved: Vec<bool>,
    /// The particles `held_moved` marks, each once.
    pub(super) held_before: Vec<u32>,
    /// The stretch springs at each particle, for the stretch hold.
    pub(super) stretch_at: StretchIncidence,
    /// Bits over the stretch springs (in spring order among them): due for
    /// the stretch hold's next look, and watched this substep.
    pub(super) hold_due: Vec<u64>,
    pub(super) hold_watch: Vec<u64>,
    /// Per block of the particle pass: its scratch.
    blocks: Vec<BlockScratch>,
    /// The particles a dynamic body presses against another obstacle, in
    /// block and particle order (scratch of [`Self::resolve`]).
    backed: Vec<Backed>,
    /// The impulses (N·s) of the backed particles' support, and the
    /// bodies' motion through it (scratch).
    support: Vec<Support>,
    moving: Vec<Moving>,
    /// Per block of [`EDGE_BLOCK`] springs: those the edge pass must look at.
    edge_blocks: Vec<EdgeList>,
    /// The stretch and shear springs that may come near an obstacle this
    /// step, in spring order ([`CollisionStage::cache_candidates`]).
    pub(super) edge_watch: Vec<u32>,
    /// The longest stretch or shear spring when the cache was made (m;
    /// infinite without a cache).
    pub(super) longest_edge: f32,
    /// The margin (m) of a cache put off until a pass needs it
    /// ([`CollisionStage::defer_candidates`]).
    deferred: Option<f32>,
}

/// The springs of a block of the edge pass that it must look at, alone on
/// its cache lines (blocks on different threads push at once).
#[derive(Debug, Default)]
#[repr(align(128))]
struct EdgeList(Vec<u32>);

/// The springs the edge pass keeps out of obstacles: stretch, then shear.
fn edge_springs(springs: &Springs) -> impl Iterator<Item = usize> {
    springs
        .range(SpringKind::Stretch)
        .chain(springs.range(SpringKind::Shear))
}

impl CollisionStage {
    /// Prepares a step of `dt` seconds for `particles` particles: bounds
    /// swept over the step, grown by `reach` metres (the thickness plus the
    /// longest sampled spring).
    pub fn begin_step(&mut self, obstacles: &[Obstacle], dt: f32, reach: f32, particles: usize) {
        self.tracks.begin_step(obstacles, dt, reach);
        self.nearest.resize(particles, NONE);
        self.normal.resize(particles, Vector::ZERO);
        self.distance.resize(particles, f32::INFINITY);
        self.surface.resize(particles, 0.0);
        self.edge_moved.resize(particles, false);
        self.moved.clear();
        self.moved.reserve(particles);
        self.held_moved.resize(particles, false);
        self.held_before.clear();
        self.held_before.reserve(particles);
        self.stretch_at.built = false;
        self.contacts.begin_step(particles, obstacles.len());
        self.longest_edge = f32::INFINITY;
        self.deferred = None;
    }

    /// Puts [`CollisionStage::cache_candidates`] with `margin` (m) off
    /// until [`CollisionStage::cache_deferred`]: a step in which the
    /// solver holds every contact itself never needs it (made anyway, it
    /// was 2–3% of the drape's frame at N = 64).
    pub(crate) fn defer_candidates(&mut self, margin: f32) {
        self.deferred = Some(margin);
    }

    /// Makes the cache put off by [`CollisionStage::defer_candidates`],
    /// if any, from the positions `x` the step started at: the cache the
    /// step would have made at its start, bit for bit.
    pub(crate) fn cache_deferred(&mut self, x: &[Vector], springs: &Springs) {
        if let Some(margin) = self.deferred.take() {
            self.cache_candidates(x, margin, springs);
        }
    }

    /// Finds once for the step which obstacles each particle at `x` may meet
    /// while it stays within `margin` metres of there (further, it is looked
    /// up afresh: the cache changes no result, only the cost).
    /// Also lists, in spring order, the stretch and shear `springs` with an
    /// end that has candidates: while no particle strays beyond its margin,
    /// the edge pass need look at no other.
    pub fn cache_candidates(&mut self, x: &[Vector], margin: f32, springs: &Springs) {
        self.tracks.cache_candidates(x, margin);
        // Room for the most the edge pass can list, so that no substep allocates.
        let most = springs.count(SpringKind::Stretch) + springs.count(SpringKind::Shear);
        self.edge_watch.clear();
        self.edge_watch.reserve(most);
        if self.edge_blocks.len() < most.div_ceil(EDGE_BLOCK) {
            self.edge_blocks.resize_with(most.div_ceil(EDGE_BLOCK), || {
                EdgeList(Vec::with_capacity(EDGE_BLOCK))
            });
        }
        let mut longest2 = 0.0f32;
        for s in edge_springs(springs) {
            let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
            if self.tracks.has_cached(a) || self.tracks.has_cached(b) {
                self.edge_watch.push(s as u32);
            }
            // NaN stays out of `max`: a NaN length leaves no bound.
            let length2 = (x[b] - x[a]).length_squared();
            longest2 = if length2.is_nan() {
                f32::INFINITY
            } else {
                longest2.max(length2)
            };
        }
        self.longest_edge = longest2.sqrt();
        self.index_stretch_springs(springs, x.len());
    }

    /// Moves the obstacles to where they are at the end of the context's substep.
    pub fn advance(&mut self, ctx: &StepContext, obstacles: &[Obstacle]) {
        self.tracks.advance_to(obstacles, ctx.substep_end(), ctx.h);
    }

    /// The particles' contacts.
    pub fn contacts(&self) -> &ContactSet {
        &self.contacts
    }

    /// Momentum handed to each obstacle during the current step.
    pub fn impulses(&self) -> &[ObstacleImpulse] {
        self.tracks.impulses()
    }

    /// Each obstacle's pose at the end of the last substep (m).
    pub fn poses(&self) -> &[Pose] {
        self.tracks.poses()
    }

    /// Records momentum `j` (N·s) handed to obstacle `o` at `point` by a solver.
    pub fn add_impulse(&mut self, o: usize, point: Vector, j: Vector) {
        self.tracks.add_impulse(o, point, j);
    }

    /// Finds which free particles touch an obstacle now (within the thickness
    /// and a hair) or will reach its thickness layer within the substep
    /// (speculative contacts: moving at `v` plus gravity times `h` relative
    /// to the surface), without moving anything. Solvers that treat contacts
    /// as constraints have it run at the start of a substep, so their result
    /// depends only on the current state.
    pub fn detect_contacts(&mut self, ctx: &StepContext, p: &Particles, obstacles: &[Obstacle]) {
        let (h, thickness) = (ctx.h, ctx.thickness);
        for i in 0..p.x.len() {
            self.contacts.clear(i);
            if obstacles.is_empty() || p.inv_mass[i] == 0.0 {
                continue;
            }
            let x = p.x[i];
            let predicted = p.v[i] + ctx.gravity * h;
            let reach = Vector::splat(thickness + CONTACT_SLACK + predicted.length() * h);
            self.tracks.gather_box(Aabb::new(x - reach, x + reach));
            // The earliest arrival wins: the smallest gap left after the motion.
            let mut best = thickness + CONTACT_SLACK;
            for c in 0..self.tracks.candidates.len() {
                let o = self.tracks.candidates[c] as usize;
                let Some(hit) = self.tracks.contact(obstacles, o, x) else {
                    continue;
                };
                let surface_v = self.tracks.surface_velocity_of(obstacles, o, hit.point);
                let approach = (predicted - surface_v).dot(hit.normal).min(0.0) * h;
                let after = hit.signed_distance + approach;
                if after < best {
                    best = after;
                    self.contacts.detect(
                        i,
                        &ParticleContact {
                            obstacle: o as u32,
                            normal: hit.normal,
                            surface_velocity: surface_v,
                            immovable: obstacles[o].body.is_none(),
                            gap: (hit.signed_distance - thickness).max(0.0),
                            friction: obstacles[o].friction,
                        },
                    );
                }
            }
        }
    }

    /// Pushes free particles out to the thickness, positions only, and
    /// calls `moved` with each one it moved. Used inside iterative solvers
    /// so that they converge to a state outside the obstacles; such solvers
    /// apply friction themselves.
    pub fn project_positions(
        &mut self,
        x: &mut [Vector],
        inv_mass: &[f32],
        obstacles: &[Obstacle],
        thickness: f32,
        mut moved: impl FnMut(usize),
    ) {
        if obstacles.is_empty() {
            return;
        }
        let bits = |p: Vector| p.to_array().map(f32::to_bits);
        for i in 0..x.len() {
            // A particle the step's cache lists no obstacle for, still
            // within its margin, is near none (the particle pass's free
            // particles): the broad phase for it found nothing.
            if inv_mass[i] == 0.0 || self.tracks.free_drift2(i, x[i]).is_some() {
                continue;
            }
            let before = bits(x[i]);
            self.move_out(&mut x[i], None, obstacles, thickness);
            if bits(x[i]) != before {
                moved(i);
            }
        }
    }

    /// The deepest obstacle the point `x` is closer than `thickness` to:
    /// its index, the surface normal and how far `x` must move along it, in
    /// metres. Used by solvers that add contacts found during their solve.
    pub fn penetration(
        &mut self,
        x: Vector,
        obstacles: &[Obstacle],
        thickness: f32,
    ) -> Option<(usize, Vector, f32)> {
        self.tracks.gather(x);
        let mut deepest = None;
        for c in 0..self.tracks.candidates.len() {
            let o = self.tracks.candidates[c] as usize;
            let Some(hit) = self.tracks.contact(obstacles, o, x) else {
                continue;
            };
            let depth = thickness - hit.signed_distance;
            if depth > 0.0 && deepest.is_none_or(|(_, _, d)| depth > d) {
                deepest = Some((o, hit.normal, depth));
            }
        }
        deepest
    }

    /// Resolves every contact after a substep, with the obstacles where
    /// [`CollisionStage::advance`] put them; with `options.edges`, stretch
    /// and shear springs too. The solver's friction policy says whether Coulomb
    /// friction acts on the touching particles here or was already decided
    /// inside its solve (then they are only put back on the surface).
    /// The particles are resolved block by block, on the team's threads,
    /// and the blocks' impulses summed in block order: the bits are
    /// those of one thread. Returns the particle contacts resolved.
    pub(crate) fn resolve(
        &mut self,
        ctx: &StepContext,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        options: ResolveOptions,
    ) -> u32 {
        if obstacles.is_empty() {
            return 0;
        }
        let thickness = ctx.thickness;
        let n = particles.len();
        let blocks = n.div_ceil(BLOCK);
        self.blocks.resize_with(blocks, BlockScratch::default);
        let Particles {
            x,
            v,
            x_prev,
            mass,
            inv_mass,
        } = particles;
        let pass = ParticlePass {
            ctx,
            tracks: &self.tracks,
            obstacles,
            x_prev,
            mass,
            inv_mass,
            friction: options.friction,
            skip_still: options.skip_still,
            far: self.tracks.reach.max(thickness + CONTACT_SLACK),
        };
        let (x, v) = (Disjoint::new(&mut x[..]), Disjoint::new(&mut v[..]));
        let nearest = Disjoint::new(&mut self.nearest[..]);
        let normal = Disjoint::new(&mut self.normal[..]);
        let distance = Disjoint::new(&mut self.distance[..]);
        let surface = Disjoint::new(&mut self.surface[..]);
        let contact_set = self.contacts.shared();
        let scratch = Disjoint::new(&mut self.blocks[..]);
        let contacts = options.team.sum_count_uneven(blocks, |b| {
            let range = b * BLOCK..((b + 1) * BLOCK).min(n);
            // SAFETY: blocks are disjoint ranges of particles, and block `b`
            // alone uses scratch `b`.
            let (mut out, scratch) = unsafe {
                (
                    BlockOut {
                        x: x.range(range.clone()),
                        v: v.range(range.clone()),
                        nearest: nearest.range(range.clone()),
                        normal: normal.range(range.clone()),
                        distance: distance.range(range.clone()),
                        surface: surface.range(range.clone()),
                        contacts: contact_set.range(range.clone()),
                    },
                    &mut scratch.range(b..b + 1)[0],
                )
            };
            pass.block(range, &mut out, scratch)
        });
        // The momentum handed to the obstacles, block by block in order.
        let (mut strays, mut drift2, mut pinned_close) = (0, 0.0f32, false);
        let mut shift2 = 0.0f32;
        for block in &self.blocks[..blocks] {
            strays += block.strays;
            drift2 = drift2.max(block.drift2);
            shift2 = shift2.max(block.shift2);
            pinned_close |= block.pinned_close;
            for (imp, sum) in self.tracks.impulses.iter_mut().zip(&block.impulses) {
                if sum.contacts > 0 {
                    imp.linear += sum.linear;
                    imp.angular_about_origin += sum.angular_about_origin;
                    imp.contacts += sum.contacts;
                }
            }
        }
        // Bodies pressing particles against other obstacles are held up
        // by them (in block and particle order: the same bits on any
        // number of threads).
        self.backed.clear();
        for block in &self.blocks[..blocks] {
            self.backed.extend_from_slice(&block.backed);
        }
        if !self.backed.is_empty() {
            let (h, dt) = (ctx.h, ctx.dt);
            let (tracks, scratch) = (&mut self.tracks, (&mut self.support, &mut self.moving));
            support_backed(tracks, obstacles, &self.backed, (h, dt), scratch);
        }
        // A stray particle may meet an obstacle along any spring.
        let watched = strays == 0 && !self.tracks.cache_is_empty();
        let clear = !pinned_close && self.springs_clear_one_ball(drift2.sqrt(), thickness);
        let edges = options.edges && !clear;
        // Whether the edge pass moved a particle: one that moved none left
        // the cloth as the particle pass did.
        let mut edges_moved = false;
        if edges {
            let team = options.team;
            edges_moved =
                self.resolve_edges(particles, springs, obstacles, (thickness, team, watched));
        }
        // A spring lengthened by at most twice the farthest a particle was
        // moved here: with room for four times that (and a hair for
        // rounding), none reaches the limit, and the hold would shorten
        // nothing. At rest on a ball that is most substeps.
        let roomy = |room: f32| 4.0 * shift2.sqrt() + ROOM_EPSILON < room;
        if edges_moved || !options.stretch_room.is_some_and(roomy) {
            let limit = (options.stretch_limit, thickness, watched);
            self.hold_stretch_limit(particles, springs, obstacles, limit, options.team);
        }
        contacts
    }

    /// The edge pass: stretch and shear springs whose ends lie near an
    /// obstacle are kept out of it, then every particle it moved is pushed
    /// back out of every obstacle. Returns whether it moved any particle.
    fn resolve_edges(
        &mut self,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        (thickness, team, watched): (f32, Team, bool),
    ) -> bool {
        // Which springs may cut an obstacle, by what the particle pass found
        // (which this pass does not change): the watched springs or all, on
        // threads, block by block; then those, in spring order, on one.
        let (stretch, shear) = (
            springs.range(SpringKind::Stretch),
            springs.range(SpringKind::Shear),
        );
        let count = if watched {
            self.edge_watch.len()
        } else {
            stretch.len() + shear.len()
        };
        let blocks = count.div_ceil(EDGE_BLOCK);
        if self.edge_blocks.len() < blocks {
            self.edge_blocks.resize_with(blocks, EdgeList::default);
        }
        let look = EdgeLook {
            ends: (&springs.a, &springs.b),
            normal: &self.normal,
            distances: EndDistances {
                nearest: &self.nearest,
                distance: &self.distance,
                reach: self.tracks.reach,
            },
            x: &particles.x,
            thickness,
        };
        let watch = &self.edge_watch[..];
        let lists = Disjoint::new(&mut self.edge_blocks[..]);
        team.sum_count_uneven(blocks, |k| {
            // SAFETY: block `k` alone uses list `k`.
            let list = unsafe { &mut lists.range(k..k + 1)[0].0 };
            list.clear();
            let block = k * EDGE_BLOCK..((k + 1) * EDGE_BLOCK).min(count);
            // One loop for each source of springs, with no test of which
            // inside (with one loop and the test, this look was an eighth
            // of the box's frame).
            if watched {
                look.list(watch[block].iter().map(|&s| s as usize), list);
            } else {
                let at = |k: usize| {
                    if k < stretch.len() {
                        stretch.start + k
                    } else {
                        shear.start + (k - stretch.len())
                    }
                };
                look.list(block.map(at), list);
            }
            0
        });
        let lists = std::mem::take(&mut self.edge_blocks);
        self.moved.clear();
        for &listed in lists[..blocks].iter().flat_map(|l| &l.0) {
            let s = (listed & !FAR) as usize;
            let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
            // Far as the pass began, and both ends where they were then:
            // far still (the same test on the same numbers). An end moved
            // by a spring before this one: tested afresh.
            let unmoved = !self.edge_moved[a] && !self.edge_moved[b];
            let far = if unmoved {
                listed & FAR != 0
            } else {
                let ends = EndDistances {
                    nearest: &self.nearest,
                    distance: &self.distance,
                    reach: self.tracks.reach,
                };
                ends.far(&particles.x, (a, b), thickness)
            };
            if far {
                continue;
            }
            self.resolve_spring(particles, a, b, obstacles, 0.5 * thickness);
        }
        self.edge_blocks = lists;
        // Particles come first: whatever the springs did, every particle
        // the edge pass moved ends the substep outside the obstacles (in
        // any order: each moves only itself).
        let moved = std::mem::take(&mut self.moved);
        for &i in &moved {
            let i = i as usize;
            self.edge_moved[i] = false;
            if particles.inv_mass[i] != 0.0 {
                self.move_out(
                    &mut particles.x[i],
                    Some(&mut particles.v[i]),
                    obstacles,
                    thickness,
                );
            }
        }
        let any = !moved.is_empty();
        self.moved = moved;
        any
    }

    /// Moves the point `x` out to the thickness of every obstacle it is
    /// inside; with a velocity, also takes away its part into each surface.
    /// Returns how far it moved along the normals, in metres.
    pub(super) fn move_out(
        &mut self,
        x: &mut Vector,
        mut v: Option<&mut Vector>,
        obstacles: &[Obstacle],
        thickness: f32,
    ) -> f32 {
        let mut moved = 0.0;
        self.tracks.gather(*x);
        for c in 0..self.tracks.candidates.len() {
            let o = self.tracks.candidates[c] as usize;
            let Some(hit) = self.tracks.contact(obstacles, o, *x) else {
                continue;
            };
            if hit.signed_distance < thickness {
                let (n, depth) = (hit.normal, thickness - hit.signed_distance);
                *x += n * depth;
                moved += depth;
                if let Some(v) = v.as_deref_mut() {
                    let vn = (*v - self.tracks.surface_velocity_of(obstacles, o, *x)).dot(n);
                    if vn < 0.0 {
                        *v -= n * vn;
                    }
                }
            }
        }
        moved
    }
}
