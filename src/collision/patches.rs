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
use crate::math::{simd_available, Vector};

/// Cells along a patch's side, at least: small enough that a wrinkled
/// skirt still has quiet patches (8 left the drape's none), and as many
/// more as keep the patches at most [`MAX_ACROSS`] along a side (the
/// patches' boxes are compared pairwise).
const PATCH: usize = 4;

/// Boxes a vector step of [`Patches::all_meeting`] tests at once.
const LANES: usize = 8;

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
    /// The patches' boxes coordinate by coordinate (`lo` x, y, z, then
    /// `hi`), padded to whole vector steps with boxes that meet none, for
    /// [`Patches::all_meeting`] eight at a time.
    boxes: [Vec<f32>; 6],
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
        let padded = count.next_multiple_of(LANES);
        for (a, b) in self.boxes.iter_mut().enumerate() {
            let (corners, none) = if a < 3 {
                (&self.lo, f32::INFINITY)
            } else {
                (&self.hi, f32::NEG_INFINITY)
            };
            b.clear();
            b.extend(corners.iter().map(|c| c[a % 3]));
            b.resize(padded, none);
        }
        for piece in &self.pieces {
            for k in piece.patches() {
                let local = k - piece.first_patch;
                let (i, j) = (local % piece.across, local / piece.across);
                // Patches of other pieces must be out of reach; of this
                // one, out of reach or a neighbour on one sheet with it.
                let quiet = self.spread[k] < MAX_CONE
                    && self.all_meeting(k, pad, |m| {
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

    /// True when `f` holds for every other patch whose box meets patch
    /// `k`'s padded by `pad` (m), asked in ascending order until one fails
    /// (ordered tests: a box that is not a number meets every other). Eight
    /// boxes at a time where the CPU has AVX2: the tests were most of an
    /// update of the `fold`'s 144 patches, a pair at a time.
    fn all_meeting(&self, k: usize, pad: Vector, mut f: impl FnMut(usize) -> bool) -> bool {
        let (lo, hi) = (self.lo[k] - pad, self.hi[k] + pad);
        #[cfg(target_arch = "x86_64")]
        if simd_available() {
            // SAFETY: only where the CPU has AVX2.
            return unsafe { self.all_meeting_avx2(k, (lo, hi), &mut f) };
        }
        self.all_meeting_portable(k, (lo, hi), f)
    }

    /// [`Patches::all_meeting`] a pair at a time, for the padded box
    /// `lo..hi`.
    fn all_meeting_portable(
        &self,
        k: usize,
        (lo, hi): (Vector, Vector),
        mut f: impl FnMut(usize) -> bool,
    ) -> bool {
        (0..self.lo.len()).all(|m| {
            let apart = lo.cmpgt(self.hi[m]).any() || hi.cmplt(self.lo[m]).any();
            apart || m == k || f(m)
        })
    }

    /// [`Patches::all_meeting`] with AVX2, for the padded box `lo..hi`.
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn all_meeting_avx2(
        &self,
        k: usize,
        (lo, hi): (Vector, Vector),
        f: &mut impl FnMut(usize) -> bool,
    ) -> bool {
        use std::arch::x86_64::*;
        let count = self.lo.len();
        let [lx, ly, lz, hx, hy, hz] = &self.boxes;
        let padded = lx.len();
        assert!(
            padded >= count && [ly, lz, hx, hy, hz].iter().all(|b| b.len() == padded),
            "the boxes padded to whole steps"
        );
        let splat = |v: Vector| [v.x, v.y, v.z].map(|c| _mm256_set1_ps(c));
        let (lo, hi) = (splat(lo), splat(hi));
        for first in (0..padded).step_by(LANES) {
            // SAFETY: lanes first..first + 8 are in every padded array.
            let at = |b: &Vec<f32>| _mm256_loadu_ps(b.as_ptr().add(first));
            let apart = [
                _mm256_cmp_ps::<_CMP_GT_OQ>(lo[0], at(hx)),
                _mm256_cmp_ps::<_CMP_GT_OQ>(lo[1], at(hy)),
                _mm256_cmp_ps::<_CMP_GT_OQ>(lo[2], at(hz)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(hi[0], at(lx)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(hi[1], at(ly)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(hi[2], at(lz)),
            ]
            .into_iter()
            .fold(_mm256_setzero_ps(), |any, a| _mm256_or_ps(any, a));
            let mut meets = !_mm256_movemask_ps(apart) as u32 & 0xff;
            while meets != 0 {
                let m = first + meets.trailing_zeros() as usize;
                meets &= meets - 1;
                if m < count && m != k && !f(m) {
                    return false;
                }
            }
        }
        true
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

    /// A crumpled cloth's patches (and one whose box is not a number):
    /// the boxes each patch's meets, and where the asking stops, are the
    /// same eight at a time as a pair at a time.
    #[test]
    fn the_boxes_meet_the_same_eight_at_a_time_as_one_at_a_time() {
        let mut cloth = ClothBuilder::new(41, 37).size(1.0, 0.9).build().unwrap();
        for i in 0..cloth.particle_count() {
            let p = cloth.positions()[i];
            let t = i as f32 * 0.37;
            let crumpled = p + Vector::new(
                0.05 * t.sin(),
                0.3 * (3.0 * p.x).sin() * p.z,
                0.04 * t.cos(),
            );
            cloth.set_position(i, crumpled).unwrap();
        }
        let mut x = cloth.positions().to_vec();
        x[cloth.index(20, 20).unwrap()] = Vector::splat(f32::NAN);
        let triangles = cloth.triangles().to_vec();
        let mut patches = Patches::default();
        patches.update(&x, cloth.topology().grid_pieces(), &triangles, 0.02);
        let count = patches.lo.len();
        assert!(
            count > LANES + 1 && !count.is_multiple_of(LANES),
            "{count} patches"
        );
        // A box that is not a number (a patch lost entirely).
        let nan = Vector::splat(f32::NAN);
        (patches.lo[3], patches.hi[3]) = (nan, nan);
        for b in &mut patches.boxes {
            b[3] = f32::NAN;
        }
        let pad = Vector::splat(0.02);
        let (mut met, mut lonely) = (0, 0);
        for k in 0..count {
            let boxed = (patches.lo[k] - pad, patches.hi[k] + pad);
            let mut one = Vec::new();
            assert!(patches.all_meeting_portable(k, boxed, |m| {
                one.push(m);
                true
            }));
            let mut eight = Vec::new();
            assert!(patches.all_meeting(k, pad, |m| {
                eight.push(m);
                true
            }));
            assert_eq!(one, eight, "patch {k}");
            assert!(!one.contains(&k));
            // Stopped at the third: the same three asked.
            let (mut a, mut b) = (0, 0);
            let stop_one = patches.all_meeting_portable(k, boxed, |_| {
                a += 1;
                a < 3
            });
            let stop_eight = patches.all_meeting(k, pad, |_| {
                b += 1;
                b < 3
            });
            assert_eq!((stop_one, a), (stop_eight, b));
            met += one.len();
            lonely += usize::from(one.len() < count - 1);
            if k == 3 {
                assert_eq!(one.len(), count - 1, "a box not a number meets every other");
            } else {
                assert!(one.contains(&3));
            }
        }
        assert!(
            met > count && lonely > 0,
            "{met} meetings, {lonely} apart from some"
        );
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
