//! The material's stretch limit on a grid cloth: its passes over the runs, the
//! marks of what moved, and the planes it holds lanes on.

use super::lanes::{apart, load, Lanes, SharedLanes, View, WIDTH};
use super::plan::{GridPlan, Segment, LIMIT_PASSES, LONG_RUNS, PARALLEL_MIN_SPRINGS, TILE_LANES};
use super::sweep::bands_and_boundaries;
use crate::cloth::SpringKind;
use crate::collision::LIMIT_SLACK;
use crate::math::simd_available;
use crate::parallel::{Disjoint, Team};
use std::sync::atomic::{AtomicU32, Ordering};

/// The material's stretch limit on a grid cloth: the stretch springs'
/// runs, up to [`LIMIT_PASSES`] Gauss–Seidel passes (the bands, then the
/// boundaries, each region's families in turn), each spring longer than
/// `factor` times its rest length (by more than [`LIMIT_SLACK`] of it)
/// shortened to it, and past it by 0.9 of its excess
/// ([`LIMIT_OVER_RELAXATION`]). After the first pass, each pass first holds the pairs
/// of stretch springs along rows and columns (the bend springs' runs) to
/// `factor` times the length the pair spans at rest: a coarser level,
/// which carries a correction twice as far a pass and which the springs at
/// their limits always satisfy (it never holds the cloth tighter than they do).
/// After a call of the same step that ended unsettled, the spans of eight
/// springs ([`LONG_SPAN`](super::plan::LONG_SPAN)) take the pairs' place: a
/// coarser level still. Returns the springs shortened, and when the last pass
/// found none to shorten, the room left: how much (m) any stretch spring may
/// still lengthen before it reaches the limit (the collision stage then knows
/// which springs it need not hold).
///
/// After the first pass, a pass looks only at the springs with an end that the
/// pass before or this one moved (eight lanes at a time): the others were found
/// within the limit and have not changed since, so the bits are those of whole
/// passes (a landing needs dozens of passes to carry a correction across the
/// cloth, and then only some springs still move). When such a pass shortens
/// nothing, the room is 0: the pass before shortened a spring to its limit.
/// Which lanes moved is also kept per tile of [`TILE_LANES`] lanes
/// ([`LimitTiles`](super::plan::LimitTiles)): a region none of whose tiles
/// moved is passed over whole, and from the third pass ([`SKIM_FROM`]) so are a
/// run's springs a tile at a time.
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
    pub(super) fn whole(&self) -> bool {
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
pub(super) struct Tally {
    /// Springs shortened.
    pub(super) shortened: u32,
    /// Springs more than [`LIMIT_FAR`] of their rest length over the limit.
    pub(super) far: u32,
    /// The least room below the limit, in squares (limit² − length², m²).
    pub(super) room: f32,
}

impl Tally {
    /// Nothing looked at.
    const NONE: Tally = Tally {
        shortened: 0,
        far: 0,
        room: f32::INFINITY,
    };

    /// Both looks together.
    pub(super) fn and(self, other: Tally) -> Tally {
        Tally {
            shortened: self.shortened + other.shortened,
            far: self.far + other.far,
            room: self.room.min(other.room),
        }
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
pub(super) const LIMIT_OVER_RELAXATION: f32 = 1.9;

/// [`limit_stretch`], with the AVX2 kernel only when `simd`.
pub(super) fn limit_stretch_with(
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
    // ([`LONG_SPAN`](super::plan::LONG_SPAN)), which reach farther a pass.
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
pub(super) fn limit_region(
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
pub(super) unsafe fn limit_runs_avx2<const PLANES: bool>(
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
pub(super) struct LimitMarks<'a> {
    pub(super) moved: &'a mut [u32],
    pub(super) first: bool,
    /// Whether springs whose tiles did not move are passed over a tile at
    /// a time ([`SKIM_FROM`]).
    pub(super) skim: bool,
    pub(super) pass: u32,
    /// The region's first lane among all.
    pub(super) start: usize,
    /// Per tile of lanes among all, the last pass that moved any of its
    /// lanes ([`LimitTiles`](super::plan::LimitTiles)).
    pub(super) tiles: &'a [AtomicU32],
    /// The lanes' planes, if the limit holds them ([`limit_stretch`]).
    pub(super) planes: Option<LanePlanes<'a>>,
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
    pub(super) unsafe fn due<const M: usize>(&self, (a, b): (usize, usize)) -> bool {
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
    pub(super) fn quiet(&self, (a, b): (usize, usize)) -> usize {
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
    pub(super) unsafe fn limit<const M: usize, const PLANES: bool>(
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
pub(super) fn limit_runs<const PLANES: bool>(
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

/// The first pass of a call of the stretch limit that passes over the
/// springs of unmoved tiles a tile at a time ([`LimitMarks::quiet`]).
/// Before it most tiles moved, and the test only added to each chunk's
/// own. Measured on the drape at N = 256, one thread, the timed frames'
/// passes alternating call by call with the lanes' own marks alone (three
/// runs): passes from the third 13–16% faster, the second 1.5%.
pub(super) const SKIM_FROM: u32 = 3;

/// Whether any tile over `lanes` was moved by pass `since` or later.
#[inline(always)]
pub(super) fn tiles_moved_since(
    tiles: &[AtomicU32],
    lanes: std::ops::Range<usize>,
    since: u32,
) -> bool {
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
pub(super) fn least<const M: usize>(mut room: [f32; M]) -> f32 {
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
pub(super) unsafe fn limit_chunk<const M: usize, const PLANES: bool>(
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
pub(super) unsafe fn hold_on_planes<const M: usize>(
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
pub(super) const SURELY_WITHIN: f32 = 1.0 - 1.0e-5;
