//! The cloth as data: particles, topology, material and physical parameters.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::energy::Energy;
use super::material::Material;
use super::particles::Particles;
use super::physics::PhysicsParams;
use super::pins::PinPreset;
use super::springs::{Spring, SpringKind, Springs};
use super::topology::{Grid, Topology};
use crate::error::{finite_vec, positive, ClothError};
use crate::math::Vector;

/// A mass-spring cloth, as data: its particles (state), its topology
/// (springs, triangles, texture coordinates, grid; shared between cloths
/// built alike), its material and the physical parameters of its world.
///
/// A cloth does not step itself: a [`crate::solver::ClothSolver`] steps it
/// (or [`crate::Simulation`], which bundles the two).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Cloth {
    pub(crate) particles: Particles,
    pub(crate) topology: Arc<Topology>,
    /// The material: spring stiffness and damping per kind, density, colour.
    pub material: Material,
    /// Gravity, drag, wind, thickness.
    pub params: PhysicsParams,
    /// Simulated time so far, in seconds.
    pub(crate) time: f64,
    /// Changes whenever a mass or a pin changes, so that solvers know when
    /// what they derived from masses and pins (a factorised matrix) is stale.
    /// Unique over the whole process, so no two cloths share one by chance.
    #[serde(skip, default = "next_mass_revision")]
    pub(crate) mass_revision: u64,
}

/// A new, never used [`Cloth::mass_revision`].
pub(super) fn next_mass_revision() -> u64 {
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

impl PartialEq for Cloth {
    fn eq(&self, other: &Self) -> bool {
        self.particles == other.particles
            && self.topology == other.topology
            && self.material == other.material
            && self.params == other.params
            && self.time == other.time
    }
}

impl Cloth {
    /// Builds a general mass-spring system from its parts: positions (m),
    /// masses (kg), springs and triangles (may be empty).
    ///
    /// Every index is checked; masses and rest lengths must be finite and > 0.
    pub fn from_parts(
        positions: Vec<Vector>,
        masses: Vec<f32>,
        springs: Vec<Spring>,
        triangles: Vec<[u32; 3]>,
        material: Material,
    ) -> Result<Cloth, ClothError> {
        let n = positions.len();
        if masses.len() != n {
            return Err(ClothError::LengthMismatch {
                what: "masses",
                expected: n,
                got: masses.len(),
            });
        }
        if n > u32::MAX as usize {
            return Err(ClothError::GridTooLarge {
                cols: n,
                rows: 1,
                max: u32::MAX as usize,
            });
        }
        for p in &positions {
            finite_vec("particle position", *p)?;
        }
        for m in &masses {
            positive("particle mass", *m)?;
        }
        for (index, s) in springs.iter().enumerate() {
            let bad = |reason: String| ClothError::InvalidTopology {
                what: "spring",
                index,
                reason,
            };
            if s.a as usize >= n || s.b as usize >= n {
                return Err(bad(format!(
                    "particle {} or {} out of range 0..{n}",
                    s.a, s.b
                )));
            }
            if s.a == s.b {
                return Err(bad("joins a particle to itself".into()));
            }
            if !(s.rest_length.is_finite() && s.rest_length > 0.0) {
                return Err(bad(format!(
                    "rest length {} is not a finite number > 0",
                    s.rest_length
                )));
            }
        }
        for (index, t) in triangles.iter().enumerate() {
            if t.iter().any(|&i| i as usize >= n) || t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return Err(ClothError::InvalidTopology {
                    what: "triangle",
                    index,
                    reason: format!("{t:?} repeats a particle or is out of range 0..{n}"),
                });
            }
        }
        material.validate()?;
        let inv_mass = masses.iter().map(|m| 1.0 / m).collect();
        Ok(Cloth {
            particles: Particles {
                v: vec![Vector::ZERO; n],
                x_prev: positions.clone(),
                x: positions,
                mass: masses,
                inv_mass,
            },
            topology: Arc::new(Topology {
                springs: Springs::from_list(springs),
                triangles,
                uvs: vec![[0.0, 0.0]; n],
                grid: None,
                split_from: None,
                splits: Vec::new(),
                pieces: Vec::new(),
            }),
            material,
            params: PhysicsParams::default(),
            time: 0.0,
            mass_revision: next_mass_revision(),
        })
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.particles.len()
    }

    /// The grid this cloth was built on, if it was built by
    /// [`super::ClothBuilder`] and has not torn since (see [`Topology::cells`]).
    pub fn grid(&self) -> Option<Grid> {
        self.topology.grid
    }

    /// The topology: springs, triangles, texture coordinates, grid.
    pub fn topology(&self) -> &Arc<Topology> {
        &self.topology
    }

    /// Gives this cloth the topology of another one built alike (same
    /// particle count): one copy in memory for both.
    pub fn share_topology(&mut self, topology: Arc<Topology>) -> Result<(), ClothError> {
        if *topology != *self.topology {
            return Err(ClothError::InvalidTopology {
                what: "shared topology",
                index: 0,
                reason: "differs from this cloth's own".into(),
            });
        }
        self.topology = topology;
        Ok(())
    }

    /// Which masses and pins the cloth has: changes whenever one changes.
    pub fn mass_revision(&self) -> u64 {
        self.mass_revision
    }

    /// Positions in metres.
    pub fn positions(&self) -> &[Vector] {
        &self.particles.x
    }

    /// Velocities in m/s.
    pub fn velocities(&self) -> &[Vector] {
        &self.particles.v
    }

    /// Masses in kg (pinned particles keep theirs).
    pub fn masses(&self) -> &[f32] {
        &self.particles.mass
    }

    /// Inverse masses in 1/kg; 0 for pinned particles.
    pub fn inverse_masses(&self) -> &[f32] {
        &self.particles.inv_mass
    }

    /// The springs.
    pub fn springs(&self) -> &Springs {
        &self.topology.springs
    }

    /// The triangles, as particle index triples (counter-clockwise seen from the front).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.topology.triangles
    }

    /// Texture coordinates of each particle, in 0..=1.
    pub fn uvs(&self) -> &[[f32; 2]] {
        &self.topology.uvs
    }

    /// Simulated time so far, in seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The distance (m) self-collision keeps the cloth's layers apart:
    /// `params.self_thickness`, or else the collision thickness but at most
    /// a quarter of the shortest stretch spring's rest length. A layer
    /// thickness near the spacing fights the springs wherever the cloth
    /// pleats (a tablecloth draped on a ball: single springs stretched 25–31%
    /// at 1 cm with a 1.6 cm spacing, 4.6% at 4 mm).
    pub fn self_thickness(&self) -> f32 {
        if let Some(t) = self.params.self_thickness {
            return t;
        }
        let springs = &self.topology.springs;
        let shortest = springs
            .range(SpringKind::Stretch)
            .map(|s| springs.rest[s])
            .fold(f32::INFINITY, f32::min);
        self.params.thickness.min(0.25 * shortest)
    }

    /// Total mass in kg.
    pub fn total_mass(&self) -> f32 {
        self.particles.mass.iter().sum()
    }

    /// Index of grid cell `(row, col)`.
    pub fn index(&self, row: usize, col: usize) -> Result<usize, ClothError> {
        let grid = self.topology.cells().ok_or(ClothError::NotAGrid)?;
        if row >= grid.rows || col >= grid.cols {
            return Err(ClothError::CellOutOfRange {
                row,
                col,
                rows: grid.rows,
                cols: grid.cols,
            });
        }
        Ok(row * grid.cols + col)
    }

    pub(super) fn check_index(&self, i: usize) -> Result<(), ClothError> {
        if i < self.particles.len() {
            Ok(())
        } else {
            Err(ClothError::ParticleOutOfRange {
                index: i,
                count: self.particles.len(),
            })
        }
    }

    /// True when particle `i` is pinned (false when out of range).
    pub fn is_pinned(&self, i: usize) -> bool {
        self.particles.inv_mass.get(i).is_some_and(|&w| w == 0.0)
    }

    /// Indices of every pinned particle.
    pub fn pinned(&self) -> Vec<usize> {
        (0..self.particles.len())
            .filter(|&i| self.is_pinned(i))
            .collect()
    }

    /// Pins particle `i` where it is: it stops and no force moves it any more.
    pub fn pin(&mut self, i: usize) -> Result<(), ClothError> {
        self.check_index(i)?;
        self.particles.v[i] = Vector::ZERO;
        if self.particles.inv_mass[i] != 0.0 {
            self.particles.inv_mass[i] = 0.0;
            self.mass_revision = next_mass_revision();
        }
        Ok(())
    }

    /// Releases particle `i`; it gets its mass back.
    pub fn unpin(&mut self, i: usize) -> Result<(), ClothError> {
        self.check_index(i)?;
        if self.particles.inv_mass[i] == 0.0 {
            self.particles.inv_mass[i] = 1.0 / self.particles.mass[i];
            self.mass_revision = next_mass_revision();
        }
        Ok(())
    }

    /// Pins grid cell `(row, col)`.
    pub fn pin_cell(&mut self, row: usize, col: usize) -> Result<(), ClothError> {
        let i = self.index(row, col)?;
        self.pin(i)
    }

    /// Releases grid cell `(row, col)`.
    pub fn unpin_cell(&mut self, row: usize, col: usize) -> Result<(), ClothError> {
        let i = self.index(row, col)?;
        self.unpin(i)
    }

    /// Releases every pin.
    pub fn unpin_all(&mut self) {
        for i in 0..self.particles.len() {
            self.particles.inv_mass[i] = 1.0 / self.particles.mass[i];
        }
        self.mass_revision = next_mass_revision();
    }

    /// Replaces the pins by a preset (grid cloths only).
    pub fn apply_pin_preset(&mut self, preset: PinPreset) -> Result<(), ClothError> {
        let grid = self.topology.cells().ok_or(ClothError::NotAGrid)?;
        self.unpin_all();
        for (r, c) in preset.cells(grid.cols, grid.rows) {
            self.pin_cell(r, c)?;
        }
        Ok(())
    }

    /// Moves particle `i` on purpose (a pinned one stays pinned there).
    pub fn set_position(&mut self, i: usize, position: Vector) -> Result<(), ClothError> {
        self.check_index(i)?;
        finite_vec("position", position)?;
        self.particles.x[i] = position;
        self.particles.x_prev[i] = position;
        Ok(())
    }

    /// Sets the velocity of particle `i` in m/s. A pinned particle keeps this
    /// velocity through the steps: it moves kinematically, dragging the cloth.
    pub fn set_velocity(&mut self, i: usize, velocity: Vector) -> Result<(), ClothError> {
        self.check_index(i)?;
        finite_vec("velocity", velocity)?;
        self.particles.v[i] = velocity;
        Ok(())
    }

    /// Sets every velocity to zero.
    pub fn stop(&mut self) {
        self.particles.v.fill(Vector::ZERO);
    }

    /// Changes the mass of particle `i`, in kg.
    pub fn set_mass(&mut self, i: usize, mass: f32) -> Result<(), ClothError> {
        self.check_index(i)?;
        positive("particle mass", mass)?;
        let pinned = self.is_pinned(i);
        self.particles.mass[i] = mass;
        if !pinned {
            self.particles.inv_mass[i] = 1.0 / mass;
        }
        self.mass_revision = next_mass_revision();
        Ok(())
    }

    /// Scales every mass so the total is `total` kg.
    pub fn set_total_mass(&mut self, total: f32) -> Result<(), ClothError> {
        positive("total mass", total)?;
        let scale = total / self.total_mass();
        for i in 0..self.particles.len() {
            let m = self.particles.mass[i] * scale;
            positive("particle mass", m)?;
            self.particles.mass[i] = m;
            if self.particles.inv_mass[i] != 0.0 {
                self.particles.inv_mass[i] = 1.0 / m;
            }
        }
        self.mass_revision = next_mass_revision();
        Ok(())
    }

    /// Length of spring `s` divided by its rest length, minus one.
    pub fn strain(&self, s: usize) -> Option<f32> {
        let sp = self.topology.springs.get(s)?;
        let d = self.particles.x[sp.b as usize] - self.particles.x[sp.a as usize];
        Some(d.length() / sp.rest_length - 1.0)
    }

    /// The springs of one kind: their first and second particles, and
    /// their rest lengths (m).
    fn springs_of(&self, kind: SpringKind) -> (&[u32], &[u32], &[f32]) {
        let springs = &self.topology.springs;
        let range = springs.range(kind);
        let (a, b) = springs.endpoints();
        (
            &a[range.clone()],
            &b[range.clone()],
            &springs.rest_lengths()[range],
        )
    }

    /// The largest strain over the springs of one kind (0 when there is none).
    pub fn max_strain(&self, kind: SpringKind) -> f32 {
        self.max_strain_at(kind, &self.particles.x)
    }

    /// [`Self::max_strain`] with the particles at `x` (m) instead of where
    /// they are; infinite for positions of another count.
    pub(crate) fn max_strain_at(&self, kind: SpringKind, x: &[Vector]) -> f32 {
        if x.len() != self.particles.x.len() {
            return f32::INFINITY;
        }
        let (a, b, rest) = self.springs_of(kind);
        // Eight running maxima (one is a chain of dependent `max`es; the
        // largest is the same value whichever way they are grouped, and
        // NaN is passed over either way). Once a step, by the solver's
        // divergence check.
        let mut most = [0.0f32; 8];
        for (k, ((&a, &b), &rest)) in a.iter().zip(b).zip(rest).enumerate() {
            let d = x[b as usize] - x[a as usize];
            let m = &mut most[k % 8];
            *m = m.max(d.length() / rest - 1.0);
        }
        most.into_iter().fold(0.0, f32::max)
    }

    /// Whether every spring of one kind is shorter than `1 + strain` times
    /// its rest length (false for a length that is not a number). The test
    /// of [`Self::max_strain`] `< strain` without a root or a division a
    /// spring: the solver's divergence check runs it once a step.
    pub fn strain_below(&self, kind: SpringKind, strain: f32) -> bool {
        self.strain_below_among(self.topology.springs.range(kind), strain)
    }

    /// [`Self::strain_below`] for the springs `range` (indices into the
    /// cloth's springs), which a divergence check shares among threads.
    pub(crate) fn strain_below_among(&self, range: std::ops::Range<usize>, strain: f32) -> bool {
        let springs = &self.topology.springs;
        let (a, b) = springs.endpoints();
        let rest = &springs.rest_lengths()[range.clone()];
        let (a, b) = (&a[range.clone()], &b[range]);
        let x = &self.particles.x;
        let factor = 1.0 + strain;
        // One `and` over all (no early exit: the loop stays branch-free).
        let mut within = true;
        for ((&a, &b), &rest) in a.iter().zip(b).zip(rest) {
            let d = x[b as usize] - x[a as usize];
            let limit = rest * factor;
            within &= d.length_squared() < limit * limit;
        }
        within
    }

    /// Kinetic, gravitational and elastic energy, in joules.
    pub fn energy(&self) -> Energy {
        let p = &self.particles;
        let g = self.params.gravity;
        let mut e = Energy::default();
        for i in 0..p.len() {
            if p.inv_mass[i] == 0.0 {
                continue;
            }
            let m = p.mass[i] as f64;
            e.kinetic += 0.5 * m * p.v[i].length_squared() as f64;
            e.gravity -= m * g.dot(p.x[i]) as f64;
        }
        let springs = &self.topology.springs;
        for kind in SpringKind::ALL {
            let k = self.material.params(kind).stiffness as f64;
            for s in springs.range(kind) {
                let d = p.x[springs.b[s] as usize] - p.x[springs.a[s] as usize];
                let stretch = d.length() as f64 - springs.rest[s] as f64;
                e.elastic += 0.5 * k * stretch * stretch;
            }
        }
        e
    }

    /// Total linear momentum of the free particles, in kg·m/s.
    pub fn momentum(&self) -> Vector {
        let p = &self.particles;
        (0..p.len())
            .filter(|&i| p.inv_mass[i] != 0.0)
            .map(|i| p.v[i] * p.mass[i])
            .sum()
    }

    /// Mass-weighted centre of the particles, in metres.
    pub fn centroid(&self) -> Vector {
        let p = &self.particles;
        let total: f32 = p.mass.iter().sum();
        (0..p.len()).map(|i| p.x[i] * p.mass[i]).sum::<Vector>() / total
    }

    /// True when every position and velocity is finite.
    pub fn is_finite(&self) -> bool {
        self.particles.x.iter().all(|x| x.is_finite())
            && self.particles.v.iter().all(|v| v.is_finite())
    }

    /// Unit normal of every particle, averaged from the triangles around it
    /// (area-weighted); `+y` for a particle in no triangle.
    pub fn vertex_normals(&self) -> Vec<Vector> {
        let mut normals = vec![Vector::ZERO; self.particles.len()];
        self.vertex_normals_into(&mut normals);
        normals
    }

    /// Like [`Cloth::vertex_normals`], into a buffer of the right length.
    pub fn vertex_normals_into(&self, normals: &mut [Vector]) {
        normals.fill(Vector::ZERO);
        let x = &self.particles.x;
        for t in &self.topology.triangles {
            let [a, b, c] = t.map(|i| i as usize);
            let n = (x[b] - x[a]).cross(x[c] - x[a]);
            normals[a] += n;
            normals[b] += n;
            normals[c] += n;
        }
        for n in normals.iter_mut() {
            *n = n.try_normalize().unwrap_or(Vector::Y);
        }
    }
}
