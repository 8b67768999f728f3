//! A substep's sweep over the grid's springs: the regions in turn, their runs
//! eight lanes a step.

use super::plan::{apart, GridPlan, Region, Segment, PARALLEL_MIN_SPRINGS};
use super::{load, store, Compliance, Lanes, SharedLanes, View};
use crate::math::simd_available;
use crate::parallel::Team;
use std::sync::atomic::{AtomicU64, Ordering};

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
/// [`SpringKind::index`](crate::cloth::SpringKind::index)).
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

/// A spring whose squared length is below this share of its squared limit
/// is surely within it, however its length rounds (a few parts in 10⁷).
pub(super) const SURELY_WITHIN: f32 = 1.0 - 1.0e-5;

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
pub(crate) fn project(
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
pub(super) const WIDTH: usize = 8;

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
