//! Pin presets: the pinning figures of the canonical scenes.

use serde::{Deserialize, Serialize};

use crate::error::ClothError;

/// A named set of pinned particles on a `cols × rows` grid.
///
/// Row 0 is the first row of the grid: the top row of a vertical cloth, the
/// `-z` edge of a horizontal one. Column 0 is the `-x` edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PinPreset {
    /// Nothing pinned.
    None,
    /// Every particle of column 0 (a flag on its pole).
    FlagColumn,
    /// Every particle of row 0 (a curtain on its rail).
    CurtainRow,
    /// The two corners of row 0.
    TwoCorners,
    /// The four corners.
    FourCorners,
    /// The single particle at the centre.
    Center,
    /// Every particle of the middle row.
    CenterRow,
    /// Four particles at (±1/4, ±1/4) of the side around the centre.
    FourCenter,
}

impl PinPreset {
    /// Every preset.
    pub const ALL: [PinPreset; 8] = [
        PinPreset::None,
        PinPreset::FlagColumn,
        PinPreset::CurtainRow,
        PinPreset::TwoCorners,
        PinPreset::FourCorners,
        PinPreset::Center,
        PinPreset::CenterRow,
        PinPreset::FourCenter,
    ];

    /// The name used by the command line and scene files.
    pub fn name(self) -> &'static str {
        match self {
            PinPreset::None => "none",
            PinPreset::FlagColumn => "flag-column",
            PinPreset::CurtainRow => "curtain-row",
            PinPreset::TwoCorners => "corners",
            PinPreset::FourCorners => "all-corners",
            PinPreset::Center => "center",
            PinPreset::CenterRow => "center-row",
            PinPreset::FourCenter => "four",
        }
    }

    /// Looks a preset up by its name.
    pub fn from_name(name: &str) -> Result<Self, ClothError> {
        crate::error::by_name(&Self::ALL, Self::name, "pin preset", name)
    }

    /// The `(row, column)` cells pinned on a `cols × rows` grid.
    /// Empty for an empty grid.
    pub fn cells(self, cols: usize, rows: usize) -> Vec<(usize, usize)> {
        if cols == 0 || rows == 0 {
            return Vec::new();
        }
        let (lc, lr) = (cols - 1, rows - 1);
        let (cc, cr) = (cols / 2, rows / 2);
        match self {
            PinPreset::None => vec![],
            PinPreset::FlagColumn => (0..rows).map(|r| (r, 0)).collect(),
            PinPreset::CurtainRow => (0..cols).map(|c| (0, c)).collect(),
            PinPreset::TwoCorners => vec![(0, 0), (0, lc)],
            PinPreset::FourCorners => vec![(0, 0), (0, lc), (lr, 0), (lr, lc)],
            PinPreset::Center => vec![(cr, cc)],
            PinPreset::CenterRow => (0..cols).map(|c| (cr, c)).collect(),
            PinPreset::FourCenter => {
                let (qc, qr) = (lc.div_ceil(4), lr.div_ceil(4));
                let (c0, c1) = (cc.saturating_sub(qc), (cc + qc).min(lc));
                let (r0, r1) = (cr.saturating_sub(qr), (cr + qr).min(lr));
                vec![(r0, c0), (r0, c1), (r1, c0), (r1, c1)]
            }
        }
    }
}
