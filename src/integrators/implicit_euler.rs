//! Implicit backward Euler after Baraff and Witkin (1998), "Large steps in
//! cloth simulation".
//!
//! The spring and damping forces are linearised about the current state and
//! `(M − h ∂f/∂v − h² ∂f/∂x) Δv = h (f + h ∂f/∂x v)` is solved for the
//! velocity change with a block-Jacobi preconditioned conjugate gradient. The
//! system is kept in block-sparse form: one symmetric 3×3 block per spring
//! (`h D + h² K`) plus the lumped masses on the diagonal, never a dense matrix.
//! Pins and contacts are constraints of the solve, enforced by the paper's
//! filtering: a pinned particle's velocity change is zero in every direction,
//! a particle pressed against an obstacle gets the surface's normal velocity
//! and stays free to slide along it. Compressed springs drop the negative
//! transverse term of their Jacobian, which keeps the matrix positive definite.

use glam::Mat3;

use crate::cloth::SpringKind;
use crate::collision::Collider;
use crate::forces::ForceModel;
use crate::math::Vector;

/// What constrains a particle during the solve.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Filter {
    /// Free in every direction.
    Free,
    /// Pinned: no velocity change.
    Fixed,
    /// Against a surface with this unit normal: free only in its tangent plane.
    Plane(Vector),
}

impl Filter {
    #[inline(always)]
    fn apply(self, v: Vector) -> Vector {
        match self {
            Filter::Free => v,
            Filter::Fixed => Vector::ZERO,
            Filter::Plane(n) => v - n * n.dot(v),
        }
    }
}

/// Scratch memory of the implicit solver.
#[derive(Debug, Default)]
pub(crate) struct ImplicitState {
    blocks: Vec<Mat3>,
    mass: Vec<f32>,
    diag: Vec<Mat3>,
    precond: Vec<Mat3>,
    filter: Vec<Filter>,
    /// All `Free`: for products that must not be filtered.
    unfiltered: Vec<Filter>,
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
}

impl ImplicitState {
    fn resize(&mut self, n: usize, springs: usize) {
        self.blocks.resize(springs, Mat3::ZERO);
        self.mass.resize(n, 0.0);
        for buf in [&mut self.diag, &mut self.precond] {
            buf.resize(n, Mat3::ZERO);
        }
        self.filter.resize(n, Filter::Free);
        self.unfiltered.resize(n, Filter::Free);
        for buf in [
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

/// One backward-Euler substep of `h` seconds, with `newton` linearisations
/// (1 is the paper's single linear solve). Returns the CG iterations used.
#[allow(clippy::too_many_arguments)]
pub(crate) fn step(
    model: &ForceModel,
    x: &mut [Vector],
    v: &mut [Vector],
    st: &mut ImplicitState,
    contacts: &mut Collider,
    h: f32,
    newton: u32,
    max_iterations: u32,
    tolerance: f32,
) -> u32 {
    let n = x.len();
    st.resize(n, model.springs.len());
    let mut xe = std::mem::take(&mut st.xe);
    let mut ve = std::mem::take(&mut st.ve);
    let mut acc = std::mem::take(&mut st.acc);
    xe.resize(n, Vector::ZERO);
    ve.resize(n, Vector::ZERO);
    acc.clear();
    acc.resize(n, Vector::ZERO);
    let mut iterations = 0;
    for round in 0..newton.max(1) {
        if round == 0 {
            xe.copy_from_slice(x);
            ve.copy_from_slice(v);
        } else {
            for i in 0..n {
                ve[i] = v[i] + acc[i];
                xe[i] = x[i] + ve[i] * h;
            }
        }
        assemble(model, &xe, &ve, &acc, round == 0, h, st);
        iterations += solve(model, v, &acc, st, contacts, max_iterations, tolerance);
        // What the contact constraints did is momentum handed to the obstacles:
        // the unfiltered residual A Δv − b of a constrained particle.
        multiply(
            model,
            &st.blocks,
            &st.mass,
            &st.unfiltered,
            &st.dv,
            &mut st.q,
        );
        for i in 0..n {
            if let Filter::Plane(nrm) = st.filter[i] {
                let push = nrm.dot(st.q[i] - st.b[i]);
                let reaction = nrm * push;
                contacts.add_impulse(contacts.contact_obstacle[i] as usize, x[i], -reaction);
                // The surface's push bounds the friction applied after the solve.
                contacts.add_normal_push(i, push.max(0.0) / model.mass[i] * h);
            }
            acc[i] += st.dv[i];
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
    iterations
}

/// Sets up the constraints and solves the assembled system for `st.dv` by
/// modified preconditioned conjugate gradient. Returns the iterations used.
fn solve(
    model: &ForceModel,
    v: &[Vector],
    acc: &[Vector],
    st: &mut ImplicitState,
    contacts: &Collider,
    max_iterations: u32,
    tolerance: f32,
) -> u32 {
    let n = v.len();
    // Constraints: pins fix the velocity, contacts fix its normal part.
    for i in 0..n {
        let (filter, z) = if model.inv_mass[i] == 0.0 {
            (Filter::Fixed, Vector::ZERO)
        } else if contacts.touching.get(i).copied().unwrap_or(false)
            && contacts.contact_immovable[i]
        {
            // Only immovable obstacles are constraints of the solve: a dynamic
            // body would be treated as infinitely heavy and thrown back.
            let nrm = contacts.contact_normal[i];
            let rel = v[i] + acc[i] - contacts.surface_velocity[i];
            // Held against the surface only while pushed into it.
            if rel.dot(nrm) <= 0.0 || st.f[i].dot(nrm) < 0.0 {
                (Filter::Plane(nrm), -nrm * rel.dot(nrm))
            } else {
                (Filter::Free, Vector::ZERO)
            }
        } else {
            (Filter::Free, Vector::ZERO)
        };
        st.filter[i] = filter;
        st.dv[i] = z;
        st.precond[i] = if filter == Filter::Fixed {
            Mat3::IDENTITY
        } else {
            st.diag[i].inverse()
        };
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
        ..
    } = st;
    // r = filter(b − A Δv), c = filter(P⁻¹ r), δ₀ = filter(b)ᵀ P⁻¹ filter(b).
    multiply(model, blocks, mass, filter, dv, q);
    let mut delta0 = 0.0f64;
    for i in 0..n {
        let fb = filter[i].apply(b[i]);
        delta0 += fb.as_dvec3().dot((precond[i] * fb).as_dvec3());
        r[i] = fb - q[i];
        c[i] = filter[i].apply(precond[i] * r[i]);
    }
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
            s[i] = precond[i] * r[i];
        }
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
