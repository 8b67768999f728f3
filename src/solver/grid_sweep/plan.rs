//! How a grid's springs are laid out in lanes: row blocks, segments, regions in
//! bands and boundaries, the stretch limit's spans and tiles, and the plan over
//! them.

use super::lanes::{apart, LAMBDA_SLOT, REST_SLOT, WIDTH};
use crate::cloth::{LaneGrid, SpringKind, Springs};
use crate::parallel::{Disjoint, Team};
use crate::solver::grid_leftover::LeftoverSprings;
use crate::solver::pin_support::PinSupport;
use crate::solver::staggered::Staggered;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// Columns of a row are stored in interleaved blocks (column `c` in block
/// `c % blocks` at `c / blocks`), so that the springs along a row that are
/// independent (one and two columns apart) are contiguous too. At least
/// this many blocks: a bend spring two columns along must start and end in
/// different blocks, and four kept the first plans' order.
pub(super) const MIN_BLOCKS: usize = 4;

/// At most this many blocks (a row's runs are then a vector step or more
/// wherever the row has 64 columns or more).
pub(super) const MAX_BLOCKS: usize = 8;

/// The blocks a row of `cols` columns is stored in: the count from
/// [`MIN_BLOCKS`] to [`MAX_BLOCKS`] whose blocks take the fewest vector
/// steps, the fewest blocks among equals. A 40-column curtain in four
/// blocks of 10 filled 10 of each 16 lanes it stepped over along its rows;
/// in five blocks of 8 it fills them all.
pub(super) fn row_blocks(cols: usize) -> usize {
    let steps = |blocks: usize| -> usize {
        (0..blocks)
            .map(|j| ((cols + blocks - 1 - j) / blocks).div_ceil(WIDTH))
            .sum()
    };
    (MIN_BLOCKS..=MAX_BLOCKS)
        .min_by_key(|&b| (steps(b), b))
        .unwrap_or(MIN_BLOCKS)
}

/// A run of independent springs whose ends are contiguous lanes: from lanes
/// `a..a + len` to lanes `b..b + len`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Segment {
    pub(super) a: u32,
    pub(super) b: u32,
    pub(super) len: u32,
}

/// One family of grid springs: from particle `(r, c)` to `(r + dr, c + dc)`.
#[derive(Debug, Clone)]
pub(super) struct Pass {
    pub(super) kind: SpringKind,
    /// From particle `(r, c)` to `(r + dr, c + dc)` (read by the tests).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) dr: usize,
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) dc: isize,
}

/// The grid's springs as passes, when every spring is one of the six grid
/// families of `grid_topology` (stretch along rows and columns, shear along
/// both diagonals, bend two apart along rows and columns).
#[derive(Debug, Clone)]
pub(crate) struct GridPlan {
    /// Columns and rows of the grid.
    pub(super) shape: (usize, usize),
    /// The lane of each particle.
    pub(super) lane: Vec<u32>,
    pub(super) passes: Vec<Pass>,
    /// The bands, then the boundaries between them: each phase's regions
    /// share no lane, in ascending lane order.
    pub(super) phases: [Vec<Region>; 2],
    /// Per phase and pass, then long spans ([`LONG_RUNS`]): its springs
    /// (a phase with few runs on one thread).
    pub(super) work: [[usize; 8]; 2],
    /// Which bands and boundaries a handout of both phases has run
    /// ([`bands_and_boundaries`](super::sweep::bands_and_boundaries)).
    pub(super) flags: PhaseFlags,
    /// Per pass: the multiplier over the substep's sweeps (N·s²) of the
    /// spring leaving each lane.
    pub(super) lambda: Staggered,
    /// Per pass: the rest length (m) of the spring leaving each lane; 0
    /// where none does.
    pub(super) rest: Staggered,
    /// Per bend family (rows, then columns): the length (m) of the two
    /// stretch springs at rest that the bend spring leaving each lane spans
    /// (0 where none leaves). The stretch limit holds these pairs too.
    pub(super) span: [Vec<f32>; 2],
    /// Per direction (rows, then columns): the length (m) at rest of the
    /// stretch springs a long span from each lane takes ([`LONG_SPAN`];
    /// ∞ where one of them is missing, 0 where no span leaves the lane).
    /// The stretch limit holds these after an unsettled call.
    pub(super) long_span: [Vec<f32>; 2],
    /// The long spans' families (rows, then columns): from particle
    /// `(r, c)` to `(r + dr, c + dc)`; their runs follow the passes' in
    /// each region's `runs` ([`LONG_RUNS`]; read by the tests).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) long_steps: [(usize, isize); 2],
    /// The longest rest length of a stretch spring (m).
    pub(super) longest_stretch: f32,
    /// Per lane: the last pass of the stretch limit that moved it (as
    /// [`LimitMarks`](super::limit::LimitMarks) counts: at most the call's
    /// base, none yet this call).
    pub(super) limit_moved: Vec<u32>,
    /// Per tile of [`TILE_LANES`] lanes: the last pass of the stretch limit
    /// that moved any of its lanes ([`LimitTiles`]).
    pub(super) limit_tiles: LimitTiles,
    /// The marks' value before the last call's first pass: a call's marks
    /// run above every earlier call's ([`GridPlan::next_limit_base`]).
    pub(super) limit_base: u32,
    /// The last call of the stretch limit this step ended unsettled.
    pub(super) limit_unsettled: bool,
    /// A torn grid's springs that no run holds (none for a whole grid).
    pub(super) leftover: LeftoverSprings,
    /// The plan is a torn grid's ([`GridPlan::torn`]).
    pub(super) torn: bool,
    /// The stretch limit's weights of a pinned cloth ([`PinSupport`]).
    pub(super) pin_support: PinSupport,
}

/// Below this many springs, a phase of a pass runs on one thread: handing
/// it out costs more than it saves.
pub(super) const PARALLEL_MIN_SPRINGS: usize = 2048;

/// Rows a band has at least: more bands would leave too little work to a
/// thread, and a boundary's rows (as many either side as the longest
/// family spans: [`LONG_SPAN`]) must not reach the next.
pub(super) const BAND_ROWS: usize = 16;

const _: () = assert!(2 * LONG_SPAN <= BAND_ROWS, "boundaries apart");

/// Where the long spans' runs are in a region's `runs`: after the six
/// passes', along rows, then along columns.
pub(super) const LONG_RUNS: [usize; 2] = [6, 7];

/// Part of the grid whose springs are swept together: the lanes of some
/// rows and, for each pass, the runs of its springs that lie within them.
#[derive(Debug, Clone)]
pub(super) struct Region {
    /// Lanes this region's springs touch, and only they.
    pub(super) lanes: std::ops::Range<usize>,
    /// The lanes the six passes' springs and the pairs touch, counted from
    /// `lanes.start`: all of them in a band, but a boundary's long spans
    /// reach [`LONG_SPAN`] rows either side and the rest two.
    pub(super) near: std::ops::Range<usize>,
    /// Per pass, then per long span ([`LONG_RUNS`]): its runs here, lanes
    /// counted from `lanes.start`, in sweep order.
    pub(super) runs: Vec<Vec<Segment>>,
}

/// Where each column's block starts in a row of `cols` lanes stored in
/// `blocks` blocks (entries past `blocks` repeat the row's end).
pub(super) fn block_offsets(cols: usize, blocks: usize) -> [usize; MAX_BLOCKS + 1] {
    let mut off = [0; MAX_BLOCKS + 1];
    for j in 0..MAX_BLOCKS {
        let count = if j < blocks {
            (cols + blocks - 1 - j) / blocks
        } else {
            0
        };
        off[j + 1] = off[j] + count;
    }
    off
}

/// The runs of the family `(dr, dc)` that start in a row `keep` accepts:
/// rows `period` apart first (they share no particle), each row's springs by
/// the block of their first column, adjacent runs merged; lanes counted from
/// the start of row `first_row`.
pub(super) fn segments(
    (cols, blocks): (usize, usize),
    rows: usize,
    (dr, dc, period): (usize, isize, usize),
    first_row: usize,
    keep: impl Fn(usize) -> bool,
) -> Vec<Segment> {
    let off = block_offsets(cols, blocks);
    let mut out: Vec<Segment> = Vec::new();
    let row_period = if dr == 0 { 1 } else { period };
    let base = first_row * cols;
    for p in 0..row_period {
        let mut r = p;
        while r + dr < rows {
            if !keep(r) {
                r += row_period;
                continue;
            }
            for j in 0..blocks {
                // Columns c = blocks k + j with 0 <= c + dc < cols.
                let ks = (0..off[j + 1] - off[j]).filter(|&k| {
                    let to = (blocks * k + j) as isize + dc;
                    to >= 0 && (to as usize) < cols
                });
                let (Some(k0), Some(k1)) = (ks.clone().next(), ks.clone().next_back()) else {
                    continue;
                };
                let to = (blocks * k0 + j) as isize + dc;
                let (bj, bk) = (to as usize % blocks, to as usize / blocks);
                let seg = Segment {
                    a: (r * cols + off[j] + k0 - base) as u32,
                    b: ((r + dr) * cols + off[bj] + bk - base) as u32,
                    len: (k1 - k0 + 1) as u32,
                };
                // Merged with the run before when both ends continue it
                // and its two ends stay apart (no particle twice in a run).
                match out.last_mut() {
                    Some(last)
                        if last.a + last.len == seg.a
                            && last.b + last.len == seg.b
                            && apart(last.a, last.b, last.len + seg.len) =>
                    {
                        last.len += seg.len;
                    }
                    _ => out.push(seg),
                }
            }
            r += row_period;
        }
    }
    out
}

/// Per particle of a grid of `n` particles: joined by a spring to one past
/// the grid's (a tear's edge: a split handed it to a new particle).
pub(super) fn at_tears(n: usize, (a, b): (&[u32], &[u32])) -> Vec<bool> {
    let mut edge = vec![false; n];
    for (&i, &j) in a.iter().zip(b) {
        let (i, j) = (i as usize, j as usize);
        if i >= n || j >= n {
            for end in [i, j].into_iter().filter(|&e| e < n) {
                edge[end] = true;
            }
        }
    }
    edge
}

/// The bands of rows and the boundaries between them, each with the runs
/// of every family `(dr, dc, period)` that lie in it (a spring from one
/// stacked piece into the next is none); the first `near` families are
/// the passes' ([`Region::near`]).
pub(super) fn regions(
    (cols, blocks): (usize, usize),
    lanes: LaneGrid,
    (families, near): (&[(usize, isize, usize)], usize),
) -> [Vec<Region>; 2] {
    let rows = lanes.grid.rows;
    let bands = (rows / BAND_ROWS).max(1);
    let cut = |k: usize| k * rows / bands;
    let most_rows =
        |families: &[(usize, isize, usize)]| families.iter().map(|f| f.0).max().unwrap_or(0);
    let (reach, near_reach) = (most_rows(families), most_rows(&families[..near]));
    // The rows `t - reach..t + reach` of the boundary at row `t` hold every
    // spring crossing it (one starts at most `reach` rows above and ends
    // less than `reach` below); those of the passes within `near_reach`.
    let near_rows = |first: usize, end: usize, t: Option<usize>| match t {
        Some(t) => (t - near_reach - first) * cols..((t + near_reach).min(end) - first) * cols,
        None => 0..(end - first) * cols,
    };
    let region =
        |first: usize, end: usize, t: Option<usize>, keep: &dyn Fn(usize, usize) -> bool| Region {
            lanes: first * cols..end * cols,
            near: near_rows(first, end, t),
            runs: families
                .iter()
                .map(|&f| {
                    let keep = |r: usize| keep(r, f.0) && lanes.same_piece(r, r + f.0);
                    segments((cols, blocks), rows, f, first, keep)
                })
                .collect(),
        };
    let inside = (0..bands)
        .map(|k| {
            let (r0, r1) = (cut(k), cut(k + 1));
            region(r0, r1, None, &|r, dr| r >= r0 && r + dr < r1)
        })
        .collect();
    let crossing = (1..bands)
        .map(|k| {
            let t = cut(k);
            region(t - reach, (t + reach).min(rows), Some(t), &|r, dr| {
                r < t && r + dr >= t
            })
        })
        .collect();
    [inside, crossing]
}

impl GridPlan {
    /// The plan for `springs` on `grid`, or `None` when they are not the grid's families.
    #[cfg(test)]
    pub fn new(grid: crate::cloth::Grid, springs: &Springs) -> Option<GridPlan> {
        let piece_rows = grid.rows;
        GridPlan::stacked(LaneGrid { grid, piece_rows }, springs)
    }

    /// The plan for `springs` on the stacked grid `lanes`, or `None` when
    /// they are not its pieces' families: every spring of each family
    /// within each piece, none crossing into another piece.
    pub fn stacked(lanes: LaneGrid, springs: &Springs) -> Option<GridPlan> {
        GridPlan::build(lanes, springs, None)
    }

    /// The plan for a torn grid cloth of `particles` particles
    /// ([`crate::cloth::Topology::torn_lane_grid`]): the grid's springs
    /// that are left in its runs (the lost ones at rest length 0) but for
    /// those at the tear's edge, which go with every other spring among
    /// the leftovers ([`LeftoverSprings`]), and the
    /// particles past the grid's in lanes of their own after its last row
    /// (in the last band: no run reaches them). `None` when the grid is
    /// not the first of the particles.
    pub fn torn(lanes: LaneGrid, springs: &Springs, particles: usize) -> Option<GridPlan> {
        GridPlan::build(lanes, springs, Some(particles))
    }

    /// [`Self::stacked`], or with `torn` (the particle count)
    /// [`Self::torn`].
    pub(super) fn build(
        lanes: LaneGrid,
        springs: &Springs,
        torn: Option<usize>,
    ) -> Option<GridPlan> {
        let grid = lanes.grid;
        let (cols, rows) = (grid.cols, grid.rows);
        if lanes.piece_rows == 0 || !rows.is_multiple_of(lanes.piece_rows) {
            return None;
        }
        let pieces = rows / lanes.piece_rows;
        let n = cols.checked_mul(rows)?;
        // Every lane: the grid's, then the torn cloth's new particles.
        let all = torn.unwrap_or(n);
        if all < n || (torn.is_some() && pieces != 1) {
            return None;
        }
        let blocks = row_blocks(cols);
        let off = block_offsets(cols, blocks);
        let lane: Vec<u32> = (0..n)
            .map(|i| ((i / cols) * cols + off[(i % cols) % blocks] + (i % cols) / blocks) as u32)
            .chain((n..all).map(|i| i as u32))
            .collect();
        let families: [(SpringKind, usize, isize, usize); 6] = [
            (SpringKind::Stretch, 0, 1, 2),
            (SpringKind::Stretch, 1, 0, 2),
            (SpringKind::Shear, 1, 1, 2),
            (SpringKind::Shear, 1, -1, 2),
            (SpringKind::Bend, 0, 2, 4),
            (SpringKind::Bend, 2, 0, 4),
        ];
        let passes: Vec<Pass> = families
            .iter()
            .map(|&(kind, dr, dc, _)| Pass { kind, dr, dc })
            .collect();
        let mut rest = Staggered::new(6, all, REST_SLOT);
        let mut count = [0usize; 6];
        let mut leftover = LeftoverSprings::default();
        let (a, b) = springs.endpoints();
        // At a tear's edge the springs are left to the leftovers' sweep, in
        // their stored colour order (as `general_sweep.rs` takes them),
        // not the runs': the runs' order along a row (blocks of columns,
        // each swept forward) left the strain beside a tear's tip uneven,
        // and the `tear` scene at N = 32 tore beside its line (two columns
        // off, 2 sweeps a substep). So, at N = 32 to 128 with 2 to 4
        // sweeps, it tears on its line, as with the general sweep.
        let edge = match torn {
            Some(_) => at_tears(n, (a, b)),
            None => Vec::new(),
        };
        // Each spring's colour class, when its springs share no particle.
        let mut class = springs
            .colour_ranges()
            .iter()
            .zip(&springs.colour_disjoint)
            .enumerate()
            .flat_map(|(k, (range, &disjoint))| {
                range.clone().map(move |_| disjoint.then_some(k as u32))
            });
        for s in 0..springs.len() {
            let (first, second) = (a[s] as usize, b[s] as usize);
            if first >= all || second >= all {
                return None;
            }
            let kind = springs.kind(s);
            let (i, j) = (first.min(second), first.max(second));
            // The family and the lane of its first end, for a grid spring.
            let in_run = (j < n)
                .then(|| {
                    let (ri, ci, rj, cj) = (i / cols, i % cols, j / cols, j % cols);
                    let (dr, dc) = (rj - ri, cj as isize - ci as isize);
                    let f = families
                        .iter()
                        .position(|&(k, fr, fc, _)| k == kind && fr == dr && fc == dc)?;
                    lanes.same_piece(ri, rj).then_some((f, lane[i] as usize))
                })
                .flatten()
                .filter(|&(f, at)| rest.get(f)[at] == 0.0)
                .filter(|_| !(edge.get(i).is_some_and(|&e| e) || edge.get(j).is_some_and(|&e| e)));
            let colour = class.next().flatten();
            match (in_run, torn) {
                (Some((f, at)), _) => {
                    rest.get_mut(f)[at] = springs.rest_lengths()[s];
                    count[f] += 1;
                }
                // Not the grid's (or the same spring twice): a torn grid
                // sweeps it on its own, a whole one is no plan.
                (None, Some(_)) => {
                    let ends = (lane[first], lane[second]);
                    leftover.push(ends, springs.rest_lengths()[s], (kind, colour));
                }
                (None, None) => return None,
            }
        }
        // Every spring of a family present in each piece: the loops run over
        // whole rows (of a piece). A torn grid's lost ones rest at 0.
        let r = lanes.piece_rows;
        let full = [
            (cols - 1) * r,
            cols * (r - 1),
            (cols - 1) * (r - 1),
            (cols - 1) * (r - 1),
            cols.saturating_sub(2) * r,
            cols * r.saturating_sub(2),
        ]
        .map(|count| count * pieces);
        if torn.is_none() && count != full {
            return None;
        }
        leftover.finish();
        let along_rows = long_span_along_rows(blocks);
        let long_steps = [(0, along_rows as isize), (LONG_SPAN, 0)];
        // The runs of the passes, then of the long spans (rows taken
        // `2 LONG_SPAN` apart, so that two spans share no particle).
        let run_families: Vec<(usize, isize, usize)> = families
            .iter()
            .map(|&(_, dr, dc, p)| (dr, dc, p))
            .chain(long_steps.map(|(dr, dc)| (dr, dc, 2 * LONG_SPAN)))
            .collect();
        debug_assert_eq!(LONG_RUNS, [families.len(), families.len() + 1]);
        let mut phases = regions((cols, blocks), lanes, (&run_families, families.len()));
        if let Some(last) = phases[0].last_mut() {
            // The new particles' lanes in the last band, so that each
            // band's loop over its particles takes them too.
            last.lanes.end = all;
            last.near.end = last.lanes.len();
        }
        let work = std::array::from_fn(|phase| {
            std::array::from_fn(|p| {
                let runs = phases[phase].iter().flat_map(|region| &region.runs[p]);
                runs.map(|seg| seg.len as usize).sum()
            })
        });
        let longest_stretch = springs
            .range(SpringKind::Stretch)
            .map(|s| springs.rest_lengths()[s])
            .fold(0.0, f32::max);
        // Along rows: (r, c) to (r, c + 2) spans the stretch springs
        // leaving (r, c) and (r, c + 1); along columns likewise.
        let span = [(0, 1), (1, cols)].map(|(family, next)| {
            let (stretch, bend) = (rest.get(family), rest.get(4 + family));
            let mut span = vec![0.0; all];
            for i in 0..n {
                let (l, m) = (lane[i] as usize, i + next);
                if bend[l] > 0.0 {
                    span[l] = stretch[l] + stretch[lane[m] as usize];
                }
            }
            span
        });
        // From (r, c) the stretch springs leaving (r, c), (r, c + 1), ...
        // along rows; likewise along columns. A span over a missing spring
        // (torn, or across stacked pieces) holds nothing.
        let long_span = [0, 1].map(|family| {
            let (dr, dc) = long_steps[family];
            let (count, next) = if family == 0 {
                (dc as usize, 1)
            } else {
                (dr, cols)
            };
            let stretch = rest.get(family);
            let mut span = vec![0.0; all];
            for i in 0..n {
                let (r, c) = (i / cols, i % cols);
                if r + dr >= rows || c + dc as usize >= cols {
                    continue;
                }
                let parts = (0..count).map(|k| stretch[lane[i + k * next] as usize]);
                span[lane[i] as usize] = if parts.clone().all(|l| l > 0.0) {
                    parts.sum()
                } else {
                    f32::INFINITY
                };
            }
            span
        });
        Some(GridPlan {
            shape: (cols, rows),
            lane,
            passes,
            flags: PhaseFlags::new(phases[0].len()),
            phases,
            work,
            lambda: Staggered::new(6, all, LAMBDA_SLOT),
            rest,
            span,
            long_span,
            long_steps,
            longest_stretch,
            leftover,
            torn: torn.is_some(),
            limit_moved: vec![0; all],
            limit_tiles: LimitTiles(
                (0..all.div_ceil(TILE_LANES))
                    .map(|_| AtomicU32::new(0))
                    .collect(),
            ),
            limit_base: 0,
            limit_unsettled: false,
            pin_support: PinSupport::default(),
        })
    }

    /// The stretch limit's weights for particles of inverse masses
    /// `inv_mass` joined by `springs`, at the cloth's mass `revision`
    /// ([`PinSupport::update`]).
    pub(crate) fn support_from_pins(&mut self, inv_mass: &[f32], springs: &Springs, revision: u64) {
        let lane = &self.lane;
        let lane_of = |i: usize| lane.get(i).map_or(usize::MAX, |&l| l as usize);
        self.pin_support
            .update(inv_mass, springs, lane_of, revision);
    }

    /// Whether the cloth has pins ([`PinSupport`]): its stretch limit
    /// weighs particles near them as heavier.
    pub(crate) fn pinned(&self) -> bool {
        self.pin_support.pinned()
    }

    /// The marks' base for a new call of the stretch limit, and whether the
    /// marks were filled for it: pass `k` of the call marks a lane
    /// `base + k`, above any mark of an earlier call, so the marks need no
    /// fill a call (a fill of every lane a substep, on the calling thread,
    /// whose lines the other thread then fetched back). Filled only when
    /// the base would overflow.
    pub(super) fn next_limit_base(&mut self) -> (u32, bool) {
        let filled = self.limit_base > u32::MAX - 2 * LIMIT_PASSES;
        if filled {
            self.limit_moved.fill(0);
            self.limit_tiles.0.iter_mut().for_each(|t| *t.get_mut() = 0);
            self.limit_base = 0;
        }
        self.limit_base += LIMIT_PASSES;
        (self.limit_base, filled)
    }

    /// Starts a step's calls of the stretch limit as if the last ended settled.
    pub(crate) fn forget_unsettled(&mut self) {
        self.limit_unsettled = false;
    }

    /// The plan is a torn grid's ([`GridPlan::torn`]): its runs miss
    /// springs, so the chain solves along rows and columns do not apply.
    pub fn is_torn(&self) -> bool {
        self.torn
    }

    /// The springs no run holds (a torn grid's), to sweep after the runs.
    pub fn leftover_mut(&mut self) -> &mut LeftoverSprings {
        &mut self.leftover
    }

    /// The lane of particle `i`.
    pub fn lane(&self, i: usize) -> usize {
        self.lane[i] as usize
    }

    /// Columns and rows of the grid.
    pub fn shape(&self) -> (usize, usize) {
        self.shape
    }

    /// The stretch springs along rows and along columns: the rest length
    /// (m) of the one leaving each lane (0 where none does), and its
    /// multiplier (N·s²), for the chain solves (`grid_chains.rs`).
    pub fn stretch_passes(&mut self) -> ([&[f32]; 2], [&mut [f32]; 2]) {
        let rest = [self.rest.get(0), self.rest.get(1)];
        let mut lambda = self.lambda.all_mut();
        let rows = lambda.next().expect("the stretch springs along rows");
        let cols = lambda.next().expect("the stretch springs along columns");
        (rest, [rows, cols])
    }

    /// Calls `f` on every run of stretch and shear springs (those the
    /// collision stage's edge pass keeps out of obstacles), each spring
    /// once: the lanes of its first ends `a..a + len` and of its second
    /// ends `b..b + len` (among all lanes). Runs hold springs only.
    pub fn for_each_edge_run(&self, mut f: impl FnMut((usize, usize, usize))) {
        for region in self.phases.iter().flatten() {
            let base = region.lanes.start;
            for (p, pass) in self.passes.iter().enumerate() {
                if pass.kind == SpringKind::Bend {
                    continue;
                }
                for seg in &region.runs[p] {
                    let (a, b) = (base + seg.a as usize, base + seg.b as usize);
                    f((a, b, seg.len as usize));
                }
            }
        }
    }

    /// The lanes of the particles `range` (whole rows: each in `range` too).
    pub fn lanes_of(&self, range: &std::ops::Range<usize>) -> &[u32] {
        &self.lane[range.clone()]
    }

    /// Runs `f` on the particles of each band of rows (a range of particle
    /// indices, which is also the band's range of lanes: lanes only reorder
    /// a row), on the `team`'s threads.
    pub fn for_each_band(&self, team: Team, f: impl Fn(std::ops::Range<usize>) + Sync) {
        team.sum_over(&self.phases[0], |band| {
            f(band.lanes.clone());
            0
        });
    }

    /// Starts a substep: runs `f` on the particles of each band and their lanes
    /// ([`Self::lanes_of`]), as [`Self::for_each_band`] does, and sets the
    /// stretch springs' multipliers of the band's lanes back to zero on the
    /// same thread (one handout, not a serial fill: 2% of the main thread's
    /// time at N = 128 on two). The chain solves read those; the sweeps take
    /// the other kinds' as zero where nothing projected them yet this substep
    /// ([`KindInSweep::from_zero`](super::project::KindInSweep::from_zero)), so
    /// theirs are not filled (four arrays of six: 1.6% of the frame at N =
    /// 128).
    pub fn for_each_band_from_zero(
        &mut self,
        team: Team,
        f: impl Fn(std::ops::Range<usize>, &[u32]) + Sync,
    ) {
        let lane = &self.lane;
        let mut arrays = self.lambda.all_mut().map(Disjoint::new);
        let lambda: [Disjoint<f32>; 2] =
            std::array::from_fn(|_| arrays.next().expect("the stretch passes first"));
        debug_assert!(self.passes[..2]
            .iter()
            .all(|p| p.kind == SpringKind::Stretch));
        team.sum_over(&self.phases[0], |band| {
            for lambda in lambda {
                // SAFETY: bands are disjoint ranges of lanes.
                unsafe { lambda.range(band.lanes.clone()) }.fill(0.0);
            }
            f(band.lanes.clone(), &lane[band.lanes.clone()]);
            0
        });
    }
}

/// Which bands and boundaries a handout of both phases has run: per band
/// and per boundary, the number of the last call that ran it (a call
/// numbers itself from [`PhaseFlags::begin`]; none is ever reset).
#[derive(Debug, Default)]
pub(super) struct PhaseFlags {
    pub(super) call: AtomicU64,
    pub(super) done: Vec<AtomicU64>,
    pub(super) claimed: Vec<AtomicU64>,
}

impl Clone for PhaseFlags {
    /// Flags for as many bands, none run.
    fn clone(&self) -> PhaseFlags {
        PhaseFlags::new(self.done.len())
    }
}

impl PhaseFlags {
    /// Flags for `bands` bands and the boundaries between them.
    pub(super) fn new(bands: usize) -> PhaseFlags {
        let none = |k: usize| (0..k).map(|_| AtomicU64::new(0)).collect();
        PhaseFlags {
            call: AtomicU64::new(0),
            done: none(bands),
            claimed: none(bands.saturating_sub(1)),
        }
    }

    /// The number of a new call (by the calling thread, before its handout).
    pub(super) fn begin(&self) -> u64 {
        self.call.fetch_add(1, Ordering::Relaxed) + 1
    }

    /// After band `i` of call `call`: the boundaries beside it whose other
    /// band is done too and that no one has claimed yet, now claimed.
    /// Sequentially consistent: of two bands done at once, at least one
    /// sees the other done (and only one claims their boundary).
    pub(super) fn ready_after(&self, i: usize, call: u64) -> impl Iterator<Item = usize> + '_ {
        self.done[i].store(call, Ordering::SeqCst);
        let done = move |b: usize| self.done[b].load(Ordering::SeqCst) == call;
        [i.wrapping_sub(1), i].into_iter().filter(move |&j| {
            j < self.claimed.len()
                && done(j)
                && done(j + 1)
                && self.claimed[j].swap(call, Ordering::SeqCst) != call
        })
    }
}

/// Gauss–Seidel passes of the grid's stretch limit at most; they stop as
/// soon as one shortens nothing, and after the first a pass looks only at
/// the springs still moving. Where the whole cloth hangs at its limit every
/// pass is a whole one: the `hammock`'s cotton rested 5.21% stretched with
/// 16 passes of the springs alone, and rests 4.83% with 8 passes that hold
/// the pairs too, in the same time a frame (4.62% with 16, a third slower).
/// The drape's landing peaks at 4.52%, 4.57% and 4.72% at N = 64, 128 and
/// 256 (BENCHMARKS.md, fourteenth session).
pub(crate) const LIMIT_PASSES: u32 = 8;

/// How many stretch springs along a row or a column the stretch limit's
/// long spans take: after a call left the limit unsettled (a landing's
/// shock at `N = 256`), the next calls hold these spans in place of the
/// pairs, and a correction crosses the cloth in fewer passes. No span is
/// held to less than its springs at their limits reach. Measured,
/// instructions (callgrind, one thread) of `bench` at `N = 256` over 40
/// frames against the pairs in every call: 40.46 → 38.10 G (−5.8%; the
/// limit's kernel 12.95 → 12.70 G, the collision stage's `move_out` after
/// the last substep 1.67 → 0.62 G, the regions' checks for moved lanes,
/// over wider boundaries, 1.16 → 1.75 G; 37.91 G and 1.57 G with the
/// pairs' calls watching only [`Region::near`]); at `N = 128` +0.2%, the
/// `hammock` +0.9%, `pins` and `box` +0.1% or less; peak stretch 4.51%
/// in each. Probes whose row runs still joined lanes of one block (see
/// [`long_span_along_rows`]), so indicative only: spans of eight in every
/// call in place of the pairs −10% at `N = 256` but +5% on the `hammock`
/// and at `N = 128`; spans of four −7% and +5%; spans and pairs both in
/// every call +18% at `N = 256`.
pub(super) const LONG_SPAN: usize = 8;

/// How many stretch springs a long span takes along a row stored in
/// `blocks` blocks: [`LONG_SPAN`], or one fewer where that many would
/// join two lanes of one block (a run's two ends would overlap).
pub(super) fn long_span_along_rows(blocks: usize) -> usize {
    if LONG_SPAN.is_multiple_of(blocks) {
        LONG_SPAN - 1
    } else {
        LONG_SPAN
    }
}

/// The stretch limit's marks per tile of [`TILE_LANES`] lanes among all:
/// the last pass that moved a lane of the tile, so never below a lane's
/// own mark. The threads of a pass may share a tile at their regions'
/// edges; each stores the pass's own number there, so what a thread reads
/// is either its own store or one as new, and a tile it finds unmoved has
/// no lane of its region moved (its springs are skipped only then: the
/// same bits on any number of threads).
#[derive(Debug, Default)]
pub(super) struct LimitTiles(pub(super) Vec<AtomicU32>);

impl Clone for LimitTiles {
    fn clone(&self) -> Self {
        LimitTiles(
            self.0
                .iter()
                .map(|t| AtomicU32::new(t.load(Ordering::Relaxed)))
                .collect(),
        )
    }
}

/// Lanes a tile of the stretch limit's marks sums up: a row's quarter at
/// N = 256.
pub(super) const TILE_LANES: usize = 64;
