//! Tethers (long-range attachments, Kim, Chentanez and Müller 2012, as in
//! Jolt's and NvCloth's cloth): each free particle is kept within its rest
//! distance of the nearest pinned particle, measured through the mesh
//! along stretch and shear springs. A pinned cloth then cannot stretch
//! under its own weight however fine its grid and however few the solver's
//! iterations: the springs only have to hold the cloth's shape, not carry
//! its whole weight through a long chain. A tether is one-sided: it stops a
//! particle going further from its pin, never pulls it nearer.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::cloth::{Cloth, Particles, SpringKind};

/// No anchor: the particle is pinned, or no pin can be reached from it.
const NONE: u32 = u32::MAX;

/// Each particle's tether: the pinned particle nearest through the mesh and
/// the rest distance to it; rebuilt when pins, masses or topology change.
#[derive(Debug, Default)]
pub(crate) struct Tethers {
    anchor: Vec<u32>,
    length: Vec<f32>,
    /// What the tethers were found for: the cloth's mass revision (it
    /// changes with every pin), its topology's address and particle count.
    made_for: Option<(u64, usize, usize)>,
    heap: BinaryHeap<Reverse<(u32, u32)>>,
}

impl Tethers {
    /// Finds every particle's tether, unless found for this cloth already.
    pub fn update(&mut self, cloth: &Cloth) {
        let n = cloth.particle_count();
        let key = (
            cloth.mass_revision(),
            std::sync::Arc::as_ptr(cloth.topology()) as usize,
            n,
        );
        if self.made_for == Some(key) {
            return;
        }
        self.made_for = Some(key);
        // Dijkstra from every pin at once over the stretch and shear
        // springs, by rest length. Distances are kept as the bits of a
        // non-negative f32, which order as the numbers do.
        self.anchor.clear();
        self.anchor.resize(n, NONE);
        self.length.clear();
        self.length.resize(n, f32::INFINITY);
        self.heap.clear();
        for i in 0..n {
            if cloth.is_pinned(i) {
                self.anchor[i] = i as u32;
                self.length[i] = 0.0;
                self.heap.push(Reverse((0, i as u32)));
            }
        }
        let springs = cloth.springs();
        let (a, b) = springs.endpoints();
        let rest = springs.rest_lengths();
        // Adjacency as compressed rows, built once per update.
        let kinds = [SpringKind::Stretch, SpringKind::Shear];
        let mut start = vec![0u32; n + 1];
        for s in kinds.iter().flat_map(|&k| springs.range(k)) {
            start[a[s] as usize + 1] += 1;
            start[b[s] as usize + 1] += 1;
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut next = vec![(0u32, 0.0f32); start[n] as usize];
        for s in kinds.iter().flat_map(|&k| springs.range(k)) {
            for (p, q) in [(a[s], b[s]), (b[s], a[s])] {
                next[fill[p as usize] as usize] = (q, rest[s]);
                fill[p as usize] += 1;
            }
        }
        while let Some(Reverse((bits, p))) = self.heap.pop() {
            let (p, d) = (p as usize, f32::from_bits(bits));
            if d > self.length[p] {
                continue;
            }
            for &(q, r) in &next[start[p] as usize..start[p + 1] as usize] {
                let (q, dq) = (q as usize, d + r);
                if dq < self.length[q] {
                    self.length[q] = dq;
                    self.anchor[q] = self.anchor[p];
                    self.heap.push(Reverse((dq.to_bits(), q as u32)));
                }
            }
        }
        // A pinned particle needs no tether.
        for i in 0..n {
            if cloth.is_pinned(i) {
                self.anchor[i] = NONE;
            }
        }
    }

    /// Brings every free particle further from its anchor than its tether
    /// back to the tether's length, and takes away its velocity away from
    /// the anchor (relative to the anchor's). Returns the particles held.
    pub fn hold(&self, particles: &mut Particles) -> u32 {
        let Particles { x, v, .. } = particles;
        let mut held = 0;
        for (i, (&anchor, &length)) in self.anchor.iter().zip(&self.length).enumerate() {
            if anchor == NONE || i >= x.len() {
                continue;
            }
            let (xa, va) = (x[anchor as usize], v[anchor as usize]);
            let d = x[i] - xa;
            let len = d.length();
            if len <= length || len == 0.0 || !len.is_finite() {
                continue;
            }
            let n = d / len;
            x[i] = xa + n * length;
            let away = (v[i] - va).dot(n);
            if away > 0.0 {
                v[i] -= n * away;
            }
            held += 1;
        }
        held
    }
}

/// The particles' tethers as (anchor, rest distance in metres): `None` for
/// a pinned particle or one no pin reaches.
#[cfg(test)]
fn tethers_of(cloth: &Cloth) -> Vec<Option<(usize, f32)>> {
    let mut t = Tethers::default();
    t.update(cloth);
    t.anchor
        .iter()
        .zip(&t.length)
        .map(|(&a, &l)| (a != NONE).then_some((a as usize, l)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;
    use crate::math::Vector;

    /// Pinned along its top row, a 5×5 sheet's particles are tethered to
    /// the pin right above them, at the rest distance down the column.
    #[test]
    fn tethers_run_through_the_mesh_to_the_nearest_pin() {
        let mut cloth = ClothBuilder::new(5, 5).size(1.0, 1.0).build().unwrap();
        for c in 0..5 {
            cloth.pin_cell(0, c).unwrap();
        }
        let t = tethers_of(&cloth);
        assert_eq!(t[2], None);
        let (anchor, length) = t[cloth.index(4, 2).unwrap()].unwrap();
        assert_eq!(anchor, 2);
        assert!((length - 1.0).abs() < 1e-6, "{length}");
        // Pulled a metre away, a particle comes back to its tether, and
        // stops moving away.
        let i = cloth.index(4, 2).unwrap();
        let mut tethers = Tethers::default();
        tethers.update(&cloth);
        let far = cloth.positions()[i] + Vector::new(0.0, 0.0, 1.0);
        cloth.set_position(i, far).unwrap();
        cloth.set_velocity(i, Vector::new(0.0, 0.0, 2.0)).unwrap();
        assert_eq!(tethers.hold(&mut cloth.particles), 1);
        let d = (cloth.positions()[i] - cloth.positions()[2]).length();
        assert!((d - 1.0).abs() < 1e-5, "{d}");
        assert!(cloth.velocities()[i].length() < 2.0);
        // Without pins nothing is tethered.
        cloth.unpin_all();
        assert!(tethers_of(&cloth).iter().all(Option::is_none));
    }
}
