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

/// A grid among the pieces of a joined cloth ([`crate::cloth::Cloth::join`]):
/// its particles follow one another from `first_particle` on, row by row,
/// and its triangles from `first_triangle` on, two per cell, row by row (as
/// a grid cloth lays them out).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct GridPiece {
    /// Index of the piece's particle `(0, 0)` in the joined cloth.
    pub first_particle: usize,
    /// Index of the piece's first triangle in the joined cloth.
    pub first_triangle: usize,
    /// The piece's grid.
    pub grid: Grid,
}

impl GridPiece {
    /// The piece's particles in the joined cloth.
    pub fn particles(&self) -> std::ops::Range<usize> {
        // Saturating: a piece read from a file may claim any size.
        let count = self.grid.cols.saturating_mul(self.grid.rows);
        self.first_particle..self.first_particle.saturating_add(count)
    }

    /// The piece's triangles in the joined cloth.
    pub fn triangles(&self) -> std::ops::Range<usize> {
        let cells =
            (self.grid.cols.saturating_sub(1)).saturating_mul(self.grid.rows.saturating_sub(1));
        self.first_triangle..self.first_triangle.saturating_add(cells.saturating_mul(2))
    }
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
    /// For cloths joined into one and not torn since: the pieces that are
    /// grids (a joined cloth is no grid, but its pieces may be).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) pieces: Vec<GridPiece>,
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

    /// The parts of the cloth that are grids: the whole cloth when it is
    /// one ([`Topology::grid`]), else the grid pieces it was joined from
    /// (none once torn).
    pub fn grid_pieces(&self) -> impl Iterator<Item = GridPiece> + '_ {
        let whole = self.grid.map(|grid| GridPiece {
            first_particle: 0,
            first_triangle: 0,
            grid,
        });
        let joined = if whole.is_none() {
            &self.pieces[..]
        } else {
            &[]
        };
        whole.into_iter().chain(joined.iter().copied())
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
