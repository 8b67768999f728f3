//! The step schedule: the stages of one step, in the one order they run.
//!
//! ```text
//! validate → asleep (sleeping on, nothing near moved or changed)? → commit
//!     the time and report, nothing solved
//! → substeps k, h = dt / k → back up → obstacle bounds over the step
//!     → candidates per particle → a team of threads for the substeps
//! per substep:  obstacle motion → contact detection (solvers that solve
//!               contacts) → integrate → self-collision (cloths that have
//!               it: a fresh look every few substeps, a pass every
//!               substep) → tethers (cloths with them) → stretch limit
//!               (solvers that do not hold it in their own substep, and
//!               every solver where layers touched or the tethers held a
//!               particle) → the lanes' contacts again (xpbd's lanes
//!               held them and layers touched) → resolve contacts (with
//!               the friction policy the integrator handed back; at the
//!               last substep only, when the integrator held every
//!               contact itself: xpbd among still balls, capsules, planes
//!               and cuboids) → the stretch limit once more, against the
//!               contacts → where that pushed a layer of a cloth with
//!               self-collision by over a quarter of its thickness, the
//!               layers parted, the limit, and the contacts resolved
//!               again (up to 16 times)
//! divergence check → roll back and report, or commit the time
//!     → tearing (cloths whose material tears: split the particles at the
//!       ends of overstrained stretch springs)
//!     → sleep (sleeping on: still for 30 steps? then asleep)
//! ```
//!
//! The stages' loops over particles, bands and springs run on the team
//! (`parallel.rs`), with the bits of one thread.

use super::cloth_solver::{substeps_with, unshortened, ClothSolver};
use super::contact_follow::follow_contacts;
use super::integrate::integrate;
use super::integrator::Integrator;
use super::lane_contacts::LaneContacts;
use super::report::{StepReport, MAX_DISTANCE, MAX_SPEED, MAX_STRAIN};
use super::stability::{
    chains_lengthen, edge_substeps, stable_substep, stable_substeps, unpinned_substeps,
};
use super::stage_times::Lap;
use super::strain_limit::{limit_stretch_after_moves, limit_stretch_supported, relaxed_passes};
use super::substep::Substep;
use super::substeps::Substeps;
use super::substeps::{self_collision_substeps, MAX_SELF_SUBSTEP};
use super::xpbd;
use crate::cloth::{Cloth, LaneGrid, Particles, SpringKind};
use crate::collision::{
    any_stretch_over_limit, LookBasis, Obstacle, ResolveOptions, SelfContactParams,
};
use crate::context::StepContext;
use crate::error::{positive, ClothError};
use crate::forces::{ForceModel, Masses};
use crate::math::Vector;
use crate::parallel::{with_team, Disjoint, Team};
use parry3d::bounding_volume::{Aabb, BoundingVolume};

impl ClothSolver {
    /// Advances `cloth` by `dt` seconds among `obstacles`.
    ///
    /// The step is split into substeps; each moves the obstacles, integrates
    /// the forces with the current integrator and then resolves contacts. If
    /// the new state is not finite, or has exploded (a speed over
    /// [`MAX_SPEED`], a distance over [`MAX_DISTANCE`], a stretch over
    /// [`MAX_STRAIN`]), the cloth is put back as it was before the step and
    /// [`ClothError::Diverged`] says which integrator diverged and how many
    /// substeps would be stable. An integrator that cannot carry dynamic
    /// bodies refuses obstacles that are ([`ClothError::CannotCarryBodies`]).
    pub fn step(
        &mut self,
        cloth: &mut Cloth,
        dt: f32,
        obstacles: &[Obstacle],
    ) -> Result<StepReport, ClothError> {
        let started = std::time::Instant::now();
        positive("dt", dt)?;
        self.settings.validate()?;
        cloth.params.validate()?;
        cloth.material.validate()?;
        for (i, o) in obstacles.iter().enumerate() {
            o.validate(i)?;
        }
        let integrator = self.settings.integrator;
        if !integrator.carries_dynamic_bodies() {
            if let Some(i) = obstacles.iter().position(|o| o.body.is_some()) {
                return Err(ClothError::CannotCarryBodies {
                    integrator: integrator.name(),
                    body: format!("obstacle {i}"),
                });
            }
        }
        // A sleeping cloth stays as it is unless something could move it.
        if !self.settings.sleep {
            self.state.sleep.wake();
        } else if self.state.sleep.stays_asleep(cloth, obstacles) {
            // No contact this step: no momentum for the obstacles.
            let n = cloth.particle_count();
            self.workspace
                .collision
                .begin_step(obstacles, dt, cloth.params.thickness, n);
            cloth.time += dt as f64;
            self.steps += 1;
            let mut report = StepReport {
                asleep: true,
                ..Default::default()
            };
            report.times.total = started.elapsed().as_secs_f64();
            return Ok(report);
        }
        // Which obstacles' edges may meet the cloth, once a step: for the
        // substeps, and for xpbd's edge pass.
        let edges = edges_within_reach(cloth, obstacles, dt);
        let k = self.substeps_near(cloth, obstacles, dt, edges);
        let edges_near = edges != EdgesNear::None;
        if cloth.params.self_collision && dt / k as f32 > MAX_SELF_SUBSTEP {
            return Err(ClothError::SelfCollisionNeedsSubsteps {
                integrator: integrator.name(),
                dt,
                substeps: k,
                needed: self_collision_substeps(dt),
                max_substep_ms: 1000.0 * MAX_SELF_SUBSTEP,
            });
        }
        // The team spans the step, its backups and its divergence check
        // too (on one thread they were a sixteenth of the drape's frame at
        // N = 128 on two).
        let busy = edges_near || self.workspace.touched_last_step;
        let threads = self.settings.parallel && shares_well(cloth, integrator, busy);
        let cloth_shares = stages_share_well(cloth, integrator, busy);
        let report = with_team(threads, |team| {
            // The cloth's own stages share the team only where they gain
            // from it; self-collision's from any size the team is made for.
            let cloth_team = if cloth_shares { team } else { Team::ALONE };
            let teams = StepTeams {
                all: team,
                cloth: cloth_team,
            };
            self.step_with_team(cloth, obstacles, (dt, k, edges_near), teams, started)
        })?;
        self.workspace.touched_last_step = report.contacts > 0;
        Ok(report)
    }

    /// [`Self::step`] from its backups on, its loops shared by the
    /// `teams`.
    fn step_with_team(
        &mut self,
        cloth: &mut Cloth,
        obstacles: &[Obstacle],
        (dt, k, edges_near): (f32, u32, bool),
        teams: StepTeams,
        started: std::time::Instant,
    ) -> Result<StepReport, ClothError> {
        let team = teams.all;
        let integrator = self.settings.integrator;
        let n = cloth.particle_count();
        let ws = &mut self.workspace;
        ws.resize(n);
        back_up(&cloth.particles, ws, team);
        let edges = self.settings.edge_collisions;
        let longest_rest = if edges { longest_rest(ws, cloth) } else { 0.0 };
        let reach = cloth.params.thickness + longest_rest;
        ws.collision.begin_step(obstacles, dt, reach, n);
        // The stretch limit's scratch made for the cloth now, so that the
        // first step whose contacts call it allocates nothing.
        if cloth.material.stretch_limit_factor().is_finite() {
            ws.limit_scratch.prepare(&cloth.topology.springs, n);
        }
        let margin = candidate_margin(cloth, dt);
        if integrator == Integrator::Xpbd && LaneContacts::may_hold(obstacles) {
            // xpbd's lanes may hold every contact of the step, and the
            // collision stage then need not run at all: its cache waits
            // for the stage's first pass (made from the step's start, the
            // backup, the same bits).
            ws.collision.defer_candidates(margin);
        } else {
            ws.collision
                .cache_candidates(&cloth.particles.x, margin, &cloth.topology.springs);
        }
        if cloth.params.tethers {
            ws.tethers.update(cloth);
        }
        // The layers' thickness, once a step (it reads every stretch
        // spring), and only for a cloth that needs it.
        let layer = if cloth.params.self_collision {
            let layer = cloth.self_thickness();
            // A margin of the collision thickness: stack 116 → 55 ms a frame
            // against looks timed from the step's speeds (half of it: 70 ms,
            // twice: 80 ms, four times: 209 ms; measured).
            // Pairs found again for fresh scratch: the same list on one
            // thread as on several.
            ws.self_contacts.begin_step(
                &mut self.state.self_look,
                &look_basis(cloth, layer),
                Team::ALONE,
            );
            layer
        } else {
            // Nothing to carry (and nothing stale in a snapshot).
            self.state.self_look = None;
            0.0
        };
        let mut report = self.substeps(
            cloth,
            obstacles,
            (dt, k, longest_rest, layer, edges_near),
            teams,
        )?;
        // Divergence check.
        if !is_sane(cloth, team) {
            let integrator = self.settings.integrator;
            restore(cloth, &self.workspace);
            let suggested = stable_substeps(cloth, &self.settings, dt).max(2 * k);
            return Err(ClothError::Diverged {
                integrator: integrator.name(),
                dt,
                substeps: k,
                suggested_substeps: suggested,
            });
        }
        cloth.time += dt as f64;
        self.steps += 1;
        report.torn_springs = self.workspace.tearing.run(cloth);
        if self.settings.sleep {
            self.state.sleep.after_step(cloth);
        }
        report.times.total = started.elapsed().as_secs_f64();
        Ok(report)
    }

    /// The number of substeps a frame step of `dt` seconds takes on `cloth`
    /// among `obstacles`: as [`Self::substeps_for`], except for the
    /// automatic substeps of the small-steps solver where its chain solves
    /// lengthen them while an obstacle with edges or corners
    /// ([`Obstacle::has_edges`]) is within reach of the cloth this step.
    /// Then they are at least 20 a frame at 60 Hz if every such obstacle is
    /// still or slides without turning (its contacts are held inside the
    /// substep as planes, in the lanes where they may hold it: a 48 × 48
    /// cotton tablecloth dropped on a table sliding at 0.5 or 1 m/s
    /// peaked at 4.51% stretch at 41 substeps, at 32 and at 20, without
    /// penetration), and the sweeps' own count if one turns or is a
    /// dynamic body. Measured (BENCHMARKS.md, sixteenth
    /// and seventeenth sessions): a 48 × 48 cotton tablecloth dropped on a
    /// table peaked at 12.3% stretch with the chains' 9 substeps and no
    /// planes, 4.58% at 32 with them (4.53% at the sweeps' 41); the drape
    /// over a ball stays under 5% at 12. A cloth without pins whose every
    /// obstacle is a still ball, capsule, half-space or (edges out of
    /// reach) cuboid takes at least 12 a frame at 60 Hz rather than 16
    /// (`stability.rs` says why).
    pub fn substeps_among(&self, cloth: &Cloth, obstacles: &[Obstacle], dt: f32) -> u32 {
        let edges = edges_within_reach(cloth, obstacles, dt);
        self.substeps_near(cloth, obstacles, dt, edges)
    }

    /// [`Self::substeps_among`], given which obstacles with edges are
    /// within reach ([`edges_within_reach`], which the step also wants).
    fn substeps_near(
        &self,
        cloth: &Cloth,
        obstacles: &[Obstacle],
        dt: f32,
        edges: EdgesNear,
    ) -> u32 {
        let lengthened =
            self.settings.substeps == Substeps::Auto && chains_lengthen(cloth, &self.settings);
        if !lengthened {
            return self.substeps_for(cloth, dt);
        }
        match edges {
            EdgesNear::None if unpinned_among_round(cloth, obstacles) => {
                unpinned_substeps(cloth, &self.settings, dt)
            }
            EdgesNear::None => self.substeps_for(cloth, dt),
            EdgesNear::Still => {
                let sweeps = substeps_with(&unshortened(&self.settings), cloth, dt);
                self.substeps_for(cloth, dt)
                    .max(edge_substeps(dt))
                    .min(sweeps)
            }
            EdgesNear::Moving => substeps_with(&unshortened(&self.settings), cloth, dt),
        }
    }

    /// The substeps of a step of `dt` seconds in `k` substeps, on the
    /// `teams`' threads; on an integrator's error the cloth is put back.
    /// `longest_rest` is the longest stretch or shear spring's rest length
    /// (m; 0 without edge collisions).
    fn substeps(
        &mut self,
        cloth: &mut Cloth,
        obstacles: &[Obstacle],
        (dt, k, longest_rest, layer, edges_near): (f32, u32, f32, f32, bool),
        teams: StepTeams,
    ) -> Result<StepReport, ClothError> {
        // Self-collision's looks and passes on the whole team, the rest on
        // the cloth's.
        let (self_team, team) = (teams.all, teams.cloth);
        let h = dt / k as f32;
        // What each self-collision pass of the step works with.
        let self_params = SelfContactParams {
            thickness: layer,
            friction: cloth.params.self_friction,
            h,
        };
        // The limit after a substep of an integrator that does not hold it
        // itself: relaxed passes (`limit_stretch_relaxed`) while the
        // substep is within the integrator's stability limit, the plain
        // passes past it (fixed substeps too long for an explicit
        // integrator), so that such a run diverges and says so rather than
        // being held together, wrong, by the limit: explicit Euler's drape
        // at one substep a frame ended bounded and 277% stretched with the
        // relaxed passes, symplectic Euler's 112%.
        let relaxed_limit = !self.settings.integrator.limits_stretch_itself()
            && h <= stable_substep(cloth, &self.settings) * (1.0 + 1.0e-4);
        let edges = self.settings.edge_collisions;
        let limits_itself = self.settings.integrator.limits_stretch_itself();
        // The cloth follows what the contacts pushed (contact_follow.rs)
        // with every integrator, unless an explicit one runs past its
        // stability limit (that run must still diverge and say so).
        let follows = relaxed_limit || limits_itself;
        let ws = &mut self.workspace;
        let mut report = StepReport {
            substeps: k,
            ..Default::default()
        };
        let times = &mut report.times;
        let mut watch = Lap::start();
        // Stages after the integrator that move the particles.
        let moved_after = cloth.params.self_collision || cloth.params.tethers;
        let grid = lane_grid(cloth);
        for substep in 0..k {
            let ctx = StepContext {
                dt,
                h,
                substep,
                substeps: k,
                time: cloth.time,
                gravity: cloth.params.gravity,
                thickness: cloth.params.thickness,
            };
            // Obstacle motion: where the obstacles are at the end of the substep.
            ws.collision.advance(&ctx, obstacles);
            // Where the substep starts, for tracing particles into moving
            // obstacles; not while xpbd's lanes hold the state, when `x`
            // is stale and xpbd writes it as it hands the state back (a
            // copy of nothing, 2% of the drape's frame at N = 128).
            let p = &mut cloth.particles;
            if !(substep > 0 && ws.xpbd.holds_state()) {
                p.x_prev.copy_from_slice(&p.x);
            }
            // Contact detection, for the solvers that take contacts into their solve.
            if self.settings.integrator.solves_contacts() {
                ws.collision
                    .detect_contacts(&ctx, &cloth.particles, obstacles);
            }
            // Integrate.
            let Particles {
                x,
                v,
                x_prev,
                mass,
                inv_mass,
            } = &mut cloth.particles;
            let sub = Substep {
                ctx: &ctx,
                model: ForceModel::new(
                    &cloth.topology,
                    &cloth.material,
                    Masses { mass, inv_mass },
                    &cloth.params,
                    team,
                )
                .at((cloth.time + (substep as f64 * h as f64)) as f32),
                settings: &self.settings,
                obstacles,
                mass_revision: cloth.mass_revision,
                grid,
                team,
                moved_after,
                edges_near,
            };
            watch.lap(&mut times.contacts);
            let outcome = match integrate(&sub, (x, v, x_prev), &mut self.state, ws) {
                Ok(outcome) => outcome,
                Err(e) => {
                    restore(cloth, ws);
                    return Err(e);
                }
            };
            watch.lap(&mut times.integrate);
            report.iterations += outcome.iterations;
            // Where the integrator left every stretch spring within the
            // limit and no tether moves a particle after self-collision,
            // the limit after its pass looks only at the springs at the
            // particles it moved (the `fold`'s limit after the pass took
            // 5.5% of its instructions over every spring; the same bits).
            let watch_moves = outcome.stretch_settled && !cloth.params.tethers;
            // Self-collision: before the stretch limit (a layer pushed off
            // another must not stretch the cloth past it) and the obstacles
            // (they win where the two disagree: a layer pressed onto a ball
            // stays outside it).
            let mut self_touching = 0;
            if cloth.params.self_collision {
                let (selfc, topology) = (&mut ws.self_contacts, &*cloth.topology);
                let look = &mut self.state.self_look;
                if selfc.due(look, &cloth.particles.x) {
                    let looked = std::time::Instant::now();
                    let basis = look_basis(cloth, layer);
                    let p = &cloth.particles;
                    selfc.find(look, (&p.x, &p.v, h), &basis, self_team);
                    report.self_looks += 1;
                    times.self_looks += looked.elapsed().as_secs_f64();
                }
                // The positions before the pass, to tell which it moves.
                if watch_moves {
                    ws.before_self.clear();
                    ws.before_self.extend_from_slice(&cloth.particles.x);
                }
                self_touching =
                    selfc.resolve(&mut cloth.particles, topology, &self_params, self_team);
                report.self_contacts += self_touching;
                watch.lap(&mut times.self_collision);
            }
            // Tethers: after the springs (they hold what those let
            // through), before the stretch limit. A tether brings a
            // particle back towards its pin alone, and a neighbour it does
            // not hold (another pin's, or slack) is left a spring's stretch
            // away: the limit after it takes that back. With the tethers
            // after the limit, the `pins` sheet hung by its corners peaked
            // at 14.2% stretch with xpbd (5.6% without tethers) and 9.4%
            // with symplectic Euler; now 4.7% and 4.5%.
            let tethered = cloth.params.tethers && ws.tethers.hold(&mut cloth.particles) > 0;
            // The stretch limit, for the integrators that do not hold it in
            // their own substep (and for all after self-collision that
            // moved a particle or tethers that held one, which may pull a
            // spring past it; with nothing touching, the limit changed no
            // bit of the golden runs and took 5% of the `fold`): before the
            // contacts, so that the contacts win where the two disagree (a
            // particle pulled towards a pin behind a ball stays outside the
            // ball); velocities lose what still stretches a limited spring
            // (strain_limit.rs says why not the move over the substep).
            // An integrator that does not hold the limit itself gets it as
            // the small-steps solver's limit on a mesh does: weighted by the
            // pins' support, over-relaxed, until it settles (a 48 × 48 sheet
            // hung by two corners peaked at 25% with symplectic Euler and
            // four plain passes, 4.51% so), within its stability limit
            // (`relaxed_limit`). After the small-steps solver's own limit, a
            // few plain passes take back what self-collision or the tethers
            // moved.
            let (factor, revision) = (cloth.material.stretch_limit_factor(), cloth.mass_revision());
            let p = &mut cloth.particles;
            let springs = &cloth.topology.springs;
            if relaxed_limit {
                limit_stretch_supported(
                    &mut ws.limit_scratch,
                    (springs, &p.inv_mass, revision),
                    (&mut p.x, Some(&mut p.v)),
                    factor,
                    (relaxed_passes(h), false),
                );
            } else if !limits_itself || self_touching > 0 || tethered {
                // Only the springs at a particle self-collision moved can be
                // over the limit (`watch_moves`); no positions before: all.
                let only_moved = self_touching > 0 && watch_moves && limit_after_moves_allowed();
                let before = if only_moved { &ws.before_self[..] } else { &[] };
                let (x, v) = (&mut p.x[..], Some(&mut p.v[..]));
                limit_stretch_after_moves(
                    &mut ws.limit_scratch,
                    (springs, &p.inv_mass),
                    (x, v),
                    factor,
                    before,
                );
            }
            // Self-collision moved particles the lanes had put out of the
            // obstacles: they are put out again at once (the stage runs
            // at the last substep).
            let lanes_held = outcome.contacts_held || outcome.still_held;
            if lanes_held && self_touching > 0 && substep + 1 < k {
                let p = &mut cloth.particles;
                xpbd::hold_contacts_again(&mut ws.xpbd, (&mut p.x, &mut p.v), team);
            }
            watch.lap(&mut times.constraints);
            // The integrator held every contact inside the substep: the
            // collision stage's exact pass waits for the step's last
            // substep. Self-collision moves particles after it by at most
            // half a layer's thickness, which the lanes have just put
            // right (the `fold` 5.1 → 4.4 ms a frame, its bar and floor
            // held in the lanes); tethers pull them towards pins behind
            // obstacles, which only the stage puts right.
            let held = outcome.contacts_held && !cloth.params.tethers;
            // What the limit left of its room, unless a stage after the
            // integrator moved the particles since.
            let room = if moved_after {
                None
            } else {
                outcome.stretch_room
            };
            if held && substep + 1 < k {
                continue;
            }
            // At the last substep too, when it would find nothing to do:
            // every stretch spring within the limit after the lanes' last
            // push, and no spring able to cut an obstacle (on a grid a
            // shear spring is at most two stretch springs long). Run
            // there, it moved no particle of the drape and cost a
            // twentieth of the frame at N = 64. The room the limit kept
            // tells without a look; where the cloth hangs at its limit it
            // is 0 and the last push's rounding (6e-8 m on the drape)
            // spoils it, so the springs are measured against the limit and
            // its slack as the stage's hold would: the drape N = 128 ran
            // the pass in 26 of 40 steps for nothing, 0.4–0.6 ms a frame.
            let limit = cloth.material.stretch_limit_factor();
            let springs = &cloth.topology.springs;
            let settled = held
                && (!edges
                    || LaneContacts::springs_stay_out(
                        obstacles,
                        2.0 * limit * longest_rest,
                        cloth.params.thickness,
                    ))
                && (room.is_some()
                    || !any_stretch_over_limit(springs, &cloth.particles.x, limit, team));
            if settled {
                report.contacts += outcome.touching;
                continue;
            }
            ws.collision
                .cache_deferred(&ws.backup_x, &cloth.topology.springs);
            // Resolve contacts, by the friction policy the integrator handed back.
            // Where the lanes held the still obstacles among moving or
            // dynamic bodies, the stage answers for the bodies alone before
            // the last substep, and for all at it.
            let skip_still = outcome.still_held && substep + 1 < k;
            let mut stretch_room = room;
            let jump = CONTACT_JUMP * layer;
            let pushed_far = |x: &[Vector], before: &[Vector]| {
                x.iter()
                    .zip(before)
                    .any(|(a, b)| (*a - *b).length_squared() > jump * jump)
            };
            for round in 0..=CONTACT_ROUNDS_WITH_LAYERS {
                if cloth.params.self_collision {
                    ws.before_self.clear();
                    ws.before_self.extend_from_slice(&cloth.particles.x);
                }
                let touched = ws.collision.resolve(
                    &ctx,
                    &mut cloth.particles,
                    &cloth.topology.springs,
                    obstacles,
                    ResolveOptions {
                        friction: outcome.friction,
                        skip_still,
                        edges,
                        stretch_limit: cloth.material.stretch_limit_factor(),
                        stretch_room,
                        team,
                    },
                );
                if round == 0 {
                    report.contacts += touched;
                }
                if follows && touched > 0 {
                    let within = (ctx.thickness, h, team);
                    report.follow_rounds += follow_contacts(cloth, obstacles, ws, within);
                }
                watch.lap(&mut times.contacts);
                // The stage pushed a layer by a good part of its thickness
                // in one go (at the last substep, after substeps in which
                // the lanes held the particles but not the edges: a sheet
                // over a round table's rim is pushed out of it by a few
                // millimetres there), through the layer lying on it: the
                // layers are parted again, and the stage puts right what
                // that pushed into the obstacles. Two sheets dropped on a
                // fixed cylinder crossed each other at its rim, or ended
                // pressed to under half their thickness, in each of 18
                // starts ([`CONTACT_ROUNDS_WITH_LAYERS`]).
                if round == CONTACT_ROUNDS_WITH_LAYERS
                    || !cloth.params.self_collision
                    || !pushed_far(&cloth.particles.x, &ws.before_self)
                {
                    break;
                }
                let parted = ws.self_contacts.resolve(
                    &mut cloth.particles,
                    &cloth.topology,
                    &self_params,
                    self_team,
                );
                report.self_contacts += parted;
                watch.lap(&mut times.self_collision);
                if parted == 0 {
                    break;
                }
                // The stretch limit over the pass's moves, as after the
                // substep's pass (every spring: the stage's hold may have
                // left one over its slack); the stage then holds it
                // against the contacts.
                let p = &mut cloth.particles;
                limit_stretch_after_moves(
                    &mut ws.limit_scratch,
                    (&cloth.topology.springs, &p.inv_mass),
                    (&mut p.x[..], Some(&mut p.v[..])),
                    cloth.material.stretch_limit_factor(),
                    &[],
                );
                watch.lap(&mut times.constraints);
                // The pass moved particles since the stage measured its room.
                stretch_room = None;
            }
        }
        Ok(report)
    }
}

/// How far (a share of the layers' thickness) the collision stage may move
/// a particle of a cloth with self-collision before the layers are parted
/// again after it: a layer lying on the pushed one is then within three
/// quarters of the thickness, and the next substep's pass parts them. A
/// larger push may carry it through the layer on it.
const CONTACT_JUMP: f32 = 0.25;

/// Times, at most, the layers are parted and the collision stage run again
/// after the stage pushed a layer far ([`CONTACT_JUMP`]), as many as the
/// rounds of `follow_contacts`. Two sheets dropped on a fixed cylinder, 18
/// starts (N = 24 and 32, cotton, silk and denim, 1.5 to 8 cm apart,
/// turned 0 or 0.4 rad), starts still crossed at the end / with a
/// self-intersection in some frame: none 18 / 18; one round 8 / 18; two
/// 4 / 16; four 1 / 4; eight 0 / 2; sixteen 0 / 0, at 9.2 ms a frame
/// against 7.5 without (most frames need a few).
const CONTACT_ROUNDS_WITH_LAYERS: u32 = 16;

/// What self-collision's looks for pairs go by this step: the layers'
/// `thickness` (`Cloth::self_thickness`, m), and a margin of the
/// collision thickness.
fn look_basis(cloth: &Cloth, thickness: f32) -> LookBasis<'_> {
    LookBasis {
        topology: &cloth.topology,
        particles: cloth.particle_count(),
        revision: cloth.mass_revision,
        thickness,
        margin: cloth.params.thickness,
    }
}

/// The grid the small-steps solver lays `cloth` out on: its own, its
/// pieces' stacked, or a torn grid's when its material has no stretch
/// limit (the grid's limit would miss the springs the tear moved off its
/// runs; `grid_sweep::GridPlan::torn`).
fn lane_grid(cloth: &Cloth) -> Option<LaneGrid> {
    let topology = cloth.topology();
    let unlimited = cloth.material.stretch_limit.is_none();
    topology
        .lane_grid()
        .or_else(|| topology.torn_lane_grid().filter(|_| unlimited))
}

/// Particles from which a step's loops are shared among threads.
const TEAM_MIN_PARTICLES: usize = 2048;

/// True when a step of `cloth` with `integrator` gains from a team of
/// threads: a few thousand particles or more (below, the loops are too
/// short to share), and loops that keep their data on one thread. Not so
/// the small-steps solver on a cloth without lanes ([`lane_grid`]: a mesh,
/// joined cloths of other shapes, a torn one with a stretch limit) and
/// without self-collision: its spring sweep runs on one thread, and the
/// particles the collision stage's blocks moved on the other came back to
/// it every substep (the torn sheet on the general sweep, 64 × 32 and 128
/// × 64: 3.0 → 3.4 and 31 → 34 ms a frame with two threads).
///
/// A cloth with lanes and without self-collision shares the small-steps solver's
/// step from [`XPBD_TEAM_MIN_PARTICLES`] particles, or from
/// [`XPBD_BUSY_TEAM_MIN_PARTICLES`] in a `busy` step (one near an
/// obstacle's edges, or after a step that touched an obstacle).
fn shares_well(cloth: &Cloth, integrator: Integrator, busy: bool) -> bool {
    if cloth.params.self_collision {
        return cloth.particle_count() >= TEAM_MIN_PARTICLES;
    }
    stages_share_well(cloth, integrator, busy)
}

/// True when the stages of a step of `cloth` other than self-collision's
/// (the integrator's, the stretch limit's, the obstacles') gain from a team
/// of threads: [`shares_well`]'s rule for the cloth without
/// self-collision. A cloth with self-collision takes the team for its looks
/// and passes from [`TEAM_MIN_PARTICLES`] (they gain at any size), and for
/// the rest only by this rule. The `stack` (three 32 × 32 cloths, 3072
/// particles) ran the small-steps solver's substeps slower on two threads
/// than on one (1.2–2.7 against 1.1 ms a frame); with them on one thread
/// inside a step on two, `run stack` 7.13 → 6.69 and 8.05 → 7.27 ms a
/// frame (medians of eight and six alternated runs; the same bits). The
/// `fold` (2304 particles) 2.07 → 2.26 in `run fold`, 2.43 → 2.28 in a
/// scratch step loop: within its budget either way.
fn stages_share_well(cloth: &Cloth, integrator: Integrator, busy: bool) -> bool {
    let n = cloth.particle_count();
    if integrator == Integrator::Xpbd {
        let least = if busy {
            XPBD_BUSY_TEAM_MIN_PARTICLES
        } else {
            XPBD_TEAM_MIN_PARTICLES
        };
        return lane_grid(cloth).is_some() && n >= least;
    }
    n >= TEAM_MIN_PARTICLES
}

/// The teams of a step: the whole team (self-collision's looks and
/// passes, the backups and the divergence check) and the one the cloth's
/// other stages share ([`stages_share_well`]; the whole team or
/// [`Team::ALONE`]).
#[derive(Clone, Copy)]
struct StepTeams<'a> {
    all: Team<'a>,
    cloth: Team<'a>,
}

/// Particles from which the small-steps solver shares the step of a grid
/// cloth without self-collision among threads: each of its substep's
/// passes over the lanes is too short below to pay for the handouts and
/// for the lanes moving between the cores. Measured, ms a frame on one
/// and on two threads (bench, medians): the drape at N = 64 0.89 / 1.13,
/// 80 1.47 / 1.89, 96 2.29 / 2.47, 112 3.51 / 3.12, 128 4.97 / 3.99; the
/// `box` at N = 64 4.32 / 4.66. (Self-collision's looks gain from a
/// second thread at any size: `fold` 48 × 48 9.0 / 7.4, `stack` 31.3 /
/// 25.9.) With the chain solves' memory laid out by thread and items
/// kept on their owners (thirty-first session; one thread, then two from
/// 2048 particles): N = 64 0.88 / 0.90–1.11, 80 1.46 / 1.41–1.42, 96
/// 2.13 / 1.75–1.98: from 8192 (N = 91 up), was 10 000.
const XPBD_TEAM_MIN_PARTICLES: usize = 8192;

/// Particles from which the small-steps solver shares the step of a grid
/// cloth without self-collision among threads when the step is busy: near
/// an obstacle's edges (a still one's take 20 substeps at 60 Hz, each with
/// the lanes' planes and the springs kept off the edges) or after a step
/// that touched an obstacle (the lanes' contacts and the stretch limit at
/// work). A falling cloth's substeps stay too short to share below
/// [`XPBD_TEAM_MIN_PARTICLES`]. Measured (thirty-fourth session, `run
/// SCENE --frames 120`, three alternated runs, ms a frame): sharing from
/// 4096 in every step, the `box` 4.17 → 4.22–4.33 and the drape at N = 64
/// 1.28–1.29 → 1.35–1.37 (its fall paid for the handouts, though `bench`,
/// which times the landed frames, went 4.16 → 3.35 and 1.10 → 0.87); in
/// busy steps only, the `box` 4.21–4.31 → 3.40–3.45, the drape at N = 64
/// 1.23–1.27 → 1.07 and at N = 80 2.02–2.05 → 1.65–1.74 (N = 56, below
/// it, 0.90–0.93 either way).
const XPBD_BUSY_TEAM_MIN_PARTICLES: usize = 4096;

/// Puts the cloth back as it was at the start of the step.
fn restore(cloth: &mut Cloth, ws: &super::workspace::Workspace) {
    let p = &mut cloth.particles;
    p.x.copy_from_slice(&ws.backup_x);
    p.v.copy_from_slice(&ws.backup_v);
    p.x_prev.copy_from_slice(&ws.backup_prev);
}

/// False when the cloth has exploded: a position or velocity that is not
/// finite or too large, or a stretch spring over [`MAX_STRAIN`]. Blocks of
/// particles and of springs on the `team`.
fn is_sane(cloth: &Cloth, team: Team) -> bool {
    let ok_v = |v: &Vector| v.is_finite() && v.length_squared() < MAX_SPEED * MAX_SPEED;
    let ok_x = |x: &Vector| x.is_finite() && x.length_squared() < MAX_DISTANCE * MAX_DISTANCE;
    let (x, v) = (cloth.positions(), cloth.velocities());
    let stretch = cloth.springs().range(SpringKind::Stretch);
    let blocks = x.len().div_ceil(PARTICLE_BLOCK);
    let insane = team.sum_count(blocks, |b| {
        let block = b * PARTICLE_BLOCK..((b + 1) * PARTICLE_BLOCK).min(x.len());
        // The block's share of the stretch springs, in proportion.
        let share = |p: usize| stretch.start + (stretch.len() * p).div_ceil(x.len().max(1));
        let springs = share(block.start)..share(block.end);
        let ok = x[block.clone()].iter().all(ok_x)
            && v[block].iter().all(ok_v)
            && cloth.strain_below_among(springs, MAX_STRAIN);
        u32::from(!ok)
    });
    insane == 0
}

/// Particles a block of the step's backups and of its divergence check
/// (with their share of the stretch springs) takes.
const PARTICLE_BLOCK: usize = 4096;

/// Copies the particles' positions, velocities and start positions to the
/// workspace's backups, blocks of particles on the `team` (each the
/// particles its member's bands hold).
fn back_up(p: &Particles, ws: &mut super::workspace::Workspace, team: Team) {
    let n = p.x.len();
    let blocks = n.div_ceil(PARTICLE_BLOCK);
    let backups = [&mut ws.backup_x, &mut ws.backup_v, &mut ws.backup_prev]
        .map(|b| Disjoint::new(&mut b[..]));
    let sources = [&p.x, &p.v, &p.x_prev];
    team.sum_count(blocks, |b| {
        let block = b * PARTICLE_BLOCK..((b + 1) * PARTICLE_BLOCK).min(n);
        for (backup, source) in backups.iter().zip(sources) {
            // SAFETY: blocks are disjoint ranges of particles.
            unsafe { backup.range(block.clone()) }.copy_from_slice(&source[block.clone()]);
        }
        0
    });
}

/// How far (m) a particle is expected to move in a step of `dt`: twice
/// the fastest particle's distance plus a fall under gravity, and the
/// thickness. The collision stage finds each particle's candidate obstacles
/// within it once a step; a particle that goes further is looked up afresh.
pub(super) fn candidate_margin(cloth: &Cloth, dt: f32) -> f32 {
    let fastest = cloth
        .velocities()
        .iter()
        .map(|v| v.length_squared())
        .fold(0.0f32, f32::max)
        .sqrt();
    let margin =
        cloth.params.thickness + 2.0 * fastest * dt + cloth.params.gravity.length() * dt * dt;
    if margin.is_finite() {
        margin
    } else {
        0.0
    }
}

/// [`max_rest_length`], found again only when the cloth's springs may
/// have changed (its mass revision, which changes with its topology).
fn longest_rest(ws: &mut super::workspace::Workspace, cloth: &Cloth) -> f32 {
    match ws.longest_rest {
        Some((revision, longest)) if revision == cloth.mass_revision => longest,
        _ => {
            let longest = max_rest_length(cloth);
            ws.longest_rest = Some((cloth.mass_revision, longest));
            longest
        }
    }
}

/// The longest rest length among the springs sampled by edge collisions.
fn max_rest_length(cloth: &Cloth) -> f32 {
    let springs = cloth.springs();
    let rest = springs.rest_lengths();
    // Eight running maxima: the same largest value, without a chain of
    // dependent `max`es (once a step, over every stretch and shear spring).
    let mut most = [0.0f32; 8];
    for kind in [SpringKind::Stretch, SpringKind::Shear] {
        for (k, &r) in rest[springs.range(kind)].iter().enumerate() {
            most[k % 8] = most[k % 8].max(r);
        }
    }
    most.into_iter().fold(0.0, f32::max)
}

/// Whether `cloth` has no pin, no self-collision, and every obstacle is a
/// still ball, half-space or cuboid: the lanes may hold their contacts
/// ([`LaneContacts::may_hold`]). Asked only while no obstacle with edges
/// is within reach ([`ClothSolver::substeps_among`]): a cuboid that may
/// be is the edge rule's. (Measured on still obstacles only: a moving
/// one keeps the substeps.)
fn unpinned_among_round(cloth: &Cloth, obstacles: &[Obstacle]) -> bool {
    !cloth.params.self_collision
        && obstacles.iter().all(Obstacle::is_still)
        && LaneContacts::may_hold(obstacles)
        && !cloth.particles.inv_mass.contains(&0.0)
}

/// Which obstacles with edges or corners may meet the cloth within a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum EdgesNear {
    /// None.
    None,
    /// Some, every one of them still ([`Obstacle::is_still`]) or sliding
    /// without turning, as the lanes hold it ([`LaneContacts::may_hold`]).
    Still,
    /// Some, and one of them turns or is a dynamic body.
    Moving,
}

/// Which obstacles with edges or corners may meet the cloth within a step
/// of `dt` seconds: those whose swept bounding box meets the cloth's, grown
/// by how far a particle may move in the step; of a still one, only an
/// edge counts ([`Obstacle::edges_may_meet`]): a cloth on the middle of a
/// floor meets a face, which holds it as a plane does. One the lanes hold
/// as it slides counts as a still one whose edges are near.
fn edges_within_reach(cloth: &Cloth, obstacles: &[Obstacle], dt: f32) -> EdgesNear {
    if !obstacles.iter().any(Obstacle::has_edges) {
        return EdgesNear::None;
    }
    let x = cloth.positions();
    let Some(&first) = x.first() else {
        return EdgesNear::None;
    };
    let (lo, hi) = x
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let cloth_box = Aabb::new(lo, hi).loosened(candidate_margin(cloth, dt));
    let mut near = EdgesNear::None;
    for o in obstacles {
        if o.has_edges() && o.swept_aabb(dt).intersects(&cloth_box) {
            if o.is_still() {
                if o.edges_may_meet(&cloth_box) {
                    near = EdgesNear::Still;
                }
            } else if LaneContacts::may_hold(std::slice::from_ref(o)) {
                near = EdgesNear::Still;
            } else {
                return EdgesNear::Moving;
            }
        }
    }
    near
}

#[cfg(test)]
thread_local! {
    /// Tests: whether the limit after self-collision may look at the
    /// springs of the particles it moved alone, and how many times it did.
    static AFTER_MOVES: std::cell::Cell<(bool, u32)> = const { std::cell::Cell::new((true, 0)) };
}

/// Whether the limit after self-collision may look at the springs of the
/// particles it moved alone (always, but in the test that compares it with
/// the limit over every spring).
#[inline]
fn limit_after_moves_allowed() -> bool {
    #[cfg(test)]
    {
        let (allowed, taken) = AFTER_MOVES.get();
        AFTER_MOVES.set((allowed, taken + allowed as u32));
        allowed
    }
    #[cfg(not(test))]
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// The `fold` (its halves meet and lie on each other, the limit holding
    /// the cloth where it hangs over the bar) gives the same bits with the
    /// limit after self-collision over the moved particles' springs alone as
    /// over every spring, and it took that way.
    #[test]
    fn the_limit_after_self_collision_at_moved_particles_gives_the_same_bits() {
        use crate::scenes::{Scene, SceneKind, SceneOptions};
        let run = |allowed: bool| {
            AFTER_MOVES.set((allowed, 0));
            let options = SceneOptions {
                n: Some(24),
                ..Default::default()
            };
            let mut scene = Scene::build(SceneKind::Fold, &options).unwrap();
            let mut touching = 0;
            for _ in 0..90 {
                touching += scene.step_frame().unwrap().self_contacts;
            }
            let p = &scene.cloth.particles;
            let bits = |p: &[Vector]| -> Vec<[u32; 3]> {
                p.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            (bits(&p.x), bits(&p.v), touching, AFTER_MOVES.get().1)
        };
        let (x, v, touching, taken) = run(true);
        let (x_all, v_all, touching_all, _) = run(false);
        assert!(touching > 100, "the halves met: {touching} contacts");
        assert!(taken > 20, "the limit at moved particles ran {taken} times");
        assert_eq!(touching, touching_all);
        assert!(
            x == x_all && v == v_all,
            "the same positions and velocities"
        );
    }

    /// The divergence check by blocks finds a lost velocity or an
    /// overstretched spring in any block, on one thread or on a team, and
    /// the backups by blocks copy every particle.
    #[test]
    fn the_check_and_the_backups_by_blocks_cover_every_particle() {
        // 80 × 80: two blocks of particles.
        let cloth = ClothBuilder::new(80, 80).build().unwrap();
        let n = cloth.particle_count();
        assert!(n > PARTICLE_BLOCK);
        let last = n - 1;
        let mut lost = cloth.clone();
        lost.particles.v[last].y = f32::NAN;
        let mut torn = cloth.clone();
        // The last particle pulled 2 (1 + MAX_STRAIN) rest lengths (of
        // the 1 m sheet's 1/79 m) along x: its springs, among the last
        // stretch springs, far over MAX_STRAIN.
        torn.particles.x[last].x += 2.0 * (1.0 + MAX_STRAIN) / 79.0;
        let check = |team: Team| {
            let sane = [&cloth, &lost, &torn].map(|c| is_sane(c, team));
            assert_eq!(sane, [true, false, false]);
            let mut moved = cloth.clone();
            for (i, p) in moved.particles.x.iter_mut().enumerate() {
                p.z = i as f32;
            }
            let mut ws = super::super::workspace::Workspace::default();
            ws.resize(n);
            back_up(&moved.particles, &mut ws, team);
            assert_eq!(ws.backup_x, moved.particles.x);
            assert_eq!(ws.backup_v, moved.particles.v);
            assert_eq!(ws.backup_prev, moved.particles.x_prev);
        };
        check(Team::ALONE);
        crate::parallel::on_threads(2, check);
    }
}
