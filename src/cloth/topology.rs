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
    /// The grid the cloth was built on, if any.
    pub(crate) grid: Option<Grid>,
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

    /// The grid, for cloths built by `ClothBuilder`.
    pub fn grid(&self) -> Option<Grid> {
        self.grid
    }
}
