//! What joins a cloth's particles: springs, triangles, texture coordinates
//! and the grid it was built on. Topology does not change as the cloth
//! moves, so cloths built alike can share one (`std::sync::Arc`).

use serde::{Deserialize, Serialize};

use super::springs::Springs;

/// The grid a cloth was built on: particle `(row, col)` has index `row * cols + col`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Grid {
    /// Particles along a row.
    pub cols: usize,
    /// Particles along a column.
    pub rows: usize,
}

/// The springs, triangles, texture coordinates and grid of a cloth.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Topology {
    /// The springs, sorted by kind and stored by colour class.
    pub(crate) springs: Springs,
    /// Triangles as particle index triples (counter-clockwise seen from the front).
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Texture coordinates of each particle, in 0..=1.
    pub(crate) uvs: Vec<[f32; 2]>,
    /// The grid the cloth was built on, if any, while it is whole.
    pub(crate) grid: Option<Grid>,
    /// The grid a torn cloth was built on: its first `cols × rows` particles
    /// keep their grid indices (`Cloth::index` still finds them), but the
    /// springs and triangles are no longer a grid's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) split_from: Option<Grid>,
    /// Every split so far, in order: the particle split and the new one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) splits: Vec<[u32; 2]>,
}

impl Topology {
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

    /// The grid, for cloths built by `ClothBuilder` and not torn since.
    pub fn grid(&self) -> Option<Grid> {
        self.grid
    }

    /// Every split so far, in order, as (particle split, new particle): a
    /// new particle started where the particle it came from was, so a frame
    /// recorded before the split can place it there (exports do).
    pub fn splits(&self) -> &[[u32; 2]] {
        &self.splits
    }

    /// The grid whose cells name the particles: [`Topology::grid`], or
    /// for a torn cloth the grid it was built on (its new particles are past
    /// the grid's).
    pub fn cells(&self) -> Option<Grid> {
        self.grid.or(self.split_from)
    }
}
