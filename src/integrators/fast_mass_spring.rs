//! The fast mass-spring solver of Liu, Bargteil, O'Brien and Kavan (2013),
//! "Fast simulation of mass-spring systems".
//!
//! Backward Euler written as the minimisation of
//! `½ (x − y)ᵀ M (x − y) + h² E(x) + ½ h (x − xₙ)ᵀ C (x − xₙ)` with
//! `y = xₙ + h vₙ + h² M⁻¹ f_ext`, solved by alternating a local step, which
//! projects every spring to its rest length (`d = L (x_j − x_i)/|x_j − x_i|`),
//! and a global step, which solves `(M + h C + h² Lₖ) x = M y + h C xₙ + h² J d`
//! for all particles at once. The matrix does not depend on the positions, so
//! its sparse Cholesky factor (nalgebra-sparse) is computed once and reused
//! until the pins, masses, step or stiffness change. Pinned particles are
//! eliminated from the system. Spring damping enters through `C`, the
//! damping-weighted graph Laplacian: it damps the relative velocity of the two
//! ends of a spring in every direction, not only along the spring.

use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::{CooMatrix, CscMatrix};

use crate::cloth::SpringKind;
use crate::collision::{Collider, Obstacle};
use crate::error::ClothError;
use crate::forces::{add_wind_forces, ForceModel};
use crate::math::Vector;

/// What the factor was computed for; any change means a new factor.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FactorKey {
    h: u32,
    params: [[u32; 2]; 3],
    particles: usize,
    springs: usize,
}

/// The factor of the global matrix, over the free particles.
#[derive(Debug)]
struct Factor {
    key: FactorKey,
    /// Free particle → row of the system (`u32::MAX` for pinned ones).
    row: Vec<u32>,
    /// Row of the system → particle.
    particle: Vec<u32>,
    /// The Cholesky factor `L` in compressed-column form (diagonal first in each column).
    col_offsets: Vec<usize>,
    row_indices: Vec<usize>,
    values: Vec<f64>,
}

/// Scratch memory and the cached factor of the fast mass-spring solver.
#[derive(Debug, Default)]
pub(crate) struct FastMassSpringState {
    factor: Option<Factor>,
    /// How many times a factor was computed since this state was made.
    pub factorizations: u64,
    y: Vec<Vector>,
    x_n: Vec<Vector>,
    f_ext: Vec<Vector>,
    rhs: Vec<[f64; 3]>,
    base: Vec<[f64; 3]>,
}

impl FastMassSpringState {
    /// Forgets the factor (pins, masses or topology changed).
    pub fn invalidate(&mut self) {
        self.factor = None;
    }
}

fn key(model: &ForceModel, h: f32, n: usize) -> FactorKey {
    FactorKey {
        h: h.to_bits(),
        params: model
            .spring_params
            .map(|p| [p.stiffness.to_bits(), p.damping.to_bits()]),
        particles: n,
        springs: model.springs.len(),
    }
}

/// Weight of spring `s` in the matrix: `h c + h² k`.
#[inline]
fn weight(model: &ForceModel, kind: SpringKind, h: f32) -> f64 {
    let p = model.spring_params[kind.index()];
    h as f64 * p.damping as f64 + (h as f64) * (h as f64) * p.stiffness as f64
}

fn build_factor(model: &ForceModel, h: f32, n: usize) -> Result<Factor, ClothError> {
    let mut row = vec![u32::MAX; n];
    let mut particle = Vec::with_capacity(n);
    for i in 0..n {
        if model.inv_mass[i] != 0.0 {
            row[i] = particle.len() as u32;
            particle.push(i as u32);
        }
    }
    let m = particle.len();
    let mut coo = CooMatrix::<f64>::new(m, m);
    for (r, &i) in particle.iter().enumerate() {
        coo.push(r, r, model.mass[i as usize] as f64);
    }
    let springs = model.springs;
    for kind in SpringKind::ALL {
        let w = weight(model, kind, h);
        for s in springs.range(kind) {
            let (ri, rj) = (row[springs.a[s] as usize], row[springs.b[s] as usize]);
            if ri != u32::MAX {
                coo.push(ri as usize, ri as usize, w);
            }
            if rj != u32::MAX {
                coo.push(rj as usize, rj as usize, w);
            }
            if ri != u32::MAX && rj != u32::MAX {
                coo.push(ri as usize, rj as usize, -w);
                coo.push(rj as usize, ri as usize, -w);
            }
        }
    }
    let csc = CscMatrix::from(&coo);
    let chol = CscCholesky::factor(&csc)
        .map_err(|e| ClothError::Solver(format!("Cholesky factorisation failed: {e:?}")))?;
    let (col_offsets, row_indices, values) = chol.take_l().disassemble();
    Ok(Factor {
        key: key(model, h, n),
        row,
        particle,
        col_offsets,
        row_indices,
        values,
    })
}

impl Factor {
    /// Solves `L Lᵀ x = b` in place for three right-hand sides at once.
    fn solve(&self, b: &mut [[f64; 3]]) {
        let (cols, rows, vals) = (&self.col_offsets, &self.row_indices, &self.values);
        let m = b.len();
        for j in 0..m {
            let (start, end) = (cols[j], cols[j + 1]);
            let d = vals[start];
            let yj = [b[j][0] / d, b[j][1] / d, b[j][2] / d];
            b[j] = yj;
            for k in start + 1..end {
                let (i, l) = (rows[k], vals[k]);
                b[i][0] -= l * yj[0];
                b[i][1] -= l * yj[1];
                b[i][2] -= l * yj[2];
            }
        }
        for j in (0..m).rev() {
            let (start, end) = (cols[j], cols[j + 1]);
            let mut acc = b[j];
            for k in start + 1..end {
                let (i, l) = (rows[k], vals[k]);
                acc[0] -= l * b[i][0];
                acc[1] -= l * b[i][1];
                acc[2] -= l * b[i][2];
            }
            let d = vals[start];
            b[j] = [acc[0] / d, acc[1] / d, acc[2] / d];
        }
    }
}

#[inline]
fn add(a: &mut [f64; 3], v: Vector, s: f64) {
    a[0] += v.x as f64 * s;
    a[1] += v.y as f64 * s;
    a[2] += v.z as f64 * s;
}

/// The obstacles, for projecting the iterates out of them.
pub(crate) struct Contacts<'a> {
    pub collider: &'a mut Collider,
    pub obstacles: &'a [Obstacle],
    pub thickness: f32,
}

/// One substep of `h` seconds with `iterations` local/global iterations.
/// After every global step the particles are projected out of the obstacles,
/// so the iterations converge to a state that rests on them.
pub(crate) fn step(
    model: &ForceModel,
    x: &mut [Vector],
    v: &mut [Vector],
    st: &mut FastMassSpringState,
    contacts: Contacts,
    h: f32,
    iterations: u32,
) -> Result<u32, ClothError> {
    let n = x.len();
    if st.factor.as_ref().is_none_or(|f| f.key != key(model, h, n)) {
        st.factor = Some(build_factor(model, h, n)?);
        st.factorizations += 1;
    }
    let FastMassSpringState {
        factor,
        y,
        x_n,
        f_ext,
        rhs,
        base,
        ..
    } = st;
    let Some(factor) = factor.as_ref() else {
        return Ok(0);
    };
    let m = factor.particle.len();
    for buf in [&mut *y, &mut *x_n, &mut *f_ext] {
        buf.resize(n, Vector::ZERO);
    }
    rhs.resize(m, [0.0; 3]);
    base.resize(m, [0.0; 3]);

    // External forces: gravity, drag and wind, taken explicitly.
    for i in 0..n {
        f_ext[i] = (model.gravity - v[i] * model.air_drag) * model.mass[i];
    }
    add_wind_forces(model.triangles, &model.wind, x, f_ext);
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
    for _ in 0..iterations {
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
        // Global step: one solve with the prefactored matrix.
        factor.solve(rhs);
        for (r, &i) in factor.particle.iter().enumerate() {
            x[i as usize] = Vector::new(rhs[r][0] as f32, rhs[r][1] as f32, rhs[r][2] as f32);
        }
        contacts.collider.project_positions(
            x,
            model.inv_mass,
            contacts.obstacles,
            contacts.thickness,
        );
    }
    let inv_h = 1.0 / h;
    for &i in &factor.particle {
        let i = i as usize;
        v[i] = (x[i] - x_n[i]) * inv_h;
    }
    Ok(iterations)
}
