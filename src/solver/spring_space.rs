//! A preconditioner for the implicit solve that takes stiff springs exactly.
//!
//! Block-Jacobi conjugate gradient needs more iterations the stiffer the
//! springs (about `√(h² k / m)`, until the grid's size bounds it), and stops
//! short at its cap for stretch springs of 1e5–1e6 N/m on a light cloth at a
//! 1/60 s step. Along its direction `d`, a spring adds the rank-one block
//! `w d dᵀ` (`w = h c + h² k`) to the system matrix `A`. This preconditioner
//! keeps those parts of the stiff kinds exactly and the rest of `A` by its
//! block diagonal `D`:
//!
//! `P = D + Jᵀ Ω J`,  `P⁻¹ = W − W Jᵀ G⁻¹ J W`,  `G = Ω⁻¹ + J W Jᵀ`
//!
//! (Woodbury), with `J` the springs' rows `dᵀ (x_b − x_a)`, `Ω` their weights
//! and `W` the inverse of `D` on each particle's free directions (zero for a
//! pinned or held particle, the tangent plane's for a sliding one), so `P`
//! respects the solve's filters. `G` has one row per stiff spring, couples
//! the springs that share a particle, and its conditioning does not grow
//! with the stiffness. Its pattern is ordered by nested dissection once per
//! cloth; its values are factored by sparse Cholesky at every linearisation.

use glam::{DMat3, DVec3, Mat3};
use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::CscMatrix;

use crate::cloth::SpringKind;
use crate::forces::ForceModel;
use crate::math::Vector;

use super::filter::Filter;
use super::ordering::nested_dissection;

/// A spring kind is taken exactly when `4 w` exceeds this many times the
/// smallest particle mass: block Jacobi would then need tens of iterations.
const STIFF_RATIO: f64 = 1000.0;

/// The spring-space factor and its scratch.
#[derive(Debug, Default)]
pub(crate) struct SpringSpace {
    /// Which kinds the pattern was built for, and the spring count.
    key: Option<([bool; 3], usize, usize)>,
    /// Row of `G` → spring.
    spring: Vec<u32>,
    /// The pattern of `G` (both triangles), column by column.
    offsets: Vec<usize>,
    rows: Vec<usize>,
    values: Vec<f64>,
    chol: Option<CscCholesky<f64>>,
    /// Per row: unit direction and weight of its spring.
    dir: Vec<DVec3>,
    weight: Vec<f64>,
    /// Per particle: `W`, the inverse of `D` on its free directions.
    inv: Vec<DMat3>,
    /// Scratch: `W r` per particle, and a vector over the rows.
    u: Vec<DVec3>,
    y: Vec<f64>,
}

/// The kinds stiff enough, at step `h`, to be worth taking exactly.
pub(crate) fn stiff_kinds(model: &ForceModel, h: f32) -> [bool; 3] {
    let m = model
        .mass
        .iter()
        .zip(model.inv_mass)
        .filter(|(_, &w)| w != 0.0)
        .map(|(&m, _)| m as f64)
        .fold(f64::INFINITY, f64::min);
    SpringKind::ALL.map(|kind| {
        let w = super::global_matrix::weight(model, kind, h);
        !model.springs.range(kind).is_empty() && w > 0.0 && 4.0 * w > STIFF_RATIO * m
    })
}

impl SpringSpace {
    /// Builds the pattern of `G` for the springs of `kinds` (when not built yet).
    fn pattern(&mut self, model: &ForceModel, kinds: [bool; 3], n: usize) {
        let springs = model.springs;
        let key = (kinds, springs.len(), n);
        if self.key == Some(key) {
            return;
        }
        self.key = Some(key);
        self.chol = None;
        let stiff: Vec<u32> = SpringKind::ALL
            .into_iter()
            .filter(|k| kinds[k.index()])
            .flat_map(|k| springs.range(k))
            .map(|s| s as u32)
            .collect();
        // Springs at each particle.
        let mut start = vec![0usize; n + 1];
        for &s in &stiff {
            start[springs.a[s as usize] as usize + 1] += 1;
            start[springs.b[s as usize] as usize + 1] += 1;
        }
        for p in 1..=n {
            start[p] += start[p - 1];
        }
        let mut fill = start.clone();
        let mut at = vec![0u32; start[n]];
        for (k, &s) in stiff.iter().enumerate() {
            for p in [springs.a[s as usize], springs.b[s as usize]] {
                at[fill[p as usize]] = k as u32;
                fill[p as usize] += 1;
            }
        }
        // The springs' graph: two are joined when they share a particle.
        let ends = |k: usize| {
            let s = stiff[k] as usize;
            [springs.a[s] as usize, springs.b[s] as usize]
        };
        let mut offsets = vec![0usize; stiff.len() + 1];
        let mut neighbours = Vec::new();
        for k in 0..stiff.len() {
            for p in ends(k) {
                neighbours.extend(
                    at[start[p]..start[p + 1]]
                        .iter()
                        .filter(|&&t| t as usize != k),
                );
            }
            offsets[k + 1] = neighbours.len();
        }
        let order = nested_dissection(&offsets, &neighbours);
        let mut row = vec![0usize; stiff.len()];
        for (r, &k) in order.iter().enumerate() {
            row[k as usize] = r;
        }
        self.spring = order.iter().map(|&k| stiff[k as usize]).collect();
        self.offsets.clear();
        self.offsets.push(0);
        self.rows.clear();
        for &k in &order {
            let first = self.rows.len();
            self.rows.push(row[k as usize]);
            let k = k as usize;
            self.rows.extend(
                neighbours[offsets[k]..offsets[k + 1]]
                    .iter()
                    .map(|&t| row[t as usize]),
            );
            self.rows[first..].sort_unstable();
            let mut kept = first;
            for i in first..self.rows.len() {
                if i == first || self.rows[i] != self.rows[kept - 1] {
                    self.rows[kept] = self.rows[i];
                    kept += 1;
                }
            }
            self.rows.truncate(kept);
            self.offsets.push(self.rows.len());
        }
        self.values.clear();
        self.values.resize(self.rows.len(), 0.0);
        self.dir.resize(self.spring.len(), DVec3::ZERO);
        self.weight.resize(self.spring.len(), 0.0);
        self.y.resize(self.spring.len(), 0.0);
    }

    /// Sets `P` up for the system linearised at `xe` with step `h`: `blocks`
    /// are the springs' blocks of `A`, `mass` its diagonal masses, `filter`
    /// what constrains each particle in the solve. Returns false when no kind is
    /// stiff or the factorisation failed: block Jacobi then does the work.
    pub(crate) fn update(
        &mut self,
        model: &ForceModel,
        xe: &[Vector],
        blocks: &[Mat3],
        mass: &[f32],
        filter: &[Filter],
        h: f32,
    ) -> bool {
        let kinds = stiff_kinds(model, h);
        if !kinds.iter().any(|&k| k) {
            return false;
        }
        let n = xe.len();
        self.pattern(model, kinds, n);
        let springs = model.springs;
        // D: masses, the soft springs' blocks and the stiff ones' transverse parts.
        self.inv.clear();
        self.inv.extend(
            mass.iter()
                .map(|&m| DMat3::from_diagonal(DVec3::splat(m as f64))),
        );
        let hd = h as f64;
        for kind in SpringKind::ALL {
            let p = model.spring_params[kind.index()];
            for s in springs.range(kind) {
                let (i, j) = (springs.a[s] as usize, springs.b[s] as usize);
                let block = if kinds[kind.index()] {
                    let d = (xe[j] - xe[i]).as_dvec3();
                    let len = d.length();
                    if len <= f64::MIN_POSITIVE {
                        continue;
                    }
                    let t = (1.0 - springs.rest[s] as f64 / len).max(0.0);
                    let dir = d / len;
                    let ddt = DMat3::from_cols(dir * dir.x, dir * dir.y, dir * dir.z);
                    (DMat3::IDENTITY - ddt) * (t * hd * hd * p.stiffness as f64)
                } else {
                    blocks[s].as_dmat3()
                };
                self.inv[i] += block;
                self.inv[j] += block;
            }
        }
        for (w, f) in self.inv.iter_mut().zip(filter) {
            *w = match *f {
                Filter::Fixed | Filter::Stick(_) => DMat3::ZERO,
                Filter::Free => w.inverse(),
                Filter::Plane(nrm) => {
                    let inv = w.inverse();
                    let a = inv * nrm.as_dvec3();
                    let q = nrm.as_dvec3().dot(a);
                    inv - DMat3::from_cols(a * a.x, a * a.y, a * a.z) * (1.0 / q)
                }
            };
        }
        for (r, &s) in self.spring.iter().enumerate() {
            let s = s as usize;
            let kind = springs.kind(s);
            let (i, j) = (springs.a[s] as usize, springs.b[s] as usize);
            self.dir[r] = (xe[j] - xe[i]).as_dvec3().normalize_or_zero();
            self.weight[r] = super::global_matrix::weight(model, kind, h);
        }
        // G = Ω⁻¹ + J W Jᵀ.
        for c in 0..self.spring.len() {
            let t = self.spring[c] as usize;
            let (ta, tb) = (springs.a[t], springs.b[t]);
            for k in self.offsets[c]..self.offsets[c + 1] {
                let r = self.rows[k];
                let s = self.spring[r] as usize;
                let (sa, sb) = (springs.a[s], springs.b[s]);
                let (ds, dt) = (self.dir[r], self.dir[c]);
                let mut g = if r == c { 1.0 / self.weight[r] } else { 0.0 };
                // Each shared particle, with the signs of the two rows there.
                for (p, sign_s) in [(sa, -1.0), (sb, 1.0)] {
                    for (q, sign_t) in [(ta, -1.0), (tb, 1.0)] {
                        if p == q {
                            g += sign_s * sign_t * ds.dot(self.inv[p as usize] * dt);
                        }
                    }
                }
                self.values[k] = g;
            }
        }
        let ok = match &mut self.chol {
            Some(chol) => chol.refactor(&self.values).is_ok(),
            None => {
                let m = self.spring.len();
                CscMatrix::try_from_csc_data(
                    m,
                    m,
                    self.offsets.clone(),
                    self.rows.clone(),
                    self.values.clone(),
                )
                .ok()
                .and_then(|g| CscCholesky::factor(&g).ok())
                .map(|chol| self.chol = Some(chol))
                .is_some()
            }
        };
        if !ok {
            // The next step starts from a fresh symbolic factorisation.
            self.chol = None;
        }
        ok
    }

    /// `out = P⁻¹ r` for the springs of `model` (after a successful `update`).
    pub(crate) fn apply(&mut self, model: &ForceModel, r: &[Vector], out: &mut [Vector]) {
        let Some(chol) = &self.chol else {
            return;
        };
        let springs = model.springs;
        self.u.clear();
        self.u
            .extend(r.iter().zip(&self.inv).map(|(r, w)| *w * r.as_dvec3()));
        for (row, &s) in self.spring.iter().enumerate() {
            let (i, j) = (
                springs.a[s as usize] as usize,
                springs.b[s as usize] as usize,
            );
            self.y[row] = self.dir[row].dot(self.u[j] - self.u[i]);
        }
        // G z = y by the factor's two triangular solves.
        let l = chol.l();
        let (cols, rows, vals) = (l.col_offsets(), l.row_indices(), l.values());
        let m = self.y.len();
        for j in 0..m {
            let yj = self.y[j] / vals[cols[j]];
            self.y[j] = yj;
            for k in cols[j] + 1..cols[j + 1] {
                self.y[rows[k]] -= vals[k] * yj;
            }
        }
        for j in (0..m).rev() {
            let mut acc = self.y[j];
            for k in cols[j] + 1..cols[j + 1] {
                acc -= vals[k] * self.y[rows[k]];
            }
            self.y[j] = acc / vals[cols[j]];
        }
        // out = W (r − Jᵀ z).
        let mut jz = std::mem::take(&mut self.u);
        jz.iter_mut().for_each(|v| *v = DVec3::ZERO);
        for (row, &s) in self.spring.iter().enumerate() {
            let (i, j) = (
                springs.a[s as usize] as usize,
                springs.b[s as usize] as usize,
            );
            let f = self.dir[row] * self.y[row];
            jz[i] -= f;
            jz[j] += f;
        }
        for p in 0..out.len() {
            out[p] = (self.inv[p] * (r[p].as_dvec3() - jz[p])).as_vec3();
        }
        self.u = jz;
    }
}
