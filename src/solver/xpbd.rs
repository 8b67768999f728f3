//! Extended position-based dynamics in small steps (Macklin, Müller and
//! Chentanez 2016, "XPBD"; Macklin et al. 2019, "Small steps in physics
//! simulation"): the same springs as every other integrator, each a distance
//! constraint with compliance `1/k` and damping `c`, solved by one
//! colour-ordered Gauss–Seidel sweep per substep. Many cheap substeps beat
//! few expensive ones: stiffness converges with the substep count, and
//! every substep meets the obstacles (the collision stage runs after each,
//! or the lanes hold them).
//! On a grid, contacts with still obstacles with edges are also held inside
//! the substep: each particle near one stays on the tangent plane it
//! started on (`collision/contact_planes.rs`) after the chains, each sweep
//! and rounds of the stretch limit, with Coulomb friction at the end. When
//! every obstacle is a still ball, capsule, half-space or cuboid, the lanes hold
//! all the contacts (`lane_contacts`): each particle is put back out
//! after the chains and after the last sweep, where Coulomb friction
//! undoes its slide (every second substep the springs are then kept off
//! a cuboid's edges), then the stretch limit runs, putting each particle
//! it moves back onto its cuboids' planes (its passes called again while
//! a spring is still far over it; at the step's last substep the
//! contacts win once more); the collision stage waits for the step's last
//! substep, and the state (positions, velocities) stays in the lanes from
//! one substep to the next, one's end and the next one's prediction in one
//! pass (`lane_motion.rs`), with the bits of the round trip through the
//! particles' arrays. Where it cannot stay (wind, self-collision, the
//! step's last substep), the prediction into the lanes and the way back
//! into the particles' arrays are passes of `lane_motion.rs` too.
//!
//! A substep of `h` seconds: predict `v += h (g − drag v + f_wind / m)`,
//! `x += h v`; for each spring, `C = |x_b − x_a| − L`, `α = 1/(k h²)`,
//! `γ = c/(k h)`, `Δλ = −(C + γ n·(Δx_b − Δx_a)) / ((1 + γ)(w_a + w_b) + α)`
//! with `Δx` the motion since the substep's start, and `x_a −= w_a Δλ n`,
//! `x_b += w_b Δλ n`; then the material's stretch limit, if it has one
//! (`solver/strain_limit.rs`); then `v = (x − x_start)/h`, computed as the predicted
//! velocity plus the sweep's correction over `h` (the same in exact
//! arithmetic, but in `f32` a substep's motion `v h` can be smaller than the
//! spacing of floats at the position: `x − x_start` would then read zero and
//! a falling cloth would never gain speed). A spring at rest length
//! under a steady load ends where `k C` balances the load: the equilibrium
//! of the force-based integrators.

use crate::cloth::{LaneGrid, SpringKind, SpringParams, Springs};
use crate::collision::{CollisionStage, ContactPlanes};
use crate::forces::{add_wind_forces, ForceModel};
use crate::math::Vector;
use crate::parallel::{Disjoint, Team};
use std::sync::atomic::{AtomicU32, Ordering};

use super::general_sweep::{self, PackedParticles};
use super::grid_chains::ChainScratch;
use super::grid_sweep::{
    limit_stretch, limit_stretch_again, sweep, Compliance, GridPlan, KindInSweep, LanePlanes, Lanes,
};
use super::lane_contacts::{Holding, LaneContacts};
use super::lane_motion::{self, correct_velocity, BandEnd, BandParticles, Motion};
use super::settings::SolverSettings;
use super::strain_limit;
use super::strain_limit::LimitScratch;
use super::substep::Substep;

/// Scratch of the small-steps solver.
#[derive(Debug, Default)]
pub(crate) struct XpbdScratch {
    /// Positions after the prediction, before the sweeps (the general sweep).
    predicted: Vec<Vector>,
    /// Wind forces (N).
    wind: Vec<Vector>,
    /// The grid's springs as row passes, for a grid cloth.
    plan: Option<GridPlan>,
    /// Which springs `plan` was made (or found impossible) for.
    planned_for: Option<PlanKey>,
    /// Structure-of-arrays copies for the grid sweep.
    lanes: Lanes,
    /// The stretch limit's weights near pins for a cloth without a grid
    /// plan (`pin_support.rs`; a grid plan holds its own, by lane), and
    /// its passes' scratch.
    limit_scratch: LimitScratch,
    /// Per spring: its multiplier over the substep's sweeps (the general sweep).
    lambda: Vec<f32>,
    /// The particles packed for the general sweep (`general_sweep.rs`).
    general: PackedParticles,
    /// Scratch of the direct solves along rows and columns (`grid_chains.rs`).
    chains: ChainScratch,
    /// The substep's contact planes (`collision/contact_planes.rs`).
    planes: ContactPlanes,
    /// The lane of each plane's particle.
    plane_lanes: Vec<u32>,
    /// Contacts with still balls, capsules, half-spaces and cuboids, held in the lanes
    /// (`lane_contacts`).
    lane_contacts: LaneContacts,
    /// Velocities (m/s) in lane order, while the state stays in the lanes.
    velocity: [Vec<f32>; 3],
    /// The lanes hold the cloth's state, the last substep's end already
    /// carried into this one's prediction (positions, starts and
    /// `velocity`), and the particles' own arrays are stale: between
    /// substeps whose contacts the lanes held, nothing else reads them.
    /// With the bits of the prediction's largest squared speed.
    resident: Option<u32>,
}

impl XpbdScratch {
    /// The lanes hold the cloth's state from the last substep of this
    /// step (`resident`): the particles' arrays are stale until the
    /// solver hands the state back, start of substep included, which it
    /// writes into `x_prev` itself.
    pub fn holds_state(&self) -> bool {
        self.resident.is_some()
    }
}

/// What a substep of the small-steps solver hands back.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct XpbdOutcome {
    /// When the grid's stretch limit left every stretch spring within it:
    /// the room (m) the one with least had left (see
    /// [`super::grid_sweep::limit_stretch`]).
    pub stretch_room: Option<f32>,
    /// Every stretch spring was within the limit by the limit's own test
    /// (`grid_sweep::limit_stretch`) when the substep handed the positions
    /// back: the grid's limit settled and nothing moved a lane after it.
    /// A stage after the substep that moves some particles then needs to
    /// look only at the springs at those ([`crate::solver::strain_limit`]).
    pub stretch_settled: bool,
    /// The substep held the contacts of every obstacle itself
    /// ([`LaneContacts::holds`]): the collision stage may wait for the
    /// step's last substep.
    pub contacts_held: bool,
    /// The substep held the contacts of the still obstacles among moving or
    /// dynamic bodies ([`Holding::Still`]): the collision stage answers
    /// for those bodies after it, and for all at the step's last substep.
    pub still_held: bool,
    /// At the step's last substep, when the lanes held the contacts: the
    /// particles they pushed out of an obstacle in it (0 otherwise).
    pub touching: u32,
}

/// What a grid plan depends on: the grid, and which springs (their storage,
/// count and first and last rest lengths: a solver handed another cloth of
/// the same grid but another size makes a new plan).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct PlanKey {
    grid: LaneGrid,
    springs: usize,
    count: usize,
    ends: [u32; 2],
    /// For a torn grid: the cloth's mass revision (a tear, which moves
    /// springs between particles, makes a new one).
    revision: Option<u64>,
}

impl PlanKey {
    fn of(grid: LaneGrid, springs: &Springs, revision: Option<u64>) -> PlanKey {
        let rest = springs.rest_lengths();
        let bits = |r: Option<&f32>| r.map_or(0, |r| r.to_bits());
        PlanKey {
            grid,
            springs: springs as *const Springs as usize,
            count: springs.len(),
            ends: [bits(rest.first()), bits(rest.last())],
            revision,
        }
    }
}

/// One substep: predict, sweep over the springs, velocities from the motion.
pub(crate) fn step(
    sub: &Substep,
    (x, v, x_prev): (&mut [Vector], &mut [Vector], &mut [Vector]),
    ws: &mut XpbdScratch,
    collision: &CollisionStage,
) -> XpbdOutcome {
    let model = &sub.model;
    let h = sub.ctx.h;
    let n = x.len();
    // Where the substep starts, before the prediction moves `x`. Not
    // where the lanes may hold every contact (a cuboid among them), or
    // every still obstacle's among moving or dynamic bodies: they hold
    // it instead, or the collision stage does after the substep.
    if LaneContacts::may_hold(sub.obstacles) || LaneContacts::may_hold_still(sub.obstacles) {
        ws.planes.clear();
    } else {
        collision.contact_planes(
            (x, v, model.inv_mass),
            sub.obstacles,
            (h, sub.ctx.thickness, sub.ctx.substep == 0),
            &mut ws.planes,
        );
    }
    let calm = model.wind.is_calm();
    if !calm {
        ws.wind.clear();
        ws.wind.resize(n, Vector::ZERO);
        add_wind_forces(
            model.triangles,
            &model.wind,
            (x, v),
            model.time,
            &mut ws.wind,
        );
    }
    let wind = if calm { None } else { Some(&ws.wind[..]) };
    let h2 = h * h;
    let compliance = model.spring_params.map(|p| Compliance {
        alpha: 1.0 / (p.stiffness * h2),
        gamma: p.damping / (p.stiffness * h),
    });
    // A grid of as many particles as the cloth (one made otherwise, or
    // pieces that claim another size, is swept as springs), or a torn
    // grid's first particles (the schedule hands one over only for a
    // material without a stretch limit: `schedule::lane_grid`).
    let cells = |g: &LaneGrid| g.grid.cols.checked_mul(g.grid.rows);
    let whole = |g: &LaneGrid| cells(g) == Some(n);
    let grid = sub.grid.filter(|g| cells(g).is_some_and(|c| c <= n));
    if let Some(grid) = grid {
        // A torn grid's springs change with each tear, which makes a new
        // mass revision.
        let revision = (!whole(&grid)).then_some(sub.mass_revision);
        let key = PlanKey::of(grid, model.springs, revision);
        if ws.planned_for != Some(key) {
            ws.plan = GridPlan::stacked(grid, model.springs)
                .or_else(|| GridPlan::torn(grid, model.springs, n));
            ws.planned_for = Some(key);
            ws.chains.replanned();
        }
    }
    match (&mut ws.plan, grid) {
        (Some(plan), Some(_)) => {
            plan.support_from_pins(model.inv_mass, model.springs, sub.mass_revision);
            let team = sub.team;
            let l = &mut ws.lanes;
            l.resize(n);
            let vel = &mut ws.velocity;
            for c in vel.iter_mut() {
                c.resize(n, 0.0);
            }
            // The state is in the lanes from the last substep of this step
            // (never across steps: the user may move particles between).
            let ahead = std::mem::take(&mut ws.resident).filter(|_| sub.ctx.substep > 0);
            let resident = ahead.is_some();
            // The state may stay in the lanes after this substep: no wind
            // (its forces are found from the particles' own arrays), no
            // stage after this one that moves the particles, and a
            // substep after it.
            let may_stay = calm && !sub.moved_after && sub.ctx.substep + 1 < sub.ctx.substeps;
            // The fastest particle after the prediction (its squared speed's
            // bits: non-negative floats order as their bits do).
            let fastest = AtomicU32::new(0);
            let lanes = l.disjoint();
            let [vx, vy, vz] = vel.each_mut().map(|c| Disjoint::new(&mut c[..]));
            // What moves a particle over the substep besides the springs
            // and the wind: the prediction's, and the next one's where the
            // state stays in the lanes.
            let moves = Motion {
                gravity: model.gravity,
                drag: model.air_drag,
                h,
            };
            if let Some(fast2) = ahead {
                // Predicted at the end of the last substep, the
                // multipliers zeroed then.
                fastest.store(fast2, Ordering::Relaxed);
            } else {
                // Predict, and copy into the lanes: positions now, at the
                // substep's start, and inverse masses (and velocities, when
                // the state may stay there); band by band.
                let (xs, vs) = (Disjoint::new(&mut x[..]), Disjoint::new(&mut v[..]));
                // The multipliers start the substep at zero, band by band too.
                plan.for_each_band_from_zero(team, |band, lanes_of_band| {
                    // SAFETY: bands are disjoint ranges of particles and of lanes.
                    let ([x, v], (band_lanes, velocities, _)) = unsafe {
                        (
                            [xs, vs].map(|s| s.range(band.clone())),
                            band_state(lanes, [vx, vy, vz], band.clone()),
                        )
                    };
                    let particles = BandParticles {
                        x,
                        v,
                        w: &model.inv_mass[band.clone()],
                        wind: wind.map(|f| &f[band.clone()]),
                        lane: lanes_of_band,
                        first_lane: band.start,
                    };
                    let velocities = may_stay.then_some(velocities);
                    let fast2 =
                        lane_motion::predict_into_lanes(particles, band_lanes, velocities, moves);
                    fastest.fetch_max(fast2.to_bits(), Ordering::Relaxed);
                });
            }
            let motion = f32::from_bits(fastest.into_inner()).sqrt() * h;
            let contacts = &mut ws.lane_contacts;
            let holding = contacts.begin_holding(
                sub.obstacles,
                (sub.ctx.thickness, motion),
                (sub.ctx.substep_end(), h),
                n,
            );
            let held = holding != Holding::None;
            if held {
                contacts.take_planes(sub.obstacles, l, team);
            }
            // The contacts inside the substep: after the chains and each
            // sweep, every particle with a plane is put back onto it.
            let lane = &mut ws.plane_lanes;
            lane.clear();
            lane.extend(
                ws.planes
                    .particle
                    .iter()
                    .map(|&i| plan.lane(i as usize) as u32),
            );
            let planes = &mut ws.planes;
            // The chains solve whole rows and columns of stretch springs,
            // which a torn grid no longer has.
            let chains = sub.settings.xpbd_chains && !plan.is_torn();
            if chains {
                let alpha = compliance[0].alpha;
                ws.chains.solve(plan, l, (alpha, sub.mass_revision), team);
                project_planes(planes, lane, l, team);
                contacts.project(l, team);
            }
            let later = later_sweep_kinds(&model.spring_params);
            let sweeps = grid_sweeps(sub.settings, chains);
            plan.leftover_mut().begin_substep();
            for it in 0..sweeps {
                let kinds = kinds_in_sweep(it, sweeps, later, chains);
                sweep(plan, l, &compliance, kinds, team);
                plan.leftover_mut().sweep(l, &compliance, kinds);
                project_planes(planes, lane, l, team);
            }
            // The lanes' contacts after the last sweep only (after each:
            // the drape's peak stretch the same at N = 128, 4.60% against
            // 4.54% at N = 64), with friction before the limit: undoing a
            // slide after it stretched the springs again (the drape N =
            // 128 peaked at 5.12% so, 4.84% this way; 4.90% with the
            // collision stage's friction every substep).
            contacts.project_with_friction(l, team);
            // The springs off a cuboid's edges and corners every
            // `CUBOID_EDGES_EVERY` substeps, before the limit takes back
            // what that stretched (unless the settings keep only the
            // particles out, as the collision stage's edge pass does, or
            // no edge is within the step's reach: the `fold` on the middle
            // of its floor).
            if held
                && sub.settings.edge_collisions
                && sub.edges_near
                && contacts.holds_cuboid()
                && (sub.ctx.substep + 1).is_multiple_of(CUBOID_EDGES_EVERY)
            {
                contacts.keep_springs_off_cuboids(plan, l);
            }
            // The limit puts each lane it moves back onto its cuboids'
            // planes at once (`hold_limit`).
            let cuboids = contacts.held_planes();
            // The limit holds its long spans after an unsettled call of
            // the same step only: a step's bits do not hang on the step
            // before (a snapshot restored between steps computes the same).
            if sub.ctx.substep == 0 {
                plan.forget_unsettled();
            }
            let room = hold_limit(plan, l, (model.stretch_limit, cuboids), team);
            let (room, settled) =
                hold_planes((planes, lane), plan, l, (model.stretch_limit, room), team);
            // At the step's last substep the lanes' contacts win over the
            // limit, as the collision stage's do; a spring lengthens by at
            // most twice the farthest a particle moves. Before it the next
            // substep's first pass puts back what the limit moved in (a
            // pass here every substep: the drape N = 128 peaked at 4.91%,
            // 4.76% without; N = 64 4.53% either way).
            let last = sub.ctx.substep + 1 == sub.ctx.substeps;
            let pushed = if last { contacts.project(l, team) } else { 0.0 };
            // A torn grid leaves springs at its tears to the leftovers,
            // which the grid's limit does not hold.
            let settled = settled && pushed == 0.0 && !plan.is_torn();
            let room = room
                .map(|room| room - 2.0 * pushed)
                .filter(|&room| room > 0.0);
            // Velocities from the motion: the predicted velocity plus the
            // sweeps' correction over `h`, the prediction being the start
            // plus `h` times it (as `predict` made it, to the bit).
            // Not while the collision stage answers for moving or dynamic
            // bodies after each substep: it works on the particles' arrays.
            let stay = holding == Holding::All && may_stay;
            let lanes = l.disjoint();
            let [vx, vy, vz] = vel.each_mut().map(|c| Disjoint::new(&mut c[..]));
            if stay {
                // This substep's velocities and the next one's prediction
                // (no wind, the same step's gravity, drag and `h`) in one
                // pass, and the multipliers zeroed for it: the state stays
                // in the lanes and nothing else reads it between the two.
                let fastest = AtomicU32::new(0);
                plan.for_each_band_from_zero(team, |band, _| {
                    // SAFETY: bands are disjoint ranges of lanes.
                    let (l, v, _) = unsafe { band_state(lanes, [vx, vy, vz], band) };
                    let fast2 = lane_motion::correct_and_predict((l, v), moves);
                    fastest.fetch_max(fast2.to_bits(), Ordering::Relaxed);
                });
                ws.resident = Some(fastest.into_inner());
            } else {
                // Back into the particles' arrays: from the lanes' state
                // (with the substep's start, which the schedule could not
                // copy from them), or from what the prediction left there.
                let (xs, vs, ps) = (
                    Disjoint::new(&mut x[..]),
                    Disjoint::new(&mut v[..]),
                    Disjoint::new(&mut x_prev[..]),
                );
                plan.for_each_band(team, |band| {
                    // SAFETY: as above.
                    let ([x, v, x_prev], (band_lanes, velocities, _)) = unsafe {
                        (
                            [xs, vs, ps].map(|s| s.range(band.clone())),
                            band_state(lanes, [vx, vy, vz], band.clone()),
                        )
                    };
                    let end = BandEnd {
                        x,
                        v,
                        x_prev,
                        w: &model.inv_mass[band.clone()],
                        lane: plan.lanes_of(&band),
                        first_lane: band.start,
                    };
                    lane_motion::lanes_into_particles(end, (band_lanes, velocities), resident, h);
                });
            }
            XpbdOutcome {
                stretch_room: room,
                stretch_settled: settled,
                contacts_held: holding == Holding::All,
                still_held: holding == Holding::Still,
                touching: if holding == Holding::All && last {
                    contacts.touching()
                } else {
                    0
                },
            }
        }
        _ => {
            let (springs, w) = (model.springs, model.inv_mass);
            ws.general.load_start(x, w);
            for i in 0..n {
                let (xi, vi) = (&mut x[i], &mut v[i]);
                predict(model, wind, i, (xi, vi), h);
            }
            ws.predicted.clear();
            ws.predicted.extend_from_slice(x);
            ws.lambda.clear();
            ws.lambda.resize(model.springs.len(), 0.0);
            ws.general.load_now(x);
            for _ in 0..sub.settings.xpbd_iterations {
                general_sweep::sweep(springs, &mut ws.general, &mut ws.lambda, &compliance);
            }
            ws.general.store(x);
            // A pinned cloth's limit moves particles near the pins less, as
            // the grid's does (`pin_support.rs`).
            strain_limit::limit_stretch_supported(
                &mut ws.limit_scratch,
                (springs, w, sub.mass_revision),
                (x, None),
                model.stretch_limit,
                (strain_limit::RELAXED_PASSES, false),
            );
            for i in 0..n {
                let correction = x[i] - ws.predicted[i];
                correct_velocity(&mut v[i], correction, model.inv_mass[i], h);
            }
            XpbdOutcome {
                stretch_room: None,
                stretch_settled: false,
                contacts_held: false,
                still_held: false,
                touching: 0,
            }
        }
    }
}

/// After a stage that moved the particles since the substep (self-collision
/// and its stretch limit), at a substep whose contacts the lanes held
/// ([`XpbdOutcome::contacts_held`]): puts every particle at `x` (m) back out
/// of the held obstacles as the lanes' pass does, and takes from its
/// velocity `v` (m/s) what still closes on the obstacle along the push.
/// Without it a layer pushed into the floor started the next substep
/// there, where a cuboid's plane holds it rather than put it out (so as
/// not to pump), and the layers came within 0.46 of their thickness on
/// landing (tests/self_collision.rs); with the collision stage after
/// every substep instead, the `fold` took 5.1 ms a frame rather than 4.4.
pub(crate) fn hold_contacts_again(
    ws: &mut XpbdScratch,
    (x, v): (&mut [Vector], &mut [Vector]),
    team: Team,
) {
    let (Some(plan), contacts) = (&ws.plan, &mut ws.lane_contacts) else {
        return;
    };
    let n = x.len();
    if contacts.is_empty() || v.len() != n {
        return;
    }
    {
        let [lx, ly, lz, ..] = ws.lanes.arrays_mut();
        if lx.len() != n {
            return;
        }
        for (i, p) in x.iter().enumerate() {
            let lane = plan.lane(i);
            (lx[lane], ly[lane], lz[lane]) = (p.x, p.y, p.z);
        }
    }
    if contacts.project(&mut ws.lanes, team) == 0.0 {
        return;
    }
    let [lx, ly, lz, ..] = ws.lanes.arrays_mut();
    for (i, (p, vi)) in x.iter_mut().zip(v.iter_mut()).enumerate() {
        let lane = plan.lane(i);
        let out = Vector::new(lx[lane], ly[lane], lz[lane]);
        if out == *p {
            continue;
        }
        let push = out - *p;
        let length = push.length();
        if length > 0.0 {
            let normal = push / length;
            let closing = vi.dot(normal).min(0.0);
            *vi -= normal * closing;
            *p = out;
        }
    }
}

/// The lanes (x, y, z, start x, y, z, w) and the lane-order velocities of
/// the lanes `band`, and its length, which every slice has (asserted once,
/// so that each index in the loops is checked once).
///
/// # Safety
/// No other slice of these lanes taken from the same arrays may be in use
/// meanwhile.
#[allow(clippy::type_complexity)]
unsafe fn band_state<'a>(
    lanes: [Disjoint<'a, f32>; 7],
    velocity: [Disjoint<'a, f32>; 3],
    band: std::ops::Range<usize>,
) -> ([&'a mut [f32]; 7], [&'a mut [f32]; 3], usize) {
    // SAFETY: by the caller's promise.
    let (l, v) = unsafe {
        (
            lanes.map(|s| s.range(band.clone())),
            velocity.map(|s| s.range(band.clone())),
        )
    };
    let len = band.len();
    let [a, b, c, d, e, f, g] = &l;
    assert!(
        [
            a.len(),
            b.len(),
            c.len(),
            d.len(),
            e.len(),
            f.len(),
            g.len()
        ] == [len; 7]
    );
    assert!([v[0].len(), v[1].len(), v[2].len()] == [len; 3]);
    (l, v, len)
}

/// Particle `i`'s prediction over `h` seconds: external forces (gravity,
/// air drag, `wind` in N if any), explicitly; a pinned particle moves with
/// its velocity.
#[inline(always)]
fn predict(
    model: &ForceModel,
    wind: Option<&[Vector]>,
    i: usize,
    (x, v): (&mut Vector, &mut Vector),
    h: f32,
) {
    let w = model.inv_mass[i];
    if w != 0.0 {
        let mut a = model.gravity - *v * model.air_drag;
        if let Some(wind) = wind {
            a += wind[i] * w;
        }
        *v += a * h;
    }
    *x += *v * h;
}

/// Planes per chunk of a pass over the contact planes, a chunk to a thread.
const PLANE_CHUNK: usize = 1024;

/// Projects every particle with a contact plane onto its half-space, in
/// the lanes (`lane` of each plane: each lane is at most one plane's); adds
/// the push to the plane's depth. Returns the farthest it pushed one (m).
fn project_planes(planes: &mut ContactPlanes, lane: &[u32], lanes: &mut Lanes, team: Team) -> f32 {
    let ContactPlanes {
        normal,
        offset,
        depth,
        ..
    } = planes;
    let count = lane.len();
    assert!(normal.len() == count && offset.len() == count && depth.len() == count);
    let [lx, ly, lz, ..] = lanes.disjoint();
    let n_lanes = lx.len();
    let depth = Disjoint::new(&mut depth[..]);
    team.largest_over_chunks((count, PLANE_CHUNK), |range| {
        // SAFETY: chunks are disjoint ranges of planes.
        let depth = unsafe { depth.range(range.clone()) };
        let mut farthest = 0.0f32;
        for (d, k) in depth.iter_mut().zip(range) {
            let at = lane[k] as usize;
            assert!(at < n_lanes);
            let n = normal[k];
            // SAFETY: in bounds (asserted); lane `at` is this plane's
            // alone, so no other thread reads or writes it meanwhile.
            unsafe {
                let p = Vector::new(
                    *lx.as_ptr().add(at),
                    *ly.as_ptr().add(at),
                    *lz.as_ptr().add(at),
                );
                let gap = n.dot(p) - offset[k];
                if gap < 0.0 {
                    let q = p - n * gap;
                    (
                        *lx.as_ptr().add(at),
                        *ly.as_ptr().add(at),
                        *lz.as_ptr().add(at),
                    ) = (q.x, q.y, q.z);
                    *d -= gap;
                    farthest = farthest.max(-gap);
                }
            }
        }
        farthest
    })
}

/// Calls of the grid's stretch limit at most, each of up to
/// `grid_sweep::LIMIT_PASSES` passes, while the last pass of one still
/// shortens a spring far over the limit (`LimitOutcome::unsettled`): a
/// long run of springs over it, as along an edge whipped round the ball as
/// the drape lands, comes back only a spring or two a pass. Each call
/// starts again from the stretch springs alone: those with an end the call
/// before still moved (`limit_stretch_again`; the rest it left within).
/// Measured, peak stretch over every frame of the drape at 16 substeps:
/// 6.7% with one call at N = 128, 4.8% with up to five; at N = 256 with
/// 64 substeps, 4.7%. (Going on within one call instead, up to 40 passes
/// of the moving springs, landed as well but pumped a curtain whose pins
/// were thrown apart, with self-collision, to 700 m/s: tests/xpbd.rs.)
/// The calls after the first run in a landing's frames, and where a
/// pinned cloth hangs with springs far over the limit at its pins: the
/// `pins` sheet hung by two corners peaks at 5.5% instead of 8.5%, the
/// `hammock` at 5.3% instead of 8.6%, each about a third slower a frame.
/// A pinned cloth takes up to [`PINNED_LIMIT_ROUNDS`].
const LIMIT_ROUNDS: u32 = 5;

/// [`LIMIT_ROUNDS`] for a cloth with pins, whose limit weighs the
/// particles near them as heavier (`pin_support.rs`): a cloth hung by its
/// pins hangs on long runs of springs at the limit, which come back a few
/// springs a call. Measured, peak stretch over every frame and ms a frame
/// (BENCHMARKS.md, thirty-sixth session), a cotton sheet hung by two
/// corners at N = 64, 96 and 128: 9.8%, 31% and 68% with 5 calls and
/// equal weights (2.6, 6.8 and 13.5 ms); with the weights, 6.5%, 20% and
/// 33% with 5 calls, 4.75%, 5.5% and 19% with 20, 4.75%, 4.75% and 13%
/// with 40 (2.4, 6.8 and 25 ms), all at 16 substeps (the side rule of
/// `stability.rs` now takes 28 at N = 128: 4.89% in 20 ms). The pinned canonical scenes (`pins`,
/// `curtain`, `flag`, `hammock`) step as fast as with 5 calls and equal
/// weights, or faster; the `box`, without pins, took 3.1 → 3.5 ms a frame
/// with 20, so a cloth without pins keeps 5.
const PINNED_LIMIT_ROUNDS: u32 = 40;

/// The stretch limit on the lanes (`factor` times the rest length, the
/// first of `limit`), in up to [`LIMIT_ROUNDS`] ([`PINNED_LIMIT_ROUNDS`]
/// for a cloth with pins) calls of
/// [`limit_stretch`]; returns the room (m) every stretch spring has left
/// below it (`None`: not known).
///
/// With the planes of the cuboids the lanes hold (the second of `limit`),
/// the limit puts each lane it moves back onto them in the same step, so
/// that the contacts and the limit meet over a cuboid's edges in one
/// call. They took turns before: up to six rounds of the lanes' contacts,
/// each followed by the limit again, while a round pushed a lane further
/// than 10 µm (`box`, a 64 × 64 cotton sheet dropped on a cube at 32
/// substeps, peak stretch over 120 frames: 7.33% with no round, 5.71% with
/// two, 5.08% with four, 4.82% with six), 2.75 calls of the limit a
/// substep. Measured against the six rounds (bench, one thread, ms a frame
/// and peak): `box` 4.58 ms, 4.77% → 3.46 ms, 4.66%; the tablecloth of
/// `tests/user_drops.rs` (a table top and its leg: two cuboids) 4.51% →
/// 4.51%. With the planes in the limit the rounds changed nothing (a
/// round's first push was under 10 µm) and were dropped.
fn hold_limit(
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    limit: (f32, Option<LanePlanes>),
    team: Team,
) -> Option<f32> {
    let mut outcome = limit_stretch(plan, lanes, limit, team);
    let rounds = if plan.pinned() {
        PINNED_LIMIT_ROUNDS
    } else {
        LIMIT_ROUNDS
    };
    for _ in 1..rounds {
        if !outcome.unsettled {
            break;
        }
        outcome = limit_stretch_again(plan, lanes, limit, team);
    }
    outcome.room
}

/// How often (in substeps) the lanes keep the springs off the edges and
/// corners of the cuboids they hold
/// ([`LaneContacts::keep_springs_off_cuboids`]): the lanes keep every
/// particle out of a cuboid, but not the springs between them off its
/// edges, and the collision stage's edge pass at the step's last substep
/// alone had to undo a whole step of springs cutting them, which
/// stretched them (a 48 × 48 tablecloth on a table, `tests/user_drops.rs`,
/// peaks at 5.66% so). Measured, tablecloth peak and `box` (32 substeps,
/// bench, one thread) ms a frame and peak: every substep 4.51%, 4.74 ms,
/// 4.78%; every second 4.51%, 4.36 ms, 4.77%; every third 4.64%, 4.20 ms;
/// every fourth 4.60%, 4.20 ms. The collision stage's edge pass did it
/// every second substep before, with its particle pass and stretch hold
/// (the state out of the lanes and back): 4.56%, 6.4 ms, 4.78%.
const CUBOID_EDGES_EVERY: u32 = 2;

/// Rounds of the contact planes against the stretch limit after the sweeps:
/// each pushes the particles back onto their planes, and all but the last
/// hold the limit again. Measured on `box` at 24 substeps (before friction
/// on the planes): the landing peaked at 6.45% stretch with the planes
/// projected only after the chains and the sweeps, 5.51% with three rounds
/// (at 16: 8.2%, 8.3% with one, 7.2% with two, 6.6% with three).
const PLANE_ROUNDS: u32 = 3;

/// The contact planes held against the stretch limit (`factor` times the
/// rest length) in [`PLANE_ROUNDS`] rounds, then Coulomb friction on every
/// particle the planes pushed: its slide over the substep (the obstacles
/// are still) is undone up to the coefficient times how far the planes
/// pushed it. Takes the room (m) the limit left every stretch spring
/// (`Some` when it settled) and returns what is left of it: a spring
/// lengthens by at most twice the farthest a particle moves (`None`: not
/// known, or none left); and whether the lanes are as a limit call that
/// settled left them.
fn hold_planes(
    (planes, lane): (&mut ContactPlanes, &[u32]),
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    (factor, room): (f32, Option<f32>),
    team: Team,
) -> (Option<f32>, bool) {
    let mut settled = room.is_some();
    if planes.is_empty() {
        return (room, settled);
    }
    let mut room = room;
    for r in 0..PLANE_ROUNDS {
        let pushed = project_planes(planes, lane, lanes, team);
        if pushed == 0.0 {
            break;
        }
        room = room.map(|room| room - 2.0 * pushed);
        settled = false;
        if r + 1 < PLANE_ROUNDS {
            room = hold_limit(plan, lanes, (factor, None), team);
            settled = room.is_some();
        }
    }
    let ContactPlanes {
        normal,
        depth,
        friction,
        ..
    } = &*planes;
    let count = lane.len();
    assert!(normal.len() == count && depth.len() == count && friction.len() == count);
    let [lx, ly, lz, sx, sy, sz, _] = lanes.disjoint();
    let n_lanes = lx.len();
    let farthest = team.largest_over_chunks((count, PLANE_CHUNK), |range| {
        let mut farthest = 0.0f32;
        for k in range {
            if depth[k] <= 0.0 {
                continue;
            }
            let at = lane[k] as usize;
            assert!(at < n_lanes);
            let n = normal[k];
            // SAFETY: in bounds (asserted); lane `at` is this plane's
            // alone, so no other thread reads or writes it meanwhile.
            unsafe {
                let p = Vector::new(
                    *lx.as_ptr().add(at),
                    *ly.as_ptr().add(at),
                    *lz.as_ptr().add(at),
                );
                let start = Vector::new(
                    *sx.as_ptr().add(at),
                    *sy.as_ptr().add(at),
                    *sz.as_ptr().add(at),
                );
                let slide = p - start;
                let tangent = slide - n * n.dot(slide);
                let (length, allowed) = (tangent.length(), friction[k] * depth[k]);
                let undone = if length <= allowed {
                    tangent
                } else {
                    tangent * (allowed / length)
                };
                let q = p - undone;
                (
                    *lx.as_ptr().add(at),
                    *ly.as_ptr().add(at),
                    *lz.as_ptr().add(at),
                ) = (q.x, q.y, q.z);
                farthest = farthest.max(length.min(allowed));
            }
        }
        farthest
    });
    let room = room
        .map(|room| room - 2.0 * farthest)
        .filter(|&room| room > 0.0);
    (room, settled && farthest == 0.0)
}

/// A kind of spring at most this fraction as stiff as the stretch springs
/// is soft: see [`later_sweep_kinds`].
const SOFT_FRACTION: f32 = 0.1;

/// The kinds of spring a grid's second and later sweeps of a substep
/// take (by [`SpringKind::index`]): all but the bend springs when they are
/// soft ([`SOFT_FRACTION`] of the stretch springs' stiffness at most, as
/// in every preset, where they are a fortieth to a three-hundredth). A
/// soft spring's compliance dominates its projection, which meets it in
/// one step whatever its neighbours do; the later sweeps are for the stiff
/// springs' coupling (the drape's and the pinned sheets' peak stretch the
/// same to 0.01% without them; the sweeps a sixth cheaper).
fn later_sweep_kinds(params: &[SpringParams; 3]) -> [bool; 3] {
    let stretch = params[SpringKind::Stretch.index()].stiffness;
    let bend = params[SpringKind::Bend.index()].stiffness;
    let mut kinds = [true; 3];
    kinds[SpringKind::Bend.index()] = bend > SOFT_FRACTION * stretch;
    kinds
}

/// The sweeps a substep of a grid cloth takes: the settings' solves
/// (`xpbd_iterations`), of which the chain solves, when they run
/// (`chains`), are the first (never no sweep: the shear and bend springs have only the
/// sweeps). The chains meet the stretch springs' compliance exactly along
/// rows and columns, and one sweep after them hangs a cloth 10 µm from
/// the force-based equilibrium (`tests/xpbd.rs`; one sweep alone, 1.2 mm).
/// Measured against two sweeps after the chains, peak stretch over every
/// frame: the drape 4.64 → 4.51% at N = 64, 4.82 → 4.84% at 128 (silk
/// 4.87 → 4.91%), the `pins` corners 5.52 → 5.42%, the curtain 5.09 →
/// 5.05%, the hammock 5.26 → 5.33%, `box` 5.18 → 5.40%; the drape's
/// frame 13–30% shorter (BENCHMARKS.md, twenty-third session).
fn grid_sweeps(settings: &SolverSettings, chains: bool) -> u32 {
    let solves = settings.xpbd_iterations.max(1);
    if chains {
        (solves - 1).max(1)
    } else {
        solves
    }
}

/// How sweep `it` of a substep's `sweeps` takes each kind of spring (by
/// [`SpringKind::index`]): the first takes every kind, the later ones the
/// kinds `later` says. A kind's multipliers start from zero where no
/// solve before this sweep projected it this substep (the chain solves,
/// when `chains`, project the stretch springs), and are kept where a later
/// sweep takes it: one sweep a substep neither reads nor stores the shear
/// and bend springs' multipliers.
fn kinds_in_sweep(it: u32, sweeps: u32, later: [bool; 3], chains: bool) -> [KindInSweep; 3] {
    let on = |k: usize, sweep: u32| sweep == 0 || later[k];
    std::array::from_fn(|k| {
        if !on(k, it) {
            return KindInSweep::OFF;
        }
        let chained = chains && k == SpringKind::Stretch.index();
        KindInSweep {
            on: true,
            from_zero: !chained && (0..it).all(|before| !on(k, before)),
            kept: (it + 1..sweeps).any(|after| on(k, after)),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::Material;

    /// The multipliers are read only where a solve before stored them and
    /// stored only where a sweep after reads them.
    #[test]
    fn sweeps_read_only_the_multipliers_stored_before_them() {
        let (stretch, shear, bend) = (0, 1, 2);
        let soft_bend = [true, true, false];
        // One sweep after the chains: the stretch springs' come from them.
        let one = kinds_in_sweep(0, 1, soft_bend, true);
        assert!(!one[stretch].from_zero && !one[stretch].kept);
        assert!(one[shear].from_zero && !one[shear].kept);
        assert!(one[bend].from_zero && !one[bend].kept);
        // Two: the second reads what the first stored, but no soft bend springs.
        let first = kinds_in_sweep(0, 2, soft_bend, true);
        let second = kinds_in_sweep(1, 2, soft_bend, true);
        assert!(first[shear].from_zero && first[shear].kept);
        assert!(first[bend].from_zero && !first[bend].kept);
        assert!(!second[shear].from_zero && !second[shear].kept);
        assert_eq!(second[bend], KindInSweep::OFF);
        // Without the chains the stretch springs start from zero too.
        let alone = kinds_in_sweep(0, 3, [true; 3], false);
        assert!(alone.iter().all(|k| k.on && k.from_zero && k.kept));
        let middle = kinds_in_sweep(1, 3, [true; 3], false);
        assert!(middle.iter().all(|k| k.on && !k.from_zero && k.kept));
    }

    /// Every preset's bend springs are soft and left to the first sweep;
    /// bend springs as stiff as a third of the stretch springs are swept
    /// every time, and stretch and shear springs always are.
    #[test]
    fn later_sweeps_leave_out_only_soft_bend_springs() {
        let bend = SpringKind::Bend.index();
        for m in Material::presets() {
            let kinds = later_sweep_kinds(&[m.stretch, m.shear, m.bend]);
            assert!(!kinds[bend], "{}: bend swept again", m.name);
            assert!(kinds[SpringKind::Stretch.index()] && kinds[SpringKind::Shear.index()]);
        }
        let m = Material::cotton();
        let mut stiff = [m.stretch, m.shear, m.bend];
        stiff[bend].stiffness = m.stretch.stiffness / 3.0;
        assert_eq!(later_sweep_kinds(&stiff), [true; 3]);
    }
}
