//! Forces: gravity, springs with damping, wind on triangles, air drag.
//!
//! Every function here is pure: it reads positions and velocities and adds
//! forces (N) or accelerations (m/s²) into a buffer.

use crate::cloth::{
    Cloth, Material, Particles, PhysicsParams, SpringKind, SpringParams, Springs, Topology, Wind,
};
use crate::math::Vector;
use crate::parallel::Team;

mod wind_lanes;

/// Force on particle `a` from a spring joining it to `b`, in newtons:
/// `k (|x_ab| - L) d + c ((v_b - v_a)·d) d` with `d` the unit vector from `a`
/// to `b`. Particle `b` feels the opposite force. Zero when the two ends coincide.
#[inline(always)]
pub fn spring_force(
    xa: Vector,
    xb: Vector,
    va: Vector,
    vb: Vector,
    rest: f32,
    params: SpringParams,
) -> Vector {
    let d = xb - xa;
    let len2 = d.length_squared();
    if len2 <= f32::MIN_POSITIVE {
        return Vector::ZERO;
    }
    let inv_len = len2.sqrt().recip();
    let dir = d * inv_len;
    let len = len2 * inv_len;
    let magnitude = params.stiffness * (len - rest) + params.damping * (vb - va).dot(dir);
    dir * magnitude
}

/// Total wind force on a triangle, in newtons: `c A (n·d) n` with `c` the
/// wind strength (N/m²), `A` the area, `n` the unit normal and `d` the unit
/// wind direction. Each corner gets a third of it. Zero for a degenerate
/// triangle or calm wind.
#[inline]
pub fn wind_force_on_triangle(p0: Vector, p1: Vector, p2: Vector, wind: &Wind) -> Vector {
    let Some(dir) = wind.direction.try_normalize() else {
        return Vector::ZERO;
    };
    let cross = (p1 - p0).cross(p2 - p0);
    let twice_area = cross.length();
    if twice_area <= f32::MIN_POSITIVE {
        return Vector::ZERO;
    }
    let n = cross / twice_area;
    n * (wind.strength * 0.5 * twice_area * n.dot(dir))
}

/// The air's velocity (m/s) at `at` (m) and time `t` (s) of a wind with a
/// speed: its direction at its speed, varied by its gusts.
pub fn air_velocity(wind: &Wind, at: Vector, t: f32) -> Vector {
    AirField::of(wind).map_or(Vector::ZERO, |air| air.at(at, t))
}

/// Gust waves of [`air_velocity`]: frequency (Hz) and amplitude (a share
/// of the turbulence) of each, downwind and across.
const GUSTS: [(f32, f32); 3] = [(0.4, 0.5), (1.1, 0.3), (2.9, 0.2)];

/// What [`air_velocity`] works out of a wind once, whatever the point and
/// time: its direction, the direction across it and the gusts' phases
/// (the wind-force loop asks for the air at every triangle each substep).
#[derive(Debug, Clone, Copy)]
struct AirField {
    wind: Wind,
    dir: Vector,
    side: Vector,
    /// Phases (rad) of the gusts downwind, then across.
    phases: [f32; 6],
}

impl AirField {
    /// The field of `wind`; `None` when it has no direction.
    fn of(wind: &Wind) -> Option<AirField> {
        let dir = wind.direction.try_normalize()?;
        let phase = |k: u32| {
            let h = (wind.seed ^ k.wrapping_mul(0x9e37_79b9)).wrapping_mul(0x85eb_ca6b);
            (h >> 8) as f32 / (1u32 << 24) as f32 * std::f32::consts::TAU
        };
        Some(AirField {
            wind: *wind,
            dir,
            side: dir.cross(Vector::Y).try_normalize().unwrap_or(Vector::X),
            phases: std::array::from_fn(|k| phase(k as u32)),
        })
    }

    /// The field of a `wind` without a direction: the air is still
    /// everywhere (the cloth's own motion makes the wind it feels).
    fn still(wind: &Wind) -> AirField {
        AirField {
            wind: Wind {
                turbulence: 0.0,
                ..*wind
            },
            dir: Vector::ZERO,
            side: Vector::ZERO,
            phases: [0.0; 6],
        }
    }

    /// The air's velocity (m/s) at `at` (m) and time `t` (s).
    #[inline(always)]
    fn at(&self, at: Vector, t: f32) -> Vector {
        let (wind, dir) = (&self.wind, self.dir);
        if wind.turbulence == 0.0 {
            return dir * wind.speed;
        }
        // Three gust waves travelling downwind at the air's speed, and three
        // across it; phases from the seed.
        let downwind = at.dot(dir);
        let side = self.side;
        let across = at.dot(side);
        let tau = std::f32::consts::TAU;
        let mut along = 0.0;
        let mut sideways = 0.0;
        let travel = t - downwind / wind.speed.max(0.1);
        for (k, (freq, amp)) in GUSTS.iter().enumerate() {
            along += amp * gust_sine(tau * freq * travel + self.phases[k]);
            sideways +=
                amp * gust_sine(tau * freq * 1.3 * travel + 2.0 * across + self.phases[k + 3]);
        }
        dir * (wind.speed * (1.0 + wind.turbulence * along))
            + side * (0.5 * wind.speed * wind.turbulence * sideways)
    }
}

/// `sin x` for the gusts, to within 3e-7 of it (tested to |x| = 620) after an
/// exact reduction: branch-free, so that the wind on eight triangles is
/// worked out at once in vector lanes (`wind_lanes.rs`); libm's `sinf`,
/// one call a gust, was a fifth of the flag's step (measured).
#[inline(always)]
fn gust_sine(x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI, TAU};
    // 2π in two parts: the first has few bits, so `k` times it is exact;
    // the second from double precision (single precision's 2π is 1.7e-7
    // off, which `k` multiplies).
    const TAU_HI: f32 = 6.28125;
    const TAU_LO: f32 = (std::f64::consts::TAU - TAU_HI as f64) as f32;
    let k = (x * (1.0 / TAU) + 0.5).floor();
    let r = (x - k * TAU_HI) - k * TAU_LO;
    // sin r = sin(±π − r): onto [-π/2, π/2], where the series converges fast.
    let r = if r > FRAC_PI_2 {
        PI - r
    } else if r < -FRAC_PI_2 {
        -PI - r
    } else {
        r
    };
    let r2 = r * r;
    // Taylor to r¹¹: the next term is under 6e-8 at π/2.
    let poly = 1.0
        + r2 * (-1.0 / 6.0
            + r2 * (1.0 / 120.0
                + r2 * (-1.0 / 5040.0 + r2 * (1.0 / 362_880.0 + r2 * (-1.0 / 39_916_800.0)))));
    r * poly
}

/// Total wind force (N) on a triangle moving at `velocity` (m/s) at time
/// `t` (s): with an air speed, the law of [`Wind`] on the air's velocity
/// relative to the triangle; without, [`wind_force_on_triangle`].
#[inline]
pub fn wind_force_on_moving_triangle(
    [p0, p1, p2]: [Vector; 3],
    velocity: Vector,
    wind: &Wind,
    t: f32,
) -> Vector {
    let air = AirField::of(wind);
    wind_force_in_field([p0, p1, p2], velocity, (wind, air.as_ref()), t)
}

/// [`wind_force_on_moving_triangle`] with the wind's field (`None`: no
/// direction, still air) worked out already.
#[inline]
fn wind_force_in_field(
    [p0, p1, p2]: [Vector; 3],
    velocity: Vector,
    (wind, air): (&Wind, Option<&AirField>),
    t: f32,
) -> Vector {
    if wind.speed <= 0.0 {
        return wind_force_on_triangle(p0, p1, p2, wind);
    }
    match air {
        Some(air) => force_in_moving_air([p0, p1, p2], velocity, air, t),
        None => force_in_moving_air([p0, p1, p2], velocity, &AirField::still(wind), t),
    }
}

/// The wind force (N) on a triangle moving at `velocity` (m/s) in the
/// moving `air` (its wind has a speed) at time `t` (s). Written without an
/// early return (a degenerate triangle, or no air relative to it, is
/// zeroed at the end), so that `wind_lanes.rs` runs it on eight triangles
/// at once with the same bits.
#[inline(always)]
fn force_in_moving_air(
    [p0, p1, p2]: [Vector; 3],
    velocity: Vector,
    air: &AirField,
    t: f32,
) -> Vector {
    let wind = &air.wind;
    let cross = (p1 - p0).cross(p2 - p0);
    let twice_area = cross.length();
    let n = cross / twice_area;
    let centroid = (p0 + p1 + p2) / 3.0;
    let u = air.at(centroid, t) - velocity;
    let speed2 = u.length_squared();
    let u_hat = u / speed2.sqrt();
    let pressure = wind.strength * speed2 / (wind.speed * wind.speed);
    let normal = n.dot(u_hat);
    let force = (n * normal + (u_hat - n * normal) * wind.friction) * (pressure * 0.5 * twice_area);
    if twice_area <= f32::MIN_POSITIVE || speed2 <= f32::MIN_POSITIVE {
        Vector::ZERO
    } else {
        force
    }
}

/// Below this many springs a colour class is evaluated on one thread.
const PARALLEL_MIN: usize = 4096;

/// Springs of a class a thread takes at a time.
const PARALLEL_CHUNK: usize = 2048;

/// Adds the spring forces (elastic and damping) of every spring into `f`.
///
/// Springs are stored colour class by colour class; on a `team` of several
/// threads each large class is split among them. A particle meets each
/// class at most once, so it sums its forces in storage order either way:
/// the result is bit-identical to the single-threaded one.
pub(crate) fn add_spring_forces(
    springs: &Springs,
    params: &[SpringParams; 3],
    (x, v): (&[Vector], &[Vector]),
    f: &mut [Vector],
    team: Team,
) {
    let (a, b, rest) = (&springs.a[..], &springs.b[..], &springs.rest[..]);
    let serial = |range: std::ops::Range<usize>, p: SpringParams, f: &mut [Vector]| {
        for s in range {
            let (i, j) = (a[s] as usize, b[s] as usize);
            let force = spring_force(x[i], x[j], v[i], v[j], rest[s], p);
            f[i] += force;
            f[j] -= force;
        }
    };
    if team.is_alone() || springs.colour_ranges.is_empty() {
        for kind in SpringKind::ALL {
            serial(springs.range(kind), params[kind.index()], f);
        }
        return;
    }
    for (range, &disjoint) in springs.colour_ranges.iter().zip(&springs.colour_disjoint) {
        let p = params[springs.kind(range.start).index()];
        if disjoint && range.len() >= PARALLEL_MIN {
            parallel_class(springs, (range.clone(), p), (x, v), f, team);
        } else {
            serial(range.clone(), p, f);
        }
    }
}

/// A pointer to the force buffer that threads may share because they write
/// disjoint elements.
#[derive(Clone, Copy)]
struct SharedForces(*mut Vector);
// SAFETY: only used by `parallel_class`, whose threads write disjoint elements.
unsafe impl Send for SharedForces {}
// SAFETY: as above.
unsafe impl Sync for SharedForces {}

impl SharedForces {
    /// The force of particle `i`.
    ///
    /// # Safety
    /// `i` is in bounds, and no other thread uses element `i` meanwhile.
    unsafe fn at(self, i: usize) -> *mut Vector {
        // SAFETY: in bounds by the caller's promise.
        unsafe { self.0.add(i) }
    }
}

/// One colour class's springs, `range` with parameters `p`, on the team.
fn parallel_class(
    springs: &Springs,
    (range, p): (std::ops::Range<usize>, SpringParams),
    (x, v): (&[Vector], &[Vector]),
    f: &mut [Vector],
    team: Team,
) {
    let (a, b, rest) = (&springs.a[..], &springs.b[..], &springs.rest[..]);
    let n = f.len();
    let out = SharedForces(f.as_mut_ptr());
    let chunks = range.len().div_ceil(PARALLEL_CHUNK);
    team.sum_count(chunks, |c| {
        let first = range.start + c * PARALLEL_CHUNK;
        for s in first..(first + PARALLEL_CHUNK).min(range.end) {
            let (i, j) = (a[s] as usize, b[s] as usize);
            let force = spring_force(x[i], x[j], v[i], v[j], rest[s], p);
            if i < n && j < n {
                // SAFETY: `i` and `j` are in bounds (checked above and
                // validated when the cloth was built), and within one colour
                // class no two springs share a particle, so no other thread
                // touches f[i] or f[j] now.
                unsafe {
                    *out.at(i) += force;
                    *out.at(j) -= force;
                }
            }
        }
        0
    });
}

/// Adds the wind force of every triangle, moving at its corners' mean
/// velocity `v`, at time `t` (s), into `f`: in moving air eight triangles
/// at a time (`wind_lanes.rs`), each force then shared among its corners
/// in triangle order, as one at a time would.
pub(crate) fn add_wind_forces(
    triangles: &[[u32; 3]],
    wind: &Wind,
    (x, v): (&[Vector], &[Vector]),
    t: f32,
    f: &mut [Vector],
) {
    if wind.is_calm() {
        return;
    }
    match AirField::of(wind) {
        Some(air) if wind.speed > 0.0 => wind_lanes::add_forces(triangles, &air, (x, v), t, f),
        air => {
            for tri in triangles {
                let [i, j, k] = tri.map(|i| i as usize);
                let velocity = (v[i] + v[j] + v[k]) / 3.0;
                let force =
                    wind_force_in_field([x[i], x[j], x[k]], velocity, (wind, air.as_ref()), t);
                let share = force / 3.0;
                f[i] += share;
                f[j] += share;
                f[k] += share;
            }
        }
    }
}

/// Everything needed to turn positions and velocities into accelerations.
pub(crate) struct ForceModel<'a> {
    pub springs: &'a Springs,
    pub spring_params: [SpringParams; 3],
    /// The longest a stretch spring may be over its rest length (infinite: no limit).
    pub stretch_limit: f32,
    pub triangles: &'a [[u32; 3]],
    pub mass: &'a [f32],
    pub inv_mass: &'a [f32],
    pub gravity: Vector,
    pub air_drag: f32,
    pub wind: Wind,
    /// Time the forces are taken at, in seconds (for the wind's gusts).
    pub time: f32,
    /// The threads that may evaluate spring forces.
    pub team: Team<'a>,
}

/// The masses of a cloth's particles, borrowed apart from its positions
/// and velocities so that integrators can write those meanwhile.
#[derive(Clone, Copy)]
pub(crate) struct Masses<'a> {
    /// Masses, in kg.
    pub mass: &'a [f32],
    /// Inverse masses, in 1/kg; 0 for pinned particles.
    pub inv_mass: &'a [f32],
}

impl<'a> Masses<'a> {
    /// The masses of `particles`.
    pub fn of(particles: &'a Particles) -> Self {
        Masses {
            mass: &particles.mass,
            inv_mass: &particles.inv_mass,
        }
    }
}

impl<'a> ForceModel<'a> {
    /// The force model of a cloth's parts; spring forces on the `team`'s threads.
    pub fn new(
        topology: &'a Topology,
        material: &Material,
        masses: Masses<'a>,
        physics: &PhysicsParams,
        team: Team<'a>,
    ) -> Self {
        ForceModel {
            springs: &topology.springs,
            spring_params: SpringKind::ALL.map(|k| material.params(k)),
            stretch_limit: material.stretch_limit_factor(),
            triangles: &topology.triangles,
            mass: masses.mass,
            inv_mass: masses.inv_mass,
            gravity: physics.gravity,
            air_drag: physics.air_drag,
            wind: physics.wind,
            time: 0.0,
            team,
        }
    }

    /// The same model taken at time `t` seconds (the wind's gusts).
    pub fn at(mut self, t: f32) -> Self {
        self.time = t;
        self
    }

    /// Total force on every particle, in newtons, written into `f`.
    pub fn forces(&self, x: &[Vector], v: &[Vector], f: &mut [Vector]) {
        for i in 0..f.len() {
            f[i] = (self.gravity - v[i] * self.air_drag) * self.mass[i];
        }
        add_spring_forces(self.springs, &self.spring_params, (x, v), f, self.team);
        add_wind_forces(self.triangles, &self.wind, (x, v), self.time, f);
    }

    /// Acceleration of every particle, in m/s², written into `a`; zero for pinned particles.
    pub fn accelerations(&self, x: &[Vector], v: &[Vector], a: &mut [Vector]) {
        self.forces(x, v, a);
        for (ai, &w) in a.iter_mut().zip(self.inv_mass) {
            *ai *= w;
        }
    }
}

impl Cloth {
    /// The total force on every particle at the current state, in newtons
    /// (gravity, springs with damping, wind, drag; pinned particles included).
    pub fn forces(&self) -> Vec<Vector> {
        let mut f = vec![Vector::ZERO; self.particle_count()];
        self.forces_into(&mut f);
        f
    }

    /// Like [`Cloth::forces`], into a buffer; does nothing if its length is not the particle count.
    pub fn forces_into(&self, f: &mut [Vector]) {
        if f.len() != self.particle_count() {
            return;
        }
        let model = ForceModel::new(
            &self.topology,
            &self.material,
            Masses::of(&self.particles),
            &self.params,
            Team::ALONE,
        )
        .at(self.time as f32);
        model.forces(&self.particles.x, &self.particles.v, f);
    }
}
