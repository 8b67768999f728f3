//! The spring sweep of the small-steps solver specialised to grid cloth:
//! springs of one kind and direction are the lanes of a row, so that rows of
//! one parity class are independent and each row is one vectorised loop over
//! structure-of-arrays positions (8 springs per AVX2 instruction, no
//! gathers). Chosen at run time: AVX2 where the CPU has it, else the same
//! loops with the baseline's 4 lanes; both give the same bits (no fused
//! multiply-add, the same IEEE operations in the same order per lane).
//!
//! Threads: the rows are cut into bands of at least [`BAND_ROWS`] rows
//! (their number depends only on the grid). A sweep runs the bands, each
//! with all its families of springs in turn, then the boundaries between
//! them (the springs that cross from one band into the next), likewise.
//! Bands share no particle, nor do boundaries, so each of the two phases
//! may run its regions on any threads in any order: the bits are those of
//! one thread. One handout to the threads a sweep, not one per family and
//! phase (twelve: at N = 64 the handshakes had cost more than the second
//! thread saved): a band's item runs the boundaries beside it once their
//! other band is done too ([`bands_and_boundaries`]), and a boundary
//! touches only its two bands. The boundary springs then lag their band's families by a
//! sweep: before the stretch limit this order landed the drape at N = 128
//! 0.3% more stretched; with it, the peak over every frame went 4.61 →
//! 4.65% (N = 64: 4.50 → 4.56%).
//!
//! A torn grid ([`GridPlan::torn`]) keeps the runs: the springs it lost
//! are lanes at rest length 0, which project nothing, its new particles
//! lanes past the grid's, and the springs the runs cannot hold are swept
//! after them (`grid_leftover.rs`).

#[cfg(test)]
use crate::cloth::Grid;
use crate::cloth::{LaneGrid, SpringKind, Springs};
use crate::math::simd_available;
use crate::parallel::{Disjoint, Team};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use super::grid_leftover::LeftoverSprings;
use super::pin_support::PinSupport;
use super::staggered::Staggered;
use crate::collision::LIMIT_SLACK;

/// Structure-of-arrays positions (m), positions at the substep's start (m)
/// and inverse masses (1/kg), in the plan's lane order ([`GridPlan::lane`]):
/// x, y, z, start x, y, z, w, staggered ([`Staggered`]).
#[derive(Debug)]
pub(crate) struct Lanes(Staggered);

/// Stagger slots: the lanes' 7 arrays, then the passes' multipliers, then
/// their rest lengths, all read at the same index by the sweep.
const LANE_SLOT: usize = 0;
const LAMBDA_SLOT: usize = 7;
const REST_SLOT: usize = 13;

impl Default for Lanes {
    fn default() -> Self {
        Lanes(Staggered::new(7, 0, LANE_SLOT))
    }
}

impl Lanes {
    /// Every array at `n` lanes.
    pub fn resize(&mut self, n: usize) {
        self.0.resize(n);
    }

    /// The arrays for threads to share by disjoint ranges: x, y, z, the
    /// substep-start x, y, z, and the inverse masses.
    pub fn disjoint(&mut self) -> [Disjoint<'_, f32>; 7] {
        let mut arrays = self.0.all_mut().map(Disjoint::new);
        std::array::from_fn(|_| arrays.next().expect("seven arrays"))
    }

    /// The arrays, to write: x, y, z, start x, y, z, w.
    pub(super) fn arrays_mut(&mut self) -> [&mut [f32]; 7] {
        let mut arrays = self.0.all_mut();
        std::array::from_fn(|_| arrays.next().expect("seven arrays"))
    }
}

/// Columns of a row are stored in interleaved blocks (column `c` in block
/// `c % blocks` at `c / blocks`), so that the springs along a row that are
/// independent (one and two columns apart) are contiguous too. At least
/// this many blocks: a bend spring two columns along must start and end in
/// different blocks, and four kept the first plans' order.
const MIN_BLOCKS: usize = 4;

/// At most this many blocks (a row's runs are then a vector step or more
/// wherever the row has 64 columns or more).
const MAX_BLOCKS: usize = 8;

/// The blocks a row of `cols` columns is stored in: the count from
/// [`MIN_BLOCKS`] to [`MAX_BLOCKS`] whose blocks take the fewest vector
/// steps, the fewest blocks among equals. A 40-column curtain in four
/// blocks of 10 filled 10 of each 16 lanes it stepped over along its rows;
/// in five blocks of 8 it fills them all.
fn row_blocks(cols: usize) -> usize {
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
struct Segment {
    a: u32,
    b: u32,
    len: u32,
}

/// One family of grid springs: from particle `(r, c)` to `(r + dr, c + dc)`.
#[derive(Debug, Clone)]
struct Pass {
    kind: SpringKind,
    /// From particle `(r, c)` to `(r + dr, c + dc)` (read by the tests).
    #[cfg_attr(not(test), allow(dead_code))]
    dr: usize,
    #[cfg_attr(not(test), allow(dead_code))]
    dc: isize,
}

/// The grid's springs as passes, when every spring is one of the six grid
/// families of `grid_topology` (stretch along rows and columns, shear along
/// both diagonals, bend two apart along rows and columns).
#[derive(Debug, Clone)]
pub(crate) struct GridPlan {
    /// Columns and rows of the grid.
    shape: (usize, usize),
    /// The lane of each particle.
    lane: Vec<u32>,
    passes: Vec<Pass>,
    /// The bands, then the boundaries between them: each phase's regions
    /// share no lane, in ascending lane order.
    phases: [Vec<Region>; 2],
    /// Per phase and pass, then long spans ([`LONG_RUNS`]): its springs
    /// (a phase with few runs on one thread).
    work: [[usize; 8]; 2],
    /// Which bands and boundaries a handout of both phases has run
    /// ([`bands_and_boundaries`]).
    flags: PhaseFlags,
    /// Per pass: the multiplier over the substep's sweeps (N·s²) of the
    /// spring leaving each lane.
    lambda: Staggered,
    /// Per pass: the rest length (m) of the spring leaving each lane; 0
    /// where none does.
    rest: Staggered,
    /// Per bend family (rows, then columns): the length (m) of the two
    /// stretch springs at rest that the bend spring leaving each lane spans
    /// (0 where none leaves). The stretch limit holds these pairs too.
    span: [Vec<f32>; 2],
    /// Per direction (rows, then columns): the length (m) at rest of the
    /// stretch springs a long span from each lane takes ([`LONG_SPAN`];
    /// ∞ where one of them is missing, 0 where no span leaves the lane).
    /// The stretch limit holds these after an unsettled call.
    long_span: [Vec<f32>; 2],
    /// The long spans' families (rows, then columns): from particle
    /// `(r, c)` to `(r + dr, c + dc)`; their runs follow the passes' in
    /// each region's `runs` ([`LONG_RUNS`]; read by the tests).
    #[cfg_attr(not(test), allow(dead_code))]
    long_steps: [(usize, isize); 2],
    /// The longest rest length of a stretch spring (m).
    longest_stretch: f32,
    /// Per lane: the last pass of the stretch limit that moved it (as
    /// [`LimitMarks`] counts: at most the call's base, none yet this call).
    limit_moved: Vec<u32>,
    /// Per tile of [`TILE_LANES`] lanes: the last pass of the stretch limit
    /// that moved any of its lanes ([`LimitTiles`]).
    limit_tiles: LimitTiles,
    /// The marks' value before the last call's first pass: a call's marks
    /// run above every earlier call's ([`GridPlan::next_limit_base`]).
    limit_base: u32,
    /// The last call of the stretch limit this step ended unsettled.
    limit_unsettled: bool,
    /// A torn grid's springs that no run holds (none for a whole grid).
    leftover: LeftoverSprings,
    /// The plan is a torn grid's ([`GridPlan::torn`]).
    torn: bool,
    /// The stretch limit's weights of a pinned cloth ([`PinSupport`]).
    pin_support: PinSupport,
}

/// Below this many springs, a phase of a pass runs on one thread: handing
/// it out costs more than it saves.
const PARALLEL_MIN_SPRINGS: usize = 2048;

/// Rows a band has at least: more bands would leave too little work to a
/// thread, and a boundary's rows (as many either side as the longest
/// family spans: [`LONG_SPAN`]) must not reach the next.
const BAND_ROWS: usize = 16;

const _: () = assert!(2 * LONG_SPAN <= BAND_ROWS, "boundaries apart");

/// Where the long spans' runs are in a region's `runs`: after the six
/// passes', along rows, then along columns.
const LONG_RUNS: [usize; 2] = [6, 7];

/// Part of the grid whose springs are swept together: the lanes of some
/// rows and, for each pass, the runs of its springs that lie within them.
#[derive(Debug, Clone)]
struct Region {
    /// Lanes this region's springs touch, and only they.
    lanes: std::ops::Range<usize>,
    /// The lanes the six passes' springs and the pairs touch, counted from
    /// `lanes.start`: all of them in a band, but a boundary's long spans
    /// reach [`LONG_SPAN`] rows either side and the rest two.
    near: std::ops::Range<usize>,
    /// Per pass, then per long span ([`LONG_RUNS`]): its runs here, lanes
    /// counted from `lanes.start`, in sweep order.
    runs: Vec<Vec<Segment>>,
}

/// Where each column's block starts in a row of `cols` lanes stored in
/// `blocks` blocks (entries past `blocks` repeat the row's end).
fn block_offsets(cols: usize, blocks: usize) -> [usize; MAX_BLOCKS + 1] {
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
fn segments(
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
fn at_tears(n: usize, (a, b): (&[u32], &[u32])) -> Vec<bool> {
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

/// True when lanes `a..a + len` and `b..b + len` do not overlap.
fn apart(a: u32, b: u32, len: u32) -> bool {
    a + len <= b || b + len <= a
}

/// The bands of rows and the boundaries between them, each with the runs
/// of every family `(dr, dc, period)` that lie in it (a spring from one
/// stacked piece into the next is none); the first `near` families are
/// the passes' ([`Region::near`]).
fn regions(
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
    pub fn new(grid: Grid, springs: &Springs) -> Option<GridPlan> {
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
    fn build(lanes: LaneGrid, springs: &Springs, torn: Option<usize>) -> Option<GridPlan> {
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
    fn next_limit_base(&mut self) -> (u32, bool) {
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

    /// Starts a substep: runs `f` on the particles of each band and their
    /// lanes ([`Self::lanes_of`]), as [`Self::for_each_band`] does, and
    /// sets the stretch springs' multipliers of the band's lanes back to
    /// zero on the same thread (one handout, not a serial fill: 2% of the
    /// main thread's time at N = 128 on two). The chain solves read those;
    /// the sweeps take the other kinds' as zero where nothing projected
    /// them yet this substep ([`KindInSweep::from_zero`]), so theirs are
    /// not filled (four arrays of six: 1.6% of the frame at N = 128).
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

/// Compliance terms of one spring kind for a substep: `α = 1/(k h²)`, `γ = c/(k h)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Compliance {
    pub alpha: f32,
    pub gamma: f32,
}

/// The lanes and the passes' multipliers, shared by the regions of one
/// phase, which touch disjoint lanes.
#[derive(Clone, Copy)]
struct SharedLanes<'a> {
    x: Disjoint<'a, f32>,
    y: Disjoint<'a, f32>,
    z: Disjoint<'a, f32>,
    sx: &'a [f32],
    sy: &'a [f32],
    sz: &'a [f32],
    w: &'a [f32],
    lambda: [Disjoint<'a, f32>; 6],
}

/// The lanes of one region: positions to update, substep-start positions and
/// inverse masses to read, indexed from the region's first lane.
struct View<'a> {
    x: &'a mut [f32],
    y: &'a mut [f32],
    z: &'a mut [f32],
    sx: &'a [f32],
    sy: &'a [f32],
    sz: &'a [f32],
    w: &'a [f32],
}

impl View<'_> {
    /// How many lanes the view has (each of its arrays that many).
    #[inline(always)]
    fn len(&self) -> usize {
        self.x.len()
    }

    /// The positions at lanes `at..at + M`: x, y, z.
    ///
    /// # Safety
    /// `at + M <= self.len()`.
    #[inline(always)]
    unsafe fn positions<const M: usize>(&self, at: usize) -> [[f32; M]; 3] {
        // SAFETY: in bounds by the caller's promise; the arrays are of one length.
        unsafe { [load(self.x, at), load(self.y, at), load(self.z, at)] }
    }

    /// Writes positions `p` (x, y, z) to lanes `at..at + M`.
    ///
    /// # Safety
    /// As for [`View::positions`].
    #[inline(always)]
    unsafe fn set_positions<const M: usize>(&mut self, at: usize, [x, y, z]: [[f32; M]; 3]) {
        // SAFETY: as above.
        unsafe {
            store(self.x, at, x);
            store(self.y, at, y);
            store(self.z, at, z);
        }
    }
}

/// Lanes `at..at + M` of `v`, as an array (a vector load for `M` = 8),
/// without a bounds check: the kernels check a run's bounds once, not
/// each of a step's 23 loads and stores twice (with their lengths spilled
/// to the stack, those compares were a sixth of the sweep's time).
///
/// # Safety
/// `at + M <= v.len()`.
#[inline(always)]
unsafe fn load<const M: usize>(v: &[f32], at: usize) -> [f32; M] {
    debug_assert!(at + M <= v.len());
    // SAFETY: in bounds by the caller's promise; `[f32; M]` has the
    // alignment of `f32`.
    unsafe { v.as_ptr().add(at).cast::<[f32; M]>().read() }
}

/// Writes `value` to lanes `at..at + M` of `v`, without a bounds check.
///
/// # Safety
/// As for [`load`].
#[inline(always)]
unsafe fn store<const M: usize>(v: &mut [f32], at: usize, value: [f32; M]) {
    debug_assert!(at + M <= v.len());
    // SAFETY: as for `load`.
    unsafe { v.as_mut_ptr().add(at).cast::<[f32; M]>().write(value) }
}

impl<'a> SharedLanes<'a> {
    /// `lanes` and the passes' multipliers `lambda`, all of one length.
    fn new(lanes: &'a mut Lanes, lambda: &'a mut Staggered) -> SharedLanes<'a> {
        let [x, y, z, sx, sy, sz, w] = lanes.arrays_mut();
        let len = x.len();
        let mut lambda = lambda.all_mut().map(|l| {
            assert_eq!(l.len(), len, "lanes of one length");
            Disjoint::new(l)
        });
        SharedLanes {
            x: Disjoint::new(x),
            y: Disjoint::new(y),
            z: Disjoint::new(z),
            sx,
            sy,
            sz,
            w,
            lambda: std::array::from_fn(|_| lambda.next().expect("six passes")),
        }
    }

    /// The lanes `range`.
    ///
    /// # Safety
    /// No other view of a range overlapping `range` may be in use meanwhile.
    unsafe fn view(self, range: std::ops::Range<usize>) -> View<'a> {
        // SAFETY: exclusive by the caller's promise.
        unsafe {
            View {
                x: self.x.range(range.clone()),
                y: self.y.range(range.clone()),
                z: self.z.range(range.clone()),
                sx: &self.sx[range.clone()],
                sy: &self.sy[range.clone()],
                sz: &self.sz[range.clone()],
                w: &self.w[range],
            }
        }
    }

    /// Pass `p`'s multipliers at the lanes `range`.
    ///
    /// # Safety
    /// As for [`SharedLanes::view`].
    unsafe fn lambda(self, p: usize, range: std::ops::Range<usize>) -> &'a mut [f32] {
        // SAFETY: exclusive by the caller's promise.
        unsafe { self.lambda[p].range(range) }
    }
}

/// One Gauss–Seidel sweep over every spring of the kinds `kinds` marks
/// (by [`crate::cloth::SpringKind::index`]): the bands, then the
/// boundaries between them, each region's passes in the plan's order; on
/// several threads of `team`, with the same bits. A region takes all its
/// passes at once: one handout per phase rather than per pass and phase
/// (a handshake costs a few microseconds, a pass in a band about as
/// much), and its lanes are still in cache for the next pass.
pub(crate) fn sweep(
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    compliance: &[Compliance; 3],
    kinds: [KindInSweep; 3],
    team: Team,
) {
    sweep_with(plan, lanes, compliance, kinds, team, simd_available());
}

/// How one sweep takes one kind of spring ([`sweep`]; by
/// [`SpringKind::index`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct KindInSweep {
    /// The kind's springs are projected.
    pub on: bool,
    /// Nothing projected them yet this substep: their multipliers are
    /// taken as zero, not read (the arrays are not filled with zeros).
    pub from_zero: bool,
    /// A later sweep of this substep reads their multipliers, so they are
    /// stored (else nothing reads them, and the stores are left out).
    pub kept: bool,
}

impl KindInSweep {
    /// Projected, with multipliers read and stored.
    #[cfg(test)]
    pub const READ_AND_KEPT: KindInSweep = KindInSweep {
        on: true,
        from_zero: false,
        kept: true,
    };

    /// Not projected.
    pub const OFF: KindInSweep = KindInSweep {
        on: false,
        from_zero: false,
        kept: false,
    };
}

/// [`sweep`], with the AVX2 kernel only when `simd`.
fn sweep_with(
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    compliance: &[Compliance; 3],
    kinds: [KindInSweep; 3],
    team: Team,
    simd: bool,
) {
    let shared = SharedLanes::new(lanes, &mut plan.lambda);
    let kind_of: [usize; 6] = std::array::from_fn(|p| plan.passes[p].kind.index());
    let k: [Compliance; 6] = std::array::from_fn(|p| compliance[plan.passes[p].kind.index()]);
    let rest: [&[f32]; 6] = std::array::from_fn(|p| plan.rest.get(p));
    let call = plan.flags.begin();
    let springs = plan.work.iter().flatten().sum();
    let team = team.for_work(springs, PARALLEL_MIN_SPRINGS);
    bands_and_boundaries((&plan.phases, &plan.flags, call), team, |region| {
        // SAFETY: the regions run at once touch disjoint lanes (the
        // regions of a phase do, the plan is built so and tested, and
        // a boundary runs only once its two bands are done), so the
        // views alive at once are disjoint; `lanes` and the passes
        // are borrowed for the sweep.
        let (mut view, lambda): (_, [&mut [f32]; 6]) = unsafe {
            (
                shared.view(region.lanes.clone()),
                std::array::from_fn(|p| shared.lambda(p, region.lanes.clone())),
            )
        };
        for (p, lambda) in lambda.into_iter().enumerate() {
            let kind = kinds[kind_of[p]];
            if !kind.on {
                continue;
            }
            let job = RegionSweep {
                region,
                p,
                rest: &rest,
                k: &k,
            };
            let (view, simd) = (&mut view, simd);
            match (kind.from_zero, kind.kept) {
                (false, true) => sweep_region_on::<false, true>(&job, view, lambda, simd),
                (true, true) => sweep_region_on::<true, true>(&job, view, lambda, simd),
                (false, false) => sweep_region_on::<false, false>(&job, view, lambda, simd),
                (true, false) => sweep_region_on::<true, false>(&job, view, lambda, simd),
            }
        }
        0
    });
}

/// Which bands and boundaries a handout of both phases has run: per band
/// and per boundary, the number of the last call that ran it (a call
/// numbers itself from [`PhaseFlags::begin`]; none is ever reset).
#[derive(Debug, Default)]
struct PhaseFlags {
    call: AtomicU64,
    done: Vec<AtomicU64>,
    claimed: Vec<AtomicU64>,
}

impl Clone for PhaseFlags {
    /// Flags for as many bands, none run.
    fn clone(&self) -> PhaseFlags {
        PhaseFlags::new(self.done.len())
    }
}

impl PhaseFlags {
    /// Flags for `bands` bands and the boundaries between them.
    fn new(bands: usize) -> PhaseFlags {
        let none = |k: usize| (0..k).map(|_| AtomicU64::new(0)).collect();
        PhaseFlags {
            call: AtomicU64::new(0),
            done: none(bands),
            claimed: none(bands.saturating_sub(1)),
        }
    }

    /// The number of a new call (by the calling thread, before its handout).
    fn begin(&self) -> u64 {
        self.call.fetch_add(1, Ordering::Relaxed) + 1
    }

    /// After band `i` of call `call`: the boundaries beside it whose other
    /// band is done too and that no one has claimed yet, now claimed.
    /// Sequentially consistent: of two bands done at once, at least one
    /// sees the other done (and only one claims their boundary).
    fn ready_after(&self, i: usize, call: u64) -> impl Iterator<Item = usize> + '_ {
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

/// Runs `region` on every band of rows and every boundary between two (the
/// two `phases`) in one handout of the bands, numbered `call` in `flags`:
/// a band's item, once done, runs each boundary beside it whose other band
/// is done too. A boundary then runs after both its bands, and touches no
/// other: the bits of the phases one after the other, in half the
/// handouts (the stretch limit's passes took eight a substep, the sweep
/// two). Returns the sum of what `region` returns.
fn bands_and_boundaries(
    (phases, flags, call): (&[Vec<Region>; 2], &PhaseFlags, u64),
    team: Team,
    region: impl Fn(&Region) -> u32 + Sync,
) -> u32 {
    let [bands, boundaries] = phases;
    debug_assert_eq!(boundaries.len() + 1, bands.len().max(1));
    team.sum_count(bands.len(), |i| {
        let mut sum = region(&bands[i]);
        for j in flags.ready_after(i, call) {
            sum += region(&boundaries[j]);
        }
        sum
    })
}

/// One family's runs in one region: the family, and per family the rest
/// lengths (whole arrays) and compliance terms.
struct RegionSweep<'a> {
    region: &'a Region,
    p: usize,
    rest: &'a [&'a [f32]; 6],
    k: &'a [Compliance; 6],
}

/// [`sweep_region`], with the AVX2 kernel only when `simd`; `ZERO` and
/// `KEPT` as [`KindInSweep::from_zero`] and [`KindInSweep::kept`].
#[inline(always)]
fn sweep_region_on<const ZERO: bool, const KEPT: bool>(
    job: &RegionSweep,
    view: &mut View,
    lambda: &mut [f32],
    simd: bool,
) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        unsafe { sweep_region_avx2::<ZERO, KEPT>(job, view, lambda) };
        return;
    }
    let _ = simd;
    sweep_region::<ZERO, KEPT>(job, view, lambda);
}

// One family a call, not the region's six: the six in one function made
// one of 60 KB whose registers spilled (the sweep 7% slower on one thread).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sweep_region_avx2<const ZERO: bool, const KEPT: bool>(
    job: &RegionSweep,
    view: &mut View,
    lambda: &mut [f32],
) {
    crate::math::align_frame();
    sweep_region::<ZERO, KEPT>(job, view, lambda);
}

/// The family's runs in the region, with its multipliers there.
#[inline(always)]
fn sweep_region<const ZERO: bool, const KEPT: bool>(
    job: &RegionSweep,
    view: &mut View,
    lambda: &mut [f32],
) {
    let rest = &job.rest[job.p][job.region.lanes.clone()];
    for &seg in &job.region.runs[job.p] {
        run::<ZERO, KEPT>(seg, rest, lambda, view, job.k[job.p]);
    }
}

/// The material's stretch limit on a grid cloth: the stretch springs'
/// runs, up to [`LIMIT_PASSES`] Gauss–Seidel passes (the bands, then the
/// boundaries, each region's families in turn), each spring longer than
/// `factor` times its rest length (by more than [`LIMIT_SLACK`] of it)
/// shortened to it, and past it by 0.9 of its excess
/// ([`LIMIT_OVER_RELAXATION`]). After the first pass, each pass first holds the pairs
/// of stretch springs along rows and columns (the bend springs' runs) to
/// `factor` times the length the pair spans at rest: a coarser level,
/// which carries a correction twice as far a pass and which the springs at
/// their limits always satisfy (it never holds the cloth tighter than they
/// do). After a call of the same step that ended unsettled, the spans of
/// eight springs ([`LONG_SPAN`]) take the pairs' place: a coarser level
/// still. Returns the springs shortened, and when the last pass
/// found none to shorten, the room left: how much (m) any stretch spring
/// may still lengthen before it reaches the limit (the collision stage then
/// knows which springs it need not hold).
///
/// After the first pass, a pass looks only at the springs with an end that
/// the pass before or this one moved (eight lanes at a time): the others
/// were found within the limit and have not changed since, so the bits are
/// those of whole passes (a landing needs dozens of passes to carry a
/// correction across the cloth, and then only some springs still move).
/// When such a pass shortens nothing, the room is 0: the pass before
/// shortened a spring to its limit. Which lanes moved is also kept per
/// tile of [`TILE_LANES`] lanes ([`LimitTiles`]): a region none of whose
/// tiles moved is passed over whole, and from the third pass
/// ([`SKIM_FROM`]) so are a run's springs a tile at a time.
///
/// With `planes` (the second of `limit`, the first being `factor`), each
/// lane a spring moved is put back onto its planes there (when behind one
/// and free) in the same step: the limit and the lanes' contacts with
/// cuboids then meet over their edges in one call.
pub(crate) fn limit_stretch(
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    limit: (f32, Option<LanePlanes>),
    team: Team,
) -> LimitOutcome {
    limit_stretch_with(plan, lanes, limit, team, (simd_available(), false))
}

/// [`limit_stretch`] called again right after a call of the same `limit`
/// that ended [`LimitOutcome::unsettled`], the lanes unchanged since: its
/// first pass looks only at the stretch springs with an end the last call's
/// last pass moved. Every other spring was found within the limit by that
/// call and has not changed since, so a look would leave it as it is: the
/// same bits as [`limit_stretch`]. (The drape at `N = 256` calls the
/// limit 1.6 times a substep over its first 40 frames: its limit takes 5%
/// fewer instructions so.)
pub(crate) fn limit_stretch_again(
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    limit: (f32, Option<LanePlanes>),
    team: Team,
) -> LimitOutcome {
    limit_stretch_with(plan, lanes, limit, team, (simd_available(), true))
}

/// Per lane, the planes that hold it, one in each of `slots` blocks of
/// `lanes` entries (unit normal x, y, z and offset, m: the lane stays
/// where `normal · x ≥ offset`; an offset of −∞ for none), as the lanes'
/// contacts take their cuboids' (`lane_contacts`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LanePlanes<'a> {
    pub arrays: [&'a [f32]; 4],
    pub slots: usize,
    pub lanes: usize,
}

impl LanePlanes<'_> {
    /// Whether every array holds its slots of lanes.
    fn whole(&self) -> bool {
        self.arrays
            .iter()
            .all(|a| a.len() == self.slots * self.lanes)
    }
}

/// What [`limit_stretch`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LimitOutcome {
    /// Springs shortened, over all passes.
    pub shortened: u32,
    /// When the last pass shortened none: how much (m) any stretch spring
    /// may still lengthen before it reaches the limit.
    pub room: Option<f32>,
    /// The last of the [`LIMIT_PASSES`] still shortened a stretch spring
    /// more than [`LIMIT_FAR`] of its rest length over the limit: more
    /// passes are called for (`xpbd::LIMIT_ROUNDS`).
    pub unsettled: bool,
}

/// How far over the limit (a share of the rest length) a spring the last
/// of [`LIMIT_PASSES`] passes shortened must have been for the limit to be
/// [`LimitOutcome::unsettled`]: 0.3%, so that a cotton limited to 4.5% is
/// left under 5% with room for contacts. A spring a little over after the
/// passes is common where a cloth hangs at its limit (the next substep's
/// passes take it) and is left. Measured, peak stretch over every frame
/// of the drape at N = 128 (16 substeps), cotton and silk: 4.83% and 4.86%
/// at 0.1% and at 0.3%, 4.95% and 4.95% at 0.5%; the `pins` sheet hung by
/// two corners 5.61%, 5.53% and 5.58%.
pub(crate) const LIMIT_FAR: f32 = 0.003;

/// What one look at some springs of the stretch limit found.
#[derive(Clone, Copy, Debug)]
struct Tally {
    /// Springs shortened.
    shortened: u32,
    /// Springs more than [`LIMIT_FAR`] of their rest length over the limit.
    far: u32,
    /// The least room below the limit, in squares (limit² − length², m²).
    room: f32,
}

impl Tally {
    /// Nothing looked at.
    const NONE: Tally = Tally {
        shortened: 0,
        far: 0,
        room: f32::INFINITY,
    };

    /// Both looks together.
    fn and(self, other: Tally) -> Tally {
        Tally {
            shortened: self.shortened + other.shortened,
            far: self.far + other.far,
            room: self.room.min(other.room),
        }
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
const LONG_SPAN: usize = 8;

/// How many stretch springs a long span takes along a row stored in
/// `blocks` blocks: [`LONG_SPAN`], or one fewer where that many would
/// join two lanes of one block (a run's two ends would overlap).
fn long_span_along_rows(blocks: usize) -> usize {
    if LONG_SPAN.is_multiple_of(blocks) {
        LONG_SPAN - 1
    } else {
        LONG_SPAN
    }
}

/// How far past its limit a pass of the grid's stretch limit shortens a
/// spring: 1.9 times its excess, so 0.9 of it below the limit
/// (successive over-relaxation of the passes' Gauss–Seidel). A pass then
/// shortens a spring by what the next spring's own shortening will pull
/// back, and a correction crosses a run of springs at their limit in
/// fewer passes; a spring below its limit is no violation (the springs
/// take it back). Measured against 1 (exact projections), the drape at
/// N = 128: the limit's samples halved at 1.5 (1572 → 724 of 3769 → 3087
/// in a 60-frame profile), peaks over every frame 4.84 → 4.67%. From 1.5
/// to 1.9 (thirtieth session; peak stretch over every frame, ms a frame
/// of `run SCENE --frames 120`): the drape at N = 96 and 128, every
/// material, 4.58–4.85% → 4.51–4.55% in the same time; the `hammock`
/// 5.28 → 5.18% and 2.70 → 2.23 ms; the curtain 4.98 → 4.87%; the `fold`
/// 4.13 → 4.50%; the rest unchanged. At N = 256 a landing's limit stayed
/// unsettled after its rounds (`xpbd::LIMIT_ROUNDS`) in most substeps at
/// 24 a frame (6.2% at 1.5, 4.6% at 1.9): the side rule's substeps
/// (`stability.rs`) come from 1.9.
const LIMIT_OVER_RELAXATION: f32 = 1.9;

/// [`limit_stretch`], with the AVX2 kernel only when `simd`.
fn limit_stretch_with(
    plan: &mut GridPlan,
    lanes: &mut Lanes,
    (factor, planes): (f32, Option<LanePlanes>),
    team: Team,
    (simd, again): (bool, bool),
) -> LimitOutcome {
    // Planes for every lane, or none at all.
    let planes = planes.filter(|p| p.whole() && p.lanes == plan.lane.len());
    if !factor.is_finite() {
        return LimitOutcome {
            shortened: 0,
            room: None,
            unsettled: false,
        };
    }
    let (base, filled) = plan.next_limit_base();
    // The last call's marks are this call's pass 0 (its last pass marked
    // `base`), unless they were filled.
    let carried = again && !filled;
    let moved = Disjoint::new(&mut plan.limit_moved[..]);
    let tiles = &plan.limit_tiles.0[..];
    let mut shared = SharedLanes::new(lanes, &mut plan.lambda);
    // A pinned cloth's limit moves particles by their weights near the
    // pins ([`PinSupport`]), not by their inverse masses.
    if let Some(weights) = plan.pin_support.weights(shared.w.len()) {
        shared.w = weights;
    }
    // The pairs of stretch springs along rows and columns first (the bend
    // families' runs, with the length the pair spans at rest), then the
    // stretch springs themselves: a correction crosses the cloth in half
    // the passes. No pair is held to less than its two springs at their
    // limits can reach, so the pairs only hasten what the springs' own
    // limit would come to (a folded pair is shorter and left alone).
    // After an unsettled call, the long spans in place of the pairs
    // ([`LONG_SPAN`]), which reach farther a pass.
    let long = plan.limit_unsettled;
    let spans = if long {
        [0, 1].map(|d| (LONG_RUNS[d], &plan.long_span[d][..]))
    } else {
        [(4, &plan.span[0][..]), (5, &plan.span[1][..])]
    };
    let limits: [(usize, &[f32]); 4] = [
        spans[0],
        spans[1],
        (0, plan.rest.get(0)),
        (1, plan.rest.get(1)),
    ];
    debug_assert!(limits.iter().filter(|&&(p, _)| p < 6).all(|&(p, _)| {
        let kind = plan.passes[p].kind;
        kind == if p < 4 {
            SpringKind::Stretch
        } else {
            SpringKind::Bend
        }
    }));
    let (phases, work, flags) = (&plan.phases, &plan.work, &plan.flags);
    // One pass: the springs it shortened, and the least room of those it
    // looked at (limit² - length², m², as bits: never negative, and
    // non-negative floats order as their bits do, so the regions' minimum
    // is the same in any order, on any thread). The first looks at every
    // spring (`all`); the others skip those whose lanes are unmoved since
    // the pass before.
    let pass = |number: u32, all: bool| -> Tally {
        let room = AtomicU32::new(f32::INFINITY.to_bits());
        let far = AtomicU32::new(0);
        // The first pass: the stretch springs alone. The pairs of those
        // it finds within their limits are within theirs too.
        let limits = if number == 1 {
            &limits[2..]
        } else {
            &limits[..]
        };
        let springs = work
            .iter()
            .flat_map(|work| limits.iter().map(|&(p, _)| work[p]))
            .sum();
        let team = team.for_work(springs, PARALLEL_MIN_SPRINGS);
        let over = bands_and_boundaries((phases, flags, flags.begin()), team, |region| {
            // SAFETY: as in `sweep_with`: disjoint regions, borrowed buffers.
            let (mut view, moved) = unsafe {
                (
                    shared.view(region.lanes.clone()),
                    moved.range(region.lanes.clone()),
                )
            };
            // No tile of the region's watched lanes moved in the pass
            // before or this one: none of its springs is due
            // (`LimitMarks::due` would say so of each), and the region is
            // passed over whole. At rest most regions are, after the
            // first pass. (The tiles, not the lanes' own marks: a scan of
            // those was 5% of the limit's instructions at N = 256.)
            let start = region.lanes.start;
            let watched = if long {
                region.lanes.clone()
            } else {
                start + region.near.start..start + region.near.end
            };
            if !all && !tiles_moved_since(tiles, watched, base + number - 1) {
                return 0;
            }
            let mut tally = Tally::NONE;
            let mut marks = LimitMarks {
                moved,
                first: all,
                skim: number >= SKIM_FROM,
                pass: base + number,
                start,
                tiles,
                planes,
            };
            for &(p, rest) in limits {
                let rest = &rest[region.lanes.clone()];
                let runs = &region.runs[p];
                let mut t = limit_region(runs, rest, &mut view, factor, (&mut marks, simd));
                // The room and the far ones are the stretch springs' alone.
                if p >= 4 {
                    (t.far, t.room) = (0, f32::INFINITY);
                }
                tally = tally.and(t);
            }
            room.fetch_min(tally.room.to_bits(), Ordering::Relaxed);
            far.fetch_add(tally.far, Ordering::Relaxed);
            tally.shortened
        });
        Tally {
            shortened: over,
            far: far.into_inner(),
            room: f32::from_bits(room.into_inner()),
        }
    };
    let mut shortened = 0;
    let mut unsettled = false;
    for number in 1..=LIMIT_PASSES {
        let all = number == 1 && !carried;
        let Tally {
            shortened: over,
            far,
            room: mut squares,
        } = pass(number, all);
        shortened += over;
        unsettled = far > 0;
        if over == 0 {
            // After a pass that shortened a spring to its limit, none has
            // room. Otherwise (the first pass, which looks at every
            // spring): a spring with l² ≤ L² - q has L - l = (L² - l²)/(L
            // + l) ≥ q / 2L, and L is at most the longest limit.
            if number == 1 && !all {
                // A carried first pass measured only the springs it
                // looked at: every spring is within the limit now, and a
                // pass over them all shortens none and measures the room.
                squares = pass(number, true).room;
            }
            let room = if number > 1 {
                0.0
            } else {
                squares / (2.0 * factor * plan.longest_stretch)
            };
            plan.limit_unsettled = false;
            return LimitOutcome {
                shortened,
                room: Some(room),
                unsettled: false,
            };
        }
    }
    plan.limit_unsettled = unsettled;
    LimitOutcome {
        shortened,
        room: None,
        unsettled,
    }
}

/// [`limit_runs`], with the AVX2 kernel only when `simd`.
fn limit_region(
    runs: &[Segment],
    rest: &[f32],
    lanes: &mut View,
    factor: f32,
    (marks, simd): (&mut LimitMarks, bool),
) -> Tally {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` only when the CPU has AVX2.
        return unsafe {
            if marks.planes.is_some() {
                limit_runs_avx2::<true>(runs, rest, lanes, factor, marks)
            } else {
                limit_runs_avx2::<false>(runs, rest, lanes, factor, marks)
            }
        };
    }
    let _ = simd;
    if marks.planes.is_some() {
        limit_runs::<true>(runs, rest, lanes, factor, marks)
    } else {
        limit_runs::<false>(runs, rest, lanes, factor, marks)
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn limit_runs_avx2<const PLANES: bool>(
    runs: &[Segment],
    rest: &[f32],
    lanes: &mut View,
    factor: f32,
    marks: &mut LimitMarks,
) -> Tally {
    crate::math::align_frame();
    limit_runs::<PLANES>(runs, rest, lanes, factor, marks)
}

/// Which lanes of a region a pass of the stretch limit moved: per lane the
/// last pass that moved it (the call's base plus the pass's number from 1;
/// at most the base: none this call), this pass's mark, and whether it is
/// the call's first pass.
struct LimitMarks<'a> {
    moved: &'a mut [u32],
    first: bool,
    /// Whether springs whose tiles did not move are passed over a tile at
    /// a time ([`SKIM_FROM`]).
    skim: bool,
    pass: u32,
    /// The region's first lane among all.
    start: usize,
    /// Per tile of lanes among all, the last pass that moved any of its
    /// lanes ([`LimitTiles`]).
    tiles: &'a [AtomicU32],
    /// The lanes' planes, if the limit holds them ([`limit_stretch`]).
    planes: Option<LanePlanes<'a>>,
}

impl LimitMarks<'_> {
    /// Whether the `M` springs from lanes `a..` to lanes `b..` need a
    /// look: always in the first pass; after it, when an end moved in the
    /// pass before or this one (the others were found within the limit
    /// then and have not changed).
    ///
    /// # Safety
    /// `a + M` and `b + M` are at most the marks' length.
    #[inline(always)]
    unsafe fn due<const M: usize>(&self, (a, b): (usize, usize)) -> bool {
        if self.first {
            return true;
        }
        // SAFETY: in bounds by the caller's promise.
        let (ma, mb) = unsafe {
            (
                self.moved.get_unchecked(a..a + M),
                self.moved.get_unchecked(b..b + M),
            )
        };
        // Whether the pass before or this one moved any end, without a
        // branch per lane (`any` took a test and a jump for each of 2M
        // lanes, a fifth of the hammock's limit): the lanes' comparisons
        // joined by `or`, which is a vector compare and one test.
        let since = self.pass - 1;
        let mut moved = 0u32;
        for c in 0..M {
            moved |= u32::from(ma[c] >= since) | u32::from(mb[c] >= since);
        }
        moved != 0
    }

    /// How many springs from lanes `a..` to lanes `b..` may be passed over
    /// without a look: up to the nearer end of their two tiles when neither
    /// moved in the pass before or this one (then none of their lanes did,
    /// and each spring is within the limit as the pass that last looked at
    /// it left it), else none; none unless skimming. A run's springs share
    /// no particle, so looking at them in other groups of eight gives the
    /// same bits.
    #[inline(always)]
    fn quiet(&self, (a, b): (usize, usize)) -> usize {
        if self.first || !self.skim {
            return 0;
        }
        let (ga, gb) = (self.start + a, self.start + b);
        let since = self.pass - 1;
        let moved = |lane: usize| self.tiles[lane / TILE_LANES].load(Ordering::Relaxed) >= since;
        if moved(ga) || moved(gb) {
            return 0;
        }
        (TILE_LANES - ga % TILE_LANES).min(TILE_LANES - gb % TILE_LANES)
    }

    /// [`limit_chunk`] on the `M` springs from lanes `a..` to lanes `b..`
    /// when they are due (else `None`: nothing shortened, no room
    /// measured), marking all their ends when it shortened any (a spring
    /// looked at again for nothing gives the same bits).
    ///
    /// # Safety
    /// `a + M` and `b + M` are at most the length of the marks, of `rest`
    /// and of the view, and the tiles hold the region's lanes (checked once
    /// a region by `limit_runs`).
    #[inline(always)]
    unsafe fn limit<const M: usize, const PLANES: bool>(
        &mut self,
        (a, b): (usize, usize),
        keep: Option<&[bool; M]>,
        rest: &[f32],
        lanes: &mut View,
        factor: f32,
    ) -> Option<Tally> {
        // SAFETY: in bounds by the caller's promise.
        unsafe {
            if !self.due::<M>((a, b)) {
                return None;
            }
            let planes = self.planes.map(|p| (p, self.start));
            let tally = limit_chunk::<M, PLANES>((a, b), keep, rest, lanes, (factor, planes));
            if tally.shortened > 0 {
                // The run's lanes only: a lane past it marked moved would
                // make springs there due for nothing, pass after pass.
                let len = keep.map_or(M, |k| k.iter().take_while(|&&kept| !kept).count());
                self.moved.get_unchecked_mut(a..a + len).fill(self.pass);
                self.moved.get_unchecked_mut(b..b + len).fill(self.pass);
                // A run of at most `M` lanes meets at most two tiles: those
                // of its ends.
                for lane in [a, a + len - 1, b, b + len - 1] {
                    self.tiles
                        .get_unchecked((self.start + lane) / TILE_LANES)
                        .store(self.pass, Ordering::Relaxed);
                }
            }
            Some(tally)
        }
    }
}

/// The stretch limit on some runs' springs, those `marks` says are due;
/// returns how many it shortened, and the least room left below the limit
/// among those it looked at (m², in squares of lengths).
#[inline(always)]
fn limit_runs<const PLANES: bool>(
    runs: &[Segment],
    rest: &[f32],
    lanes: &mut View,
    factor: f32,
    marks: &mut LimitMarks,
) -> Tally {
    let mut tally = Tally::NONE;
    let lanes_len = lanes.len();
    assert!(
        rest.len() == lanes_len && marks.moved.len() == lanes_len,
        "rest lengths and marks for each lane"
    );
    let end = marks.start + lanes_len;
    assert!(
        end.div_ceil(TILE_LANES) <= marks.tiles.len(),
        "tiles for each lane"
    );
    if let Some(planes) = marks.planes {
        assert!(
            planes.whole() && end <= planes.lanes,
            "planes for each lane"
        );
    }
    for seg in runs {
        let (a, b, len) = (seg.a as usize, seg.b as usize, seg.len as usize);
        // Once a run, for every step's unchecked loads and stores below.
        assert!(a.max(b) + len <= lanes_len, "a run within its region");
        let mut done = 0;
        // A run's springs share no particle: `WIDTH` of them at once give
        // the bits of one at a time.
        // Springs not due are passed over with no tally at all (joined,
        // their nothing changed no number, but the join was a fifth of
        // the limit where most are not due: the hammock).
        while done + WIDTH <= len {
            let quiet = marks.quiet((a + done, b + done));
            if quiet > 0 {
                done = (done + quiet).min(len);
                continue;
            }
            // SAFETY: within the run (asserted).
            let t = unsafe {
                marks.limit::<WIDTH, PLANES>((a + done, b + done), None, rest, lanes, factor)
            };
            if let Some(t) = t {
                tally = tally.and(t);
            }
            done += WIDTH;
        }
        if done == len {
            continue;
        }
        // The short last step as a full one whose lanes past the run keep
        // their bits, where its lanes stay in the region and its two ends'
        // lanes do not meet (as the sweep's `run`; one spring at a time it
        // was a third of the limit on the hammock's short runs). Past the
        // run it shortens nothing and measures no room; it may look at the
        // run's last springs when only a lane past them moved, and finds
        // them within the limit, as they were.
        let (ta, tb) = (a + done, b + done);
        if ta.max(tb) + WIDTH <= lanes_len && apart(ta as u32, tb as u32, WIDTH as u32) {
            let keep: [bool; WIDTH] = std::array::from_fn(|t| t >= len - done);
            // SAFETY: within the region (tested just above).
            let t =
                unsafe { marks.limit::<WIDTH, PLANES>((ta, tb), Some(&keep), rest, lanes, factor) };
            if let Some(t) = t {
                tally = tally.and(t);
            }
            continue;
        }
        while done < len {
            // SAFETY: as above.
            let t = unsafe {
                marks.limit::<1, PLANES>((a + done, b + done), None, rest, lanes, factor)
            };
            if let Some(t) = t {
                tally = tally.and(t);
            }
            done += 1;
        }
    }
    tally
}

/// The stretch limit's marks per tile of [`TILE_LANES`] lanes among all:
/// the last pass that moved a lane of the tile, so never below a lane's
/// own mark. The threads of a pass may share a tile at their regions'
/// edges; each stores the pass's own number there, so what a thread reads
/// is either its own store or one as new, and a tile it finds unmoved has
/// no lane of its region moved (its springs are skipped only then: the
/// same bits on any number of threads).
#[derive(Debug, Default)]
struct LimitTiles(Vec<AtomicU32>);

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

/// The first pass of a call of the stretch limit that passes over the
/// springs of unmoved tiles a tile at a time ([`LimitMarks::quiet`]).
/// Before it most tiles moved, and the test only added to each chunk's
/// own. Measured on the drape at N = 256, one thread, the timed frames'
/// passes alternating call by call with the lanes' own marks alone (three
/// runs): passes from the third 13–16% faster, the second 1.5%.
const SKIM_FROM: u32 = 3;

/// Lanes a tile of the stretch limit's marks sums up: a row's quarter at
/// N = 256.
const TILE_LANES: usize = 64;

/// Whether any tile over `lanes` was moved by pass `since` or later.
#[inline(always)]
fn tiles_moved_since(tiles: &[AtomicU32], lanes: std::ops::Range<usize>, since: u32) -> bool {
    if lanes.is_empty() {
        return false;
    }
    let (first, last) = (lanes.start / TILE_LANES, (lanes.end - 1) / TILE_LANES);
    tiles[first..=last]
        .iter()
        .any(|t| t.load(Ordering::Relaxed) >= since)
}

/// The least of `M` rooms, halves against halves so that the comparisons
/// run as vectors (a chain of `f32::min` was a tenth of the hammock's
/// limit). The rooms are numbers at least +0 (never -0: a difference of
/// equal squares is +0), so every order of comparison finds the same bits.
#[inline(always)]
fn least<const M: usize>(mut room: [f32; M]) -> f32 {
    let mut width = M;
    while width > 1 {
        let half = width / 2;
        for c in 0..half {
            let other = room[c + width - half];
            room[c] = if other < room[c] { other } else { room[c] };
        }
        width -= half;
    }
    if M == 0 {
        f32::INFINITY
    } else {
        room[0]
    }
}

/// The stretch limit on the `M` springs from lanes `a..a + M` to lanes
/// `b..b + M`: each longer than `factor` times its rest length (and with
/// a free end) shortened to it and past it by 0.9 of its excess
/// ([`LIMIT_OVER_RELAXATION`]), its ends moved by their inverse masses.
/// Returns how many it shortened, how many of those were more than
/// [`LIMIT_FAR`] of their rest length over, and the least room the springs
/// had below the limit, in squares (limit² - length², m²; 0 for one over
/// it, or not a number).
///
/// # Safety
/// `a + M` and `b + M` are at most the length of `rest` and of the view.
#[inline(always)]
unsafe fn limit_chunk<const M: usize, const PLANES: bool>(
    (a, b): (usize, usize),
    keep: Option<&[bool; M]>,
    rest: &[f32],
    lanes: &mut View,
    (factor, planes): (f32, Option<(LanePlanes, usize)>),
) -> Tally {
    // The lanes `keep` marks hold no spring of this run: never over, no
    // room (`None`: none kept, which the inlining folds away).
    let kept = |c: usize| keep.is_some_and(|k| k[c]);
    // SAFETY: in bounds by the caller's promise.
    let [xa, ya, za] = unsafe { lanes.positions::<M>(a) };
    let [xb, yb, zb] = unsafe { lanes.positions::<M>(b) };
    let (wa, wb, r) = unsafe {
        (
            load::<M>(lanes.w, a),
            load::<M>(lanes.w, b),
            load::<M>(rest, a),
        )
    };
    // First the squares alone: most springs are surely within the limit
    // (by a margin far above rounding), and then nothing below changes a
    // position, so the root, the division and the stores are not made.
    let (mut room, mut within) = ([0.0f32; M], true);
    for c in 0..M {
        let d = [xb[c] - xa[c], yb[c] - ya[c], zb[c] - za[c]];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let limit2 = (r[c] * factor) * (r[c] * factor);
        let q = limit2 - len2;
        room[c] = if kept(c) {
            f32::INFINITY
        } else if q >= 0.0 {
            q
        } else {
            0.0
        };
        within &= kept(c) || len2 < limit2 * SURELY_WITHIN;
    }
    let room = least(room);
    if within {
        return Tally {
            room,
            ..Tally::NONE
        };
    }
    let (mut over, mut far) = (0, 0);
    // The new positions into new arrays, not selected back over the old
    // (that became masked stores, whose reads could not be forwarded: as
    // in `lane_motion.rs`).
    let [mut na, mut nb] = [[[0.0f32; M]; 3]; 2];
    let mut shortened = [false; M];
    for c in 0..M {
        let d = [xb[c] - xa[c], yb[c] - ya[c], zb[c] - za[c]];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let excess = len - r[c] * factor;
        let w = wa[c] + wb[c];
        // False for an excess that is not a number too.
        let on = excess > r[c] * factor * LIMIT_SLACK && w != 0.0 && !kept(c);
        shortened[c] = on;
        let s = excess * LIMIT_OVER_RELAXATION / (w * len);
        let (sa, sb) = (wa[c] * s, wb[c] * s);
        // Selected, not added as zero: a zero change can flip a zero's sign.
        let pick = |moved: f32, kept: f32| if on { moved } else { kept };
        na[0][c] = pick(xa[c] + d[0] * sa, xa[c]);
        na[1][c] = pick(ya[c] + d[1] * sa, ya[c]);
        na[2][c] = pick(za[c] + d[2] * sa, za[c]);
        nb[0][c] = pick(xb[c] - d[0] * sb, xb[c]);
        nb[1][c] = pick(yb[c] - d[1] * sb, yb[c]);
        nb[2][c] = pick(zb[c] - d[2] * sb, zb[c]);
        over += on as u32;
        far += (on && excess > r[c] * LIMIT_FAR) as u32;
    }
    // `PLANES` known when compiled: without planes the step is the one
    // it was before they came (a branch here slowed the hammock's limit,
    // which holds it at rest, by a tenth).
    if let Some((planes, first)) = planes.filter(|_| PLANES) {
        // SAFETY: the planes hold the region's lanes (checked once a region
        // by `limit_runs`).
        unsafe {
            hold_on_planes::<M>(planes, first + a, &mut na, (&wa, &shortened));
            hold_on_planes::<M>(planes, first + b, &mut nb, (&wb, &shortened));
        }
    }
    // SAFETY: as above.
    unsafe {
        lanes.set_positions(a, na);
        lanes.set_positions(b, nb);
    }
    Tally {
        shortened: over,
        far,
        room,
    }
}

/// Puts each of the `M` lanes from `at` (among all) whose spring was
/// `shortened` and that is free (inverse mass `w` not zero) back onto each
/// of its planes in `planes` that it lies behind (m), slot by slot, as
/// the lanes' contacts do.
///
/// # Safety
/// `at + M` is at most the planes' lanes, and every array holds its slots.
#[inline(always)]
unsafe fn hold_on_planes<const M: usize>(
    planes: LanePlanes,
    at: usize,
    p: &mut [[f32; M]; 3],
    (w, shortened): (&[f32; M], &[bool; M]),
) {
    for slot in 0..planes.slots {
        let at = slot * planes.lanes + at;
        // SAFETY: in bounds by the caller's promise.
        let [nx, ny, nz, offset] = planes.arrays.map(|a| unsafe { load::<M>(a, at) });
        for c in 0..M {
            let gap = offset[c] - (nx[c] * p[0][c] + ny[c] * p[1][c] + nz[c] * p[2][c]);
            let behind = shortened[c] && w[c] != 0.0 && gap > 0.0;
            let n = [nx[c], ny[c], nz[c]];
            for a in 0..3 {
                p[a][c] = if behind {
                    p[a][c] + n[a] * gap
                } else {
                    p[a][c]
                };
            }
        }
    }
}

/// A spring whose squared length is below this share of its squared limit
/// is surely within it, however its length rounds (a few parts in 10⁷).
const SURELY_WITHIN: f32 = 1.0 - 1.0e-5;

/// One spring's projection: new positions of its ends `a` and `b` (m),
/// given the motion of `b` relative to `a` since the substep's start, the
/// inverse masses `w` of the ends, the rest length (0: no spring here) and
/// the multiplier `lambda` so far this substep, which it updates.
///
/// With `d = b − a`, `l = |d|` and `D = (1 + γ)(w_a + w_b) + α`:
/// `Δλ = −(l − L + αλ + γ d·m / l) / D`, and the ends move by `w Δλ d / l`.
/// Both are written over `l² D`, which needs no root:
/// `s = −(l (l − L + αλ) + γ d·m) / (l² D)`, `Δλ = s l`, moves `w s d`.
/// The one division then runs beside the root instead of after it (a
/// root, then two divisions one after the other, was the sweep's longest
/// chain).
#[inline(always)]
pub(super) fn project(
    a: [f32; 3],
    b: [f32; 3],
    motion: [f32; 3],
    w: [f32; 2],
    (rest, lambda): (f32, &mut f32),
    k: Compliance,
) -> ([f32; 3], [f32; 3]) {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let wsum = w[0] + w[1];
    // A missing spring, two pinned ends or coincident ends: no change.
    let active = rest > 0.0 && wsum > 0.0 && len2 > f32::MIN_POSITIVE;
    let denom = (1.0 + k.gamma) * wsum + k.alpha;
    let inv_l2d = 1.0 / (len2 * denom);
    let len = len2.sqrt();
    let rate = d[0] * motion[0] + d[1] * motion[1] + d[2] * motion[2];
    let num = len * (len - rest + k.alpha * *lambda) + k.gamma * rate;
    let s = if active { -num * inv_l2d } else { 0.0 };
    *lambda += s * len;
    let (sa, sb) = (w[0] * s, w[1] * s);
    (
        [a[0] - d[0] * sa, a[1] - d[1] * sa, a[2] - d[2] * sa],
        [b[0] + d[0] * sb, b[1] + d[1] * sb, b[2] + d[2] * sb],
    )
}

/// Springs handled by one vector step: the 8 lanes of an AVX2 register.
const WIDTH: usize = 8;

/// The springs of one run, `WIDTH` at a time (`ZERO`, `KEPT`: as for
/// [`chunk`]).
#[inline(always)]
fn run<const ZERO: bool, const KEPT: bool>(
    seg: Segment,
    rest: &[f32],
    lambda: &mut [f32],
    lanes: &mut View,
    k: Compliance,
) {
    let (a0, b0, len) = (seg.a as usize, seg.b as usize, seg.len as usize);
    let room = lanes.len();
    // Once a run, for every step's unchecked loads and stores below.
    assert!(
        a0.max(b0) + len <= room && rest.len() == room && lambda.len() == room,
        "a run within its region"
    );
    let mut done = 0;
    while done + WIDTH <= len {
        // Full steps: copies of a constant length, which are vector loads and stores.
        // SAFETY: within the run, which is within the region (asserted).
        unsafe { chunk::<WIDTH, ZERO, KEPT>((a0 + done, b0 + done), None, rest, lambda, lanes, k) };
        done += WIDTH;
    }
    if done == len {
        return;
    }
    // The short last step: a full step whose lanes past the run keep their
    // values, when its lanes stay in the region and the two ends' lanes do
    // not meet (each lane then read and written once); otherwise one spring
    // at a time. Either way the same arithmetic for each spring, so the
    // same bits; the masked step costs what a full one does, where the
    // spring-at-a-time tail cost as much as the rest of a 16-spring run.
    let (a, b) = (a0 + done, b0 + done);
    if a.max(b) + WIDTH <= room && apart(a as u32, b as u32, WIDTH as u32) {
        let keep: [bool; WIDTH] = std::array::from_fn(|t| t >= len - done);
        // SAFETY: within the region (tested just above).
        unsafe { chunk::<WIDTH, ZERO, KEPT>((a, b), Some(&keep), rest, lambda, lanes, k) };
        return;
    }
    while done < len {
        // SAFETY: within the run (asserted above).
        unsafe { chunk::<1, ZERO, KEPT>((a0 + done, b0 + done), None, rest, lambda, lanes, k) };
        done += 1;
    }
}

/// Projects the `M` springs from lanes `a..a + M` to lanes `b..b + M`,
/// leaving the lanes `keep` marks as they were (their springs are not
/// projected; `None`: no lane kept, which the inlining folds away). With
/// `ZERO` the multipliers start at zero instead of being read; with
/// `KEPT` they are stored. Zero read or zero taken, the bits are the same.
///
/// # Safety
/// `a + M` and `b + M` are at most the view's length, which `rest` and
/// `lambda` have too.
#[inline(always)]
unsafe fn chunk<const M: usize, const ZERO: bool, const KEPT: bool>(
    (a, b): (usize, usize),
    keep: Option<&[bool; M]>,
    rest: &[f32],
    lambda: &mut [f32],
    lanes: &mut View,
    k: Compliance,
) {
    // SAFETY: in bounds by the caller's promise. (No closures here: one
    // passed to `array::map` is not compiled for AVX2, and its loads were
    // not vector loads.)
    let [mut xa, mut ya, mut za] = unsafe { lanes.positions::<M>(a) };
    let [mut xb, mut yb, mut zb] = unsafe { lanes.positions::<M>(b) };
    let (sxa, sya, sza) = unsafe {
        (
            load::<M>(lanes.sx, a),
            load::<M>(lanes.sy, a),
            load::<M>(lanes.sz, a),
        )
    };
    let (sxb, syb, szb) = unsafe {
        (
            load::<M>(lanes.sx, b),
            load::<M>(lanes.sy, b),
            load::<M>(lanes.sz, b),
        )
    };
    let (wa, wb) = unsafe { (load::<M>(lanes.w, a), load::<M>(lanes.w, b)) };
    let mut r = unsafe { load::<M>(rest, a) };
    // The lanes kept need their multipliers as they were, to store back.
    let mut l = if ZERO && (keep.is_none() || !KEPT) {
        [0.0; M]
    } else {
        unsafe { load::<M>(lambda, a) }
    };
    if let Some(keep) = keep {
        // A rest length of 0: no spring, no change (`project`).
        for c in 0..M {
            r[c] = if keep[c] { 0.0 } else { r[c] };
        }
    }
    let old = keep.map(|_| (xa, ya, za, xb, yb, zb, l));
    if ZERO {
        l = [0.0; M];
    }
    for c in 0..M {
        let motion = [
            (xb[c] - sxb[c]) - (xa[c] - sxa[c]),
            (yb[c] - syb[c]) - (ya[c] - sya[c]),
            (zb[c] - szb[c]) - (za[c] - sza[c]),
        ];
        let (na, nb) = project(
            [xa[c], ya[c], za[c]],
            [xb[c], yb[c], zb[c]],
            motion,
            [wa[c], wb[c]],
            (r[c], &mut l[c]),
            k,
        );
        [xa[c], ya[c], za[c]] = na;
        [xb[c], yb[c], zb[c]] = nb;
    }
    if let (Some(keep), Some((oxa, oya, oza, oxb, oyb, ozb, ol))) = (keep, old) {
        // Back as they were, bit for bit (a zero change can flip a zero's sign).
        for c in 0..M {
            if keep[c] {
                (xa[c], ya[c], za[c]) = (oxa[c], oya[c], oza[c]);
                (xb[c], yb[c], zb[c]) = (oxb[c], oyb[c], ozb[c]);
                l[c] = ol[c];
            }
        }
    }
    // SAFETY: as above.
    unsafe {
        lanes.set_positions(a, [xa, ya, za]);
        lanes.set_positions(b, [xb, yb, zb]);
        if KEPT {
            store(lambda, a, l);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::{Cloth, ClothBuilder};

    /// A 13×9 grid, jittered, with a few pinned particles, as lanes.
    fn setup() -> (GridPlan, Lanes) {
        grid_lanes((13, 9), |i, p| {
            let j = (i as f32 * 0.37).sin() * 0.01;
            [p.x + j, p.y - j, p.z + 0.5 * j]
        })
    }

    /// A `cols` × `rows` grid's plan and lanes: particle `i` at
    /// `place(i, p)`, `p` where the builder put it (and where the substep
    /// started), every 17th pinned.
    fn grid_lanes(
        (cols, rows): (usize, usize),
        place: impl Fn(usize, crate::math::Vector) -> [f32; 3],
    ) -> (GridPlan, Lanes) {
        let cloth = ClothBuilder::new(cols, rows).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        let mut lanes = Columns::default();
        for (i, &p) in cloth.positions().iter().enumerate() {
            let [x, y, z] = place(i, p);
            lanes.x.push(x);
            lanes.y.push(y);
            lanes.z.push(z);
            lanes.sx.push(p.x);
            lanes.sy.push(p.y);
            lanes.sz.push(p.z);
            lanes.w.push(if i % 17 == 0 { 0.0 } else { 100.0 });
        }
        let lanes = in_lane_order(&plan, lanes);
        (plan, lanes)
    }

    /// Lanes' arrays filled in particle order.
    #[derive(Default)]
    struct Columns {
        x: Vec<f32>,
        y: Vec<f32>,
        z: Vec<f32>,
        sx: Vec<f32>,
        sy: Vec<f32>,
        sz: Vec<f32>,
        w: Vec<f32>,
    }

    /// `lanes` filled in particle order, moved to the plan's lane order.
    fn in_lane_order(plan: &GridPlan, lanes: Columns) -> Lanes {
        let mut out = Lanes::default();
        out.resize(lanes.x.len());
        let from = [
            lanes.x, lanes.y, lanes.z, lanes.sx, lanes.sy, lanes.sz, lanes.w,
        ];
        for (to, from) in out.arrays_mut().into_iter().zip(from) {
            for (i, v) in from.into_iter().enumerate() {
                to[plan.lane(i)] = v;
            }
        }
        out
    }

    /// The positions' bits, x then y then z.
    fn bits(lanes: &mut Lanes) -> Vec<u32> {
        let [x, y, z, ..] = lanes.arrays_mut();
        x.iter()
            .chain(&*y)
            .chain(&*z)
            .map(|v| v.to_bits())
            .collect()
    }

    /// A torn grid's plan holds each spring once, in a run at its lane or
    /// among the leftovers: those of the new particles and of the particles
    /// at the tear's edge there; each particle has one lane, the new ones
    /// past the grid's, in the last band. A whole grid has no leftovers.
    #[test]
    fn a_torn_grids_plan_holds_every_spring_once() {
        let runs = |plan: &GridPlan| -> usize {
            (0..6)
                .map(|p| plan.rest.get(p).iter().filter(|&&r| r > 0.0).count())
                .sum()
        };
        let mut cloth = ClothBuilder::new(13, 9).build().unwrap();
        let whole = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        assert_eq!(whole.leftover.len(), 0);
        assert_eq!(runs(&whole), cloth.springs().len());
        for r in 2..=5 {
            let i = cloth.index(r, 6).unwrap();
            assert!(cloth
                .split_particle(i, crate::math::Vector::X)
                .unwrap()
                .is_some());
        }
        let lanes = cloth.topology().torn_lane_grid().unwrap();
        let (grid, n) = (13 * 9, cloth.particle_count());
        assert_eq!(n, grid + 4);
        assert!(GridPlan::stacked(lanes, cloth.springs()).is_none());
        let plan = GridPlan::torn(lanes, cloth.springs(), n).unwrap();
        assert!(plan.is_torn());
        assert_eq!(runs(&plan) + plan.leftover.len(), cloth.springs().len());
        let (a, b) = cloth.springs().endpoints();
        let edge = at_tears(grid, (a, b));
        let at_edge = (0..a.len())
            .filter(|&s| {
                [a[s], b[s]]
                    .iter()
                    .any(|&e| e as usize >= grid || edge[e as usize])
            })
            .count();
        assert!(at_edge > 4, "the tear's springs: {at_edge}");
        assert_eq!(plan.leftover.len(), at_edge);
        let mut seen = plan.lane.clone();
        seen.sort_unstable();
        assert!(seen.iter().copied().eq(0..n as u32), "a lane each");
        assert!((grid..n).all(|i| plan.lane(i) == i));
        assert_eq!(plan.phases[0].last().unwrap().lanes.end, n);
    }

    #[test]
    fn the_vectorised_and_the_portable_sweeps_give_the_same_bits() {
        let k = [
            Compliance {
                alpha: 0.5,
                gamma: 0.1,
            },
            Compliance {
                alpha: 2.0,
                gamma: 0.0,
            },
            Compliance {
                alpha: 50.0,
                gamma: 0.3,
            },
        ];
        let (mut plan_a, mut a) = setup();
        let (mut plan_b, mut b) = setup();
        for _ in 0..3 {
            sweep(
                &mut plan_a,
                &mut a,
                &k,
                [KindInSweep::READ_AND_KEPT; 3],
                Team::ALONE,
            );
            sweep_with(
                &mut plan_b,
                &mut b,
                &k,
                [KindInSweep::READ_AND_KEPT; 3],
                Team::ALONE,
                false,
            );
        }
        assert_eq!(bits(&mut a), bits(&mut b));
        // And the sweep did move them: the check can fail.
        let (_, mut fresh) = setup();
        assert_ne!(bits(&mut a), bits(&mut fresh));
    }

    /// A call of the stretch limit with `factor` and no planes, on one
    /// thread, with the AVX2 kernel only when `simd`.
    fn limit_with_simd(
        plan: &mut GridPlan,
        lanes: &mut Lanes,
        factor: f32,
        simd: bool,
    ) -> LimitOutcome {
        limit_stretch_with(plan, lanes, (factor, None), Team::ALONE, (simd, false))
    }

    /// A call of the limit with `factor` on `setup()`'s lanes, with the
    /// portable kernel and with AVX2 where the CPU has it, shortens
    /// `shortened` springs and leaves the bits of `reference`; `then` looks
    /// further at each kernel's plan and outcome.
    fn each_kernel_limits_as(
        setup: impl Fn() -> (GridPlan, Lanes),
        factor: f32,
        (reference, shortened): (&mut Lanes, u32),
        mut then: impl FnMut(&mut GridPlan, LimitOutcome, bool),
    ) {
        let reference = bits(reference);
        for simd in [false, simd_available()] {
            let (mut plan, mut lanes) = setup();
            let outcome = limit_with_simd(&mut plan, &mut lanes, factor, simd);
            assert_eq!(outcome.shortened, shortened);
            assert_eq!(bits(&mut lanes), reference);
            then(&mut plan, outcome, simd);
        }
    }

    /// The stretch limit as it was written first, one spring at a time.
    fn limit_one_by_one(plan: &GridPlan, lanes: &mut Lanes, factor: f32) -> u32 {
        limit_one_by_one_with(plan, lanes, factor, Spans::Pairs)
    }

    /// What the reference limit holds besides the stretch springs.
    #[derive(Clone, Copy, PartialEq)]
    enum Spans {
        None,
        Pairs,
        Long,
    }

    /// [`limit_one_by_one`], with the pairs of stretch springs, the long
    /// spans or neither.
    fn limit_one_by_one_with(plan: &GridPlan, lanes: &mut Lanes, factor: f32, spans: Spans) -> u32 {
        let [x, y, z, _, _, _, w] = lanes.arrays_mut();
        let mut over = 0;
        for number in 1..=LIMIT_PASSES {
            let mut this_pass = 0;
            // The pairs or long spans along rows and columns (after the
            // first pass), then the stretch springs, region by region.
            let [rows, cols]: [(usize, &[f32]); 2] = match spans {
                Spans::Long => [
                    (LONG_RUNS[0], &plan.long_span[0]),
                    (LONG_RUNS[1], &plan.long_span[1]),
                ],
                _ => [(4, &plan.span[0]), (5, &plan.span[1])],
            };
            let limits: &[(usize, &[f32])] =
                &[rows, cols, (0, plan.rest.get(0)), (1, plan.rest.get(1))];
            let limits = if number == 1 || spans == Spans::None {
                &limits[2..]
            } else {
                limits
            };
            for region in plan.phases.iter().flatten() {
                for &(p, rest) in limits {
                    let o = region.lanes.start;
                    let rest = &rest[o..];
                    for seg in &region.runs[p] {
                        for t in 0..seg.len as usize {
                            let (a, b) = (seg.a as usize + t, seg.b as usize + t);
                            let (ga, gb) = (o + a, o + b);
                            let d = [x[gb] - x[ga], y[gb] - y[ga], z[gb] - z[ga]];
                            let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                            let limit = rest[a] * factor;
                            let excess = len - limit;
                            let wsum = w[ga] + w[gb];
                            if excess.is_nan() || excess <= limit * LIMIT_SLACK || wsum == 0.0 {
                                continue;
                            }
                            let s = excess * LIMIT_OVER_RELAXATION / (wsum * len);
                            let (sa, sb) = (w[ga] * s, w[gb] * s);
                            x[ga] += d[0] * sa;
                            y[ga] += d[1] * sa;
                            z[ga] += d[2] * sa;
                            x[gb] -= d[0] * sb;
                            y[gb] -= d[1] * sb;
                            z[gb] -= d[2] * sb;
                            this_pass += 1;
                        }
                    }
                }
            }
            over += this_pass;
            if this_pass == 0 {
                break;
            }
        }
        over
    }

    #[test]
    fn the_vectorised_stretch_limit_gives_the_bits_of_one_spring_at_a_time() {
        // Stretched by 8% along x and z: most stretch springs over 2%.
        let stretched = || {
            let (plan, mut lanes) = setup();
            for v in lanes.arrays_mut().into_iter().step_by(2).take(2) {
                v.iter_mut().for_each(|v| *v *= 1.08);
            }
            (plan, lanes)
        };
        let (plan, mut reference) = stretched();
        let shortened = limit_one_by_one(&plan, &mut reference, 1.02);
        assert!(shortened > 50, "only {shortened} springs over the limit");
        each_kernel_limits_as(stretched, 1.02, (&mut reference, shortened), |_, _, _| {});
    }

    /// A limit that moves a few springs in a large grid passes over most
    /// tiles ([`LimitTiles`]) from its third pass: the same bits as one
    /// spring at a time, and the tiles far from the pulled corner unmoved.
    #[test]
    fn the_stretch_limit_passing_over_unmoved_tiles_gives_the_bits_of_one_spring_at_a_time() {
        // 96 × 80: 120 tiles. A corner of 6 × 6 particles pulled 10% out.
        let pulled = || {
            grid_lanes((96, 80), |i, p| {
                let (r, c) = (i / 96, i % 96);
                let s = if r < 6 && c < 6 { 1.1 } else { 1.0 };
                [p.x * s, p.y, p.z * s]
            })
        };
        let (plan, mut reference) = pulled();
        let shortened = limit_one_by_one(&plan, &mut reference, 1.02);
        assert!(shortened > 20, "only {shortened} springs over the limit");
        each_kernel_limits_as(pulled, 1.02, (&mut reference, shortened), |plan, _, _| {
            let tiles = &plan.limit_tiles.0;
            let unmoved = tiles
                .iter()
                .filter(|t| t.load(Ordering::Relaxed) == 0)
                .count();
            assert!(
                unmoved > tiles.len() / 2,
                "{unmoved} of {} tiles unmoved",
                tiles.len()
            );
        });
    }

    /// After an unsettled call the limit holds the long spans in place of
    /// the pairs, with the bits of one spring at a time, and their lengths
    /// are those of the stretch springs they take.
    #[test]
    fn after_an_unsettled_call_the_limit_holds_the_long_spans() {
        let stretched = || {
            let (mut plan, mut lanes) = grid_lanes((21, 2 * BAND_ROWS + 5), |i, p| {
                let j = (i as f32 * 0.37).sin() * 0.01;
                [p.x + j, p.y - j, p.z + 0.5 * j]
            });
            plan.limit_unsettled = true;
            for v in lanes.arrays_mut().into_iter().step_by(2).take(2) {
                v.iter_mut().for_each(|v| *v *= 1.08);
            }
            (plan, lanes)
        };
        let (plan, mut reference) = stretched();
        let (cols, rows) = plan.shape;
        let (dr, dc) = (plan.long_steps[1].0, plan.long_steps[0].1 as usize);
        assert!(dr == LONG_SPAN && (dc == LONG_SPAN || dc == LONG_SPAN - 1));
        // The grid is spaced evenly: a span is its springs' rest lengths.
        let (dx, dz) = (1.0 / (cols - 1) as f32, 1.0 / (rows - 1) as f32);
        for i in 0..cols * rows {
            let (r, c, lane) = (i / cols, i % cols, plan.lane(i));
            let along_row = if c + dc < cols { dc as f32 * dx } else { 0.0 };
            let along_column = if r + dr < rows { dr as f32 * dz } else { 0.0 };
            assert!((plan.long_span[0][lane] - along_row).abs() < 1e-5);
            assert!((plan.long_span[1][lane] - along_column).abs() < 1e-5);
        }
        let shortened = limit_one_by_one_with(&plan, &mut reference, 1.02, Spans::Long);
        let (plan_pairs, mut pairs) = stretched();
        limit_one_by_one_with(&plan_pairs, &mut pairs, 1.02, Spans::Pairs);
        assert_ne!(bits(&mut pairs), bits(&mut reference), "the spans held");
        assert!(shortened > 50, "only {shortened} springs over the limit");
        each_kernel_limits_as(
            stretched,
            1.02,
            (&mut reference, shortened),
            |plan, outcome, _| {
                assert_eq!(plan.limit_unsettled, outcome.unsettled);
            },
        );
    }

    /// A cloth of several bands of rows stretched at one end only: after
    /// the first pass the limit passes over the regions none of whose lanes
    /// moved, and still gives the bits of every spring looked at in every
    /// pass.
    #[test]
    fn regions_left_unmoved_are_passed_over_with_the_same_bits() {
        let stretched = || {
            let (plan, lanes) = grid_lanes((12, 5 * BAND_ROWS), |i, p| {
                // The first rows stretched by 8% along x and z; the rest as built.
                let f = if i < 3 * 12 { 1.08 } else { 1.0 };
                let j = (i as f32 * 0.37).sin() * 1.0e-4;
                [p.x * f + j, p.y, p.z * f]
            });
            assert!(plan.phases[0].len() >= 4, "bands of rows");
            (plan, lanes)
        };
        let (plan, mut reference) = stretched();
        let shortened = limit_one_by_one(&plan, &mut reference, 1.02);
        assert!(shortened > 20, "only {shortened} springs over the limit");
        let reference_bits = bits(&mut reference);
        each_kernel_limits_as(
            stretched,
            1.02,
            (&mut reference, shortened),
            |plan, _, simd| {
                // Some region was passed over whole in the later passes: its
                // marks are all 0 (unmoved in every pass).
                let untouched = plan.phases[0]
                    .iter()
                    .filter(|r| plan.limit_moved[r.lanes.clone()].iter().all(|&m| m == 0))
                    .count();
                assert!(untouched > 0, "every region moved");
                // Calls again on the same plan: their marks above the first
                // call's (never filled), and once with the base come round
                // (the marks filled then): the same bits.
                for base in [None, Some(u32::MAX - LIMIT_PASSES)] {
                    let (_, mut again) = stretched();
                    if let Some(base) = base {
                        plan.limit_base = base;
                    }
                    // As a step's first call: with the pairs, whatever the
                    // call before ended with.
                    plan.forget_unsettled();
                    let outcome = limit_with_simd(plan, &mut again, 1.02, simd);
                    assert_eq!(outcome.shortened, shortened);
                    assert_eq!(bits(&mut again), reference_bits);
                }
                assert_eq!(plan.limit_base, LIMIT_PASSES, "the base came round");
            },
        );
    }

    /// Each pair of stretch springs along a row or a column is held to the
    /// length the two span at rest (on a grid spaced unevenly along rows
    /// and columns), and holding the pairs brings a cloth stretched far past
    /// the limit closer to it in the same passes than the springs alone.
    #[test]
    fn the_pairs_of_stretch_springs_hasten_the_limit() {
        let cloth = ClothBuilder::new(13, 9).size(1.3, 0.7).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        let (cols, rows) = (13, 9);
        let (dx, dz) = (1.3 / 12.0, 0.7 / 8.0);
        for r in 0..rows {
            for c in 0..cols {
                let lane = plan.lane(r * cols + c);
                let along_row = if c + 2 < cols { 2.0 * dx } else { 0.0 };
                let along_column = if r + 2 < rows { 2.0 * dz } else { 0.0 };
                assert!((plan.span[0][lane] - along_row).abs() < 1e-6);
                assert!((plan.span[1][lane] - along_column).abs() < 1e-6);
            }
        }
        // The worst stretch of a free cloth stretched 40% along x and z,
        // after the limit of 1% with the pairs and without.
        let worst = |spans: Spans| {
            let (plan, mut lanes) = setup();
            let [x, _, z, .., w] = lanes.arrays_mut();
            for v in x.iter_mut().chain(z.iter_mut()) {
                *v *= 1.4;
            }
            w.fill(100.0);
            limit_one_by_one_with(&plan, &mut lanes, 1.01, spans);
            let [x, y, z, ..] = lanes.arrays_mut();
            let springs = cloth_springs();
            springs
                .range(SpringKind::Stretch)
                .map(|s| {
                    let (a, b) = (
                        plan.lane(springs.a[s] as usize),
                        plan.lane(springs.b[s] as usize),
                    );
                    let d = [x[b] - x[a], y[b] - y[a], z[b] - z[a]];
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() / springs.rest[s]
                })
                .fold(0.0, f32::max)
        };
        let (with, without) = (worst(Spans::Pairs), worst(Spans::None));
        assert!(
            without > 1.02,
            "{without}: the test needs a limit not reached"
        );
        assert!(
            with < without - 0.005,
            "with the pairs {with}, without {without}"
        );
    }

    /// With planes, every free lane the limit moves ends on the front of
    /// each of its planes (two slots: two planes a lane, some lanes with
    /// none); without them the same limit leaves lanes behind. Lanes start
    /// on their planes, so any move into one shows.
    #[test]
    fn the_limit_puts_the_lanes_it_moves_back_onto_their_planes() {
        let normals = [
            crate::math::Vector::new(0.3, 1.0, -0.2).normalize(),
            crate::math::Vector::new(-0.5, 0.2, 1.0).normalize(),
        ];
        let run = |with: bool| {
            let (mut plan, mut lanes) = setup();
            let n = plan.lane.len();
            let [x, y, z, .., w] = lanes.arrays_mut();
            for v in x.iter_mut().chain(z.iter_mut()) {
                *v *= 1.4;
            }
            w.iter_mut().filter(|w| **w != 0.0).for_each(|w| *w = 100.0);
            let mut arrays: [Vec<f32>; 4] = Default::default();
            for (slot, m) in normals.iter().enumerate() {
                for k in 0..n {
                    let p = crate::math::Vector::new(x[k], y[k], z[k]);
                    let some = (k + slot) % 3 != 0;
                    let plane = [
                        m.x,
                        m.y,
                        m.z,
                        if some { m.dot(p) } else { f32::NEG_INFINITY },
                    ];
                    for (a, v) in arrays.iter_mut().zip(plane) {
                        a.push(v);
                    }
                }
            }
            let planes = LanePlanes {
                arrays: arrays.each_ref().map(|a| &a[..]),
                slots: 2,
                lanes: n,
            };
            let limit = (1.02, with.then_some(planes));
            let shortened = limit_stretch(&mut plan, &mut lanes, limit, Team::ALONE).shortened;
            assert!(shortened > 0);
            let [x, y, z, .., w] = lanes.arrays_mut();
            // The deepest a free lane lies behind one of its planes (m).
            let mut deepest = 0.0f32;
            for (slot, m) in normals.iter().enumerate() {
                for k in (0..n).filter(|&k| w[k] != 0.0) {
                    let p = crate::math::Vector::new(x[k], y[k], z[k]);
                    deepest = deepest.max(arrays[3][slot * n + k] - m.dot(p));
                }
            }
            deepest
        };
        let (with, without) = (run(true), run(false));
        assert!(
            without > 1.0e-3,
            "{without} m: the test needs lanes moved behind"
        );
        assert!(with <= 1.0e-6, "{with} m behind a plane");
    }

    /// The springs of the cloth of [`setup`].
    fn cloth_springs() -> crate::cloth::Springs {
        ClothBuilder::new(13, 9).build().unwrap().springs().clone()
    }

    /// A call of the limit again after one that ended unsettled looks
    /// only at the springs that call still moved, with the same bits.
    #[test]
    fn a_call_again_gives_the_bits_of_a_call_that_looks_at_every_spring() {
        for simd in [false, simd_available()] {
            // Stretched 5% against a 1% limit: unsettled for some calls, then
            // settled.
            let stretched = || {
                let (plan, mut lanes) = setup();
                for v in lanes.arrays_mut().into_iter().take(3) {
                    v.iter_mut().for_each(|v| *v *= 1.05);
                }
                (plan, lanes)
            };
            let (mut plan, mut lanes) = stretched();
            let (mut plan_again, mut lanes_again) = stretched();
            let (mut unsettled, mut settled) = (0, 0);
            // Past the calls that settle it too: a call again after a
            // settled one finds every spring within, and measures the room.
            for call in 0..40 {
                let limit = (1.01, None);
                let fresh =
                    limit_stretch_with(&mut plan, &mut lanes, limit, Team::ALONE, (simd, false));
                // The first call of the other is a fresh one too.
                let again = limit_stretch_with(
                    &mut plan_again,
                    &mut lanes_again,
                    limit,
                    Team::ALONE,
                    (simd, call > 0),
                );
                assert_eq!(
                    (
                        fresh.shortened,
                        fresh.unsettled,
                        fresh.room.map(f32::to_bits)
                    ),
                    (
                        again.shortened,
                        again.unsettled,
                        again.room.map(f32::to_bits)
                    )
                );
                assert_eq!(bits(&mut lanes), bits(&mut lanes_again));
                unsettled += u32::from(fresh.unsettled);
                settled += u32::from(fresh.room.is_some());
            }
            assert!(unsettled > 1, "{unsettled} {settled}");
            assert!(settled > 1, "{unsettled} {settled}");
        }
    }

    /// The room the limit reports is, over every stretch spring of the
    /// cloth, the least of limit² - length² over twice the longest limit:
    /// never more than the least room (limit - length), and close to it
    /// for springs near their limit. When the passes could not bring every
    /// spring within it, no room is claimed and the limit is unsettled.
    #[test]
    fn the_stretch_limit_reports_the_least_room_left() {
        let cloth = ClothBuilder::new(13, 9).build().unwrap();
        let springs = cloth.springs();
        let stretch = springs.range(SpringKind::Stretch);
        let longest = stretch.clone().map(|s| springs.rest[s]).fold(0.0, f32::max);
        // (least limit - length, least limit² - length² over 2 × longest limit)
        let rooms = |plan: &GridPlan, lanes: &mut Lanes, factor: f32| {
            let [x, y, z, ..] = lanes.arrays_mut();
            let (mut least, mut squares) = (f32::INFINITY, f32::INFINITY);
            for s in stretch.clone() {
                let (a, b) = (
                    plan.lane(springs.a[s] as usize),
                    plan.lane(springs.b[s] as usize),
                );
                let d = [x[b] - x[a], y[b] - y[a], z[b] - z[a]];
                let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                let limit = springs.rest[s] * factor;
                least = least.min(limit - len2.sqrt());
                squares = squares.min(limit * limit - len2);
            }
            (least, squares / (2.0 * factor * longest))
        };
        for simd in [false, simd_available()] {
            // Within a generous limit.
            let (mut plan, mut lanes) = setup();
            let limited = limit_with_simd(&mut plan, &mut lanes, 1.3, simd);
            let LimitOutcome {
                shortened: n, room, ..
            } = limited;
            assert_eq!(n, 0);
            let (least, bound) = rooms(&plan, &mut lanes, 1.3);
            assert!(least > 0.0 && least < 0.3 * longest);
            assert!(bound <= least && bound > 0.5 * least, "{bound} {least}");
            assert_eq!(room.map(f32::to_bits), Some(bound.to_bits()));
            // Jostled against a 5% limit: a few springs over it, brought
            // within it in a few passes, the passes after the first looking
            // only at the springs still moving; a spring was shortened to its
            // limit, so none has room.
            let (mut plan, mut lanes) = setup();
            let limited = limit_with_simd(&mut plan, &mut lanes, 1.05, simd);
            let LimitOutcome {
                shortened: n,
                room,
                unsettled,
            } = limited;
            assert!(n > 5, "{n}");
            let (least, _) = rooms(&plan, &mut lanes, 1.05);
            assert!(least > -1e-4 * longest, "{least}");
            assert_eq!(room, Some(0.0));
            assert!(!unsettled);
            // Stretched 30% against a 1% limit: the passes do not bring
            // every spring within it, and no room is claimed.
            let (mut plan, mut lanes) = setup();
            for v in lanes.arrays_mut().into_iter().take(3) {
                v.iter_mut().for_each(|v| *v *= 1.3);
            }
            let limited = limit_with_simd(&mut plan, &mut lanes, 1.01, simd);
            let LimitOutcome {
                shortened: n,
                room,
                unsettled,
            } = limited;
            assert!(n > 0);
            let least = rooms(&plan, &mut lanes, 1.01).0;
            assert!(least < -LIMIT_FAR * longest, "{least}");
            assert_eq!(room, None);
            // Far over it still, after every pass it may take.
            assert!(unsettled);
        }
    }

    #[test]
    fn a_masked_last_step_gives_the_bits_of_one_spring_at_a_time() {
        // A run of 11 springs from lanes 0.. to lanes 16..: one full step,
        // then 3 springs in a masked step whose other 5 lanes hold springs
        // of their own (rest lengths > 0) that must stay untouched.
        let n = 32;
        let arrays = || -> [Vec<f32>; 9] {
            let f = |s: f32| (0..n).map(|i| (i as f32 * s).sin()).collect::<Vec<_>>();
            [
                f(0.37),
                f(0.71),
                f(1.13),
                f(0.5),
                f(0.9),
                f(1.3),
                (0..n).map(|i| if i % 7 == 0 { 0.0 } else { 2.0 }).collect(),
                (0..n).map(|i| 0.1 + 0.01 * i as f32).collect(),
                (0..n).map(|i| -0.001 * i as f32).collect(),
            ]
        };
        let k = Compliance {
            alpha: 0.3,
            gamma: 0.2,
        };
        let seg = Segment {
            a: 0,
            b: 16,
            len: 11,
        };
        // Multipliers read, or taken as zero (`zero`): the lanes past the
        // run keep theirs either way.
        let sweep = |masked: bool, zero: bool| {
            let [mut x, mut y, mut z, sx, sy, sz, w, rest, mut lambda] = arrays();
            let mut view = View {
                x: &mut x,
                y: &mut y,
                z: &mut z,
                sx: &sx,
                sy: &sy,
                sz: &sz,
                w: &w,
            };
            let (rest, lambda_ref) = (&rest, &mut lambda);
            match (masked, zero) {
                (true, false) => run::<false, true>(seg, rest, lambda_ref, &mut view, k),
                (true, true) => run::<true, true>(seg, rest, lambda_ref, &mut view, k),
                (false, _) => {
                    for t in 0..seg.len as usize {
                        assert!(16 + t < view.len() && rest.len() == view.len());
                        let at = (t, 16 + t);
                        // SAFETY: in bounds (asserted).
                        unsafe {
                            if zero {
                                chunk::<1, true, true>(at, None, rest, lambda_ref, &mut view, k)
                            } else {
                                chunk::<1, false, true>(at, None, rest, lambda_ref, &mut view, k)
                            }
                        };
                    }
                }
            }
            [x, y, z, lambda].map(|v| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
        };
        for zero in [false, true] {
            let (masked, single) = (sweep(true, zero), sweep(false, zero));
            assert_eq!(masked, single);
            let [x, .., lambda] = arrays();
            assert_ne!(masked[0][10], x[10].to_bits(), "the last spring moved");
            assert_eq!(masked[0][11], x[11].to_bits(), "a masked lane stayed");
            assert_eq!(masked[3][11], lambda[11].to_bits(), "its multiplier too");
        }
        // Taken as zero, the multipliers give other positions than those read.
        assert_ne!(sweep(true, true)[0], sweep(true, false)[0]);
    }

    #[test]
    fn rows_are_stored_in_blocks_that_fill_the_vector_steps() {
        // Four blocks where they fill the steps (the first plans' order).
        for cols in [2, 3, 16, 32, 64, 128, 256] {
            assert_eq!(row_blocks(cols), 4, "{cols}");
        }
        // 40 columns: five blocks of 8, not four of 10.
        assert_eq!(row_blocks(40), 5);
        assert!((MIN_BLOCKS..=MAX_BLOCKS).contains(&row_blocks(47)));
    }

    #[test]
    fn the_runs_hold_every_spring_once_and_no_particle_twice() {
        let sizes = [
            (2, 2),
            (3, 2),
            (5, 7),
            (13, 9),
            (16, 4),
            (64, 3),
            (7, 33),
            (9, 70),
            (40, 5),
            (47, 6),
        ];
        let grids = sizes.map(|(cols, rows)| ClothBuilder::new(cols, rows).build().unwrap());
        // Cloths joined into one: their grids stacked, a band's cut inside a
        // piece and on a piece's edge.
        let joined = [(7, 9, 3), (13, 20, 2), (5, 16, 3)].map(|(cols, rows, pieces)| {
            let piece = ClothBuilder::new(cols, rows).build().unwrap();
            Cloth::join(vec![piece; pieces]).unwrap()
        });
        for cloth in grids.into_iter().chain(joined) {
            let lanes = cloth.topology().lane_grid().unwrap();
            let (cols, rows) = (lanes.grid.cols, lanes.grid.rows);
            let plan = GridPlan::stacked(lanes, cloth.springs()).unwrap();
            let n = cols * rows;
            let mut particle = vec![usize::MAX; n];
            for i in 0..n {
                particle[plan.lane(i)] = i;
            }
            assert!(
                particle.iter().all(|&i| i < n),
                "{cols}x{rows}: lanes not a permutation"
            );
            assert_eq!(plan.phases[0].len(), (rows / BAND_ROWS).max(1));
            // The lanes of a run's first ends, each spring checked: within
            // the region, of the family `(dr, dc)`, within one piece, no
            // particle twice in the run.
            let run_lanes = |seg: &Segment, region: &Region, (dr, dc): (usize, isize)| {
                let mut in_run = std::collections::HashSet::new();
                let base = region.lanes.start;
                (0..seg.len as usize)
                    .map(|t| {
                        let (la, lb) = (seg.a as usize + t, seg.b as usize + t);
                        assert!(la.max(lb) < region.lanes.len(), "a run leaves its region");
                        let (la, lb) = (la + base, lb + base);
                        let (a, b) = (particle[la], particle[lb]);
                        assert_eq!(b / cols, a / cols + dr, "{cols}x{rows}");
                        assert!(lanes.same_piece(a / cols, b / cols), "across pieces");
                        assert_eq!((b % cols) as isize, (a % cols) as isize + dc);
                        assert!(
                            in_run.insert(a) && in_run.insert(b),
                            "a particle twice in a run"
                        );
                        la
                    })
                    .collect::<Vec<_>>()
            };
            let mut springs = 0;
            let mut seen_a = vec![vec![false; n]; plan.passes.len()];
            for phase in &plan.phases {
                // The regions of a phase may run on any threads: no lane in two.
                for pair in phase.windows(2) {
                    assert!(pair[0].lanes.end <= pair[1].lanes.start, "{cols}x{rows}");
                }
                for region in phase {
                    for (p, pass) in plan.passes.iter().enumerate() {
                        for seg in &region.runs[p] {
                            // Within the lanes a limit with the pairs watches.
                            let (a, b, len) = (seg.a as usize, seg.b as usize, seg.len as usize);
                            assert!(region.near.start <= a.min(b), "{cols}x{rows}");
                            assert!(a.max(b) + len <= region.near.end, "{cols}x{rows}");
                            for la in run_lanes(seg, region, (pass.dr, pass.dc)) {
                                assert!(
                                    plan.rest.get(p)[la] > 0.0,
                                    "{cols}x{rows}: a run over a missing spring"
                                );
                                assert!(
                                    !std::mem::replace(&mut seen_a[p][la], true),
                                    "a spring twice"
                                );
                                springs += 1;
                            }
                        }
                    }
                }
            }
            assert_eq!(springs, cloth.springs().len(), "{cols}x{rows}");
            // The long spans likewise: each once, none across pieces, no
            // particle twice in a run, every one with its length.
            let r = lanes.piece_rows;
            for (d, &(dr, dc)) in plan.long_steps.iter().enumerate() {
                let p = LONG_RUNS[d];
                let mut seen = vec![false; n];
                for region in plan.phases.iter().flatten() {
                    for seg in &region.runs[p] {
                        for la in run_lanes(seg, region, (dr, dc)) {
                            let span = plan.long_span[d][la];
                            assert!(span > 0.0 && span.is_finite(), "{cols}x{rows}: {span}");
                            assert!(!std::mem::replace(&mut seen[la], true), "a span twice");
                        }
                    }
                }
                let dc = dc as usize;
                let count = if d == 0 {
                    cols.saturating_sub(dc) * rows
                } else {
                    cols * r.saturating_sub(dr) * (rows / r)
                };
                let held = seen.iter().filter(|&&s| s).count();
                assert_eq!(held, count, "{cols}x{rows}: long spans {d}");
            }
        }
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn a_sweep_on_two_threads_gives_the_bits_of_one() {
        // 70 rows: four bands and three boundaries.
        let cloth = ClothBuilder::new(21, 70).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        assert_eq!(plan.phases[1].len(), 3);
        let lanes = || {
            let mut lanes = Columns::default();
            for (i, p) in cloth.positions().iter().enumerate() {
                let j = (i as f32 * 0.37).sin() * 0.01;
                lanes.x.push(p.x * 1.08 + j);
                lanes.y.push(p.y - j);
                lanes.z.push(p.z * 1.08);
                lanes.sx.push(p.x);
                lanes.sy.push(p.y);
                lanes.sz.push(p.z);
                lanes.w.push(if i % 23 == 0 { 0.0 } else { 50.0 });
            }
            in_lane_order(&plan, lanes)
        };
        let k = [Compliance {
            alpha: 0.2,
            gamma: 0.05,
        }; 3];
        let run = |threads: usize, parallel: bool| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (mut plan, mut lanes) = (plan.clone(), lanes());
            let limited = pool.install(|| {
                crate::parallel::with_team(parallel, |team| {
                    sweep(
                        &mut plan,
                        &mut lanes,
                        &k,
                        [KindInSweep::READ_AND_KEPT; 3],
                        team,
                    );
                    limit_stretch(&mut plan, &mut lanes, (1.02, None), team)
                })
            });
            (bits(&mut lanes), limited)
        };
        let one = run(1, false);
        assert!(one.1.shortened > 0, "the limit had springs to shorten");
        assert_eq!(run(2, true), one);
        assert_eq!(run(1, true), one);
    }

    #[test]
    fn grids_narrower_than_a_family_period_sweep() {
        // Bend springs along rows come in classes four columns apart: a row
        // of two or three columns has fewer columns than classes.
        for (cols, rows) in [(2, 2), (3, 2), (2, 5), (4, 3)] {
            let cloth = ClothBuilder::new(cols, rows).build().unwrap();
            let mut plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
            let mut lanes = Columns::default();
            for p in cloth.positions() {
                lanes.x.push(p.x * 1.1);
                lanes.y.push(p.y);
                lanes.z.push(p.z * 1.1);
                lanes.sx.push(p.x);
                lanes.sy.push(p.y);
                lanes.sz.push(p.z);
                lanes.w.push(1.0);
            }
            let mut lanes = in_lane_order(&plan, lanes);
            let k = Compliance {
                alpha: 0.0,
                gamma: 0.0,
            };
            sweep(
                &mut plan,
                &mut lanes,
                &[k; 3],
                [KindInSweep::READ_AND_KEPT; 3],
                Team::ALONE,
            );
            // Stretched by 10%, the sweep pulls every row back inwards.
            let last = plan.lane(cols - 1);
            assert!(
                lanes.arrays_mut()[0][last] < cloth.positions()[cols - 1].x * 1.1,
                "{cols}x{rows}"
            );
        }
    }

    #[test]
    fn a_cloth_that_is_not_the_grid_families_gets_no_plan() {
        let cloth = ClothBuilder::new(6, 5).build().unwrap();
        let grid = cloth.grid().unwrap();
        assert!(GridPlan::new(grid, cloth.springs()).is_some());
        let wider = Grid { cols: 5, rows: 6 };
        assert!(GridPlan::new(wider, cloth.springs()).is_none());
        // Two joined: a plan by pieces; none as one grid (the springs
        // between them missing) nor by pieces of another height.
        let two = Cloth::join(vec![cloth.clone(), cloth]).unwrap();
        let lanes = two.topology().lane_grid().unwrap();
        assert_eq!(lanes.grid, Grid { cols: 6, rows: 10 });
        assert_eq!(lanes.piece_rows, 5);
        assert!(GridPlan::stacked(lanes, two.springs()).is_some());
        assert!(GridPlan::new(lanes.grid, two.springs()).is_none());
        for piece_rows in [2, 3, 10] {
            let other = LaneGrid {
                piece_rows,
                ..lanes
            };
            assert!(GridPlan::stacked(other, two.springs()).is_none());
        }
    }

    /// Each boundary's lanes lie within its two bands and meet no other
    /// boundary's (what `bands_and_boundaries` runs a boundary on), at
    /// every height from one band to many.
    #[test]
    fn a_boundary_lies_within_its_two_bands() {
        for rows in [
            BAND_ROWS,
            2 * BAND_ROWS - 1,
            2 * BAND_ROWS,
            37,
            64,
            100,
            129,
        ] {
            let cloth = ClothBuilder::new(6, rows).build().unwrap();
            let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
            let [bands, boundaries] = &plan.phases;
            assert_eq!(boundaries.len() + 1, bands.len(), "{rows} rows");
            for (j, b) in boundaries.iter().enumerate() {
                let (lo, hi) = (&bands[j].lanes, &bands[j + 1].lanes);
                assert!(
                    lo.start <= b.lanes.start && b.lanes.end <= hi.end,
                    "{rows} rows, boundary {j}"
                );
                if let Some(next) = boundaries.get(j + 1) {
                    assert!(
                        b.lanes.end <= next.lanes.start,
                        "{rows} rows, boundaries {j} and {}",
                        j + 1
                    );
                }
            }
        }
    }

    /// One handout of both phases runs every band and every boundary once,
    /// each boundary after its two bands, call after call, on one thread
    /// and on two (bands of uneven lengths, so that they end in any order).
    #[test]
    fn each_boundary_runs_once_after_its_two_bands() {
        let cloth = ClothBuilder::new(8, 6 * BAND_ROWS).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        let [bands, boundaries] = &plan.phases;
        assert_eq!((bands.len(), boundaries.len()), (6, 5));
        let check = |team: Team| {
            for call in 0..20u64 {
                let ran: Vec<AtomicU32> = (0..11).map(|_| AtomicU32::new(0)).collect();
                let clock = AtomicU32::new(0);
                let sum = bands_and_boundaries(
                    (&plan.phases, &plan.flags, plan.flags.begin()),
                    team,
                    |region| {
                        let k = bands
                            .iter()
                            .chain(boundaries)
                            .position(|r| std::ptr::eq(r, region))
                            .unwrap();
                        // Uneven work: the bands end in a different order each call.
                        let spin = (k as u64 * 7 + call * 13) % 11;
                        std::thread::sleep(std::time::Duration::from_micros(20 * spin));
                        let tick = clock.fetch_add(1, Ordering::SeqCst) + 1;
                        assert_eq!(ran[k].swap(tick, Ordering::SeqCst), 0, "region {k} twice");
                        1
                    },
                );
                assert_eq!(sum, 11);
                let at = |k: usize| ran[k].load(Ordering::SeqCst);
                for j in 0..5 {
                    assert!(
                        at(6 + j) > at(j) && at(6 + j) > at(j + 1),
                        "boundary {j} early"
                    );
                }
            }
        };
        check(Team::ALONE);
        crate::parallel::on_threads(2, check);
    }
}
