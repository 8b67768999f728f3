//! A substep's sweep over the grid's springs: the regions in turn, their runs
//! eight lanes a step.

use super::lanes::{apart, load, store, Lanes, SharedLanes, View, WIDTH};
use super::plan::{GridPlan, PhaseFlags, Region, Segment, PARALLEL_MIN_SPRINGS};
use super::project::{project, Compliance, KindInSweep};
use crate::math::simd_available;
use crate::parallel::Team;

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

/// [`sweep`], with the AVX2 kernel only when `simd`.
pub(super) fn sweep_with(
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

/// Runs `region` on every band of rows and every boundary between two (the
/// two `phases`) in one handout of the bands, numbered `call` in `flags`:
/// a band's item, once done, runs each boundary beside it whose other band
/// is done too. A boundary then runs after both its bands, and touches no
/// other: the bits of the phases one after the other, in half the
/// handouts (the stretch limit's passes took eight a substep, the sweep
/// two). Returns the sum of what `region` returns.
pub(super) fn bands_and_boundaries(
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
pub(super) struct RegionSweep<'a> {
    pub(super) region: &'a Region,
    pub(super) p: usize,
    pub(super) rest: &'a [&'a [f32]; 6],
    pub(super) k: &'a [Compliance; 6],
}

/// [`sweep_region`], with the AVX2 kernel only when `simd`; `ZERO` and
/// `KEPT` as [`KindInSweep::from_zero`] and [`KindInSweep::kept`].
#[inline(always)]
pub(super) fn sweep_region_on<const ZERO: bool, const KEPT: bool>(
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
pub(super) unsafe fn sweep_region_avx2<const ZERO: bool, const KEPT: bool>(
    job: &RegionSweep,
    view: &mut View,
    lambda: &mut [f32],
) {
    crate::math::align_frame();
    sweep_region::<ZERO, KEPT>(job, view, lambda);
}

/// The family's runs in the region, with its multipliers there.
#[inline(always)]
pub(super) fn sweep_region<const ZERO: bool, const KEPT: bool>(
    job: &RegionSweep,
    view: &mut View,
    lambda: &mut [f32],
) {
    let rest = &job.rest[job.p][job.region.lanes.clone()];
    for &seg in &job.region.runs[job.p] {
        run::<ZERO, KEPT>(seg, rest, lambda, view, job.k[job.p]);
    }
}

/// The springs of one run, `WIDTH` at a time (`ZERO`, `KEPT`: as for
/// [`chunk`]).
#[inline(always)]
pub(super) fn run<const ZERO: bool, const KEPT: bool>(
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
pub(super) unsafe fn chunk<const M: usize, const ZERO: bool, const KEPT: bool>(
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
