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

/// The grid the small-steps solver lays a cloth's particles out on
/// (`solver/grid_sweep`): the cloth's own grid, or for cloths of one
/// grid shape joined into one, their grids stacked one under the other
/// (piece `k`'s row `r` is row `k · piece_rows + r`), no spring crossing
/// from a piece into the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LaneGrid {
    /// The whole stack: columns, and rows of every piece together.
    pub grid: Grid,
    /// Rows of each piece (`grid.rows` for a grid cloth).
    pub piece_rows: usize,
}

impl LaneGrid {
    /// True when rows `a` and `b` are of the same piece.
    pub fn same_piece(&self, a: usize, b: usize) -> bool {
        let rows = self.piece_rows.max(1);
        a / rows == b / rows
    }

    /// The longer side (particles) of a piece.
    pub fn piece_side(&self) -> usize {
        self.grid.cols.max(self.piece_rows)
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

    /// The grid the small-steps solver lays the particles out on
    /// ([`LaneGrid`]): the cloth's grid, or the grids of its pieces
    /// stacked when every particle is in one of them, in order, and all
    /// have one shape; none otherwise (a torn cloth, a mesh, pieces of
    /// different widths).
    pub fn lane_grid(&self) -> Option<LaneGrid> {
        if let Some(grid) = self.grid {
            return Some(LaneGrid {
                grid,
                piece_rows: grid.rows,
            });
        }
        let first = self.pieces.first()?.grid;
        let count = first.cols.checked_mul(first.rows)?;
        let triangles = 2 * first
            .cols
            .checked_sub(1)?
            .checked_mul(first.rows.checked_sub(1)?)?;
        let stacked = self.pieces.iter().enumerate().all(|(k, piece)| {
            piece.grid == first
                && Some(piece.first_particle) == k.checked_mul(count)
                && Some(piece.first_triangle) == k.checked_mul(triangles)
        });
        let rows = first.rows.checked_mul(self.pieces.len())?;
        // Every particle (one texture coordinate each) and triangle in a piece.
        let whole = Some(self.uvs.len()) == rows.checked_mul(first.cols)
            && Some(self.triangles.len()) == triangles.checked_mul(self.pieces.len());
        (stacked && whole).then_some(LaneGrid {
            grid: Grid {
                cols: first.cols,
                rows,
            },
            piece_rows: first.rows,
        })
    }

    /// For a torn grid cloth (one grid, not joined, split since): the grid
    /// it was built on, whose `cols × rows` particles keep their cells and
    /// come first, the particles the splits made after them. Most of its
    /// springs are still the grid's; the small-steps solver sweeps those on
    /// the grid's lanes and the rest one by one (`solver/grid_leftover.rs`).
    pub fn torn_lane_grid(&self) -> Option<LaneGrid> {
        let grid = self.split_from.filter(|_| self.grid.is_none())?;
        let count = grid.cols.checked_mul(grid.rows)?;
        (self.pieces.is_empty() && self.uvs.len() >= count).then_some(LaneGrid {
            grid,
            piece_rows: grid.rows,
        })
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
