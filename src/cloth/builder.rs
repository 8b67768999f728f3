//! The grid builder.

use std::sync::Arc;

use super::cloth::Cloth;
use super::material::Material;
use super::physics::PhysicsParams;
use super::pins::PinPreset;
use super::springs::{grid_topology, Spring};
use super::topology::Grid;
use crate::error::{positive, ClothError};
use crate::math::{Pose, Rotation, Vector};

/// How the mass of a grid cloth is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MassSpec {
    /// Total mass in kg, spread by area: each particle carries its share
    /// of the cells (or faces) it is a corner of.
    Total(f32),
    /// From the material's areal density (kg/m²) times the area.
    FromDensity,
}

/// Builds a rectangular grid cloth.
///
/// The grid is laid out in its local x–z plane, centred on the origin, with
/// column `c` at `x = -width/2 + c·width/(cols-1)` and row `r` at
/// `z = -height/2 + r·height/(rows-1)`; its front faces `+y`. The pose then
/// places it in the world: [`ClothBuilder::vertical`] turns it upright in the
/// x–y plane with row 0 on top.
///
/// ```
/// use cloth3d::prelude::*;
/// let cloth = ClothBuilder::new(16, 16)
///     .size(1.0, 1.0)
///     .horizontal(Vector::new(0.0, 0.6, 0.0))
///     .total_mass(1.0)
///     .material(Material::denim())
///     .pins(PinPreset::TwoCorners)
///     .build()
///     .unwrap();
/// assert_eq!(cloth.particle_count(), 256);
/// ```
#[derive(Debug, Clone)]
pub struct ClothBuilder {
    cols: usize,
    rows: usize,
    width: f32,
    height: f32,
    pose: Pose,
    mass: MassSpec,
    material: Material,
    preset: PinPreset,
    pins: Vec<usize>,
    params: PhysicsParams,
}

impl ClothBuilder {
    /// A `cols × rows` grid of particles, 1 × 1 m, horizontal at the origin,
    /// 1 kg, cotton, nothing pinned.
    pub fn new(cols: usize, rows: usize) -> Self {
        Self {
            cols,
            rows,
            width: 1.0,
            height: 1.0,
            pose: Pose::IDENTITY,
            mass: MassSpec::Total(1.0),
            material: Material::cotton(),
            preset: PinPreset::None,
            pins: Vec::new(),
            params: PhysicsParams::default(),
        }
    }

    /// Width (along the columns, local x) and height (along the rows, local z), in metres.
    pub fn size(mut self, width: f32, height: f32) -> Self {
        self.width = width;
        self.height = height;
        self
    }

    /// Places the grid with any pose.
    pub fn pose(mut self, pose: Pose) -> Self {
        self.pose = pose;
        self
    }

    /// Horizontal, facing up, centred on `center`.
    pub fn horizontal(mut self, center: Vector) -> Self {
        self.pose = Pose::from_translation(center);
        self
    }

    /// Upright in the x–y plane, facing `+z`, row 0 on top, centred on `center`.
    pub fn vertical(mut self, center: Vector) -> Self {
        self.pose = Pose::from_parts(
            center,
            Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2),
        );
        self
    }

    /// Total mass in kg, spread by area: an inner particle carries a cell's
    /// worth, a border particle half that, a corner a quarter.
    pub fn total_mass(mut self, mass: f32) -> Self {
        self.mass = MassSpec::Total(mass);
        self
    }

    /// Mass from the material's density times the area.
    pub fn mass_from_density(mut self) -> Self {
        self.mass = MassSpec::FromDensity;
        self
    }

    /// The material.
    pub fn material(mut self, material: Material) -> Self {
        self.material = material;
        self
    }

    /// Pins a preset figure.
    pub fn pins(mut self, preset: PinPreset) -> Self {
        self.preset = preset;
        self
    }

    /// Pins one more particle by index.
    pub fn pin(mut self, index: usize) -> Self {
        self.pins.push(index);
        self
    }

    /// The physical parameters: gravity, air drag, wind, thickness,
    /// self-collision.
    pub fn params(mut self, params: PhysicsParams) -> Self {
        self.params = params;
        self
    }

    /// Keep the cloth from passing through itself (its particles stay the
    /// thickness away from its own triangles); off by default.
    pub fn self_collision(mut self, on: bool) -> Self {
        self.params.self_collision = on;
        self
    }

    /// Tethers on or off (see [`PhysicsParams::tethers`]).
    pub fn tethers(mut self, on: bool) -> Self {
        self.params.tethers = on;
        self
    }

    /// Checks everything and builds the cloth.
    pub fn build(self) -> Result<Cloth, ClothError> {
        let (cols, rows) = (self.cols, self.rows);
        if cols < 2 || rows < 2 {
            return Err(ClothError::GridTooSmall { cols, rows });
        }
        const MAX: usize = 1 << 26;
        if cols.checked_mul(rows).is_none_or(|n| n > MAX) {
            return Err(ClothError::GridTooLarge {
                cols,
                rows,
                max: MAX,
            });
        }
        positive("width", self.width)?;
        positive("height", self.height)?;
        if !(self.pose.translation.is_finite() && self.pose.rotation.is_finite()) {
            return Err(ClothError::NonFinite { name: "cloth pose" });
        }
        self.material.validate()?;
        self.params.validate()?;
        let n = cols * rows;
        let total = match self.mass {
            MassSpec::Total(m) => positive("total mass", m)?,
            MassSpec::FromDensity => self.material.density * self.width * self.height,
        };
        // Each cell's mass is shared by its four corners: an inner particle
        // carries a cell's worth of cloth, one on the border half, a corner
        // a quarter (the masses a mesh cloth of the same cells gets).
        let cells = (cols - 1) * (rows - 1);
        let cell_mass = positive("particle mass", total / cells as f32)?;
        let border = |i: usize, last: usize| if i == 0 || i == last { 0.5 } else { 1.0 };
        let masses = (0..n)
            .map(|i| cell_mass * border(i % cols, cols - 1) * border(i / cols, rows - 1))
            .collect();
        let (dx, dz) = (
            self.width / (cols - 1) as f32,
            self.height / (rows - 1) as f32,
        );
        let mut positions = Vec::with_capacity(n);
        let mut uvs = Vec::with_capacity(n);
        for r in 0..rows {
            for c in 0..cols {
                let local = Vector::new(
                    -0.5 * self.width + c as f32 * dx,
                    0.0,
                    -0.5 * self.height + r as f32 * dz,
                );
                positions.push(self.pose.transform_point(local));
                uvs.push([c as f32 / (cols - 1) as f32, r as f32 / (rows - 1) as f32]);
            }
        }
        let (topology, triangles) = grid_topology(cols, rows);
        let springs = topology
            .into_iter()
            .map(|(a, b, kind)| Spring {
                a: a as u32,
                b: b as u32,
                rest_length: (positions[b] - positions[a]).length(),
                kind,
            })
            .collect();
        let mut cloth = Cloth::from_parts(positions, masses, springs, triangles, self.material)?;
        let topology = Arc::make_mut(&mut cloth.topology);
        topology.uvs = uvs;
        topology.grid = Some(Grid { cols, rows });
        cloth.params = self.params;
        cloth.apply_pin_preset(self.preset)?;
        for i in self.pins {
            cloth.pin(i)?;
        }
        Ok(cloth)
    }
}
