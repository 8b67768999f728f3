//! The global matrix of a mass-spring cloth, `M + h C + h² K` with every
//! spring taken isotropically (weight `h c + h² k` on the graph Laplacian),
//! factored once by sparse Cholesky (nalgebra-sparse) in nested-dissection
//! order; the fast mass-spring solver's global step solves with it. Extra
//! weights on the diagonal (particles held by contacts) cost a numeric
//! refactorisation with the same pattern.

use nalgebra_sparse::factorization::CscCholesky;
use nalgebra_sparse::{CooMatrix, CscMatrix};
use serde::{Deserialize, Serialize};

use crate::cloth::SpringKind;
use crate::error::ClothError;
use crate::forces::ForceModel;

use super::ordering::nested_dissection;

/// What the factor was computed for; any change means a new factor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct FactorKey {
    h: u32,
    params: [[u32; 2]; 3],
    particles: usize,
    springs: usize,
    /// The cloth's masses and pins (`Cloth::mass_revision`).
    masses: u64,
}

/// The factor of the global matrix, over the free particles.
#[derive(Debug)]
pub(crate) struct Factor {
    pub key: FactorKey,
    /// Free particle → row of the system (`u32::MAX` for pinned ones).
    pub row: Vec<u32>,
    /// Row of the system → particle, in nested-dissection order.
    pub particle: Vec<u32>,
    /// The sparse Cholesky factor `L` (diagonal first in each column).
    chol: CscCholesky<f64>,
    /// The matrix's values without contacts, in the factor's input order.
    pub base_values: Vec<f64>,
    /// Per row: where its diagonal entry is in `base_values`.
    pub diagonal: Vec<usize>,
    /// Per row: the contact weight on the diagonal of the current factor.
    contact: Vec<f64>,
    /// The values of `L` in use: `chol`'s after a full factorisation, then
    /// changed in place by rank-one updates.
    l_values: Vec<f64>,
    /// Elimination tree: per column of `L`, its first off-diagonal row
    /// (`usize::MAX` at a root).
    parent: Vec<usize>,
    /// Rank-one updates since the last full factorisation.
    updates: usize,
    /// A hash (FNV-1a) of the masses and free rows the factor was built with.
    mass_hash: u64,
    /// Dense scratch of the updates.
    work: Vec<f64>,
    /// Scratch: the matrix's values with the contact weights, for a refactorisation.
    values: Vec<f64>,
}

/// How the factor in use came to be, so that a solver resumed from a
/// snapshot rebuilds it bit for bit: rank-one updates round differently
/// from a fresh factorisation, so the resumed solver must take the same
/// path. The contact weights (as `f64` bits, exact through any format) of
/// the last full factorisation, and every rank-one update since, in order.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub(crate) struct FactorHistory {
    /// The factor this history is of (none: no factor yet): its key with the
    /// cloth's mass revision (which a snapshot does not keep) replaced by a
    /// hash of the masses and pins themselves.
    key: Option<FactorKey>,
    /// Rows with a contact weight at the last full factorisation, and the
    /// weights' bits (empty: the factor as first built, without contacts).
    fresh: Vec<(u32, u64)>,
    /// Each rank-one update since: the row and its new weight's bits.
    updates: Vec<(u32, u64)>,
}

impl FactorHistory {
    /// True when there is nothing to keep: no factor yet.
    pub fn is_empty(&self) -> bool {
        self.key.is_none()
    }

    /// Starts the history of a factor just built for `key`, of `m` rows,
    /// with room for all it can hold (a warmed-up step allocates nothing):
    /// `set_contacts` refactors before the updates pass `4 m`.
    fn start(&mut self, key: FactorKey, m: usize) {
        self.key = Some(key);
        self.fresh.clear();
        self.updates.clear();
        self.reserve(m);
    }

    /// Room for all a factor of `m` rows can record (see [`Self::start`]).
    fn reserve(&mut self, m: usize) {
        self.fresh.reserve(m.saturating_sub(self.fresh.len()));
        self.updates
            .reserve((5 * m).saturating_sub(self.updates.len()));
    }

    /// Records a full factorisation with the weights `contact`.
    fn refactored(&mut self, contact: &[f64]) {
        self.fresh.clear();
        self.updates.clear();
        for (r, &w) in contact.iter().enumerate() {
            if w != 0.0 {
                self.fresh.push((r as u32, w.to_bits()));
            }
        }
    }
}

/// What a factor for this model and step depends on.
pub(crate) fn key(model: &ForceModel, h: f32, n: usize, masses: u64) -> FactorKey {
    FactorKey {
        h: h.to_bits(),
        params: model
            .spring_params
            .map(|p| [p.stiffness.to_bits(), p.damping.to_bits()]),
        particles: n,
        springs: model.springs.len(),
        masses,
    }
}

/// Weight of spring `s` in the matrix: `h c + h² k`.
#[inline]
pub(crate) fn weight(model: &ForceModel, kind: SpringKind, h: f32) -> f64 {
    let p = model.spring_params[kind.index()];
    h as f64 * p.damping as f64 + (h as f64) * (h as f64) * p.stiffness as f64
}

/// The free particles in nested-dissection order of the spring graph.
fn free_order(model: &ForceModel, n: usize) -> Vec<u32> {
    let free: Vec<u32> = (0..n as u32)
        .filter(|&i| model.inv_mass[i as usize] != 0.0)
        .collect();
    let mut index = vec![u32::MAX; n];
    for (k, &i) in free.iter().enumerate() {
        index[i as usize] = k as u32;
    }
    let springs = model.springs;
    let mut degree = vec![0usize; free.len() + 1];
    let pairs = || {
        (0..springs.len()).filter_map(|s| {
            let (a, b) = (index[springs.a[s] as usize], index[springs.b[s] as usize]);
            (a != u32::MAX && b != u32::MAX).then_some((a, b))
        })
    };
    for (a, b) in pairs() {
        degree[a as usize + 1] += 1;
        degree[b as usize + 1] += 1;
    }
    for k in 1..degree.len() {
        degree[k] += degree[k - 1];
    }
    let offsets = degree.clone();
    let mut fill = degree;
    let mut neighbours = vec![0u32; offsets[free.len()]];
    for (a, b) in pairs() {
        neighbours[fill[a as usize]] = b;
        fill[a as usize] += 1;
        neighbours[fill[b as usize]] = a;
        fill[b as usize] += 1;
    }
    nested_dissection(&offsets, &neighbours)
        .into_iter()
        .map(|k| free[k as usize])
        .collect()
}

/// Orders, assembles and factors the global matrix for substeps of `h` seconds.
pub(crate) fn build_factor(
    model: &ForceModel,
    h: f32,
    n: usize,
    key: FactorKey,
) -> Result<Factor, ClothError> {
    let particle = free_order(model, n);
    let mut row = vec![u32::MAX; n];
    for (r, &i) in particle.iter().enumerate() {
        row[i as usize] = r as u32;
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
    let mut diagonal = vec![0usize; m];
    for (j, d) in diagonal.iter_mut().enumerate() {
        let start = csc.col_offsets()[j];
        let rows = &csc.row_indices()[start..csc.col_offsets()[j + 1]];
        *d = start + rows.iter().position(|&r| r == j).unwrap_or(0);
    }
    let mass_hash = mass_hash(model.mass, &row);
    let chol = CscCholesky::factor(&csc)
        .map_err(|e| ClothError::Solver(format!("Cholesky factorisation failed: {e:?}")))?;
    Ok(Factor {
        key,
        row,
        particle,
        l_values: chol.l().values().to_vec(),
        parent: elimination_tree(chol.l()),
        chol,
        base_values: csc.values().to_vec(),
        diagonal,
        contact: vec![0.0; m],
        updates: 0,
        mass_hash,
        work: vec![0.0; m],
        values: Vec::new(),
    })
}

/// FNV-1a over the masses' bits and the rows of the free particles.
fn mass_hash(mass: &[f32], row: &[u32]) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for word in mass.iter().map(|m| m.to_bits()).chain(row.iter().copied()) {
        for byte in word.to_le_bytes() {
            hash = (hash ^ byte as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    hash
}

impl Factor {
    /// Solves `L Lᵀ x = b` in place for three right-hand sides at once.
    pub fn solve(&self, b: &mut [[f64; 3]]) {
        let l = self.chol.l();
        let (cols, rows, vals) = (l.col_offsets(), l.row_indices(), &self.l_values);
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

    /// Puts the contact weights `contact` on the diagonal and brings the
    /// factor up to date if they differ from the current ones: a few changed
    /// rows by sparse rank-one updates along the elimination tree (Davis and
    /// Hager), many by a numeric refactorisation with the same pattern.
    /// Returns whether the factor changed.
    pub fn set_contacts(
        &mut self,
        contact: &[f64],
        history: &mut FactorHistory,
    ) -> Result<bool, ClothError> {
        if self.contact == contact {
            return Ok(false);
        }
        let m = contact.len();
        let changed = contact
            .iter()
            .zip(&self.contact)
            .filter(|(a, b)| a != b)
            .count();
        // An update costs a path of the tree (measured on a 64 × 64 drape,
        // about a refactorisation's worth at m/16 rows) and rounding adds
        // up: past that share, or after many, start afresh.
        let fresh = changed * 16 > m || self.updates + changed > 4 * m;
        if !fresh {
            for r in 0..m {
                let delta = contact[r] - self.contact[r];
                if delta != 0.0 {
                    if !self.rank_one(r, delta) {
                        history.refactored(contact);
                        return self.refactor(contact);
                    }
                    history.updates.push((r as u32, contact[r].to_bits()));
                }
                self.contact[r] = contact[r];
            }
            self.updates += changed;
            return Ok(true);
        }
        history.refactored(contact);
        self.refactor(contact)
    }

    /// The factor's key as a snapshot can restore it: the mass revision
    /// replaced by the hash of the masses and pins it was built with.
    fn lasting_key(&self) -> FactorKey {
        FactorKey {
            masses: self.mass_hash,
            ..self.key
        }
    }

    /// Brings a factor just built for `key` to where `history` left the
    /// solver's (a snapshot's), by the same full factorisation and rank-one
    /// updates in the same order; a history of another factor is started
    /// afresh instead.
    pub fn adopt(&mut self, history: &mut FactorHistory) -> Result<(), ClothError> {
        let key = self.lasting_key();
        let m = self.contact.len();
        let in_range = |&(r, _): &(u32, u64)| (r as usize) < m;
        if history.key != Some(key)
            || !(history.fresh.iter().all(in_range) && history.updates.iter().all(in_range))
        {
            history.start(key, m);
            return Ok(());
        }
        history.reserve(m);
        if !history.fresh.is_empty() {
            let mut contact = vec![0.0; m];
            for &(r, w) in &history.fresh {
                contact[r as usize] = f64::from_bits(w);
            }
            self.refactor(&contact)?;
        }
        for &(r, w) in &history.updates {
            let (r, w) = (r as usize, f64::from_bits(w));
            let delta = w - self.contact[r];
            if delta != 0.0 && !self.rank_one(r, delta) {
                // Cannot happen on the same path; start afresh if it does.
                let mut contact = self.contact.clone();
                contact[r] = w;
                history.refactored(&contact);
                return self.refactor(&contact).map(|_| ());
            }
            self.contact[r] = w;
            self.updates += 1;
        }
        Ok(())
    }

    /// Factors the matrix with the weights `contact` afresh (same pattern).
    fn refactor(&mut self, contact: &[f64]) -> Result<bool, ClothError> {
        let values = &mut self.values;
        values.clear();
        values.extend_from_slice(&self.base_values);
        for (r, &w) in contact.iter().enumerate() {
            values[self.diagonal[r]] += w;
        }
        self.chol
            .refactor(values)
            .map_err(|e| ClothError::Solver(format!("Cholesky factorisation failed: {e:?}")))?;
        self.l_values.copy_from_slice(self.chol.l().values());
        self.contact.copy_from_slice(contact);
        self.updates = 0;
        Ok(true)
    }

    /// `L Lᵀ += delta · e_r e_rᵀ` in place (an update for `delta > 0`, a
    /// downdate for `delta < 0`); false if the result would not be positive
    /// definite (then nothing useful is left in `L` and it must be refactored).
    fn rank_one(&mut self, r: usize, delta: f64) -> bool {
        let l = self.chol.l();
        let (cols, rows) = (l.col_offsets(), l.row_indices());
        let vals = &mut self.l_values;
        let w = &mut self.work;
        let sigma = delta.signum();
        // The update's pattern is the path from r to the root.
        let mut j = r;
        while j != usize::MAX {
            w[j] = 0.0;
            j = self.parent[j];
        }
        w[r] = delta.abs().sqrt();
        let mut beta = 1.0f64;
        let mut j = r;
        while j != usize::MAX {
            let p = cols[j];
            let alpha = w[j] / vals[p];
            let beta2 = beta * beta + sigma * alpha * alpha;
            if beta2.is_nan() || beta2 <= 0.0 {
                return false;
            }
            let beta2 = beta2.sqrt();
            let (d, gamma) = if sigma > 0.0 {
                (beta / beta2, alpha / (beta2 * beta))
            } else {
                (beta2 / beta, -alpha / (beta2 * beta))
            };
            vals[p] = d * vals[p] + if sigma > 0.0 { gamma * w[j] } else { 0.0 };
            beta = beta2;
            for q in p + 1..cols[j + 1] {
                let i = rows[q];
                let w1 = w[i];
                let w2 = w1 - alpha * vals[q];
                w[i] = w2;
                vals[q] = d * vals[q] + gamma * if sigma > 0.0 { w1 } else { w2 };
            }
            j = self.parent[j];
        }
        true
    }
}

/// The elimination tree of a Cholesky factor: each column's first
/// off-diagonal row.
fn elimination_tree(l: &CscMatrix<f64>) -> Vec<usize> {
    (0..l.ncols())
        .map(|j| {
            let (start, end) = (l.col_offsets()[j], l.col_offsets()[j + 1]);
            if end > start + 1 {
                l.row_indices()[start + 1]
            } else {
                usize::MAX
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;
    use crate::forces::Masses;

    /// Solves with the factor for a right-hand side of ones.
    fn solution(f: &Factor) -> Vec<[f64; 3]> {
        let mut b: Vec<[f64; 3]> = (0..f.particle.len())
            .map(|r| [1.0, r as f64 * 1e-3, -1.0])
            .collect();
        f.solve(&mut b);
        b
    }

    #[test]
    fn rank_one_updates_match_a_fresh_factor() {
        let n = 24;
        let cloth = ClothBuilder::new(n, n).build().unwrap();
        let model = ForceModel::new(
            cloth.topology(),
            &cloth.material,
            Masses::of(&cloth.particles),
            &cloth.params,
            crate::parallel::Team::ALONE,
        );
        let h = 1.0 / 60.0;
        let key = key(&model, h, n * n, cloth.mass_revision());
        let mut updated = build_factor(&model, h, n * n, key).unwrap();
        let mut history = FactorHistory::default();
        updated.adopt(&mut history).unwrap();
        let mut contact = vec![0.0; n * n];
        // Weights come and go on a few rows at a time, as contacts do.
        for round in 0..30usize {
            for k in 0..12 {
                let r = (round * 37 + k * 53) % (n * n);
                contact[r] = if contact[r] == 0.0 {
                    8.0 * updated.base_values[updated.diagonal[r]]
                } else {
                    0.0
                };
            }
            updated.set_contacts(&contact, &mut history).unwrap();
            if round == 12 {
                // Many rows at once: a full factorisation, then updates again.
                contact.iter_mut().step_by(5).for_each(|w| *w = 1.0);
                updated.set_contacts(&contact, &mut history).unwrap();
            }
        }
        assert!(
            updated.updates > 0 && !history.fresh.is_empty(),
            "the rows changed few at a time were updated, after a full factorisation"
        );
        // A factor rebuilt from the history (as from a snapshot) is the same
        // to the bit; without it, it differs in the last bits.
        let mut resumed = build_factor(&model, h, n * n, key).unwrap();
        resumed.adopt(&mut history.clone()).unwrap();
        assert_eq!(resumed.contact, updated.contact);
        assert!(resumed.l_values == updated.l_values, "bit for bit");
        let mut fresh_only = build_factor(&model, h, n * n, key).unwrap();
        fresh_only.refactor(&contact).unwrap();
        assert!(fresh_only.l_values != updated.l_values, "the path matters");
        let mut fresh = build_factor(&model, h, n * n, key).unwrap();
        fresh.refactor(&contact).unwrap();
        let (a, b) = (solution(&updated), solution(&fresh));
        let worst = a
            .iter()
            .zip(&b)
            .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs() / y[c].abs().max(1e-9)))
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "relative difference {worst}");
    }
}
