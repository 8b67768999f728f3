//! The cloth model: particles, springs, triangles, pins, material and parameters.

mod builder;
mod material;
mod pins;
mod springs;

pub use builder::{ClothBuilder, MassSpec};
pub use material::{Material, SpringParams};
pub use pins::PinPreset;
pub use springs::{Spring, SpringKind, Springs};

use serde::{Deserialize, Serialize};

use crate::error::{finite_vec, non_negative, positive, ClothError};
use crate::integrators::{Integrator, Preconditioner, Workspace};
use crate::math::Vector;

/// The particles of a cloth, as structure-of-arrays.
///
/// A particle with inverse mass 0 is pinned: no force moves it; it moves only
/// with the velocity it is given (a kinematic pin) or when it is set on purpose.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Particles {
    /// Positions, in metres.
    pub(crate) x: Vec<Vector>,
    /// Velocities, in m/s.
    pub(crate) v: Vec<Vector>,
    /// Positions at the start of the last substep, in metres.
    pub(crate) x_prev: Vec<Vector>,
    /// Masses, in kg (kept while pinned, so unpinning restores them).
    pub(crate) mass: Vec<f32>,
    /// Inverse masses, in 1/kg; 0 for a pinned particle.
    pub(crate) inv_mass: Vec<f32>,
    /// Per particle: the pull (in the fast mass-spring solver's units) with
    /// which static friction held it on a surface in the last substep, zero
    /// when not held; the next substep keeps the hold while it stays in the
    /// friction cone. Part of the state, so a snapshot resumes bit for bit;
    /// empty until that solver runs.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) held_force: Vec<Vector>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there is no particle.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
}

/// Wind blowing on every triangle: `F = c A (n·d) n`, with `c` the strength,
/// `A` the triangle's area, `d` the unit direction and `n` the unit normal,
/// shared equally among the triangle's three particles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wind {
    /// Direction the wind blows towards (need not be normalised; zero means no wind).
    #[serde(deserialize_with = "crate::error::de::finite_vec")]
    pub direction: Vector,
    /// Strength `c`, a pressure in N/m².
    #[serde(deserialize_with = "crate::error::de::non_negative")]
    pub strength: f32,
}

impl Wind {
    /// No wind.
    pub const NONE: Wind = Wind {
        direction: Vector::ZERO,
        strength: 0.0,
    };

    /// Wind towards `direction` with pressure `strength` in N/m².
    pub fn new(direction: Vector, strength: f32) -> Self {
        Self {
            direction,
            strength,
        }
    }

    /// True when it exerts no force.
    pub fn is_calm(&self) -> bool {
        self.strength == 0.0 || self.direction.length_squared() == 0.0
    }
}

/// How many substeps a frame step is split into.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Substeps {
    /// Exactly this many (at least 1).
    Fixed(u32),
    /// As many as the integrator needs to stay within its stability limit,
    /// estimated from the stiffest spring and the lightest particle.
    Auto,
}

impl std::fmt::Display for Substeps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Substeps::Fixed(k) => write!(f, "{k}"),
            Substeps::Auto => write!(f, "auto"),
        }
    }
}

impl std::str::FromStr for Substeps {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Substeps::Auto);
        }
        match s.parse::<u32>() {
            Ok(k) if k >= 1 => Ok(Substeps::Fixed(k)),
            _ => Err(format!(
                "invalid substeps '{s}': expected a whole number >= 1 or 'auto'"
            )),
        }
    }
}

/// The simulation parameters of a cloth; all can change between steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulationParams {
    /// The time integrator.
    pub integrator: Integrator,
    /// How each frame step is split.
    pub substeps: Substeps,
    /// Gravity, in m/s².
    pub gravity: Vector,
    /// Air drag: each particle feels `-drag · m · v`; in 1/s.
    pub air_drag: f32,
    /// Wind on the triangles.
    pub wind: Wind,
    /// Collision thickness: particles are kept this far outside obstacles, in metres.
    pub thickness: f32,
    /// Linearisations per substep of the implicit integrator (1 is Baraff and
    /// Witkin's single linear solve; more are Newton iterations that keep
    /// large steps of strongly bent cloth from overshooting).
    pub newton_iterations: u32,
    /// Maximum conjugate-gradient iterations of the implicit integrator, per linearisation.
    pub cg_max_iterations: u32,
    /// Relative residual at which conjugate gradient stops.
    pub cg_tolerance: f32,
    /// Preconditioner of that conjugate gradient.
    #[serde(default)]
    pub preconditioner: Preconditioner,
    /// Local/global iterations of the fast mass-spring solver.
    pub fms_iterations: u32,
    /// Also keep stretch and shear springs (not only particles) out of obstacles,
    /// so cloth cannot cut through edges and corners.
    pub edge_collisions: bool,
    /// Evaluate spring forces on several threads (with the `parallel` feature;
    /// ignored without it). The results are bit-identical either way.
    #[serde(default = "default_true")]
    pub parallel: bool,
}

fn default_true() -> bool {
    true
}

impl Default for SimulationParams {
    fn default() -> Self {
        Self {
            integrator: Integrator::SymplecticEuler,
            substeps: Substeps::Auto,
            gravity: Vector::new(0.0, -9.81, 0.0),
            air_drag: 0.02,
            wind: Wind::NONE,
            thickness: 0.01,
            newton_iterations: 2,
            cg_max_iterations: 100,
            cg_tolerance: 1e-4,
            preconditioner: Preconditioner::BlockJacobi,
            fms_iterations: 10,
            edge_collisions: true,
            parallel: true,
        }
    }
}

impl SimulationParams {
    /// Checks every value and says which one is wrong.
    pub fn validate(&self) -> Result<(), ClothError> {
        if let Substeps::Fixed(0) = self.substeps {
            return Err(ClothError::InvalidParameter {
                name: "substeps",
                value: 0.0,
                expected: "a whole number >= 1 or auto",
            });
        }
        finite_vec("gravity", self.gravity)?;
        non_negative("air drag", self.air_drag)?;
        finite_vec("wind direction", self.wind.direction)?;
        non_negative("wind strength", self.wind.strength)?;
        non_negative("thickness", self.thickness)?;
        if self.newton_iterations == 0 {
            return Err(ClothError::InvalidParameter {
                name: "newton iterations",
                value: 0.0,
                expected: "a whole number >= 1",
            });
        }
        if self.cg_max_iterations == 0 {
            return Err(ClothError::InvalidParameter {
                name: "cg iterations",
                value: 0.0,
                expected: "a whole number >= 1",
            });
        }
        positive("cg tolerance", self.cg_tolerance)?;
        if self.fms_iterations == 0 {
            return Err(ClothError::InvalidParameter {
                name: "fast mass-spring iterations",
                value: 0.0,
                expected: "a whole number >= 1",
            });
        }
        Ok(())
    }
}

/// The grid a cloth was built on: particle `(row, col)` has index `row * cols + col`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Grid {
    /// Particles along a row.
    pub cols: usize,
    /// Particles along a column.
    pub rows: usize,
}

/// Kinetic, gravitational and elastic energy of a cloth, in joules.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Energy {
    /// `Σ ½ m v²` over free particles.
    pub kinetic: f64,
    /// `Σ -m g·x` over free particles.
    pub gravity: f64,
    /// `Σ ½ k (|x_ij| - L)²` over all springs.
    pub elastic: f64,
}

impl Energy {
    /// The sum of the three parts.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravity + self.elastic
    }
}

/// A mass-spring cloth: particles, springs, triangles, pins, material and
/// simulation parameters, plus the integrators' scratch memory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Cloth {
    pub(crate) particles: Particles,
    pub(crate) springs: Springs,
    pub(crate) triangles: Vec<[u32; 3]>,
    pub(crate) uvs: Vec<[f32; 2]>,
    pub(crate) grid: Option<Grid>,
    /// The material: spring stiffness and damping per kind, density, colour.
    pub material: Material,
    /// Integrator, substeps, gravity, drag, wind, thickness.
    pub params: SimulationParams,
    /// Simulated time so far, in seconds.
    pub(crate) time: f64,
    #[serde(skip)]
    pub(crate) workspace: Workspace,
}

impl PartialEq for Cloth {
    fn eq(&self, other: &Self) -> bool {
        self.particles == other.particles
            && self.springs == other.springs
            && self.triangles == other.triangles
            && self.uvs == other.uvs
            && self.grid == other.grid
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
                held_force: Vec::new(),
            },
            springs: Springs::from_list(springs),
            triangles,
            uvs: vec![[0.0, 0.0]; n],
            grid: None,
            material,
            params: SimulationParams::default(),
            time: 0.0,
            workspace: Workspace::default(),
        })
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.particles.len()
    }

    /// The grid this cloth was built on, if it was built by [`ClothBuilder`].
    pub fn grid(&self) -> Option<Grid> {
        self.grid
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
        &self.springs
    }

    /// The triangles, as particle index triples (counter-clockwise seen from the front).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Texture coordinates of each particle, in 0..=1.
    pub fn uvs(&self) -> &[[f32; 2]] {
        &self.uvs
    }

    /// Simulated time so far, in seconds.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Total mass in kg.
    pub fn total_mass(&self) -> f32 {
        self.particles.mass.iter().sum()
    }

    /// Index of grid cell `(row, col)`.
    pub fn index(&self, row: usize, col: usize) -> Result<usize, ClothError> {
        let grid = self.grid.ok_or(ClothError::NotAGrid)?;
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

    fn check_index(&self, i: usize) -> Result<(), ClothError> {
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
            self.workspace.invalidate();
        }
        Ok(())
    }

    /// Releases particle `i`; it gets its mass back.
    pub fn unpin(&mut self, i: usize) -> Result<(), ClothError> {
        self.check_index(i)?;
        if self.particles.inv_mass[i] == 0.0 {
            self.particles.inv_mass[i] = 1.0 / self.particles.mass[i];
            self.workspace.invalidate();
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
        self.workspace.invalidate();
    }

    /// Replaces the pins by a preset (grid cloths only).
    pub fn apply_pin_preset(&mut self, preset: PinPreset) -> Result<(), ClothError> {
        let grid = self.grid.ok_or(ClothError::NotAGrid)?;
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
        self.workspace.invalidate();
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
        self.workspace.invalidate();
        Ok(())
    }

    /// Switches the integrator; the cloth keeps its state.
    pub fn set_integrator(&mut self, integrator: Integrator) {
        self.params.integrator = integrator;
    }

    /// Length of spring `s` divided by its rest length, minus one.
    pub fn strain(&self, s: usize) -> Option<f32> {
        let sp = self.springs.get(s)?;
        let d = self.particles.x[sp.b as usize] - self.particles.x[sp.a as usize];
        Some(d.length() / sp.rest_length - 1.0)
    }

    /// The largest strain over the springs of one kind (0 when there is none).
    pub fn max_strain(&self, kind: SpringKind) -> f32 {
        self.springs
            .range(kind)
            .filter_map(|s| self.strain(s))
            .fold(0.0, f32::max)
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
        for kind in SpringKind::ALL {
            let k = self.material.params(kind).stiffness as f64;
            for s in self.springs.range(kind) {
                let d = p.x[self.springs.b[s] as usize] - p.x[self.springs.a[s] as usize];
                let stretch = d.length() as f64 - self.springs.rest[s] as f64;
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
        for t in &self.triangles {
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
