//! Implicit backward Euler after Baraff and Witkin (1998), "Large steps in
//! cloth simulation".
//!
//! The spring and damping forces are linearised about the current state and
//! `(M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f + h ∂f/∂x v)` is solved for the
//! velocity change with a preconditioned conjugate gradient (block Jacobi,
//! or the [`spring_space`](super::spring_space) preconditioner, which stays
//! fast however stiff the springs). The
//! system is kept in block-sparse form: one symmetric 3×3 block per spring
//! (`h D + h² K`) plus the lumped masses on the diagonal, never a dense matrix.
//! Pins and contacts are constraints of the solve, enforced by the paper's
//! filtering: a pinned particle's velocity change is zero in every direction;
//! a particle pressed against an obstacle, or about to reach it within the
//! step, gets the surface's normal velocity and, by Coulomb's law decided
//! from the start state, either stays held (static friction: its whole
//! velocity is set) or slides with the kinetic friction impulse. Friction
//! inside the solve lets the cloth around a held particle answer in the same
//! step. Compressed springs drop the negative transverse term of their
//! Jacobian, which keeps the matrix positive definite.
//!
//! Further linearisations (`newton_iterations`) are Newton steps on the
//! backward-Euler objective ([`objective`]), each followed by a line search
//! that only accepts a step that lowers it, so re-linearising can never make
//! the step worse.
//!
//! A particle the step carries into an obstacle although it was free at the
//! start (pulled there by its neighbours) is put on the surface and
//! constrained to its tangent plane, and the solve goes on with it (up to
//! [`CONTACT_ROUNDS`] more linearisations). Pushing it out after the solve
//! instead would stretch a stiff spring by the whole penetration.

use glam::Mat3;

use crate::cloth::SpringKind;
use crate::collision::{CollisionStage, ContactSet, Response};
use crate::forces::{add_wind_forces, ForceModel};
use crate::math::Vector;

use super::filter::Filter;
use super::preconditioner::Preconditioner;
use super::spring_space::SpringSpace;
use super::substep::Substep;

/// Newton iterations past `newton_iterations` allowed for contacts that the
/// step itself ran into.
const CONTACT_ROUNDS: u32 = 4;

/// Scratch memory of the implicit solver.
#[derive(Debug, Default)]
pub(crate) struct ImplicitState {
    blocks: Vec<Mat3>,
    mass: Vec<f32>,
    diag: Vec<Mat3>,
    precond: Vec<Mat3>,
    filter: Vec<Filter>,
    /// Per particle: the velocity change its constraint prescribes.
    z: Vec<Vector>,
    /// Per particle: gravity and wind at the start of the step (N).
    external: Vec<Vector>,
    /// Per particle: the kinetic friction impulse of a sliding contact (N·s).
    friction: Vec<Vector>,
    f: Vec<Vector>,
    b: Vec<Vector>,
    dv: Vec<Vector>,
    r: Vec<Vector>,
    c: Vec<Vector>,
    q: Vec<Vector>,
    s: Vec<Vector>,
    xe: Vec<Vector>,
    ve: Vec<Vector>,
    acc: Vec<Vector>,
    trial: Vec<Vector>,
    /// Per particle: the obstacle a contact constraint holds it against.
    obstacle: Vec<u32>,
    /// The stiff springs' preconditioner.
    spring_space: SpringSpace,
}

impl ImplicitState {
    fn resize(&mut self, n: usize, springs: usize) {
        self.blocks.resize(springs, Mat3::ZERO);
        self.mass.resize(n, 0.0);
        for buf in [&mut self.diag, &mut self.precond] {
            buf.resize(n, Mat3::ZERO);
        }
        self.filter.resize(n, Filter::Free);
        self.obstacle.resize(n, u32::MAX);
        for buf in [
            &mut self.z,
            &mut self.external,
            &mut self.friction,
            &mut self.f,
            &mut self.b,
            &mut self.dv,
            &mut self.r,
            &mut self.c,
            &mut self.q,
            &mut self.s,
        ] {
            buf.resize(n, Vector::ZERO);
        }
    }
}

/// `out = filter(A x)`, with `A = M' + Σ_s B_s ⊗ (e_i − e_j)(e_i − e_j)ᵀ`
/// (`M'` the masses with the drag term, `B_s = h D_s + h² K_s`).
fn multiply(
    model: &ForceModel,
    blocks: &[Mat3],
    mass: &[f32],
    filter: &[Filter],
    x: &[Vector],
    out: &mut [Vector],
) {
    for i in 0..x.len() {
        out[i] = x[i] * mass[i];
    }
    let (a, b) = (&model.springs.a, &model.springs.b);
    for s in 0..a.len() {
        let (i, j) = (a[s] as usize, b[s] as usize);
        let y = blocks[s] * (x[i] - x[j]);
        out[i] += y;
        out[j] -= y;
    }
    for i in 0..x.len() {
        out[i] = filter[i].apply(out[i]);
    }
}

fn dot(a: &[Vector], b: &[Vector]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.as_dvec3().dot(y.as_dvec3()))
        .sum::<f64>()
}

/// Assembles the system at the linearisation point `(xe, ve)`: the per-spring
/// blocks `h D + h² K`, the diagonal, and the right-hand side
/// `h f(xe, ve) − M acc`, plus `h² K (v_j − v_i)` when `kv` is given (the
/// paper's first step, linearised at the start of the step).
fn assemble(
    model: &ForceModel,
    xe: &[Vector],
    ve: &[Vector],
    acc: &[Vector],
    kv: bool,
    h: f32,
    st: &mut ImplicitState,
) {
    let n = xe.len();
    let springs = model.springs;
    model.forces(xe, ve, &mut st.f);
    for i in 0..n {
        st.b[i] = st.f[i] * h - acc[i] * model.mass[i];
        let m = model.mass[i] * (1.0 + h * model.air_drag);
        st.mass[i] = m;
        st.diag[i] = Mat3::from_diagonal(Vector::splat(m));
    }
    let h2 = h * h;
    for kind in SpringKind::ALL {
        let p = model.spring_params[kind.index()];
        for s in springs.range(kind) {
            let (i, j) = (springs.a[s] as usize, springs.b[s] as usize);
            let d = xe[j] - xe[i];
            let len = d.length();
            if len <= f32::MIN_POSITIVE {
                st.blocks[s] = Mat3::ZERO;
                continue;
            }
            let dir = d / len;
            let ddt = Mat3::from_cols(dir * dir.x, dir * dir.y, dir * dir.z);
            // Definiteness fix: a compressed spring keeps no negative transverse stiffness.
            let transverse = (1.0 - springs.rest[s] / len).max(0.0);
            let k = (ddt + (Mat3::IDENTITY - ddt) * transverse) * p.stiffness;
            if kv {
                let kv = k * (ve[j] - ve[i]) * h2;
                st.b[i] += kv;
                st.b[j] -= kv;
            }
            let block = k * h2 + ddt * (p.damping * h);
            st.blocks[s] = block;
            st.diag[i] += block;
            st.diag[j] += block;
        }
    }
}

/// The backward-Euler objective at the velocity change `acc` (new velocity
/// `v + acc`, new positions `x + h (v + acc)`), whose minimum is the step:
/// `½ accᵀ M acc + U(x_new) + h/2 Σ c (d̂·Δv_new)² + h/2 γ Σ m |v_new|²
/// − h Σ f_ext·v_new − Σ J·v_new`, with the damping directions `d̂` of the
/// start of the step, the external forces `f_ext` (gravity, wind) taken there
/// and `J` the kinetic friction impulses. Its gradient is `M acc − h f − J`,
/// so Newton's method on it is the linearised step, and a line search on it
/// keeps stiff springs from overshooting. Free particles only.
fn objective(
    model: &ForceModel,
    x: &[Vector],
    v: &[Vector],
    acc: &[Vector],
    st: &ImplicitState,
    h: f32,
) -> f64 {
    let h = h as f64;
    let mut phi = 0.0f64;
    for i in 0..x.len() {
        if model.inv_mass[i] == 0.0 {
            continue;
        }
        let m = model.mass[i] as f64;
        let a = acc[i].as_dvec3();
        let vn = (v[i] + acc[i]).as_dvec3();
        phi += 0.5 * m * a.length_squared()
            + 0.5 * h * model.air_drag as f64 * m * vn.length_squared()
            - (st.external[i].as_dvec3() * h + st.friction[i].as_dvec3()).dot(vn);
    }
    let springs = model.springs;
    for kind in SpringKind::ALL {
        let p = model.spring_params[kind.index()];
        let (k, c) = (p.stiffness as f64, p.damping as f64);
        for s in springs.range(kind) {
            let (i, j) = (springs.a[s] as usize, springs.b[s] as usize);
            let (vi, vj) = ((v[i] + acc[i]).as_dvec3(), (v[j] + acc[j]).as_dvec3());
            let d = (x[j].as_dvec3() + vj * h) - (x[i].as_dvec3() + vi * h);
            let stretch = d.length() - springs.rest[s] as f64;
            phi += 0.5 * k * stretch * stretch;
            if c > 0.0 {
                let dir = (x[j] - x[i]).as_dvec3().normalize_or_zero();
                let rate = dir.dot(vj - vi);
                phi += 0.5 * h * c * rate * rate;
            }
        }
    }
    phi
}

/// One backward-Euler substep of `h` seconds by Newton's method with a line
/// search: `newton` linearisations, the first being Baraff and Witkin's
/// single linear solve, and up to [`CONTACT_ROUNDS`] more while the step
/// still runs into obstacles. Returns the CG iterations used.
pub(crate) fn step(
    sub: &Substep,
    x: &mut [Vector],
    v: &mut [Vector],
    st: &mut ImplicitState,
    collision: &mut CollisionStage,
) -> u32 {
    let (model, h) = (&sub.model, sub.ctx.h);
    let newton = sub.settings.newton_iterations;
    let (max_iterations, tolerance) = (sub.settings.cg_max_iterations, sub.settings.cg_tolerance);
    let preconditioner = sub.settings.preconditioner;
    let n = x.len();
    st.resize(n, model.springs.len());
    let mut xe = std::mem::take(&mut st.xe);
    let mut ve = std::mem::take(&mut st.ve);
    let mut acc = std::mem::take(&mut st.acc);
    let mut trial = std::mem::take(&mut st.trial);
    for buf in [&mut xe, &mut ve, &mut acc, &mut trial] {
        buf.clear();
        buf.resize(n, Vector::ZERO);
    }
    // External forces, held at the start of the step.
    for i in 0..n {
        st.external[i] = model.gravity * model.mass[i];
        st.friction[i] = Vector::ZERO;
    }
    add_wind_forces(
        model.triangles,
        &model.wind,
        (x, v),
        model.time,
        &mut st.external,
    );
    let mut iterations = 0;
    let mut phi = f64::INFINITY;
    let (mut round, mut extra) = (0u32, 0u32);
    loop {
        if round == 0 {
            // Baraff and Witkin's step: linearised at the start of the step.
            xe.copy_from_slice(x);
            ve.copy_from_slice(v);
        } else {
            for i in 0..n {
                ve[i] = v[i] + acc[i];
                xe[i] = x[i] + ve[i] * h;
            }
        }
        assemble(model, &xe, &ve, &acc, round == 0, h, st);
        if round == 0 {
            // The constraints, from the start state (`st.f` holds its forces).
            constrain(model, v, st, collision.contacts(), h);
        }
        for i in 0..n {
            st.b[i] += st.friction[i];
            st.dv[i] = if round == 0 { st.z[i] } else { Vector::ZERO };
        }
        iterations += solve(model, &xe, st, preconditioner, h, max_iterations, tolerance);
        if round == 0 {
            // The constraints' own part of the change is taken whole.
            acc.copy_from_slice(&st.z);
            for i in 0..n {
                st.dv[i] -= st.z[i];
            }
            phi = objective(model, x, v, &acc, st, h);
        }
        // Line search: the longest of 1, ½, ¼, ... that lowers the objective.
        let mut alpha = 1.0f32;
        let mut accepted = false;
        for _ in 0..8 {
            for i in 0..n {
                trial[i] = acc[i] + st.dv[i] * alpha;
            }
            let now = objective(model, x, v, &trial, st, h);
            if now.is_finite() && now <= phi {
                phi = now;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if accepted {
            std::mem::swap(&mut acc, &mut trial);
        }
        round += 1;
        // Contacts the step ran into are constraints from now on.
        let added = activate(sub, x, v, &mut acc, st, collision);
        if added {
            phi = objective(model, x, v, &acc, st, h);
        }
        if !accepted && !added {
            break;
        }
        if round >= newton.max(1) {
            if !added || extra >= CONTACT_ROUNDS {
                break;
            }
            extra += 1;
        }
    }
    // What the contact constraints did is momentum handed to the obstacles:
    // the force that holds a constrained particle, M acc − h f − J at the end.
    let held = |f: &Filter| matches!(f, Filter::Plane(_) | Filter::Stick(_));
    if st.filter.iter().any(held) {
        for i in 0..n {
            ve[i] = v[i] + acc[i];
            xe[i] = x[i] + ve[i] * h;
        }
        model.forces(&xe, &ve, &mut st.f);
    }
    for i in 0..n {
        if let Filter::Plane(nrm) | Filter::Stick(nrm) = st.filter[i] {
            let force = acc[i] * model.mass[i] - st.f[i] * h - st.friction[i];
            // Sliding, the surface pushes along its normal only; stuck,
            // friction holds the rest too.
            let reaction = match st.filter[i] {
                Filter::Stick(_) => force,
                _ => nrm * nrm.dot(force),
            };
            collision.add_impulse(st.obstacle[i] as usize, x[i], -reaction);
        }
    }
    for i in 0..n {
        // Pinned particles keep their velocity: a moving pin moves them.
        if model.inv_mass[i] != 0.0 {
            v[i] += acc[i];
        }
        x[i] += v[i] * h;
    }
    st.xe = xe;
    st.ve = ve;
    st.acc = acc;
    st.trial = trial;
    iterations
}

/// Finds the free particles whose end of step `x + h (v + acc)` lies inside
/// the thickness of a fixed or kinematic obstacle, puts them on its surface (changing `acc` along
/// the normal) and constrains them there, sliding without friction, for the
/// rest of the solve. Returns true when it found any.
fn activate(
    sub: &Substep,
    x: &[Vector],
    v: &[Vector],
    acc: &mut [Vector],
    st: &mut ImplicitState,
    collision: &mut CollisionStage,
) -> bool {
    let (model, h) = (&sub.model, sub.ctx.h);
    if sub.obstacles.is_empty() {
        return false;
    }
    let mut added = false;
    for i in 0..x.len() {
        if st.filter[i] != Filter::Free || model.inv_mass[i] == 0.0 {
            continue;
        }
        let end = x[i] + (v[i] + acc[i]) * h;
        if let Some((o, nrm, depth)) = collision.penetration(end, sub.obstacles, sub.ctx.thickness)
        {
            // A dynamic body answers through the contact pass after the step.
            if sub.obstacles[o].body.is_some() {
                continue;
            }
            acc[i] += nrm * (depth / h);
            st.filter[i] = Filter::Plane(nrm);
            st.obstacle[i] = o as u32;
            added = true;
        }
    }
    added
}

/// Sets the constraints of the step from the start state: pins fix the
/// velocity; a contact fixes its normal part (sliding, with the kinetic
/// friction impulse added to `b` and kept in `friction`) or all of it
/// (stuck). `z` is the velocity change each constraint prescribes, and the
/// starting guess of the first solve.
fn constrain(
    model: &ForceModel,
    v: &[Vector],
    st: &mut ImplicitState,
    contacts: &ContactSet,
    h: f32,
) {
    let n = v.len();
    for i in 0..n {
        st.obstacle[i] = contacts.last_obstacle(i);
        let (filter, z) = if model.inv_mass[i] == 0.0 {
            (Filter::Fixed, Vector::ZERO)
        } else {
            let nrm = contacts.normal(i);
            let rel = v[i] - contacts.surface_velocity(i);
            match contacts.response(i, v[i], st.f[i] / model.mass[i], h) {
                Response::Free => (Filter::Free, Vector::ZERO),
                Response::Stick { velocity } => (Filter::Stick(nrm), velocity - rel),
                Response::Slide {
                    normal_velocity,
                    friction,
                } => {
                    st.friction[i] = friction * model.mass[i];
                    (Filter::Plane(nrm), nrm * (normal_velocity - rel.dot(nrm)))
                }
            }
        };
        st.filter[i] = filter;
        st.z[i] = z;
    }
}

/// Solves the assembled system for `st.dv` by modified preconditioned
/// conjugate gradient, from the guess in `st.dv`, with the filters in
/// `st.filter`, preconditioned by block Jacobi or, when asked for and some
/// springs are stiff, the spring-space preconditioner set up for the
/// linearisation point `xe`. Returns the iterations used.
fn solve(
    model: &ForceModel,
    xe: &[Vector],
    st: &mut ImplicitState,
    preconditioner: Preconditioner,
    h: f32,
    max_iterations: u32,
    tolerance: f32,
) -> u32 {
    let n = st.dv.len();
    let spring_space_ready = preconditioner == Preconditioner::SpringSpace
        && st
            .spring_space
            .update(model, xe, &st.blocks, &st.mass, &st.filter, h);
    if !spring_space_ready {
        for i in 0..n {
            st.precond[i] = if matches!(st.filter[i], Filter::Fixed | Filter::Stick(_)) {
                Mat3::IDENTITY
            } else {
                st.diag[i].inverse()
            };
        }
    }
    // Modified preconditioned conjugate gradient (Baraff & Witkin, section 5.3).
    let ImplicitState {
        blocks,
        mass,
        precond,
        filter,
        b,
        dv,
        r,
        c,
        q,
        s,
        spring_space,
        ..
    } = st;
    // out = filter(P⁻¹ x).
    let mut precondition = |x: &[Vector], out: &mut [Vector]| {
        if spring_space_ready {
            // Its W already leaves the constrained directions out, up to
            // rounding; the filter makes that exact.
            spring_space.apply(model, x, out);
            for i in 0..n {
                out[i] = filter[i].apply(out[i]);
            }
        } else {
            for i in 0..n {
                out[i] = filter[i].apply(precond[i] * x[i]);
            }
        }
    };
    // r = filter(b − A Δv), c = filter(P⁻¹ r), δ₀ = filter(b)ᵀ P⁻¹ filter(b).
    multiply(model, blocks, mass, filter, dv, q);
    for i in 0..n {
        s[i] = filter[i].apply(b[i]);
        r[i] = s[i] - q[i];
    }
    precondition(s, q);
    let delta0 = dot(s, q);
    precondition(r, c);
    let mut delta_new = dot(r, c);
    let eps2 = (tolerance as f64) * (tolerance as f64);
    let mut iterations = 0;
    while delta_new > eps2 * delta0 && iterations < max_iterations {
        multiply(model, blocks, mass, filter, c, q);
        let cq = dot(c, q);
        if cq <= 0.0 || !cq.is_finite() {
            break;
        }
        let alpha = (delta_new / cq) as f32;
        for i in 0..n {
            dv[i] += c[i] * alpha;
            r[i] -= q[i] * alpha;
        }
        precondition(r, s);
        let delta_old = delta_new;
        delta_new = dot(r, s);
        let beta = (delta_new / delta_old) as f32;
        for i in 0..n {
            c[i] = filter[i].apply(s[i] + c[i] * beta);
        }
        iterations += 1;
    }
    iterations
}
