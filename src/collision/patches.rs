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
//! and layers do not.

use crate::cloth::Grid;
use crate::math::Vector;

/// Cells along a patch's side, at least: small enough that a wrinkled
/// skirt still has quiet patches (8 left the drape's none), and as many
/// more as keep the patches at most [`MAX_ACROSS`] along a side (the
/// patches' boxes are compared pairwise).
const PATCH: usize = 4;

/// Patches along a side of the grid, at most.
const MAX_ACROSS: usize = 16;

/// The largest angle (radians) between the normals of two neighbouring
/// patches and one direction for the two to count as one sheet.
const MAX_CONE: f32 = std::f32::consts::FRAC_PI_3;

/// The patches of a grid cloth and which are quiet at the last update.
#[derive(Debug, Default, Clone)]
pub(crate) struct Patches {
    /// Patches along a row and along a column.
    across: usize,
    down: usize,
    /// Cells along a row and along a column of the grid.
    cells_across: usize,
    cells_down: usize,
    /// Cells along a patch's side.
    side: usize,
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
}

impl Patches {
    /// Works out which patches of the cloth on `grid` (its triangles two
    /// per cell, row by row, as `ClothBuilder` makes them) are quiet at
    /// positions `x`, for pairs within `reach` metres. Off a grid, or with
    /// triangles laid out otherwise, none is.
    pub fn update(&mut self, x: &[Vector], grid: Option<Grid>, triangles: &[[u32; 3]], reach: f32) {
        let Some(g) = grid.filter(|g| {
            g.cols >= 2 && g.rows >= 2 && triangles.len() == 2 * (g.cols - 1) * (g.rows - 1)
        }) else {
            self.across = 0;
            self.quiet.clear();
            return;
        };
        self.cells_across = g.cols - 1;
        self.cells_down = g.rows - 1;
        self.side = PATCH.max(self.cells_across.max(self.cells_down).div_ceil(MAX_ACROSS));
        self.across = self.cells_across.div_ceil(self.side);
        self.down = self.cells_down.div_ceil(self.side);
        let count = self.across * self.down;
        self.lo.clear();
        self.lo.resize(count, Vector::splat(f32::INFINITY));
        self.hi.clear();
        self.hi.resize(count, Vector::splat(f32::NEG_INFINITY));
        self.axis.clear();
        self.axis.resize(count, Vector::ZERO);
        for (t, tri) in triangles.iter().enumerate() {
            let k = self.patch_of(t);
            let [a, b, c] = tri.map(|i| x[i as usize]);
            self.lo[k] = self.lo[k].min(a.min(b).min(c));
            self.hi[k] = self.hi[k].max(a.max(b).max(c));
            self.axis[k] += (b - a).cross(c - a);
        }
        self.spread.clear();
        self.spread.resize(count, 0.0);
        for (t, tri) in triangles.iter().enumerate() {
            let k = self.patch_of(t);
            let [a, b, c] = tri.map(|i| x[i as usize]);
            let n = (b - a).cross(c - a);
            let cos = n.dot(self.axis[k]) / (n.length() * self.axis[k].length());
            // NaN (a degenerate triangle or axis) counts as the widest.
            let angle = if cos.is_finite() {
                cos.clamp(-1.0, 1.0).acos()
            } else {
                std::f32::consts::PI
            };
            self.spread[k] = self.spread[k].max(angle);
        }
        self.quiet.clear();
        let pad = Vector::splat(reach);
        for k in 0..count {
            let (i, j) = (k % self.across, k / self.across);
            let quiet = self.spread[k] < MAX_CONE
                && (0..count).filter(|&m| m != k).all(|m| {
                    let apart = (self.lo[k] - pad).cmpgt(self.hi[m]).any()
                        || (self.hi[k] + pad).cmplt(self.lo[m]).any();
                    let neighbour =
                        (m % self.across).abs_diff(i) <= 1 && (m / self.across).abs_diff(j) <= 1;
                    apart || (neighbour && self.one_sheet(k, m))
                });
            self.quiet.push(quiet);
        }
    }

    /// True when triangle `t` needs no look.
    pub fn quiet_triangle(&self, t: usize) -> bool {
        self.across > 0 && self.quiet[self.patch_of(t)]
    }

    /// True when particle `p` of the grid lies only in quiet patches' cells
    /// (the cells of which it is a corner).
    pub fn quiet_particle(&self, p: usize) -> bool {
        if self.across == 0 {
            return false;
        }
        let cols = self.cells_across + 1;
        let (r, c) = (p / cols, p % cols);
        let rows = [r.saturating_sub(1), r.min(self.cells_down - 1)];
        let columns = [c.saturating_sub(1), c.min(self.cells_across - 1)];
        rows.iter().all(|&cr| {
            columns.iter().all(|&cc| {
                let k = (cr / self.side).min(self.down - 1) * self.across
                    + (cc / self.side).min(self.across - 1);
                self.quiet[k]
            })
        })
    }

    /// The patch of triangle `t` (two per cell, row by row).
    fn patch_of(&self, t: usize) -> usize {
        let cell = t / 2;
        let (r, c) = (cell / self.cells_across, cell % self.cells_across);
        (r / self.side) * self.across + c / self.side
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
    use crate::cloth::ClothBuilder;

    /// A flat cloth needs no look anywhere; folded in two, the patches
    /// facing each other across the fold do, and the flat ones beyond the
    /// other layer's reach do not.
    #[test]
    fn flat_is_quiet_and_facing_layers_are_not() {
        let mut cloth = ClothBuilder::new(33, 17).size(1.0, 0.5).build().unwrap();
        let (grid, triangles) = (cloth.grid(), cloth.triangles().to_vec());
        let mut patches = Patches::default();
        patches.update(cloth.positions(), grid, &triangles, 0.02);
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
        patches.update(cloth.positions(), grid, &triangles, 0.02);
        // Cell (8, 28) lies in the flap, cell (8, 18) under it, cell (8, 4)
        // far from both.
        let t = |r: usize, c: usize| 2 * (r * 32 + c);
        assert!(!patches.quiet_triangle(t(8, 28)));
        assert!(!patches.quiet_triangle(t(8, 18)));
        assert!(patches.quiet_triangle(t(8, 4)));
        // Off a grid, nothing is quiet.
        patches.update(cloth.positions(), None, &triangles, 0.02);
        assert!(!patches.quiet_triangle(0));
    }
}
