//! The particle pass against one ball or one cuboid, eight particles at a
//! time. A cloth draped over a ball or a table (the `drape` and `box`
//! scenes, a ball dropped on a sheet, a tablecloth) has a single obstacle
//! and thousands of particles near it; the general pass gathers each
//! particle's candidates into a list and answers them through the shape's
//! kind, a few dozen nanoseconds a particle. Here the shape's law (the
//! bounding test, the contact, the push out and Coulomb friction) is
//! written without branches and run over structure-of-arrays lanes (AVX2
//! when the CPU has it, lane by lane otherwise), then the results are
//! written back and the momentum summed in particle order. Every operation
//! is the general pass's, in its order, without fused multiply-adds: the
//! bits are the same. A particle found inside the shape goes through the
//! general pass instead, which traces its path back out through the side
//! it came in (or, in a cuboid, finds the nearest face).

use super::contact::cuboid_outside;
use super::contact_set::{ParticleContact, NONE};
use super::one_obstacle::{LaneShape, OneObstacleLaw};
use super::particle_pass::{push_out, select, BlockOut, BlockScratch, ParticlePass, CONTACT_SLACK};
use super::response::FrictionPolicy;
use crate::math::{simd_available, Vector};

/// Particles in a batch: eight AVX2 registers of `f32` lanes. Filled one
/// particle at a time and read eight lanes at a time, a batch of one
/// register stalled its loads on the stores just made (store forwarding
/// fails from narrow stores to a wide load); a larger one has its stores
/// done before it is read, and still fits the first-level cache.
const LANES: usize = 64;

/// The same for every lane of a block: the obstacle, and the pass's settings.
#[derive(Clone, Copy)]
struct Shared {
    law: OneObstacleLaw,
    thickness: f32,
    far: f32,
    h: f32,
    friction_applies: bool,
}

/// One batch, coordinate by coordinate: what goes in per lane, and what
/// the law gives back.
struct Batch {
    x: [[f32; LANES]; 3],
    v: [[f32; LANES]; 3],
    inv_mass: [f32; LANES],
    mass: [f32; LANES],
    /// Where the particle was when the step's cache was made (m), 1 when
    /// there is a cache, and 1 when it listed the obstacle for the particle.
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
    /// 1 when the obstacle counts (a candidate, within reach, a finite contact).
    near: [u32; LANES],
    /// 1 when the particle is inside the obstacle: the general pass takes it.
    inside: [u32; LANES],
    /// 1 when the particle touches and was resolved.
    touching: [u32; LANES],
    normal: [[f32; LANES]; 3],
    signed_distance: [f32; LANES],
    x_out: [[f32; LANES]; 3],
    v_out: [[f32; LANES]; 3],
    surface_velocity: [[f32; LANES]; 3],
    /// Where (m) and how much momentum (N·s) the particle handed the obstacle.
    point: [[f32; LANES]; 3],
    impulse: [[f32; LANES]; 3],
}

impl Default for Batch {
    fn default() -> Self {
        Batch {
            x: [[0.0; LANES]; 3],
            v: [[0.0; LANES]; 3],
            inv_mass: [0.0; LANES],
            mass: [0.0; LANES],
            anchor: [[0.0; LANES]; 3],
            has_anchor: [0; LANES],
            listed: [0; LANES],
            from_cache: [0; LANES],
            drift2: [0.0; LANES],
            shift2: [0.0; LANES],
            near: [0; LANES],
            inside: [0; LANES],
            touching: [0; LANES],
            normal: [[0.0; LANES]; 3],
            signed_distance: [0.0; LANES],
            x_out: [[0.0; LANES]; 3],
            v_out: [[0.0; LANES]; 3],
            surface_velocity: [[0.0; LANES]; 3],
            point: [[0.0; LANES]; 3],
            impulse: [[0.0; LANES]; 3],
        }
    }
}

impl ParticlePass<'_> {
    /// [`ParticlePass::block`] when the one obstacle is `law`'s.
    pub(super) fn lanes_block(
        &self,
        law: &OneObstacleLaw,
        range: std::ops::Range<usize>,
        out: &mut BlockOut,
        scratch: &mut BlockScratch,
    ) -> u32 {
        self.lanes_block_with(law, range, out, (scratch, simd_available()))
    }

    /// [`ParticlePass::lanes_block`], with the AVX2 lanes only when `simd`.
    fn lanes_block_with(
        &self,
        law: &OneObstacleLaw,
        range: std::ops::Range<usize>,
        out: &mut BlockOut,
        (scratch, simd): (&mut BlockScratch, bool),
    ) -> u32 {
        let shared = Shared {
            law: *law,
            thickness: self.ctx.thickness,
            far: self.far,
            h: self.ctx.h,
            friction_applies: self.friction == FrictionPolicy::Apply,
        };
        let mut batch = Batch::default();
        let mut contacts = 0;
        let start = range.start;
        // The farthest drift and shift, per lane: one running maximum over
        // the block was a chain of dependent `max`es a particle, an eighth
        // of the block's time. Every value is a square (never −0) or not a
        // number, which `max` passes over, so their order changes no bit.
        let (mut drift2, mut shift2) = ([0.0f32; LANES], [0.0f32; LANES]);
        // The block's particles' arrays, of one length checked once (each
        // index below is then checked once, not per array).
        let n = range.len();
        let cache = self.tracks.cache_for(range.clone());
        let (inv_mass, mass) = (&self.inv_mass[range.clone()], &self.mass[range.clone()]);
        assert!([out.x.len(), out.v.len(), inv_mass.len(), mass.len()] == [n; 4]);
        if let Some(cache) = &cache {
            assert!(cache.anchor.iter().all(|a| a.len() == n) && cache.listed.len() == n);
        }
        // Without a cache: no anchor, no list (left so in every batch).
        batch.has_anchor = [cache.is_some() as u32; LANES];
        for chunk in (0..n).step_by(LANES) {
            let count = LANES.min(n - chunk);
            let lanes = chunk..chunk + count;
            // What stays put through the step comes as arrays already:
            // copies of whole runs.
            copy_run(&mut batch.inv_mass, &inv_mass[lanes.clone()]);
            copy_run(&mut batch.mass, &mass[lanes.clone()]);
            if let Some(cache) = &cache {
                for a in 0..3 {
                    copy_run(&mut batch.anchor[a], &cache.anchor[a][lanes.clone()]);
                }
                copy_run(&mut batch.listed, &cache.listed[lanes.clone()]);
            }
            for lane in 0..count {
                let k = chunk + lane;
                let (x, v) = (out.x[k], out.v[k]);
                for a in 0..3 {
                    batch.x[a][lane] = x[a];
                    batch.v[a][lane] = v[a];
                }
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
                drift2[lane] = drift2[lane].max(batch.drift2[lane]);
                shift2[lane] = shift2[lane].max(batch.shift2[lane]);
            }
        }
        scratch.drift2 = drift2.into_iter().fold(scratch.drift2, f32::max);
        scratch.shift2 = shift2.into_iter().fold(scratch.shift2, f32::max);
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
        out.surface[k] = out.normal[k].dot(out.x[k]) - signed;
        out.distance[k] = if free { signed.max(thickness) } else { signed };
        if !free && signed < thickness {
            scratch.pinned_close = true;
        }
        if batch.touching[lane] == 0 {
            return 0;
        }
        out.x[k] = get(&batch.x_out);
        out.v[k] = get(&batch.v_out);
        let law = &shared.law;
        out.contacts.touch(
            k,
            &ParticleContact {
                obstacle: 0,
                normal: get(&batch.normal),
                surface_velocity: get(&batch.surface_velocity),
                immovable: law.immovable,
                gap: 0.0,
                friction: law.friction,
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

/// `run` into the first lanes of `lanes` (at most all of them): a copy of
/// known length, in registers, when the run fills the batch (a call to
/// `memmove` otherwise, 1% of the drape's time).
#[inline(always)]
fn copy_run<T: Copy>(lanes: &mut [T; LANES], run: &[T]) {
    match <&[T; LANES]>::try_from(run) {
        Ok(full) => *lanes = *full,
        Err(_) => lanes[..run.len()].copy_from_slice(run),
    }
}

/// Every lane of the batch through the obstacle's law.
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
    crate::math::align_frame();
    solve_lanes(batch, shared);
}

/// The obstacle's law, lane by lane, without branches: the general pass's
/// candidate test ([`super::tracks::ObstacleTracks::gather_particle`]) and
/// far test ([`super::tracks::ObstacleTracks::surely_beyond`]), the shape's
/// contact (`contact::ball_contact`, [`cuboid_outside`]) and the push out
/// with friction (`ParticlePass::resolve`), each operation as they do it.
#[inline(always)]
fn solve_lanes(batch: &mut Batch, shared: &Shared) {
    match shared.law.shape {
        LaneShape::Ball { centre, radius } => lanes_with(
            batch,
            shared,
            #[inline(always)]
            |x| {
                let offset = x - centre;
                let dist = offset.length();
                let normal = select(dist > 1e-9, offset / dist, Vector::Y);
                let surface = centre + normal * radius;
                let signed = dist - radius;
                let finite = surface.is_finite() && normal.is_finite() && signed.is_finite();
                // Inside where the contact says so (a traced path then).
                (normal, signed, finite, finite && signed < 0.0)
            },
        ),
        LaneShape::Cuboid { half, pose } => lanes_with(
            batch,
            shared,
            #[inline(always)]
            |x| cuboid_outside(half, &pose, x),
        ),
    }
}

/// [`solve_lanes`] with the shape's contact `contact`: of a point, the
/// outward normal, the signed distance (m), whether they are finite, and
/// whether the general pass must take the point (inside).
#[inline(always)]
fn lanes_with(
    batch: &mut Batch,
    shared: &Shared,
    contact: impl Fn(Vector) -> (Vector, f32, bool, bool),
) {
    let law = &shared.law;
    let thickness = shared.thickness;
    for lane in 0..LANES {
        let get = |c: &[[f32; LANES]; 3]| Vector::new(c[0][lane], c[1][lane], c[2][lane]);
        let (x, v, anchor) = (get(&batch.x), get(&batch.v), get(&batch.anchor));
        // A candidate: within the bounds, and listed by the cache unless
        // the particle drifted beyond its margin (a NaN drift keeps it).
        let drifted = (x - anchor).abs().max_element() > law.cache_margin;
        let from_cache = batch.has_anchor[lane] != 0 && !drifted;
        let (lo, hi) = (law.bounds_min, law.bounds_max);
        let meets = (lo.x <= x.x) & (lo.y <= x.y) & (lo.z <= x.z);
        let meets = meets & (hi.x >= x.x) & (hi.y >= x.y) & (hi.z >= x.z);
        let candidate = meets & (!from_cache | (batch.listed[lane] != 0));
        // Far: outside the bounding sphere grown by the reach.
        let reach = law.bound_radius + shared.far;
        let beyond = (x - law.bound_centre).length_squared() > reach * reach;
        let (normal, signed, finite, inside) = contact(x);
        let near = candidate && !beyond && finite;
        let free = batch.inv_mass[lane] != 0.0;
        let touching = near && free && signed < thickness + CONTACT_SLACK;
        // The push out, and friction against the surface's motion.
        let pushed = push_out(
            (x, v),
            (normal, signed),
            thickness,
            #[inline(always)]
            |p| law.linear + law.angular.cross(p - law.about),
            (law.friction, shared.friction_applies, shared.h),
        );
        let (new_x, surface_v, v_new, x_new) =
            (pushed.surface, pushed.surface_velocity, pushed.v, pushed.x);
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
        batch.inside[lane] = (candidate && !beyond && inside) as u32;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::contact_set::ContactSet;
    use crate::collision::obstacle::{DynamicBody, Obstacle};
    use crate::collision::tracks::ObstacleTracks;
    use crate::context::StepContext;

    // Two full batches and a short one.
    const N: usize = 2 * LANES + 22;

    /// Particles around a ball of radius 0.5 at the origin (and cuboids of
    /// about that size, which some are inside): far, near,
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
            // From 0.05 m inside to 0.15 m out of the ball (0.12 m beyond
            // the reach); every eleventh far beyond the cuboids' too.
            let d = if i % 11 == 10 {
                1.0
            } else {
                0.45 + 0.2 * ((s * 0.37) % 1.0)
            };
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
    fn outcome(obstacle: &Obstacle, friction: FrictionPolicy, lanes: Option<bool>) -> Vec<u32> {
        let obstacles = [obstacle.clone()];
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
            skip_still: false,
            far: 0.12,
        };
        let (mut nearest, mut normal, mut distance, mut surface) =
            (vec![7; N], vec![Vector::ONE; N], vec![9.0; N], vec![9.0; N]);
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
                surface: &mut surface,
                // SAFETY: the one range in use.
                contacts: unsafe { shared.range(0..N) },
            };
            match lanes {
                Some(simd) => {
                    let law = tracks.one_obstacle_law(&obstacles).unwrap();
                    pass.lanes_block_with(&law, 0..N, &mut out, (&mut scratch, simd))
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

    /// A fixed, a moving (and turning) and a dynamic version of `fixed`.
    fn in_motion(fixed: Obstacle) -> [Obstacle; 3] {
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
        [fixed, moving, dynamic]
    }

    /// The lanes give the general pass's bits, with and without AVX2, for
    /// a fixed, a moving and a dynamic ball and cuboid (laid along the
    /// axes, and turned), with friction applied or already solved; and
    /// every case the lanes distinguish occurs.
    #[test]
    fn the_lanes_give_the_general_pass_s_bits() {
        let ball = Obstacle::ball(Vector::ZERO, 0.5).with_friction(0.6);
        let half = Vector::new(0.42, 0.36, 0.47);
        let laid = Obstacle::cuboid(half, crate::math::Pose::IDENTITY).with_friction(0.6);
        let turn = crate::math::Rotation::from_scaled_axis(Vector::new(0.3, -0.5, 0.2));
        let turned = Obstacle::cuboid(half, crate::math::Pose::from_parts(Vector::ZERO, turn))
            .with_friction(0.6);
        let obstacles = [ball, laid, turned].into_iter().flat_map(in_motion);
        for obstacle in obstacles {
            for friction in [FrictionPolicy::Apply, FrictionPolicy::AlreadySolved] {
                let general = outcome(&obstacle, friction, None);
                let (contacts, strays, pinned_close) = (general[0], general[1], general[2]);
                assert!(
                    contacts > 10 && contacts < N as u32 - 10,
                    "{contacts} contacts"
                );
                assert!(strays > 0 && pinned_close == 1);
                let nearest = &general[general.len() - 3 - 2 * N..general.len() - 3 - N];
                assert!(nearest.contains(&NONE), "none beyond the reach");
                for simd in [false, simd_available()] {
                    let lanes = outcome(&obstacle, friction, Some(simd));
                    assert_eq!(lanes, general, "simd {simd}: {obstacle:?}");
                }
            }
        }
    }
}
