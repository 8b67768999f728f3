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
    #[serde(default)]
    pub(crate) colour_ranges: Vec<Range<usize>>,
    /// Per colour range: true when no two of its springs share a particle.
    #[serde(default)]
    pub(crate) colour_disjoint: Vec<bool>,
    /// Per kind: the most springs of that kind at any one particle.
    #[serde(default)]
    pub(crate) max_degree: [u32; 3],
    /// Per particle, per kind: the springs of that kind at the particle
    /// (empty when read from a snapshot written before it was kept).
    #[serde(default)]
    pub(crate) degree: Vec<[u32; 3]>,
}

/// Greedy colouring of the springs, kind by kind: each spring gets the lowest
/// colour not yet used at either of its particles. Colours past 63 share one
/// last class, whose springs may share particles (it is run serially).
fn colour(list: &[Spring]) -> Vec<u32> {
    /// The colour whose springs may share particles.
    const OVERFLOW: u32 = 64;
    let n = list
        .iter()
        .map(|s| s.a.max(s.b) as usize + 1)
        .max()
        .unwrap_or(0);
    let mut colours = vec![0u32; list.len()];
    for kind in SpringKind::ALL {
        let mut used = vec![0u64; n];
        for (s, spring) in list.iter().enumerate().filter(|(_, sp)| sp.kind == kind) {
            let (a, b) = (spring.a as usize, spring.b as usize);
            let taken = used[a] | used[b];
            let c = (!taken).trailing_zeros();
            if c < 64 {
                used[a] |= 1 << c;
                used[b] |= 1 << c;
                colours[s] = c;
            } else {
                colours[s] = OVERFLOW;
            }
        }
    }
    colours
}

impl Springs {
    /// Builds the flat arrays from a list of springs (any order).
    pub(crate) fn from_list(mut list: Vec<Spring>) -> Self {
        // Colour the springs of each kind so that no two of one colour share a
        // particle, and store them kind by kind, colour by colour: a colour
        // class can then be evaluated in parallel, and each particle still sums
        // its spring forces in the same order as the serial loop.
        let colours = colour(&list);
        let mut order: Vec<usize> = (0..list.len()).collect();
        order.sort_by_key(|&s| (list[s].kind.index(), colours[s]));
        let sorted_colours: Vec<u32> = order.iter().map(|&s| colours[s]).collect();
        list = order.iter().map(|&s| list[s]).collect();
        let mut colour_ranges = Vec::new();
        let mut colour_disjoint = Vec::new();
        let mut start = 0;
        for s in 1..=list.len() {
            if s == list.len()
                || list[s].kind != list[start].kind
                || sorted_colours[s] != sorted_colours[start]
            {
                colour_ranges.push(start..s);
                colour_disjoint.push(sorted_colours[start] < 64);
                start = s;
            }
        }
        let mut ranges: [Range<usize>; 3] = [0..0, 0..0, 0..0];
        for kind in SpringKind::ALL {
            let start = list
                .iter()
                .position(|s| s.kind == kind)
                .unwrap_or(list.len());
            let count = list.iter().filter(|s| s.kind == kind).count();
            ranges[kind.index()] = start..start + count;
        }
        let n = list
            .iter()
            .map(|s| s.a.max(s.b) as usize + 1)
            .max()
            .unwrap_or(0);
        let mut degree = vec![[0u32; 3]; n];
        for s in &list {
            degree[s.a as usize][s.kind.index()] += 1;
            degree[s.b as usize][s.kind.index()] += 1;
        }
        let max_degree = SpringKind::ALL.map(|kind| {
            let k = kind.index();
            degree.iter().map(|d| d[k]).max().unwrap_or(0)
        });
        Self {
            max_degree,
            degree,
            a: list.iter().map(|s| s.a).collect(),
            b: list.iter().map(|s| s.b).collect(),
            rest: list.iter().map(|s| s.rest_length).collect(),
            ranges,
            colour_ranges,
            colour_disjoint,
        }
    }

    /// Ranges of springs of one kind and one colour: no two springs of a range
    /// share a particle.
    pub fn colour_ranges(&self) -> &[Range<usize>] {
        &self.colour_ranges
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
