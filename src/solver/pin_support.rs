//! The stretch limit's weights near pins: how a pinned cloth's limit
//! carries the pins' support out through the cloth in few passes.
//!
//! The grid's stretch limit (`grid_sweep::limit_stretch`) shortens each
//! spring past its limit by moving its ends by their inverse masses, in
//! Gauss–Seidel passes. A cloth hung from pins hangs on long runs of
//! springs at their limit, and a pass with equal weights carries a pin's
//! correction only a spring or two along such a run: the rest of the run
//! pulls the spring at the pin long again. The passes a run needs grow
//! with the square of its length: a 64 × 64 cotton sheet hung by two
//! corners peaked at 9.8% stretch as it swung, 31% at N = 96 and 68% at
//! 128 (BENCHMARKS.md, thirty-sixth session).
//!
//! So the limit weighs a particle near a pin as heavier than one further
//! out: within [`PIN_SUPPORT_SPRINGS`] stretch springs of the nearest
//! pinned particle (inverse mass 0: a pin, or a point attached to a body),
//! its inverse mass is scaled by its distance in springs over that many
//! (1/16 next to a pin, 1 from 16 springs on). A spring near a pin then
//! moves mostly its outer end, as a chain hung from a fixed point is held
//! (shock propagation, Guendelman et al. 2003, in a mild form), and the
//! pin's correction travels the run in fewer passes. Only the limit
//! weighs so; the springs' sweeps and the chain solves keep the masses,
//! and a cloth without pins is limited as before. The limit of a cloth
//! without a grid plan, and the one every other integrator gets after its
//! substep (`strain_limit::limit_stretch_relaxed`), weigh by the same
//! weights, by particle rather than by lane (and the velocities they take
//! from a shortened spring's ends too). A limit that has
//! converged holds the same lengths whatever the weights: they change how
//! fast it gets there, and which end of a spring moves on the way.

use crate::cloth::{SpringKind, Springs};
use crate::collision::StretchIncidence;

/// Stretch springs from the nearest pin over which the stretch limit's
/// weights grow to the particles' own inverse masses (linearly: `d /
/// PIN_SUPPORT_SPRINGS` at `d` springs). Measured, peak stretch over every
/// frame (with [`super::xpbd`]'s rounds of the limit for a pinned cloth;
/// BENCHMARKS.md, thirty-sixth session): a cotton sheet hung by two corners
/// at N = 64, 96 and 128: 4.75%, 4.75% and 13% (equal weights: 4.76%, 4.8%,
/// 14%, and at N = 96 twice the time); by four corners at N = 128 7.5%
/// (8.7%); the `hammock` 5.14% (5.18%). (Those at 16 substeps; the side
/// rule of `stability.rs` now takes 20 and 28 at N = 96 and 128: 4.77%
/// and 4.89% by two corners, 4.66% by four.) Over 32 springs, or with the
/// weights halved a spring, the hammock's cotton peaked at 5.3–6.4%.
pub(crate) const PIN_SUPPORT_SPRINGS: u32 = 16;

/// The stretch limit's weight of each lane of a grid plan (or of each
/// particle, the lanes then the particles' own order), for a cloth with
/// pins ([`PinSupport::update`]); none for a cloth without.
#[derive(Debug, Default, Clone)]
pub(crate) struct PinSupport {
    /// Per lane: the inverse mass the limit moves the particle by (1/kg);
    /// empty when the cloth has no pinned particle.
    weights: Vec<f32>,
    /// The cloth's mass revision the weights are of.
    of: Option<u64>,
    /// Scratch: each particle's distance in springs from the nearest pin,
    /// the breadth-first queue, and the stretch springs at each particle.
    distance: Vec<u32>,
    queue: Vec<u32>,
    springs_at: StretchIncidence,
}

impl PinSupport {
    /// The weights for particles of inverse masses `inv_mass` joined by
    /// `springs`, particle `i` in lane `lane_of(i)`; found again only when
    /// the cloth's mass `revision` (which changes with its masses, pins
    /// and topology) is not the one they are of.
    pub(crate) fn update(
        &mut self,
        inv_mass: &[f32],
        springs: &Springs,
        lane_of: impl Fn(usize) -> usize,
        revision: u64,
    ) {
        if self.of == Some(revision) {
            return;
        }
        self.of = Some(revision);
        self.weights.clear();
        let n = inv_mass.len();
        if !inv_mass.contains(&0.0) {
            return;
        }
        self.springs_at.build(springs, n);
        let (a, b) = springs.endpoints();
        let first = springs.range(SpringKind::Stretch).start;
        // Breadth first from every pin at once.
        self.distance.clear();
        self.distance.resize(n, u32::MAX);
        self.queue.clear();
        for (i, &w) in inv_mass.iter().enumerate() {
            if w == 0.0 {
                self.distance[i] = 0;
                self.queue.push(i as u32);
            }
        }
        let mut next = 0;
        while next < self.queue.len() {
            let i = self.queue[next] as usize;
            next += 1;
            let d = self.distance[i] + 1;
            if d > PIN_SUPPORT_SPRINGS {
                break; // every particle nearer is found
            }
            for &k in self.springs_at.at(i) {
                let s = first + k as usize;
                let j = if a[s] as usize == i { b[s] } else { a[s] } as usize;
                if self.distance[j] == u32::MAX {
                    self.distance[j] = d;
                    self.queue.push(j as u32);
                }
            }
        }
        self.weights.resize(n, 0.0);
        for (i, (&w, &d)) in inv_mass.iter().zip(&self.distance).enumerate() {
            let share = d.min(PIN_SUPPORT_SPRINGS) as f32 / PIN_SUPPORT_SPRINGS as f32;
            if let Some(weight) = self.weights.get_mut(lane_of(i)) {
                *weight = w * share;
            }
        }
    }

    /// The limit's weight of each lane, when the cloth has pins and there
    /// are `lanes` of them.
    pub(crate) fn weights(&self, lanes: usize) -> Option<&[f32]> {
        (!self.weights.is_empty() && self.weights.len() == lanes).then_some(&self.weights[..])
    }

    /// Whether the cloth the weights are of has pins.
    pub(crate) fn pinned(&self) -> bool {
        !self.weights.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    #[test]
    fn weights_grow_with_the_springs_from_the_nearest_pin() {
        let cloth = ClothBuilder::new(40, 3).build().unwrap();
        let mut w = vec![2.0f32; cloth.particle_count()];
        // Pinned: the first particle of the first row.
        w[0] = 0.0;
        let mut support = PinSupport::default();
        // Lanes in reverse particle order, to see the map is used.
        let n = w.len();
        support.update(&w, cloth.springs(), |i| n - 1 - i, 7);
        let weights = support.weights(n).expect("pinned");
        let at = |row: usize, col: usize| weights[n - 1 - (row * 40 + col)];
        assert_eq!(at(0, 0), 0.0);
        assert_eq!(at(0, 1), 2.0 / 16.0);
        assert_eq!(at(1, 1), 2.0 * 2.0 / 16.0);
        assert_eq!(at(2, 13), 2.0 * 15.0 / 16.0);
        assert_eq!(at(2, 14), 2.0);
        assert_eq!(at(0, 39), 2.0);
        assert!(support.pinned());

        // Not found again for the same revision, found for a new one.
        w[0] = 2.0;
        support.update(&w, cloth.springs(), |i| n - 1 - i, 7);
        assert!(support.pinned());
        support.update(&w, cloth.springs(), |i| n - 1 - i, 8);
        assert!(!support.pinned(), "no pin: the lanes' own weights");
        assert_eq!(support.weights(n), None);
    }
}
