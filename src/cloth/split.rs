//! Splitting a particle in two across a plane: how a cloth tears (after
//! Robson's vertex splitting, and Müller et al. 2005's "Fast and robust
//! tearing"). The particle's triangles in front of the plane move to a new
//! particle at the same place, so the mesh opens between the two; its springs
//! follow their triangles, and springs that ran across the particle from one
//! side to the other (the bend springs over it) are cut.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::cloth::{next_mass_revision, Cloth};
use super::particles::Particles;
use super::springs::{Spring, Springs};
use super::topology::Topology;
use crate::error::{finite_vec, ClothError};
use crate::math::Vector;

/// What splitting one particle did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ParticleSplit {
    /// The particle that was split; it keeps the triangles behind the plane.
    pub particle: u32,
    /// The new particle (the last index), holding the triangles in front.
    pub new_particle: u32,
    /// Springs that ran across the particle from one side to the other and
    /// were cut.
    pub cut_springs: u32,
}

/// Which side of the plane a particle's triangles lie on.
const BEHIND: u8 = 1;
/// See [`BEHIND`].
const IN_FRONT: u8 = 2;

/// A cloth's topology while particles are being split: the springs as a
/// list, so that any number of splits costs one rebuild of the flat, coloured
/// spring arrays ([`TopologyEdit::commit`]).
pub(crate) struct TopologyEdit {
    springs: Vec<Spring>,
    triangles: Vec<[u32; 3]>,
    uvs: Vec<[f32; 2]>,
    splits: Vec<[u32; 2]>,
    /// Per particle touched by the current split: which sides of the plane
    /// its triangles with the split particle lie on (scratch).
    sides: Vec<(u32, u8)>,
}

impl TopologyEdit {
    /// Starts editing `topology`.
    pub(crate) fn of(topology: &Topology) -> Self {
        TopologyEdit {
            springs: topology.springs.iter().collect(),
            triangles: topology.triangles.clone(),
            uvs: topology.uvs.clone(),
            splits: topology.splits.clone(),
            sides: Vec::new(),
        }
    }

    /// Adds to `out` the particles that share a triangle with `p` (and are
    /// not in it yet).
    pub(crate) fn add_ring(&self, p: u32, out: &mut Vec<u32>) {
        for t in self.triangles.iter().filter(|t| t.contains(&p)) {
            for &u in t.iter().filter(|&&u| u != p) {
                if !out.contains(&u) {
                    out.push(u);
                }
            }
        }
    }

    /// Splits particle `p` across the plane through it with unit `normal`, or
    /// returns `None` when all its triangles lie on one side (nothing would
    /// open). `ring` receives the particles that shared a triangle with `p`.
    pub(crate) fn split(
        &mut self,
        particles: &mut Particles,
        p: usize,
        normal: Vector,
        ring: &mut Vec<u32>,
    ) -> Option<ParticleSplit> {
        let n = particles.len();
        if n >= u32::MAX as usize {
            return None;
        }
        let (pi, q) = (p as u32, n as u32);
        let origin = particles.x[p];
        let x = &particles.x;
        let in_front = |t: &[u32; 3]| {
            let centroid = (x[t[0] as usize] + x[t[1] as usize] + x[t[2] as usize]) / 3.0;
            (centroid - origin).dot(normal) > 0.0
        };
        // Which side each of p's triangles is on, and so each particle of its ring.
        self.sides.clear();
        let (mut behind, mut front) = (0usize, 0usize);
        for t in self.triangles.iter().filter(|t| t.contains(&pi)) {
            let side = if in_front(t) { IN_FRONT } else { BEHIND };
            if side == IN_FRONT {
                front += 1;
            } else {
                behind += 1;
            }
            for &u in t.iter().filter(|&&u| u != pi) {
                match self.sides.iter_mut().find(|(v, _)| *v == u) {
                    Some((_, s)) => *s |= side,
                    None => self.sides.push((u, side)),
                }
            }
        }
        if behind == 0 || front == 0 {
            return None;
        }
        let side_of = |sides: &[(u32, u8)], u: u32| {
            sides.iter().find(|(v, _)| *v == u).map_or(0, |&(_, s)| s)
        };
        // The triangles in front move to the new particle.
        for t in self.triangles.iter_mut() {
            if let Some(k) = t.iter().position(|&u| u == pi) {
                if in_front(t) {
                    t[k] = q;
                }
            }
        }
        // Springs at p follow their triangles: an edge of triangles on both
        // sides is doubled, one that is no triangle's edge goes by where its
        // other end lies. Springs between the two sides across p are cut.
        let mut cut = 0u32;
        let mut doubled = Vec::new();
        self.springs.retain_mut(|s| {
            let other = if s.a == pi {
                Some(s.b)
            } else if s.b == pi {
                Some(s.a)
            } else {
                None
            };
            match other {
                Some(r) => {
                    let side = match side_of(&self.sides, r) {
                        0 if (x[r as usize] - origin).dot(normal) > 0.0 => IN_FRONT,
                        0 => BEHIND,
                        s => s,
                    };
                    let moved = Spring {
                        a: if s.a == pi { q } else { s.a },
                        b: if s.b == pi { q } else { s.b },
                        ..*s
                    };
                    if side == IN_FRONT {
                        *s = moved;
                    } else if side == BEHIND | IN_FRONT {
                        doubled.push(moved);
                    }
                    true
                }
                None => {
                    let across = matches!(
                        (side_of(&self.sides, s.a), side_of(&self.sides, s.b)),
                        (BEHIND, IN_FRONT) | (IN_FRONT, BEHIND)
                    );
                    cut += u32::from(across);
                    !across
                }
            }
        });
        self.springs.extend(doubled);
        // The new particle: p's place and motion, and the share of its mass
        // of the triangles it takes (a pinned particle's halves stay pinned).
        let share = front as f32 / (front + behind) as f32;
        let (mass, pinned) = (particles.mass[p], particles.inv_mass[p] == 0.0);
        let (m_front, m_behind) = (mass * share, mass * (1.0 - share));
        let inverse = |m: f32| if pinned { 0.0 } else { 1.0 / m };
        particles.x.push(origin);
        particles.v.push(particles.v[p]);
        particles.x_prev.push(particles.x_prev[p]);
        particles.mass.push(m_front);
        particles.inv_mass.push(inverse(m_front));
        particles.mass[p] = m_behind;
        particles.inv_mass[p] = inverse(m_behind);
        let uv = self.uvs.get(p).copied().unwrap_or_default();
        self.uvs.push(uv);
        self.splits.push([pi, q]);
        ring.extend(self.sides.iter().map(|&(u, _)| u));
        Some(ParticleSplit {
            particle: pi,
            new_particle: q,
            cut_springs: cut,
        })
    }

    /// True when particle `p` lies on the mesh's border (a torn edge or the
    /// cloth's own): its triangles do not close around it, so it has more
    /// neighbours through triangles than triangles.
    pub(crate) fn on_border(&mut self, p: usize) -> bool {
        let p = p as u32;
        let mut triangles = 0;
        self.sides.clear();
        for t in self.triangles.iter().filter(|t| t.contains(&p)) {
            triangles += 1;
            for &u in t.iter().filter(|&&u| u != p) {
                if !self.sides.iter().any(|&(v, _)| v == u) {
                    self.sides.push((u, 0));
                }
            }
        }
        self.sides.len() > triangles
    }

    /// Gives `cloth` the edited topology. A split cloth is no longer a grid.
    pub(crate) fn commit(self, cloth: &mut Cloth) {
        cloth.topology = Arc::new(Topology {
            springs: Springs::from_list(self.springs),
            triangles: self.triangles,
            uvs: self.uvs,
            grid: None,
            split_from: cloth.topology.cells(),
            splits: self.splits,
            pieces: Vec::new(),
        });
        cloth.mass_revision = next_mass_revision();
    }
}

impl Cloth {
    /// Splits particle `i` in two across the plane through it with normal
    /// `normal` (any length): its triangles on the normal's side move to a
    /// new particle at the same place, with the same velocity and their share
    /// of the mass, so the mesh opens between the two. Springs follow their
    /// triangles; springs that ran across the particle from one side to the
    /// other are cut. Returns `None`, changing nothing, when all of the
    /// particle's triangles lie on one side.
    ///
    /// The new particle is the last one; every other index is kept. A split
    /// cloth is no longer a grid ([`Cloth::grid`] is `None`), but
    /// [`Cloth::index`] still finds the particles it was built with. This is what
    /// tearing does ([`super::Material::tear_strain`]); a knife tool can call
    /// it directly.
    pub fn split_particle(
        &mut self,
        i: usize,
        normal: Vector,
    ) -> Result<Option<ParticleSplit>, ClothError> {
        self.check_index(i)?;
        finite_vec("split normal", normal)?;
        let normal = normal.normalize_or_zero();
        if normal == Vector::ZERO {
            return Err(ClothError::InvalidParameter {
                name: "split normal length",
                value: 0.0,
                expected: "a direction (a vector of length > 0)",
            });
        }
        let mut edit = TopologyEdit::of(&self.topology);
        let split = edit.split(&mut self.particles, i, normal, &mut Vec::new());
        if split.is_some() {
            edit.commit(self);
        }
        Ok(split)
    }
}
