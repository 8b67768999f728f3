//! Springs: kinds, the flat spring list, and the grid topology.

use std::ops::Range;

use serde::{Deserialize, Serialize};

/// The three kinds of spring of a cloth grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SpringKind {
    /// Structural springs between the four grid neighbours: resist stretching.
    Stretch,
    /// Diagonal springs across each grid cell: resist shearing.
    Shear,
    /// Springs two apart along rows and columns: resist bending.
    Bend,
}

impl SpringKind {
    /// All kinds, in storage order.
    pub const ALL: [SpringKind; 3] = [SpringKind::Stretch, SpringKind::Shear, SpringKind::Bend];

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            SpringKind::Stretch => "stretch",
            SpringKind::Shear => "shear",
            SpringKind::Bend => "bend",
        }
    }

    /// Position in [`SpringKind::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// One spring, as handed to users.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spring {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length in metres.
    pub rest_length: f32,
    /// Kind of spring.
    pub kind: SpringKind,
}

/// The springs of a cloth as flat arrays, sorted by kind so that each kind is
/// one contiguous range.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Springs {
    pub(crate) a: Vec<u32>,
    pub(crate) b: Vec<u32>,
    pub(crate) rest: Vec<f32>,
    pub(crate) ranges: [Range<usize>; 3],
}

impl Springs {
    /// Builds the flat arrays from a list of springs (any order).
    pub(crate) fn from_list(mut list: Vec<Spring>) -> Self {
        list.sort_by_key(|s| s.kind.index());
        let mut ranges: [Range<usize>; 3] = [0..0, 0..0, 0..0];
        for kind in SpringKind::ALL {
            let start = list
                .iter()
                .position(|s| s.kind == kind)
                .unwrap_or(list.len());
            let count = list.iter().filter(|s| s.kind == kind).count();
            ranges[kind.index()] = start..start + count;
        }
        Self {
            a: list.iter().map(|s| s.a).collect(),
            b: list.iter().map(|s| s.b).collect(),
            rest: list.iter().map(|s| s.rest_length).collect(),
            ranges,
        }
    }

    /// Number of springs.
    pub fn len(&self) -> usize {
        self.a.len()
    }

    /// True when there is no spring.
    pub fn is_empty(&self) -> bool {
        self.a.is_empty()
    }

    /// Indices of the springs of one kind.
    pub fn range(&self, kind: SpringKind) -> Range<usize> {
        self.ranges[kind.index()].clone()
    }

    /// Number of springs of one kind.
    pub fn count(&self, kind: SpringKind) -> usize {
        self.ranges[kind.index()].len()
    }

    /// Kind of spring `s`.
    pub fn kind(&self, s: usize) -> SpringKind {
        if s < self.ranges[0].end {
            SpringKind::Stretch
        } else if s < self.ranges[1].end {
            SpringKind::Shear
        } else {
            SpringKind::Bend
        }
    }

    /// Spring `s`, or `None` when out of range.
    pub fn get(&self, s: usize) -> Option<Spring> {
        Some(Spring {
            a: *self.a.get(s)?,
            b: *self.b.get(s)?,
            rest_length: *self.rest.get(s)?,
            kind: self.kind(s),
        })
    }

    /// Iterates over all springs.
    pub fn iter(&self) -> impl Iterator<Item = Spring> + '_ {
        (0..self.len()).filter_map(|s| self.get(s))
    }

    /// First and second particle arrays.
    pub fn endpoints(&self) -> (&[u32], &[u32]) {
        (&self.a, &self.b)
    }

    /// Rest lengths, in metres.
    pub fn rest_lengths(&self) -> &[f32] {
        &self.rest
    }
}

/// A spring of the grid topology: its two particles and its kind.
pub(crate) type GridSpring = (usize, usize, SpringKind);

/// Springs and triangles of a `cols × rows` grid, particle `(r, c)` at index `r * cols + c`.
pub(crate) fn grid_topology(cols: usize, rows: usize) -> (Vec<GridSpring>, Vec<[u32; 3]>) {
    let id = |r: usize, c: usize| r * cols + c;
    let mut springs = Vec::new();
    for r in 0..rows {
        for c in 0..cols {
            if c + 1 < cols {
                springs.push((id(r, c), id(r, c + 1), SpringKind::Stretch));
            }
            if r + 1 < rows {
                springs.push((id(r, c), id(r + 1, c), SpringKind::Stretch));
            }
        }
    }
    for r in 0..rows.saturating_sub(1) {
        for c in 0..cols.saturating_sub(1) {
            springs.push((id(r, c), id(r + 1, c + 1), SpringKind::Shear));
            springs.push((id(r, c + 1), id(r + 1, c), SpringKind::Shear));
        }
    }
    for r in 0..rows {
        for c in 0..cols {
            if c + 2 < cols {
                springs.push((id(r, c), id(r, c + 2), SpringKind::Bend));
            }
            if r + 2 < rows {
                springs.push((id(r, c), id(r + 2, c), SpringKind::Bend));
            }
        }
    }
    let mut triangles = Vec::with_capacity(2 * (cols - 1) * (rows - 1));
    for r in 0..rows - 1 {
        for c in 0..cols - 1 {
            let (p00, p01, p10, p11) = (id(r, c), id(r, c + 1), id(r + 1, c), id(r + 1, c + 1));
            // Alternate the diagonal so the mesh has no preferred direction.
            if (r + c) % 2 == 0 {
                triangles.push([p00 as u32, p10 as u32, p11 as u32]);
                triangles.push([p00 as u32, p11 as u32, p01 as u32]);
            } else {
                triangles.push([p00 as u32, p10 as u32, p01 as u32]);
                triangles.push([p01 as u32, p10 as u32, p11 as u32]);
            }
        }
    }
    (springs, triangles)
}
