//! The fast mass-spring solver of Liu, Bargteil, O'Brien and Kavan (2013),
//! "Fast simulation of mass-spring systems".
//!
//! Backward Euler written as the minimisation of
//! `½ (x − y)ᵀ M (x − y) + h² E(x) + ½ h (x − xₙ)ᵀ C (x − xₙ)` with
//! `y = xₙ + h vₙ + h² M⁻¹ f_ext`, solved by alternating a local step, which
//! projects every spring to its rest length (`d = L (x_j − x_i)/|x_j − x_i|`),
//! and a global step, which solves `(M + h C + h² Lₖ) x = M y + h C xₙ + h² J d`
//! for all particles at once. The matrix does not depend on the positions, so
//! its sparse Cholesky factor (nalgebra-sparse, in nested-dissection order:
//! see [`super::global_matrix`]) is computed once and reused until the pins,
//! masses, step or stiffness change. Pinned particles are eliminated from
//! the system. Contacts and Coulomb friction are decided at the start of each
//! substep and enter the solve (see [`step`]). Spring damping enters through `C`, the
//! damping-weighted graph Laplacian: it damps the relative velocity of the two
//! ends of a spring in every direction, not only along the spring.

use crate::cloth::SpringKind;
use crate::collision::{CollisionStage, Response};
use crate::error::ClothError;
use crate::forces::add_wind_forces;
use crate::math::Vector;

use super::global_matrix::{build_factor, key, weight, Factor, FactorHistory};
use super::substep::Substep;

/// Weight of a particle held by static friction in the global matrix, as a
/// multiple of its own diagonal entry (its mass plus its springs' weights):
/// the surface holds it this many times harder than its springs and inertia
/// move it.
const CONTACT_WEIGHT: f64 = 8.0;

/// Scratch memory and the cached factor of the fast mass-spring solver.
#[derive(Debug, Default)]
pub(crate) struct FastMassSpringState {
    factor: Option<Factor>,
    /// How many times a factor was computed from scratch (ordering, symbolic
    /// and numeric) since this state was made.
    pub factorizations: u64,
    /// How many times the numeric factor was recomputed for a new set of contacts.
    pub refactorizations: u64,
    y: Vec<Vector>,
    x_n: Vec<Vector>,
    f_ext: Vec<Vector>,
    rhs: Vec<[f64; 3]>,
    base: Vec<[f64; 3]>,
    /// Per row: the contact weight wanted this substep.
    contact: Vec<f64>,
    /// Per row: where static friction holds the particle at the end of the
    /// substep (when its contact weight is not zero).
    held: Vec<Vector>,
    /// Per row: the kinetic friction impulse of a sliding contact (N·s).
    slide_impulse: Vec<Vector>,
    /// Forces at the start of the substep (N).
    force: Vec<Vector>,
}

#[inline]
fn add(a: &mut [f64; 3], v: Vector, s: f64) {
    a[0] += v.x as f64 * s;
    a[1] += v.y as f64 * s;
    a[2] += v.z as f64 * s;
}

/// One substep of `h` seconds with `iterations` local/global iterations.
///
/// Contacts and friction enter the solve: every particle that touches a
/// fixed or kinematic obstacle, or will reach it within the substep, is
/// classified from the start state
/// ([`respond`](crate::collision::respond)). One held by static
/// friction gets a stiff spring (weight [`CONTACT_WEIGHT`] times its
/// diagonal) to where the surface carries it, so the cloth around it answers
/// in the same solve; the weights change the matrix's diagonal only, so a
/// new set of held particles costs a numeric refactorisation with the same
/// pattern. A sliding one gets the kinetic friction impulse. After every
/// global step the particles are projected out of the obstacles' surfaces.
/// `held_force` is the solver's hold memory (see `SolverState::held_force`).
pub(crate) fn step(
    sub: &Substep,
    x: &mut [Vector],
    v: &mut [Vector],
    st: &mut FastMassSpringState,
    (held_force, history): (&mut Vec<Vector>, &mut FactorHistory),
    collision: &mut CollisionStage,
) -> Result<u32, ClothError> {
    let (model, h, iterations) = (&sub.model, sub.ctx.h, sub.settings.fms_iterations);
    let n = x.len();
    let key = key(model, h, n, sub.mass_revision);
    if st.factor.as_ref().is_none_or(|f| f.key != key) {
        let mut factor = build_factor(model, h, n, key)?;
        // A snapshot's factor is taken up where it was left.
        factor.adopt(history)?;
        st.factor = Some(factor);
        st.factorizations += 1;
    }
    let FastMassSpringState {
        factor,
        y,
        x_n,
        f_ext,
        rhs,
        base,
        contact,
        held,
        slide_impulse,
        force,
        refactorizations,
        ..
    } = st;
    let Some(factor) = factor.as_mut() else {
        return Ok(0);
    };
    let m = factor.particle.len();
    for buf in [&mut *y, &mut *x_n, &mut *f_ext] {
        buf.resize(n, Vector::ZERO);
    }
    rhs.resize(m, [0.0; 3]);
    base.resize(m, [0.0; 3]);
    contact.resize(m, 0.0);
    held.resize(m, Vector::ZERO);
    slide_impulse.resize(m, Vector::ZERO);
    force.resize(n, Vector::ZERO);
    held_force.resize(n, Vector::ZERO);

    // How each contact found by `CollisionStage::detect_contacts` responds: a
    // particle held by static friction gets a stiff spring to where the
    // surface carries it; a sliding one gets the kinetic friction impulse and
    // is kept out by the projections.
    // The forces are needed only for the friction cone of a contact.
    if !sub.obstacles.is_empty() {
        model.forces(x, v, force);
    }
    for (r, &i) in factor.particle.iter().enumerate() {
        let i = i as usize;
        contact[r] = 0.0;
        held[r] = Vector::ZERO;
        slide_impulse[r] = Vector::ZERO;
        let contacts = collision.contacts();
        let mut response = contacts.response(i, v[i], force[i] * model.inv_mass[i], h);
        let (nrm, surface) = (contacts.normal(i), contacts.surface_velocity(i));
        let mu = contacts.friction(i);
        // Static friction holds on while the force that held the particle in
        // the last substep stays inside the friction cone: the start-state
        // estimate alone sees every spring's pull, not what the cloth around
        // answers, and would let a resting particle flicker between held and
        // sliding.
        if let Response::Slide {
            normal_velocity, ..
        } = response
        {
            let f = held_force[i];
            let push = f.dot(nrm);
            if push > 0.0 && (f - nrm * push).length() <= mu * push {
                response = Response::Stick {
                    velocity: nrm * normal_velocity,
                };
            }
        }
        match response {
            Response::Free => {}
            Response::Stick { velocity } => {
                held[r] = x[i] + (surface + velocity) * h;
                contact[r] = CONTACT_WEIGHT * factor.base_values[factor.diagonal[r]];
            }
            Response::Slide { friction, .. } => {
                slide_impulse[r] = friction * model.mass[i];
            }
        }
    }
    if factor.set_contacts(contact, history)? {
        *refactorizations += 1;
    }
    let factor = &*factor;

    // External forces: gravity, drag and wind, taken explicitly.
    for i in 0..n {
        f_ext[i] = (model.gravity - v[i] * model.air_drag) * model.mass[i];
    }
    add_wind_forces(model.triangles, &model.wind, (x, v), model.time, f_ext);
    let h2 = h as f64 * h as f64;
    for i in 0..n {
        x_n[i] = x[i];
        if model.inv_mass[i] == 0.0 {
            // A moving pin is where its velocity takes it by the end of the substep.
            x[i] += v[i] * h;
        }
        y[i] = x[i] + v[i] * h + f_ext[i] * (model.inv_mass[i] * h * h);
    }
    // The part of the right-hand side that does not change between iterations:
    // M y + h C xₙ, plus the pinned neighbours moved over from the matrix.
    for (r, &i) in factor.particle.iter().enumerate() {
        let i = i as usize;
        base[r] = [0.0; 3];
        add(&mut base[r], y[i], model.mass[i] as f64);
        // Kinetic friction: its impulse moves the particle h J / m.
        add(&mut base[r], slide_impulse[r], h as f64);
    }
    let springs = model.springs;
    for kind in SpringKind::ALL {
        let p = model.spring_params[kind.index()];
        let hc = h as f64 * p.damping as f64;
        let w = weight(model, kind, h);
        for s in springs.range(kind) {
            let (i, j) = (springs.a[s] as usize, springs.b[s] as usize);
            let (ri, rj) = (factor.row[i], factor.row[j]);
            let rel = x_n[i] - x_n[j];
            if ri != u32::MAX {
                add(&mut base[ri as usize], rel, hc);
                if rj == u32::MAX {
                    add(&mut base[ri as usize], x[j], w);
                }
            }
            if rj != u32::MAX {
                add(&mut base[rj as usize], rel, -hc);
                if ri == u32::MAX {
                    add(&mut base[rj as usize], x[i], w);
                }
            }
        }
    }
    // Start from the inertial guess.
    for &i in &factor.particle {
        x[i as usize] = y[i as usize];
    }
    for it in 0..iterations {
        rhs.copy_from_slice(base);
        // Local step: every spring to its rest length, h² k J d into the right-hand side.
        for kind in SpringKind::ALL {
            let k = model.spring_params[kind.index()].stiffness as f64 * h2;
            for s in springs.range(kind) {
                let (i, j) = (springs.a[s] as usize, springs.b[s] as usize);
                let d = x[j] - x[i];
                let len = d.length();
                if len <= f32::MIN_POSITIVE {
                    continue;
                }
                let d = d * (springs.rest[s] / len);
                let (ri, rj) = (factor.row[i], factor.row[j]);
                if ri != u32::MAX {
                    add(&mut rhs[ri as usize], d, -k);
                }
                if rj != u32::MAX {
                    add(&mut rhs[rj as usize], d, k);
                }
            }
        }
        // Contacts held by friction: a stiff spring to the held point.
        for (r, &w) in contact.iter().enumerate() {
            if w > 0.0 {
                add(&mut rhs[r], held[r], w);
            }
        }
        // Global step: one solve with the prefactored matrix.
        factor.solve(rhs);
        for (r, &i) in factor.particle.iter().enumerate() {
            x[i as usize] = Vector::new(rhs[r][0] as f32, rhs[r][1] as f32, rhs[r][2] as f32);
        }
        if it + 1 == iterations {
            // What held each particle, for static friction in the next substep.
            for (r, &i) in factor.particle.iter().enumerate() {
                let i = i as usize;
                held_force[i] = if contact[r] > 0.0 {
                    (held[r] - x[i]) * contact[r] as f32
                } else {
                    Vector::ZERO
                };
            }
        }
        collision.project_positions(x, model.inv_mass, sub.obstacles, sub.ctx.thickness, |_| {});
    }
    let inv_h = 1.0 / h;
    for &i in &factor.particle {
        let i = i as usize;
        v[i] = (x[i] - x_n[i]) * inv_h;
    }
    Ok(iterations)
}
