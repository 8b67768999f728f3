//! Normal-cone culling of self-collision (Volino and Magnenat-Thalmann
//! 1994, "Efficient self-collision detection on smoothly discretized
//! surface animations"): a grid cloth cut into square patches of a few
//! cells ([`PATCH`]), each with its box and the cone of its triangles'
//! normals. A patch whose box meets only its neighbouring patches, and
//! whose normals together with each such neighbour's stay within
//! [`MAX_CONE`] of one direction, is a bent sheet that cannot touch itself
//! (points near each other in space are then near along the cloth, where
//! the springs hold them); its triangles skip the look for pairs. A cloth
//! lying flat or draped over a ball skips most of its triangles; folds
//! and layers do not. Cloths joined into one are patched piece by piece:
//! patches of two pieces are quiet only while out of each other's reach.

use crate::cloth::GridPiece;
use crate::math::Vector;

/// Cells along a patch's side, at least: small enough that a wrinkled
/// skirt still has quiet patches (8 left the drape's none), and as many
/// more as keep the patches at most [`MAX_ACROSS`] along a side (the
/// patches' boxes are compared pairwise).
const PATCH: usize = 4;

/// Patches along a side of a grid, at most.
const MAX_ACROSS: usize = 16;

/// The largest angle (radians) between the normals of two neighbouring
/// patches and one direction for the two to count as one sheet.
const MAX_CONE: f32 = std::f32::consts::FRAC_PI_3;

/// How one grid piece of the cloth is cut into patches.
#[derive(Debug, Clone, Copy)]
struct PieceLayout {
    /// Where the piece's particles and triangles start in the cloth.
    first_particle: usize,
    first_triangle: usize,
    /// Cells along a row and along a column of its grid.
    cells_across: usize,
    cells_down: usize,
    /// Cells along a patch's side.
    side: usize,
    /// Patches along a row and along a column.
    across: usize,
    down: usize,
    /// Index of its first patch among all the cloth's.
    first_patch: usize,
}

impl PieceLayout {
    fn particles(&self) -> std::ops::Range<usize> {
        self.first_particle..self.first_particle + (self.cells_across + 1) * (self.cells_down + 1)
    }

    fn patches(&self) -> std::ops::Range<usize> {
        self.first_patch..self.first_patch + self.across * self.down
    }

    /// Calls `f` with each of the piece's cells' first triangle (counted
    /// in the cloth; two per cell, row by row) and its patch, in triangle
    /// order, without a division (a division or two a triangle were a
    /// tenth of the update).
    fn for_each_cell(&self, mut f: impl FnMut(usize, usize)) {
        for r in 0..self.cells_down {
            let row_patch = self.first_patch + (r / self.side) * self.across;
            let row_triangle = self.first_triangle + 2 * r * self.cells_across;
            for i in 0..self.across {
                let end = ((i + 1) * self.side).min(self.cells_across);
                for c in i * self.side..end {
                    f(row_triangle + 2 * c, row_patch + i);
                }
            }
        }
    }

    /// The patch at `(column, row)` among the piece's patches.
    fn patch_at(&self, i: usize, j: usize) -> usize {
        self.first_patch + j.min(self.down - 1) * self.across + i.min(self.across - 1)
    }
}

/// The patches of a cloth's grids and which are quiet at the last update.
#[derive(Debug, Default, Clone)]
pub(crate) struct Patches {
    /// The grid pieces, in triangle (and particle) order.
    pieces: Vec<PieceLayout>,
    /// Per patch: its box (m).
    lo: Vec<Vector>,
    hi: Vec<Vector>,
    /// Per patch: the sum of its triangles' area-weighted normals.
    axis: Vec<Vector>,
    /// Per patch: the widest angle (radians) between a triangle's normal
    /// and the patch's axis.
    spread: Vec<f32>,
    /// Per patch: true when its triangles need no look.
    quiet: Vec<bool>,
    /// Per triangle of the cloth: its patch's `quiet` (false in no patch).
    quiet_triangles: Vec<bool>,
    /// Per triangle of the cloth: its normal scaled by twice its area
    /// (zero in no patch), scratch of the update.
    normals: Vec<Vector>,
}

impl Patches {
    /// Works out which patches of the cloth's grid `pieces` (each with its
    /// triangles two per cell, row by row, as `ClothBuilder` makes them) are
    /// quiet at positions `x`, for pairs within `reach` metres. Triangles in
    /// no grid piece are never quiet; a piece that does not fit the cloth
    /// (fewer particles or triangles than it claims) is left out.
    pub fn update(
        &mut self,
        x: &[Vector],
        pieces: impl Iterator<Item = GridPiece>,
        triangles: &[[u32; 3]],
        reach: f32,
    ) {
        self.pieces.clear();
        let mut count = 0;
        let mut next_triangle = 0;
        for piece in pieces {
            let g = piece.grid;
            let fits = g.cols >= 2
                && g.rows >= 2
                && piece.first_triangle >= next_triangle
                && piece.triangles().end <= triangles.len()
                && piece.particles().end <= x.len();
            if !fits {
                continue;
            }
            next_triangle = piece.triangles().end;
            let (cells_across, cells_down) = (g.cols - 1, g.rows - 1);
            let side = PATCH.max(cells_across.max(cells_down).div_ceil(MAX_ACROSS));
            let layout = PieceLayout {
                first_particle: piece.first_particle,
                first_triangle: piece.first_triangle,
                cells_across,
                cells_down,
                side,
                across: cells_across.div_ceil(side),
                down: cells_down.div_ceil(side),
                first_patch: count,
            };
            count = layout.patches().end;
            self.pieces.push(layout);
        }
        self.lo.clear();
        self.lo.resize(count, Vector::splat(f32::INFINITY));
        self.hi.clear();
        self.hi.resize(count, Vector::splat(f32::NEG_INFINITY));
        self.axis.clear();
        self.axis.resize(count, Vector::ZERO);
        // First each patch's least cosine (−∞ for a triangle or axis that
        // is not a number): the widest angle is its arc cosine, one a patch
        // rather than one a triangle (the arc cosine was 2% of the fold).
        self.spread.clear();
        self.spread.resize(count, 1.0);
        self.normals.clear();
        self.normals.resize(triangles.len(), Vector::ZERO);
        let (lo, hi, axis, normals) = (
            &mut self.lo,
            &mut self.hi,
            &mut self.axis,
            &mut self.normals,
        );
        for piece in &self.pieces {
            piece.for_each_cell(|first, k| {
                for t in [first, first + 1] {
                    let [a, b, c] = triangles[t].map(|i| x[i as usize]);
                    lo[k] = lo[k].min(a.min(b).min(c));
                    hi[k] = hi[k].max(a.max(b).max(c));
                    let n = (b - a).cross(c - a);
                    normals[t] = n;
                    axis[k] += n;
                }
            });
        }
        let spread = &mut self.spread;
        for piece in &self.pieces {
            piece.for_each_cell(|first, k| {
                for n in [normals[first], normals[first + 1]] {
                    let cos = n.dot(axis[k]) / (n.length() * axis[k].length());
                    let cos = if cos.is_finite() {
                        cos
                    } else {
                        f32::NEG_INFINITY
                    };
                    spread[k] = spread[k].min(cos);
                }
            });
        }
        for spread in &mut self.spread {
            // NaN (a degenerate triangle or axis) counts as the widest.
            *spread = if *spread == f32::NEG_INFINITY {
                std::f32::consts::PI
            } else {
                spread.clamp(-1.0, 1.0).acos()
            };
        }
        self.quiet.clear();
        let pad = Vector::splat(reach);
        for piece in &self.pieces {
            for k in piece.patches() {
                let local = k - piece.first_patch;
                let (i, j) = (local % piece.across, local / piece.across);
                // Patches of other pieces must be out of reach; of this
                // one, out of reach or a neighbour on one sheet with it.
                let quiet = self.spread[k] < MAX_CONE
                    && (0..count).filter(|&m| m != k).all(|m| {
                        let apart = (self.lo[k] - pad).cmpgt(self.hi[m]).any()
                            || (self.hi[k] + pad).cmplt(self.lo[m]).any();
                        if apart {
                            return true;
                        }
                        if !piece.patches().contains(&m) {
                            return false;
                        }
                        let other = m - piece.first_patch;
                        let (mi, mj) = (other % piece.across, other / piece.across);
                        match mi.abs_diff(i).max(mj.abs_diff(j)) {
                            1 => self.one_sheet(k, m),
                            // A grid turned about its normal has boxes
                            // wider than its patches, which reach the
                            // patches two away: one sheet with those
                            // between too.
                            2 => self.one_sheet_over(
                                piece,
                                (i.min(mi), j.min(mj)),
                                (i.max(mi), j.max(mj)),
                            ),
                            _ => false,
                        }
                    });
                self.quiet.push(quiet);
            }
        }
        self.quiet_triangles.clear();
        self.quiet_triangles.resize(triangles.len(), false);
        let quiet_triangles = &mut self.quiet_triangles;
        for piece in &self.pieces {
            piece.for_each_cell(|first, k| {
                quiet_triangles[first] = self.quiet[k];
                quiet_triangles[first + 1] = self.quiet[k];
            });
        }
    }

    /// True when triangle `t` needs no look.
    pub fn quiet_triangle(&self, t: usize) -> bool {
        self.quiet_triangles.get(t).copied().unwrap_or(false)
    }

    /// True when particle `p` lies in a grid piece, and there only in quiet
    /// patches' cells (the cells of which it is a corner).
    pub fn quiet_particle(&self, p: usize) -> bool {
        let Some(piece) = self
            .pieces
            .iter()
            .find(|piece| piece.particles().contains(&p))
        else {
            return false;
        };
        let cols = piece.cells_across + 1;
        let local = p - piece.first_particle;
        let (r, c) = (local / cols, local % cols);
        let rows = [r.saturating_sub(1), r.min(piece.cells_down - 1)];
        let columns = [c.saturating_sub(1), c.min(piece.cells_across - 1)];
        rows.iter().all(|&cr| {
            columns
                .iter()
                .all(|&cc| self.quiet[piece.patch_at(cc / piece.side, cr / piece.side)])
        })
    }

    /// True when the patches of `piece` from column and row `from` to `to`
    /// (inclusive) together keep their normals within [`MAX_CONE`] of one
    /// direction: their summed axis, and each patch's cone about it.
    fn one_sheet_over(
        &self,
        piece: &PieceLayout,
        from: (usize, usize),
        to: (usize, usize),
    ) -> bool {
        let block = || {
            (from.1..=to.1).flat_map(move |j| (from.0..=to.0).map(move |i| piece.patch_at(i, j)))
        };
        let axis = block().fold(Vector::ZERO, |sum, k| sum + self.axis[k]);
        block().all(|k| {
            let a = self.axis[k];
            let cos = a.dot(axis) / (a.length() * axis.length());
            cos.is_finite() && cos.clamp(-1.0, 1.0).acos() + self.spread[k] < MAX_CONE
        })
    }

    /// True when patches `k` and `m` together keep their normals within
    /// [`MAX_CONE`] of one direction.
    fn one_sheet(&self, k: usize, m: usize) -> bool {
        let (a, b) = (self.axis[k], self.axis[m]);
        let cos = a.dot(b) / (a.length() * b.length());
        if !cos.is_finite() {
            return false;
        }
        let between = cos.clamp(-1.0, 1.0).acos();
        // The narrowest cone over both: the wider one if it holds the
        // other, else half of the axes' angle and both spreads.
        let (sk, sm) = (self.spread[k], self.spread[m]);
        sk.max(sm).max(0.5 * (between + sk + sm)) < MAX_CONE
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Cloth, ClothBuilder, Grid};
    use crate::math::{Pose, Rotation};

    /// A flat cloth needs no look anywhere; folded in two, the patches
    /// facing each other across the fold do, and the flat ones beyond the
    /// other layer's reach do not.
    #[test]
    fn flat_is_quiet_and_facing_layers_are_not() {
        let mut cloth = ClothBuilder::new(33, 17).size(1.0, 0.5).build().unwrap();
        let triangles = cloth.triangles().to_vec();
        let topology = cloth.topology().clone();
        let grid = || topology.grid_pieces();
        let mut patches = Patches::default();
        patches.update(cloth.positions(), grid(), &triangles, 0.02);
        assert!((0..triangles.len()).all(|t| patches.quiet_triangle(t)));
        assert!(patches.quiet_particle(0) && patches.quiet_particle(33 * 17 - 1));
        // Lay columns 24.. back over columns 16..24, 1.5 cm above: a flap.
        for r in 0..17 {
            for c in 24..33 {
                let i = cloth.index(r, c).unwrap();
                let under = cloth.positions()[cloth.index(r, 48 - c).unwrap()];
                cloth
                    .set_position(i, under + Vector::new(0.0, 0.015, 0.0))
                    .unwrap();
            }
        }
        patches.update(cloth.positions(), grid(), &triangles, 0.02);
        // Cell (8, 28) lies in the flap, cell (8, 18) under it, cell (8, 4)
        // far from both.
        let t = |r: usize, c: usize| 2 * (r * 32 + c);
        assert!(!patches.quiet_triangle(t(8, 28)));
        assert!(!patches.quiet_triangle(t(8, 18)));
        assert!(patches.quiet_triangle(t(8, 4)));
        // Off a grid, nothing is quiet.
        patches.update(cloth.positions(), std::iter::empty(), &triangles, 0.02);
        assert!(!patches.quiet_triangle(0));
    }

    /// Cloths joined into one are patched piece by piece: two flat pieces
    /// far apart need no look; one lowered to 1.5 cm above the other, the
    /// patches facing each other do (a patch of one piece is never the
    /// other's neighbour), and a third piece far off still needs none.
    #[test]
    fn joined_pieces_are_quiet_apart_and_not_stacked() {
        // Turned about its normal (the third piece), a grid's patch boxes
        // reach the patches two away: those are one sheet with it too.
        let piece = |y: f32, x: f32, turn: f32| {
            let at = Vector::new(x, y, 0.0);
            ClothBuilder::new(17, 9)
                .size(0.5, 0.25)
                .pose(Pose::from_parts(at, Rotation::from_rotation_y(turn)))
                .build()
                .unwrap()
        };
        let mut cloth = Cloth::join(vec![
            piece(0.0, 0.0, 0.0),
            piece(1.0, 0.0, 0.0),
            piece(0.0, 5.0, 0.8),
        ])
        .unwrap();
        assert!(cloth.grid().is_none());
        let topology = cloth.topology().clone();
        assert_eq!(topology.grid_pieces().count(), 3);
        let triangles = cloth.triangles().to_vec();
        let (per_piece, per_piece_triangles) = (17 * 9, 2 * 16 * 8);
        let mut patches = Patches::default();
        patches.update(cloth.positions(), topology.grid_pieces(), &triangles, 0.02);
        assert!((0..triangles.len()).all(|t| patches.quiet_triangle(t)));
        assert!((0..3 * per_piece).all(|p| patches.quiet_particle(p)));
        // The second piece down to 1.5 cm above the first.
        for i in per_piece..2 * per_piece {
            let below = cloth.positions()[i - per_piece];
            cloth
                .set_position(i, below + Vector::new(0.0, 0.015, 0.0))
                .unwrap();
        }
        patches.update(cloth.positions(), topology.grid_pieces(), &triangles, 0.02);
        for t in 0..2 * per_piece_triangles {
            assert!(
                !patches.quiet_triangle(t),
                "triangle {t} of a stacked piece"
            );
        }
        assert!(!patches.quiet_particle(0) && !patches.quiet_particle(per_piece));
        let third = 2 * per_piece_triangles..3 * per_piece_triangles;
        assert!(third.clone().all(|t| patches.quiet_triangle(t)));
        assert!(patches.quiet_particle(2 * per_piece + 5));
        // Past the last piece's triangles (none here) or with pieces that
        // claim more than the cloth has: nothing quiet, nothing out of bounds.
        patches.update(
            &cloth.positions()[..10],
            topology.grid_pieces(),
            &triangles,
            0.02,
        );
        assert!(!patches.quiet_triangle(0) && !patches.quiet_particle(0));
        let huge = GridPiece {
            first_particle: 5,
            first_triangle: 0,
            grid: Grid {
                cols: usize::MAX,
                rows: 3,
            },
        };
        patches.update(cloth.positions(), std::iter::once(huge), &triangles, 0.02);
        assert!(!patches.quiet_triangle(0) && !patches.quiet_particle(7));
    }
}
