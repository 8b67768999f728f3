//! The particle pass against one ball, eight particles at a time. A cloth
//! draped over a ball (the `drape` scene, a ball dropped on a sheet) has a
//! single obstacle and thousands of particles near it; the general pass
//! gathers each particle's candidates into a list and answers them through
//! the shape's kind, a few dozen nanoseconds a particle. Here the ball's
//! law (the bounding test, the contact, the push out and Coulomb friction)
//! is written without branches and run over structure-of-arrays lanes
//! (AVX2 when the CPU has it, lane by lane otherwise), then the results are
//! written back and the momentum summed in particle order. Every operation
//! is the general pass's, in its order, without fused multiply-adds: the
//! bits are the same. A particle found inside the ball goes through the
//! general pass instead, which traces its path back out through the side
//! it came in.

use super::contact_set::{ParticleContact, NONE};
use super::particle_pass::{BlockOut, BlockScratch, ParticlePass, CONTACT_SLACK};
use super::response::FrictionPolicy;
use crate::math::{simd_available, Vector};

/// Particles in a batch: eight `f32` lanes, one AVX2 register.
const LANES: usize = 8;

/// What the lanes need of the one obstacle, a ball, where it is now.
#[derive(Debug, Clone, Copy)]
pub(super) struct BallLaw {
    /// Its bounds over the step, grown by the reach (m): a particle outside
    /// them has no candidate.
    pub bounds_min: Vector,
    pub bounds_max: Vector,
    /// How far (m, along any axis) a particle may drift from where the
    /// step's cache found its candidates before it is looked up afresh.
    pub cache_margin: f32,
    /// Its centre (m) and radius (m).
    pub centre: Vector,
    pub radius: f32,
    /// The sphere that bounds it: centre (m) and radius (m), as the
    /// general pass's far test takes it.
    pub bound_centre: Vector,
    pub bound_radius: f32,
    /// Its surface's velocity at `p` is `linear + angular × (p - about)`
    /// (m/s, rad/s, m).
    pub linear: Vector,
    pub angular: Vector,
    pub about: Vector,
    /// Coulomb friction coefficient.
    pub friction: f32,
    /// Fixed or kinematic: the cloth's push does not move it.
    pub immovable: bool,
}

/// The same for every lane of a block: the ball, and the pass's settings.
#[derive(Clone, Copy)]
struct Shared {
    ball: BallLaw,
    thickness: f32,
    far: f32,
    h: f32,
    friction_applies: bool,
}

/// One batch, coordinate by coordinate: what goes in per lane, and what
/// the law gives back.
#[derive(Default)]
struct Batch {
    x: [[f32; LANES]; 3],
    v: [[f32; LANES]; 3],
    inv_mass: [f32; LANES],
    mass: [f32; LANES],
    /// Where the particle was when the step's cache was made (m), 1 when
    /// there is a cache, and 1 when it listed the ball for the particle.
    anchor: [[f32; LANES]; 3],
    has_anchor: [u32; LANES],
    listed: [u32; LANES],
    /// 1 when the candidates came from the cache (the particle stayed
    /// within its margin).
    from_cache: [u32; LANES],
    /// How far (squared, m²) the particle is from its anchor after
    /// resolution (infinite without a cache), and how far it was moved.
    drift2: [f32; LANES],
    shift2: [f32; LANES],
    /// 1 when the ball counts (a candidate, within reach, a finite contact).
    near: [u32; LANES],
    /// 1 when the particle is inside the ball: the general pass takes it.
    inside: [u32; LANES],
    /// 1 when the particle touches and was resolved.
    touching: [u32; LANES],
    normal: [[f32; LANES]; 3],
    signed_distance: [f32; LANES],
    x_out: [[f32; LANES]; 3],
    v_out: [[f32; LANES]; 3],
    surface_velocity: [[f32; LANES]; 3],
    /// Where (m) and how much momentum (N·s) the particle handed the ball.
    point: [[f32; LANES]; 3],
    impulse: [[f32; LANES]; 3],
}

impl ParticlePass<'_> {
    /// [`ParticlePass::block`] when the one obstacle is `ball`.
    pub(super) fn ball_block(
        &self,
        ball: &BallLaw,
        range: std::ops::Range<usize>,
        out: &mut BlockOut,
        scratch: &mut BlockScratch,
    ) -> u32 {
        self.ball_block_with(ball, range, out, (scratch, simd_available()))
    }

    /// [`ParticlePass::ball_block`], with the AVX2 lanes only when `simd`.
    fn ball_block_with(
        &self,
        ball: &BallLaw,
        range: std::ops::Range<usize>,
        out: &mut BlockOut,
        (scratch, simd): (&mut BlockScratch, bool),
    ) -> u32 {
        let shared = Shared {
            ball: *ball,
            thickness: self.ctx.thickness,
            far: self.far,
            h: self.ctx.h,
            friction_applies: self.friction == FrictionPolicy::Apply,
        };
        let mut batch = Batch::default();
        let mut contacts = 0;
        let start = range.start;
        for chunk in (0..range.len()).step_by(LANES) {
            let count = LANES.min(range.len() - chunk);
            for lane in 0..count {
                let (k, i) = (chunk + lane, start + chunk + lane);
                let (x, v) = (out.x[k], out.v[k]);
                let (anchor, has_anchor, listed) = match self.tracks.cache_of(i) {
                    Some((anchor, listed)) => (anchor, true, listed),
                    None => (Vector::ZERO, false, false),
                };
                for a in 0..3 {
                    batch.x[a][lane] = x[a];
                    batch.v[a][lane] = v[a];
                    batch.anchor[a][lane] = anchor[a];
                }
                batch.inv_mass[lane] = self.inv_mass[i];
                batch.mass[lane] = self.mass[i];
                batch.has_anchor[lane] = has_anchor as u32;
                batch.listed[lane] = listed as u32;
            }
            // Lanes past a short last batch hold earlier particles and are
            // not read.
            solve(&mut batch, &shared, simd);
            for lane in 0..count {
                let (k, i) = (chunk + lane, start + chunk + lane);
                if batch.inside[lane] != 0 {
                    contacts += self.particle(k, i, out, scratch);
                    continue;
                }
                contacts += self.write_lane(&batch, lane, (k, i), (out, scratch), &shared);
                if batch.from_cache[lane] == 0 && out.nearest[k] != NONE {
                    scratch.strays += 1;
                }
                scratch.drift2 = scratch.drift2.max(batch.drift2[lane]);
                scratch.shift2 = scratch.shift2.max(batch.shift2[lane]);
            }
        }
        contacts
    }

    /// Writes what the law gave lane `lane` (particle `i`, the block's
    /// `k`th) back, and sums its momentum; returns the contacts resolved.
    fn write_lane(
        &self,
        batch: &Batch,
        lane: usize,
        (k, i): (usize, usize),
        (out, scratch): (&mut BlockOut, &mut BlockScratch),
        shared: &Shared,
    ) -> u32 {
        let get = |c: &[[f32; LANES]; 3]| Vector::new(c[0][lane], c[1][lane], c[2][lane]);
        out.nearest[k] = NONE;
        out.contacts.clear(k);
        if batch.near[lane] == 0 {
            return 0;
        }
        let (thickness, signed) = (shared.thickness, batch.signed_distance[lane]);
        let free = self.inv_mass[i] != 0.0;
        out.nearest[k] = 0;
        out.normal[k] = get(&batch.normal);
        out.distance[k] = if free { signed.max(thickness) } else { signed };
        if !free && signed < thickness {
            scratch.pinned_close = true;
        }
        if batch.touching[lane] == 0 {
            return 0;
        }
        out.x[k] = get(&batch.x_out);
        out.v[k] = get(&batch.v_out);
        let ball = &shared.ball;
        out.contacts.touch(
            k,
            &ParticleContact {
                obstacle: 0,
                normal: get(&batch.normal),
                surface_velocity: get(&batch.surface_velocity),
                immovable: ball.immovable,
                gap: 0.0,
                friction: ball.friction,
            },
        );
        let (point, j) = (get(&batch.point), get(&batch.impulse));
        let sum = &mut scratch.impulses[0];
        sum.linear += j;
        sum.angular_about_origin += point.cross(j);
        sum.contacts += 1;
        1
    }
}

/// Every lane of the batch through the ball's law.
fn solve(batch: &mut Batch, shared: &Shared, simd: bool) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        unsafe { solve_avx2(batch, shared) };
        return;
    }
    let _ = simd;
    solve_lanes(batch, shared);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn solve_avx2(batch: &mut Batch, shared: &Shared) {
    solve_lanes(batch, shared);
}

/// The ball's law, lane by lane, without branches: the general pass's
/// candidate test ([`super::tracks::ObstacleTracks::gather_particle`]) and
/// far test ([`super::tracks::ObstacleTracks::surely_beyond`]), the ball's
/// contact (`contact::ball_contact`) and the push out with friction
/// (`ParticlePass::resolve`), each operation as they do it.
#[inline(always)]
fn solve_lanes(batch: &mut Batch, shared: &Shared) {
    let ball = &shared.ball;
    let thickness = shared.thickness;
    for lane in 0..LANES {
        let get = |c: &[[f32; LANES]; 3]| Vector::new(c[0][lane], c[1][lane], c[2][lane]);
        let (x, v, anchor) = (get(&batch.x), get(&batch.v), get(&batch.anchor));
        // A candidate: within the bounds, and listed by the cache unless
        // the particle drifted beyond its margin (a NaN drift keeps it).
        let drifted = (x - anchor).abs().max_element() > ball.cache_margin;
        let from_cache = batch.has_anchor[lane] != 0 && !drifted;
        let (lo, hi) = (ball.bounds_min, ball.bounds_max);
        let meets = (lo.x <= x.x) & (lo.y <= x.y) & (lo.z <= x.z);
        let meets = meets & (hi.x >= x.x) & (hi.y >= x.y) & (hi.z >= x.z);
        let candidate = meets & (!from_cache | (batch.listed[lane] != 0));
        // Far: outside the bounding sphere grown by the reach.
        let reach = ball.bound_radius + shared.far;
        let beyond = (x - ball.bound_centre).length_squared() > reach * reach;
        // The contact.
        let offset = x - ball.centre;
        let dist = offset.length();
        let normal = select(dist > 1e-9, offset / dist, Vector::Y);
        let surface = ball.centre + normal * ball.radius;
        let signed = dist - ball.radius;
        let finite = surface.is_finite() && normal.is_finite() && signed.is_finite();
        let near = candidate && !beyond && finite;
        let free = batch.inv_mass[lane] != 0.0;
        let touching = near && free && signed < thickness + CONTACT_SLACK;
        // The push out, and friction against the surface's motion.
        let new_x = x + normal * (thickness - signed).max(0.0);
        let surface_v = ball.linear + ball.angular.cross(new_x - ball.about);
        let rel = v - surface_v;
        let vn = rel.dot(normal);
        let removed = (-vn).max(0.0);
        let rel_t = rel - normal * vn;
        let slip = rel_t.length();
        let limit = ball.friction * removed;
        let slowed = select(slip <= limit, Vector::ZERO, rel_t * (1.0 - limit / slip));
        let rel_t_new = select(shared.friction_applies, slowed, rel_t);
        let v_new = surface_v + normal * vn.max(0.0) + rel_t_new;
        let x_new = new_x + (rel_t_new - rel_t) * shared.h;
        let j = (v - v_new) * batch.mass[lane];
        let x_final = select(touching, x_new, x);
        let drift2 = (x_final - anchor).length_squared();
        batch.drift2[lane] = if batch.has_anchor[lane] != 0 {
            drift2
        } else {
            f32::INFINITY
        };
        batch.shift2[lane] = (x_final - x).length_squared();
        batch.from_cache[lane] = from_cache as u32;
        batch.near[lane] = near as u32;
        batch.inside[lane] = (near && signed < 0.0) as u32;
        batch.touching[lane] = touching as u32;
        batch.signed_distance[lane] = signed;
        for a in 0..3 {
            batch.normal[a][lane] = normal[a];
            batch.x_out[a][lane] = x_new[a];
            batch.v_out[a][lane] = v_new[a];
            batch.surface_velocity[a][lane] = surface_v[a];
            batch.point[a][lane] = new_x[a];
            batch.impulse[a][lane] = j[a];
        }
    }
}

/// `a` where `pick`, else `b`, coordinate by coordinate.
#[inline(always)]
fn select(pick: bool, a: Vector, b: Vector) -> Vector {
    Vector::new(
        if pick { a.x } else { b.x },
        if pick { a.y } else { b.y },
        if pick { a.z } else { b.z },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::contact_set::ContactSet;
    use crate::collision::obstacle::{DynamicBody, Obstacle};
    use crate::collision::tracks::ObstacleTracks;
    use crate::context::StepContext;

    const N: usize = 61;

    /// Particles around a ball of radius 0.5 at the origin: far, near,
    /// touching, inside (some entered this substep, some were in before),
    /// one at the centre, every seventh pinned; the first ten anchored far
    /// from where they are (not from the step's cache). Positions at the
    /// substep's start, now, velocities, masses.
    fn particles() -> [Vec<Vector>; 3] {
        let mut x = Vec::new();
        let mut prev = Vec::new();
        let mut v = Vec::new();
        for i in 0..N {
            let s = i as f32;
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin()).normalize();
            // From 0.05 m inside to 0.15 m out (0.12 m beyond the reach).
            let d = 0.45 + 0.2 * ((s * 0.37) % 1.0);
            x.push(dir * d);
            let back = if i % 3 == 0 { 0.2 } else { 0.01 };
            prev.push(dir * (d + back));
            v.push(Vector::new(
                0.3 * (s * 0.9).cos(),
                -1.0 + 0.05 * s,
                0.2 * (s * 1.7).sin(),
            ));
        }
        x[5] = Vector::ZERO;
        [prev, x, v]
    }

    /// What a pass left: positions, velocities, nearest obstacles, normals,
    /// distances, contacts, the momentum handed to the ball and the block's
    /// counts, as bits.
    fn outcome(ball: &Obstacle, friction: FrictionPolicy, lanes: Option<bool>) -> Vec<u32> {
        let obstacles = [ball.clone()];
        let mut tracks = ObstacleTracks::default();
        let (dt, h) = (1.0 / 60.0, 1.0 / 600.0);
        tracks.begin_step(&obstacles, dt, 0.12);
        let [x_prev, mut x, mut v] = particles();
        let mut anchors = x.clone();
        for a in &mut anchors[..10] {
            *a += Vector::splat(1.0);
        }
        tracks.cache_candidates(&anchors, 0.1);
        tracks.advance_to(&obstacles, 2.0 * h, h);
        let mass: Vec<f32> = (0..N).map(|i| 0.01 + 0.001 * i as f32).collect();
        let inv_mass: Vec<f32> = (0..N)
            .map(|i| if i % 7 == 3 { 0.0 } else { 1.0 / mass[i] })
            .collect();
        let ctx = StepContext {
            dt,
            h,
            substep: 2,
            substeps: 10,
            time: 0.0,
            gravity: Vector::new(0.0, -9.81, 0.0),
            thickness: 0.01,
        };
        let pass = ParticlePass {
            ctx: &ctx,
            tracks: &tracks,
            obstacles: &obstacles,
            x_prev: &x_prev,
            mass: &mass,
            inv_mass: &inv_mass,
            friction,
            far: 0.12,
        };
        let (mut nearest, mut normal, mut distance) =
            (vec![7; N], vec![Vector::ONE; N], vec![9.0; N]);
        let mut set = ContactSet::default();
        set.begin_step(N, 1);
        let mut scratch = BlockScratch::default();
        scratch.impulses.resize(1, Default::default());
        let contacts = {
            let shared = set.shared();
            let mut out = BlockOut {
                x: &mut x,
                v: &mut v,
                nearest: &mut nearest,
                normal: &mut normal,
                distance: &mut distance,
                // SAFETY: the one range in use.
                contacts: unsafe { shared.range(0..N) },
            };
            match lanes {
                Some(simd) => {
                    let law = tracks.one_ball_law(&obstacles).unwrap();
                    pass.ball_block_with(&law, 0..N, &mut out, (&mut scratch, simd))
                }
                None => (0..N)
                    .map(|k| pass.particle(k, k, &mut out, &mut scratch))
                    .sum(),
            }
        };
        let mut bits = vec![contacts, scratch.strays, scratch.pinned_close as u32];
        let mut put = |v: Vector| bits.extend(v.to_array().map(f32::to_bits));
        for i in 0..N {
            put(x[i]);
            put(v[i]);
            put(normal[i]);
            let c = set.get(i);
            put(c.map_or(Vector::NAN, |c| c.surface_velocity));
            put(c.map_or(Vector::NAN, |c| c.normal));
        }
        let sum = scratch.impulses[0];
        put(sum.linear);
        put(sum.angular_about_origin);
        bits.extend(nearest);
        bits.extend(distance.iter().map(|d| d.to_bits()));
        bits.extend([
            scratch.drift2.to_bits(),
            scratch.shift2.to_bits(),
            sum.contacts,
        ]);
        bits
    }

    /// The lanes give the general pass's bits, with and without AVX2, for
    /// a fixed, a moving and a dynamic ball, with friction applied or
    /// already solved; and every case the lanes distinguish occurs.
    #[test]
    fn the_lanes_give_the_general_pass_s_bits() {
        let fixed = Obstacle::ball(Vector::ZERO, 0.5).with_friction(0.6);
        let moving = fixed
            .clone()
            .with_velocity(Vector::new(0.5, 2.0, -0.3), Vector::new(1.0, -2.0, 3.0));
        let mut dynamic = moving.clone();
        dynamic.body = Some(DynamicBody {
            inverse_mass: Vector::splat(0.5),
            inverse_inertia: glam::Mat3::from_diagonal(Vector::splat(3.0)),
            center_of_mass: Vector::new(0.01, 0.0, 0.0),
            acceleration: Vector::new(0.0, -9.81, 0.0),
        });
        for ball in [fixed, moving, dynamic] {
            for friction in [FrictionPolicy::Apply, FrictionPolicy::AlreadySolved] {
                let general = outcome(&ball, friction, None);
                let (contacts, strays, pinned_close) = (general[0], general[1], general[2]);
                assert!(
                    contacts > 10 && contacts < N as u32 - 10,
                    "{contacts} contacts"
                );
                assert!(strays > 0 && pinned_close == 1);
                let nearest = &general[general.len() - 2 - 2 * N..general.len() - 2 - N];
                assert!(nearest.contains(&NONE), "none beyond the reach");
                for simd in [false, simd_available()] {
                    assert_eq!(outcome(&ball, friction, Some(simd)), general, "simd {simd}");
                }
            }
        }
    }
}
