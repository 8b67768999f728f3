//! The tearing stage, run once at the end of a step whose cloth's material
//! has a tear strain: every stretch spring strained past it tears the cloth
//! at one of its ends, worst first, by splitting that particle across the
//! spring (`Cloth::split_particle`). Only the worst springs tear in one step
//! (those strained at least halfway from the tear strain to the worst), and
//! not within two rings of a particle split in the same step: the others wait for the
//! next step, when the cloth has opened and their load has changed. So a
//! tear runs along the overloaded line a particle or two a step, as a crack
//! does, instead of shattering the cloth at once.

use serde::{Deserialize, Serialize};

use crate::cloth::{Cloth, TopologyEdit};
use crate::math::Vector;

/// Which springs tear in one step: those strained at least this fraction of
/// the way from the tear strain to the worst spring's strain.
const FOCUS: f32 = 0.5;

/// One tear: a stretch spring strained past the material's tear strain, and
/// the particle the cloth split at.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TearEvent {
    /// The spring's two particles (indices as they were before the tear).
    pub spring: [u32; 2],
    /// Its strain when it tore (0.3: 30% past its rest length).
    pub strain: f32,
    /// The particle split: one of the spring's two.
    pub particle: u32,
    /// The new particle, which took the triangles on the spring's far side.
    pub new_particle: u32,
    /// Where the cloth tore, in metres.
    pub position: Vector,
}

/// The tearing stage's scratch and the last step's events.
#[derive(Debug, Default)]
pub(crate) struct Tearing {
    /// What tore during the last step.
    pub events: Vec<TearEvent>,
    /// Overstrained springs: strain and particles.
    overstrained: Vec<(f32, u32, u32)>,
    /// Particles split, or within two rings of one split, in this step.
    touched: Vec<bool>,
    /// Per particle: how far its overstrained springs are past the tear
    /// strain, summed.
    load: Vec<f32>,
    ring: Vec<u32>,
}

impl Tearing {
    /// Tears `cloth` where its stretch springs are strained past the
    /// material's tear strain; returns how many springs tore.
    pub fn run(&mut self, cloth: &mut Cloth) -> u32 {
        self.events.clear();
        let Some(tear) = cloth.material.tear_strain else {
            return 0;
        };
        let springs = cloth.springs();
        let x = cloth.positions();
        let (a, b) = springs.endpoints();
        let rest = springs.rest_lengths();
        self.overstrained.clear();
        for s in springs.range(crate::cloth::SpringKind::Stretch) {
            let length = (x[b[s] as usize] - x[a[s] as usize]).length();
            let strain = length / rest[s] - 1.0;
            if strain > tear {
                self.overstrained.push((strain, a[s], b[s]));
            }
        }
        if self.overstrained.is_empty() {
            return 0;
        }
        // Worst first; equal strains by particle, so the order is the same
        // on every machine and thread count.
        self.overstrained
            .sort_by(|p, q| q.0.total_cmp(&p.0).then((p.1, p.2).cmp(&(q.1, q.2))));
        self.load.clear();
        self.load.resize(cloth.particle_count(), 0.0);
        for &(strain, a, b) in &self.overstrained {
            self.load[a as usize] += strain - tear;
            self.load[b as usize] += strain - tear;
        }
        // Only the worst tear now (see the module's docs).
        let worst = self.overstrained[0].0;
        let now = tear + FOCUS * (worst - tear);
        self.touched.clear();
        self.touched.resize(cloth.particle_count(), false);
        let mut edit = TopologyEdit::of(cloth.topology());
        for &(strain, a, b) in self.overstrained.iter().take_while(|o| o.0 >= now) {
            let (ia, ib) = (a as usize, b as usize);
            if self.touched[ia] || self.touched[ib] {
                continue;
            }
            let (xa, xb) = (cloth.particles.x[ia], cloth.particles.x[ib]);
            // Split an end across the spring, its far side going with the
            // new particle: the end more overloaded (pulled apart by more
            // springs: the tip of a tear, which then runs on), else one on
            // the border (a tear's edge rather than a new hole beside it).
            // An end whose triangles all lie on one side (a border particle
            // pulled inwards) cannot open, so then the other.
            self.ring.clear();
            let d = (xb - xa).normalize_or_zero();
            let mut ends = [(ia, d), (ib, -d)];
            let (la, lb) = (self.load[ia], self.load[ib]);
            if lb > la || (lb == la && !edit.on_border(ia) && edit.on_border(ib)) {
                ends.swap(0, 1);
            }
            let particles = &mut cloth.particles;
            let split = edit
                .split(particles, ends[0].0, ends[0].1, &mut self.ring)
                .or_else(|| edit.split(particles, ends[1].0, ends[1].1, &mut self.ring));
            let Some(split) = split else { continue };
            self.touched.push(true);
            // Two rings around the split wait, not one: as a sheet parts,
            // its last row holds the whole load, and a spring two columns
            // from the tip tore with it (the `tear` scene at N = 96 and
            // 128 tore beside its line so in its edge rows; with two rings
            // the tip's split unloads them first). The range is the first
            // ring's, fixed before the loop adds the second behind it.
            for k in 0..self.ring.len() {
                let u = self.ring[k];
                edit.add_ring(u, &mut self.ring);
            }
            for &p in [a, b].iter().chain(&self.ring) {
                self.touched[p as usize] = true;
            }
            self.events.push(TearEvent {
                spring: [a, b],
                strain,
                particle: split.particle,
                new_particle: split.new_particle,
                position: cloth.particles.x[split.particle as usize],
            });
        }
        if !self.events.is_empty() {
            edit.commit(cloth);
        }
        self.events.len() as u32
    }
}
