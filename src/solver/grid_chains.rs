//! Direct solves of a grid cloth's stretch springs along its rows and its
//! columns, before each substep's Gauss–Seidel sweeps (`xpbd.rs`).
//!
//! Why: a sweep carries a correction one spring a substep, so a sweep-only
//! solver needs substeps in proportion to the cloth's size before a
//! hanging sheet stops stretching (55 at N = 64, 109 at N = 128 in the
//! drape). The stretch springs of one row form a chain; linearised at the
//! predicted positions, XPBD's system for one chain,
//! `(J W Jᵀ + α) Δλ = −C`, is tridiagonal and solved exactly in one
//! forward and one backward pass (the Thomas algorithm). One solve of
//! every row, then of every column, carries a correction across the whole
//! cloth in one substep; the sweeps that follow take the shear and bend
//! springs, the damping and what the linearisation missed. The spike that
//! led here (BENCHMARKS.md, "A spike: direct solves along rows and
//! columns") held the drape's peak under 5% with 12 substeps at N = 64 and
//! 24 at N = 128.
//!
//! Layout: chains are lanes. A column chain runs down the rows of the
//! sweep's lanes (`grid_sweep::Lanes`), a lane of each row, so the columns
//! are solved side by side, a vector of chains a step, with no gather. The
//! rows are copied, a chunk of [`CHUNK`] rows at a time, into a transposed
//! scratch where they are columns, solved the same way, and copied back,
//! each chunk by one item on one thread (the rows a band of the sweeps
//! holds). The columns cross every band, and are solved from both ends at
//! once (the twisted Thomas algorithm, [`solve_all_twisted`]): a thread
//! eliminates and substitutes in its own band's half of every column.
//! Chains are independent: they are cut into chunks of [`CHUNK`] that
//! threads take in any order, with the bits of one thread; no fused
//! multiply-add, so the AVX2 build and the baseline give the same bits
//! too.
//!
//! Two threads share the scratch, so what a thread writes is its own
//! stretch of memory: a chunk's rows in the transposed scratch, and
//! separate work arrays for the rows and the columns (each thread's share
//! interleaved with the other's, or one array written by both in turn,
//! the CPU's prefetchers and the cores' caches moved the lines between
//! the cores: two threads took longer over the chain solves than one).

use crate::cloth::{Cloth, SpringKind};
use crate::math::simd_available;
use crate::parallel::{Disjoint, Team};

use super::chain_transpose::{assert_within, copy_rows, scratch_len, Pair, Way};
use super::grid_sweep::{GridPlan, Lanes};
use super::staggered::Staggered;

/// Chains a chunk solves side by side (four AVX2 vectors): small enough
/// that a 128-column grid gives two threads two chunks each.
const CHUNK: usize = 32;

// The rows' chains are copied in and back a chunk of rows at a time, the
// same rows on the same thread as their solve.
const _: () = assert!(CHUNK == super::chain_transpose::CHUNK);

/// Below this many springs in a direction, its chunks run on one thread.
const PARALLEL_MIN_SPRINGS: usize = 4096;

/// Scratch of the chain solves.
#[derive(Debug, Default)]
pub(crate) struct ChainScratch {
    /// Per chain element: the spring's unit direction (x, y, z), then the
    /// forward pass's eliminated super-diagonal and right-hand side; five
    /// arrays for the rows (in the transposed scratch's layout), five for
    /// the columns.
    work: Staggered,
    /// The rows transposed (element [`super::chain_transpose::scratch_at`]`(c,
    /// r)` holds particle `(r, c)`):
    /// x, y, z, inverse mass, the rest length (m) of the row's stretch
    /// spring leaving it, and that spring's multiplier (N·s²).
    rows: Staggered,
    /// The column of each lane of a row.
    column: Vec<u32>,
    /// The mass revision the transposed inverse masses and rest lengths
    /// were copied at (`None`: not since the plan or the shape changed).
    constants_for: Option<u64>,
    /// The grid's shape (columns, rows) the scratch was made for.
    shape: Option<(usize, usize)>,
    /// Solve the columns from their first spring on, as the rows (the
    /// tests' reference for the twisted solve).
    #[cfg(test)]
    columns_from_one_end: bool,
}

/// Slots of the transposed arrays.
const TX: usize = 0;
const TY: usize = 1;
const TZ: usize = 2;
const TW: usize = 3;
const TREST: usize = 4;
const TLAMBDA: usize = 5;

/// One set of chains side by side: chain `j` has elements `k · stride +
/// first(j)` for `k` in `0..len`, where chain `j` of a chunk of [`CHUNK`]
/// starts at `first(j) = (j / CHUNK) · pitch + j % CHUNK`; the spring from
/// element `k` to `k + 1` has its rest length and multiplier at element
/// `k`. Down the columns of the lanes, the pitch is `CHUNK` (`first(j) =
/// j`); along the rows, in the transposed scratch
/// ([`super::chain_transpose::scratch_at`]), a chunk's stretch of memory.
#[derive(Clone, Copy)]
struct Chains<'a> {
    x: Disjoint<'a, f32>,
    y: Disjoint<'a, f32>,
    z: Disjoint<'a, f32>,
    /// Inverse masses and rest lengths: read only while the chains are
    /// solved (raw: along the rows, a chunk's are copied in by the item
    /// that solves it, while other items solve theirs).
    w: *const f32,
    rest: *const f32,
    /// How many elements `w` and `rest` hold.
    held: usize,
    lambda: Disjoint<'a, f32>,
    /// Scratch: direction x, y, z, eliminated super-diagonal, right-hand side.
    work: [Disjoint<'a, f32>; 5],
    len: usize,
    stride: usize,
    pitch: usize,
    /// Compliance (`1/(k h²)`).
    alpha: f32,
    /// The multipliers start from zero: written, not added to (the last
    /// element's, of no spring, set to zero). Zeroing the rows' scratch
    /// beforehand on the calling thread handed every line of it to that
    /// thread's core, from which the other thread then had to fetch its
    /// share back (the rows' solve, 9 µs on one thread at N = 128, took
    /// 19 on the second of two).
    fresh_lambda: bool,
}

// SAFETY: the raw arrays are only read, by items that each solve their
// own chains; `Chains` is otherwise `Disjoint`s and numbers.
unsafe impl Sync for Chains<'_> {}

impl Chains<'_> {
    /// Checks what the kernels' unchecked loads and stores rely on: the
    /// first `width` chains lie within every array.
    fn assert_holds(&self, width: usize) {
        assert!(width >= 1 && self.len >= 2);
        let total = self.extent(width);
        let arrays = [self.x, self.y, self.z, self.lambda];
        assert!(arrays.iter().all(|a| a.len() >= total));
        assert!(self.work.iter().all(|a| a.len() >= total) && self.held >= total);
    }

    /// The positions x, y, z and the inverse masses, as [`particle`]
    /// reads them (the masses only read).
    #[inline(always)]
    fn particles(&self) -> [*mut f32; 4] {
        [
            self.x.as_ptr(),
            self.y.as_ptr(),
            self.z.as_ptr(),
            self.w as *mut f32,
        ]
    }

    /// The first element of chain `j`.
    #[inline(always)]
    fn first(&self, j: usize) -> usize {
        (j / CHUNK) * self.pitch + j % CHUNK
    }

    /// One past the last element of the first `width` chains.
    fn extent(&self, width: usize) -> usize {
        self.first(width - 1) + (self.len - 1) * self.stride + 1
    }
}

impl ChainScratch {
    /// One direct solve of every row's stretch chain, then of every
    /// column's, on the lanes' positions, with compliance `alpha`
    /// (`1/(k h²)`); the multipliers go into the plan's stretch passes, so
    /// that the sweeps after go on from them. `revision`: the cloth's mass
    /// revision (the inverse masses are copied again when it changes).
    pub fn solve(
        &mut self,
        plan: &mut GridPlan,
        lanes: &mut Lanes,
        (alpha, revision): (f32, u64),
        team: Team,
    ) {
        self.solve_with(plan, lanes, (alpha, revision), team, simd_available());
    }

    /// [`Self::solve`], with the AVX2 kernel only when `simd`.
    fn solve_with(
        &mut self,
        plan: &mut GridPlan,
        lanes: &mut Lanes,
        (alpha, revision): (f32, u64),
        team: Team,
        simd: bool,
    ) {
        let (cols, rows) = plan.shape();
        if cols < 2 || rows < 2 {
            return;
        }
        let n = cols * rows;
        let padded = scratch_len((cols, rows));
        if self.shape != Some((cols, rows)) {
            self.rows = Staggered::new(6, padded, 7);
            self.work = Staggered::new(10, padded, 13);
            self.column.clear();
            self.column.resize(cols, 0);
            for (c, &lane) in plan.lanes_of(&(0..cols)).iter().enumerate() {
                self.column[lane as usize] = c as u32;
            }
            self.constants_for = None;
            self.shape = Some((cols, rows));
        }
        let column = &self.column[..];
        let ([rest_rows, rest_cols], [lambda_rows, lambda_cols]) = plan.stretch_passes();
        let [lx, ly, lz, _, _, _, lw] = lanes.disjoint();
        let mut t = self.rows.all_mut().map(Disjoint::new);
        let t: [Disjoint<f32>; 6] = std::array::from_fn(|_| t.next().expect("six"));
        let (work, column_work) = {
            let mut w = self.work.all_mut().map(Disjoint::new);
            let mut five =
                || -> [Disjoint<f32>; 5] { std::array::from_fn(|_| w.next().expect("ten")) };
            (five(), five())
        };
        let shape = (cols, rows);
        // Rows: each chunk of them copied into the transposed scratch,
        // solved and copied back by one item, on one thread. Inverse
        // masses and rest lengths copied only when the masses or the plan
        // changed.
        let constants = self.constants_for != Some(revision);
        self.constants_for = Some(revision);
        let into: [Pair; 5] = [
            (lx.as_ptr(), t[TX].as_ptr()),
            (ly.as_ptr(), t[TY].as_ptr()),
            (lz.as_ptr(), t[TZ].as_ptr()),
            (lw.as_ptr(), t[TW].as_ptr()),
            (rest_rows.as_ptr(), t[TREST].as_ptr()),
        ];
        let back: [Pair; 4] = [
            (t[TX].as_ptr(), lx.as_ptr()),
            (t[TY].as_ptr(), ly.as_ptr()),
            (t[TZ].as_ptr(), lz.as_ptr()),
            (t[TLAMBDA].as_ptr(), lambda_rows.as_mut_ptr()),
        ];
        let copies = RowCopies {
            into: &into[..if constants { 5 } else { 3 }],
            back,
        };
        let lanes_len = lx.len().min(ly.len()).min(lz.len()).min(lw.len());
        let held = t.iter().map(|a| a.len()).min().unwrap_or(0);
        assert_within(
            &[(lanes_len.min(rest_rows.len()), held)],
            column,
            shape,
            Way::In,
        );
        assert_within(
            &[(held, lanes_len.min(lambda_rows.len()))],
            column,
            shape,
            Way::Out,
        );
        let chains = Chains {
            x: t[TX],
            y: t[TY],
            z: t[TZ],
            w: t[TW].as_ptr(),
            rest: t[TREST].as_ptr(),
            held,
            lambda: t[TLAMBDA],
            work,
            len: cols,
            stride: CHUNK,
            pitch: CHUNK * cols,
            alpha,
            fresh_lambda: true,
        };
        chains.assert_holds(rows);
        // Whole, not by field: the struct is what may be shared.
        let copies = &copies;
        team.for_work(n, PARALLEL_MIN_SPRINGS)
            .sum_count(rows.div_ceil(CHUNK), |q| {
                let part = q * CHUNK..((q + 1) * CHUNK).min(rows);
                // SAFETY: the arrays hold the grid (asserted); this item
                // alone reads and writes these rows of the lanes, of the
                // rows' multipliers and of the scratch (the chunk's
                // stretch of it), and solves their chains.
                unsafe {
                    copy_rows(copies.into, column, shape, part.clone(), (Way::In, simd));
                    solve_chains(&chains, part.clone(), simd);
                    copy_rows(&copies.back, column, shape, part, (Way::Out, simd));
                }
                0
            });
        // Columns: in place, down the rows of the lanes.
        let chains = Chains {
            x: lx,
            y: ly,
            z: lz,
            w: lw.as_ptr(),
            rest: rest_cols.as_ptr(),
            held: lw.len().min(rest_cols.len()),
            lambda: Disjoint::new(lambda_cols),
            work: column_work,
            len: rows,
            stride: cols,
            pitch: CHUNK,
            alpha,
            fresh_lambda: false,
        };
        #[cfg(test)]
        if self.columns_from_one_end {
            chains.assert_holds(cols);
            for q in 0..cols.div_ceil(CHUNK) {
                // SAFETY: within the arrays (asserted), on this thread.
                unsafe { solve_chains(&chains, q * CHUNK..((q + 1) * CHUNK).min(cols), simd) };
            }
            return;
        }
        solve_all_twisted(chains, cols, team, simd);
    }

    /// Forgets the copied inverse masses and rest lengths (a new plan).
    pub fn replanned(&mut self) {
        self.constants_for = None;
    }
}

/// A transpose's arrays, shared by the items that copy their own rows.
struct RowCopies<'a> {
    into: &'a [Pair],
    back: [Pair; 4],
}

// SAFETY: each item copies only its own rows (`ChainScratch::solve_with`).
unsafe impl Sync for RowCopies<'_> {}

/// Solves the chains `j` of `chains` (within a chunk of [`CHUNK`]), in the
/// AVX2 kernel when `simd`.
///
/// # Safety
/// The chains passed [`Chains::assert_holds`], and no other thread touches
/// them meanwhile; `simd` only where the CPU has AVX2.
unsafe fn solve_chains(chains: &Chains, j: std::ops::Range<usize>, simd: bool) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: the caller's promise.
        unsafe { solve_chunk_avx2(chains, j) };
        return;
    }
    let _ = simd;
    // SAFETY: the caller's promise.
    unsafe { solve_chunk(chains, j) };
}

/// The two ends of a chain solved from both ends at once
/// ([`solve_all_twisted`]): its first springs up to the middle one, and the
/// springs after the middle one.
#[derive(Clone, Copy, PartialEq)]
enum Half {
    Top,
    Bottom,
}

/// The two passes of a twisted solve, each over both halves: elimination
/// towards the middle spring, then substitution away from it.
#[derive(Clone, Copy, PartialEq)]
enum Pass {
    Eliminate,
    Substitute,
}

/// Solves the `width` chains of `chains` from both ends at once (the
/// twisted Thomas algorithm, or "burn at both ends"): the springs up to
/// the middle one are eliminated from the first down, those after it from
/// the last up; the middle spring's multiplier follows from both sides;
/// each half then substitutes back away from the middle. Along the
/// columns, which cross every band of rows, a thread then works in its own
/// band's half of each column only (solved whole, half of what a column
/// read had last been written on the other core: the chain solves took
/// 471 samples on two threads against 245 on one at N = 128). The same
/// operations on any number of threads.
fn solve_all_twisted(chains: Chains, width: usize, team: Team, simd: bool) {
    chains.assert_holds(width);
    let chunks = width.div_ceil(CHUNK);
    let team = team.for_work(width * chains.len, PARALLEL_MIN_SPRINGS);
    for pass in [Pass::Eliminate, Pass::Substitute] {
        // The top halves first: member 0 of two takes them, member 1 the
        // bottom ones (the bands of rows each holds in the sweeps).
        team.sum_count(2 * chunks, |q| {
            let half = if q < chunks { Half::Top } else { Half::Bottom };
            let c = q % chunks;
            let j = c * CHUNK..((c + 1) * CHUNK).min(width);
            #[cfg(target_arch = "x86_64")]
            if simd {
                // SAFETY: `simd` only when the CPU has AVX2; chunks are
                // disjoint sets of chains, and a pass's two halves write
                // disjoint elements of them (`twisted_group`), within the
                // arrays (asserted).
                unsafe { twisted_chunk_avx2(&chains, j, (half, pass)) };
                return 0;
            }
            // SAFETY: as above.
            unsafe { twisted_chunk(&chains, j, (half, pass)) };
            0
        });
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn twisted_chunk_avx2(chains: &Chains, j: std::ops::Range<usize>, step: (Half, Pass)) {
    crate::math::align_frame();
    // SAFETY: the caller's promise.
    unsafe { twisted_chunk(chains, j, step) };
}

/// [`solve_chunk`]'s grouping, for one half and pass of a twisted solve.
///
/// # Safety
/// As for [`twisted_group`].
#[inline(always)]
unsafe fn twisted_chunk(chains: &Chains, j: std::ops::Range<usize>, step: (Half, Pass)) {
    let mut at = j.start;
    while at + GROUP <= j.end {
        // SAFETY: the caller's promise.
        unsafe { twisted_group::<GROUP>(chains, at, step) };
        at += GROUP;
    }
    while at + LANES <= j.end {
        // SAFETY: the caller's promise.
        unsafe { twisted_group::<LANES>(chains, at, step) };
        at += LANES;
    }
    while at < j.end {
        // SAFETY: the caller's promise.
        unsafe { twisted_group::<1>(chains, at, step) };
        at += 1;
    }
}

/// One half and pass of the twisted solve of the `M` chains from `j`, side
/// by side. With `m` springs and the middle one `h = m / 2`: the top half
/// reads particles `0..=h + 1` and writes the scratch of springs `0..=h`
/// when eliminating, then writes particles `0..=h` and the multipliers of
/// springs `0..=h`; the bottom half reads particles `h + 1..=m`, writes the
/// scratch of springs `h + 1..m`, then particles `h + 1..=m` and their
/// multipliers. Both read the scratch of springs `h` and `h + 1` when
/// substituting, and find the middle multiplier alike ([`middle`]).
///
/// Scratch, per spring `k`: its direction; on top, `k < h`, as
/// [`solve_group`] (the eliminated super-diagonal and right-hand side); at
/// `h`, its pivot and right-hand side with the top eliminated; below, the
/// eliminated sub-diagonal and right-hand side (at `h + 1`, the inverse
/// pivot in place of the sub-diagonal, which needs the middle's direction).
///
/// # Safety
/// As for [`solve_chunk`], the two halves of a pass excepted (they touch
/// disjoint elements).
#[inline(always)]
unsafe fn twisted_group<const M: usize>(c: &Chains, j: usize, (half, pass): (Half, Pass)) {
    // Down the columns only, whose multipliers go on from the rows'.
    debug_assert!(!c.fresh_lambda);
    let j = c.first(j);
    let alpha = c.alpha;
    let s = c.stride;
    let m = c.len - 1;
    let h = m / 2;
    let lambda = c.lambda.as_ptr();
    let [nxp, nyp, nzp, cpp, dpp] = c.work.map(|a| a.as_ptr());
    let rest = c.rest;
    // Not closures: a closure would not be compiled for AVX2.
    let at = c.particles();
    // SAFETY (every load and store below): element `k · s + j .. + M` for
    // `k < len` is within the arrays and belongs to these chains only; of
    // them, this half and pass write only what the docs say.
    unsafe {
        match (half, pass) {
            (Half::Top, Pass::Eliminate) => {
                // As `solve_group`'s forward pass, up to the middle spring,
                // whose pivot and right-hand side are kept undivided.
                eliminate_down::<M>(c, j, h + 1, true);
            }
            (Half::Bottom, Pass::Eliminate) => {
                // The mirror image, from the last spring up to the one after
                // the middle: the coupling of spring k to k + 1 is
                // `−w_{k+1} (n_k · n_{k+1})`.
                let (mut qn, mut qinv, mut qeq) = ([[0.0f32; M]; 3], [0.0f32; M], [0.0f32; M]);
                let mut b = particle::<M>(at, m * s + j);
                for k in (h + 1..m).rev() {
                    let ka = k * s + j;
                    let a = particle::<M>(at, ka);
                    let r = load::<M>(rest, ka);
                    let (mut n, mut sub, mut inv, mut eq) =
                        ([[0.0f32; M]; 3], [0.0f32; M], [0.0f32; M], [0.0f32; M]);
                    for i in 0..M {
                        let (u, stretch) = direction(&a, &b, r[i], i);
                        (n[0][i], n[1][i], n[2][i]) = (u[0], u[1], u[2]);
                        let off = -b[3][i] * (u[0] * qn[0][i] + u[1] * qn[1][i] + u[2] * qn[2][i]);
                        sub[i] = off * qinv[i];
                        let pivot = a[3][i] + b[3][i] + alpha - off * sub[i];
                        inv[i] = if pivot > 0.0 { 1.0 / pivot } else { 0.0 };
                        eq[i] = (-stretch - off * qeq[i]) * inv[i];
                    }
                    if k + 1 < m {
                        store(cpp, ka + s, sub);
                    }
                    if k == h + 1 {
                        store(cpp, ka, inv);
                    }
                    store(nxp, ka, n[0]);
                    store(nyp, ka, n[1]);
                    store(nzp, ka, n[2]);
                    store(dpp, ka, eq);
                    (qn, qinv, qeq, b) = (n, inv, eq, a);
                }
            }
            (Half::Top, Pass::Substitute) => {
                let (d, _) = middle::<M>(c, j);
                let kh = h * s + j;
                let n = [load::<M>(nxp, kh), load(nyp, kh), load(nzp, kh)];
                let mut lam = load::<M>(lambda, kh);
                let mut b = particle::<M>(at, kh);
                for i in 0..M {
                    lam[i] += d[i];
                    let db = b[3][i] * d[i];
                    for e in 0..3 {
                        b[e][i] -= n[e][i] * db;
                    }
                }
                store(lambda, kh, lam);
                // As `solve_group`'s backward pass, from the middle spring.
                let mut next = d;
                for k in (0..h).rev() {
                    let ka = k * s + j;
                    let mut a = particle::<M>(at, ka);
                    let n = [load::<M>(nxp, ka), load(nyp, ka), load(nzp, ka)];
                    let (dp, cp) = (load::<M>(dpp, ka), load::<M>(cpp, ka));
                    let mut lam = load::<M>(lambda, ka);
                    substitute((&dp, &cp), &mut next, &mut lam, &n, (&mut a, &mut b));
                    store(lambda, ka, lam);
                    store_particle(at, ka + s, b);
                    b = a;
                }
                store_particle(at, j, b);
            }
            (Half::Bottom, Pass::Substitute) => {
                let (d, sub) = middle::<M>(c, j);
                let kh = h * s + j;
                let n = [load::<M>(nxp, kh), load(nyp, kh), load(nzp, kh)];
                let mut a = particle::<M>(at, kh + s);
                for i in 0..M {
                    let da = a[3][i] * d[i];
                    for e in 0..3 {
                        a[e][i] += n[e][i] * da;
                    }
                }
                // Down from the spring after the middle, each moving both
                // its ends.
                let mut prev = d;
                for k in h + 1..m {
                    let ka = k * s + j;
                    let mut b = particle::<M>(at, ka + s);
                    let n = [load::<M>(nxp, ka), load(nyp, ka), load(nzp, ka)];
                    let eq = load::<M>(dpp, ka);
                    let g = if k == h + 1 { sub } else { load::<M>(cpp, ka) };
                    let mut lam = load::<M>(lambda, ka);
                    substitute((&eq, &g), &mut prev, &mut lam, &n, (&mut a, &mut b));
                    store(lambda, ka, lam);
                    store_particle(at, ka, a);
                    a = b;
                }
                store_particle(at, m * s + j, a);
            }
        }
    }
}

/// One spring's substitution, in each of `M` lanes: its multiplier's
/// change `d = rhs − coupling · before` (then the change before the next
/// spring's), added to `lam`, moving its ends `a` by `−n w_a d` and `b` by
/// `n w_b d` (positions x, y, z and inverse mass `w`).
#[inline(always)]
fn substitute<const M: usize>(
    (rhs, coupling): (&[f32; M], &[f32; M]),
    before: &mut [f32; M],
    lam: &mut [f32; M],
    n: &[[f32; M]; 3],
    (a, b): (&mut [[f32; M]; 4], &mut [[f32; M]; 4]),
) {
    for i in 0..M {
        let d = rhs[i] - coupling[i] * before[i];
        before[i] = d;
        lam[i] += d;
        let (da, db) = (a[3][i] * d, b[3][i] * d);
        for e in 0..3 {
            a[e][i] -= n[e][i] * da;
            b[e][i] += n[e][i] * db;
        }
    }
}

/// The unit direction from `a` to `b` in lane `i` (zero when they
/// coincide) and the stretch of a spring of rest length `r` between them;
/// for a rest length of zero (no spring: the gap between two stacked
/// pieces) both zero, which cuts the chain there: the spring's row of the
/// system is then decoupled from its neighbours' and its multiplier stays
/// zero.
#[inline(always)]
fn direction<const M: usize>(
    a: &[[f32; M]; 4],
    b: &[[f32; M]; 4],
    r: f32,
    i: usize,
) -> ([f32; 3], f32) {
    let (dx, dy, dz) = (b[0][i] - a[0][i], b[1][i] - a[1][i], b[2][i] - a[2][i]);
    let l = (dx * dx + dy * dy + dz * dz).sqrt();
    let inv_l = if l > 0.0 && r > 0.0 { 1.0 / l } else { 0.0 };
    let stretch = if r > 0.0 { l - r } else { 0.0 };
    ([dx * inv_l, dy * inv_l, dz * inv_l], stretch)
}

/// Positions x, y, z and inverse mass of `M` chains' elements at `at + k`
/// of the arrays `p` (x, y, z, inverse masses).
///
/// # Safety
/// As for [`load`].
#[inline(always)]
unsafe fn particle<const M: usize>(p: [*mut f32; 4], k: usize) -> [[f32; M]; 4] {
    // SAFETY: the caller's promise.
    unsafe { [load(p[0], k), load(p[1], k), load(p[2], k), load(p[3], k)] }
}

/// Stores the positions of [`particle`]'s elements back.
///
/// # Safety
/// As for [`store`].
#[inline(always)]
unsafe fn store_particle<const M: usize>(p: [*mut f32; 4], k: usize, v: [[f32; M]; 4]) {
    // SAFETY: the caller's promise.
    unsafe {
        for e in 0..3 {
            store(p[e], k, v[e]);
        }
    }
}

/// The middle spring's multiplier change in a twisted solve, from both
/// halves' eliminations, and the eliminated sub-diagonal of the spring
/// after it (zero when there is none): the same values for either half.
///
/// # Safety
/// As for [`twisted_group`]; both eliminations done.
#[inline(always)]
unsafe fn middle<const M: usize>(c: &Chains, j: usize) -> ([f32; M], [f32; M]) {
    let (s, m) = (c.stride, c.len - 1);
    let h = m / 2;
    let [nxp, nyp, nzp, cpp, dpp] = c.work.map(|a| a.as_ptr());
    let kh = h * s + j;
    // SAFETY: the caller's promise.
    unsafe {
        let (pivot, rhs) = (load::<M>(cpp, kh), load::<M>(dpp, kh));
        let (mut d, mut sub) = ([0.0f32; M], [0.0f32; M]);
        if h + 1 < m {
            let k1 = kh + s;
            let n = [load::<M>(nxp, kh), load(nyp, kh), load(nzp, kh)];
            let n1 = [load::<M>(nxp, k1), load(nyp, k1), load(nzp, k1)];
            let (w1, inv1, eq1) = (load::<M>(c.w, k1), load::<M>(cpp, k1), load::<M>(dpp, k1));
            for i in 0..M {
                let off = -w1[i] * (n[0][i] * n1[0][i] + n[1][i] * n1[1][i] + n[2][i] * n1[2][i]);
                sub[i] = off * inv1[i];
                let p = pivot[i] - off * sub[i];
                let inv = if p > 0.0 { 1.0 / p } else { 0.0 };
                d[i] = (rhs[i] - off * eq1[i]) * inv;
            }
        } else {
            for i in 0..M {
                let inv = if pivot[i] > 0.0 { 1.0 / pivot[i] } else { 0.0 };
                d[i] = rhs[i] * inv;
            }
        }
        (d, sub)
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn solve_chunk_avx2(chains: &Chains, j: std::ops::Range<usize>) {
    crate::math::align_frame();
    // SAFETY: the caller's promise.
    unsafe { solve_chunk(chains, j) };
}

/// Chains `j`: groups of [`GROUP`] chains, then vectors of [`LANES`], then one at a time.
///
/// # Safety
/// Chains `j` lie within the arrays, and no other thread touches them meanwhile.
#[inline(always)]
unsafe fn solve_chunk(chains: &Chains, j: std::ops::Range<usize>) {
    let mut at = j.start;
    while at + GROUP <= j.end {
        // SAFETY: the caller's promise.
        unsafe { solve_group::<GROUP>(chains, at) };
        at += GROUP;
    }
    while at + LANES <= j.end {
        // SAFETY: the caller's promise.
        unsafe { solve_group::<LANES>(chains, at) };
        at += LANES;
    }
    while at < j.end {
        // SAFETY: the caller's promise.
        unsafe { solve_group::<1>(chains, at) };
        at += 1;
    }
}

/// Chains a vector holds (AVX2's 8 `f32`).
const LANES: usize = 8;

/// Chains solved side by side where a chunk has them: a chain's forward
/// pass is a chain of dependent operations (a division per spring), so
/// that several vectors of chains in flight at once hide its latency.
const GROUP: usize = 16;

/// Loads `M` floats at `p + at`.
///
/// # Safety
/// In bounds, and not written by another thread meanwhile.
#[inline(always)]
unsafe fn load<const M: usize>(p: *const f32, at: usize) -> [f32; M] {
    // SAFETY: the caller's promise; `[f32; M]` has the alignment of `f32`.
    unsafe { p.add(at).cast::<[f32; M]>().read() }
}

/// Stores `M` floats at `p + at`.
///
/// # Safety
/// As for [`load`], and used by no other thread meanwhile.
#[inline(always)]
unsafe fn store<const M: usize>(p: *mut f32, at: usize, v: [f32; M]) {
    // SAFETY: the caller's promise.
    unsafe { p.add(at).cast::<[f32; M]>().write(v) }
}

/// The Thomas algorithm's forward pass on springs `0..end` of the `M`
/// chains whose first element is `j`, side by side: each spring's
/// direction, its coupling to the one before (the particle they share:
/// `−w (n_{k−1} · n_k)`, none before the first) eliminated, the
/// eliminated super-diagonal stored at the spring before and the
/// right-hand side divided by the pivot at the spring itself. With
/// `middle`, the last spring's pivot and right-hand side are stored
/// undivided instead (the twisted solve's middle spring, [`middle`]).
/// Returns the particles at the last spring's far end, as loaded.
///
/// # Safety
/// As for [`solve_group`], `j` being the chains' first element.
#[inline(always)]
unsafe fn eliminate_down<const M: usize>(
    c: &Chains,
    j: usize,
    end: usize,
    middle: bool,
) -> [[f32; M]; 4] {
    let (alpha, s) = (c.alpha, c.stride);
    let at = c.particles();
    let [nxp, nyp, nzp, cpp, dpp] = c.work.map(|a| a.as_ptr());
    // SAFETY (every load and store below): the caller's promise.
    unsafe {
        let (mut pn, mut pinv, mut pdp) = ([[0.0f32; M]; 3], [0.0f32; M], [0.0f32; M]);
        let mut a = particle::<M>(at, j);
        for k in 0..end {
            let (ka, kb) = (k * s + j, (k + 1) * s + j);
            let b = particle::<M>(at, kb);
            let r = load::<M>(c.rest, ka);
            let kept = middle && k + 1 == end;
            let (mut n, mut sup, mut inv, mut dp) =
                ([[0.0f32; M]; 3], [0.0f32; M], [0.0f32; M], [0.0f32; M]);
            let mut pivot = [0.0f32; M];
            for i in 0..M {
                let (u, stretch) = direction(&a, &b, r[i], i);
                (n[0][i], n[1][i], n[2][i]) = (u[0], u[1], u[2]);
                let off = -a[3][i] * (pn[0][i] * u[0] + pn[1][i] * u[1] + pn[2][i] * u[2]);
                sup[i] = off * pinv[i];
                pivot[i] = a[3][i] + b[3][i] + alpha - off * sup[i];
                inv[i] = if pivot[i] > 0.0 { 1.0 / pivot[i] } else { 0.0 };
                dp[i] = -stretch - off * pdp[i];
                if !kept {
                    dp[i] *= inv[i];
                }
            }
            if k > 0 {
                store(cpp, ka - s, sup);
            }
            store(nxp, ka, n[0]);
            store(nyp, ka, n[1]);
            store(nzp, ka, n[2]);
            store(dpp, ka, dp);
            if kept {
                store(cpp, ka, pivot);
            }
            (pn, pinv, pdp, a) = (n, inv, dp, b);
        }
        a
    }
}

/// The Thomas algorithm on the `M` chains from `j`, side by side: the
/// forward pass eliminates each spring's coupling to the one before (the
/// particle they share: `−w (n_{k−1} · n_k)`), the backward pass finds the
/// multipliers from the last spring back and moves both ends of each
/// spring by them. Each lane does the same operations in the same order
/// whatever `M`, so the bits do not depend on how chains are grouped.
///
/// # Safety
/// As for [`solve_chunk`].
#[inline(always)]
unsafe fn solve_group<const M: usize>(c: &Chains, j: usize) {
    let j = c.first(j);
    let s = c.stride;
    let m = c.len - 1;
    let (at, lambda) = (c.particles(), c.lambda.as_ptr());
    let [nxp, nyp, nzp, cpp, dpp] = c.work.map(|a| a.as_ptr());
    // SAFETY (every load and store below): element `k · s + j .. + M` for
    // `k < len` is within the arrays and belongs to these chains only.
    unsafe {
        // Forward, every spring.
        let last = eliminate_down::<M>(c, j, m, false);
        // Backward, from the last spring (nothing after it), each row's
        // positions kept in registers between the two springs that move it.
        let mut next = [0.0f32; M];
        let mut b = last; // the last row, as the forward pass left it
        for k in (0..m).rev() {
            let ka = k * s + j;
            let mut a = particle::<M>(at, ka);
            let n = [load::<M>(nxp, ka), load(nyp, ka), load(nzp, ka)];
            let dp = load::<M>(dpp, ka);
            let cp = if k + 1 < m {
                load::<M>(cpp, ka)
            } else {
                [0.0; M]
            };
            let mut lam = if c.fresh_lambda {
                [0.0; M]
            } else {
                load::<M>(lambda, ka)
            };
            substitute((&dp, &cp), &mut next, &mut lam, &n, (&mut a, &mut b));
            store(lambda, ka, lam);
            store_particle(at, ka + s, b);
            b = a;
        }
        store_particle(at, j, b);
        if c.fresh_lambda {
            store(lambda, m * s + j, [0.0; M]);
        }
    }
}

/// True when the chain solves apply to `cloth`: it is a whole grid (or
/// pieces of one shape joined, [`crate::cloth::LaneGrid`]), with every
/// spring of the grid's six families (the grid sweep's plan then
/// exists; `GridPlan::new` checks each spring, this only counts them).
pub(crate) fn apply_to(cloth: &Cloth) -> bool {
    let Some(lanes) = cloth.topology().lane_grid() else {
        return false;
    };
    let (c, r) = (lanes.grid.cols, lanes.piece_rows);
    if c < 2 || r < 2 || lanes.grid.cols * lanes.grid.rows != cloth.particle_count() {
        return false;
    }
    let pieces = lanes.grid.rows / r;
    let springs = cloth.springs();
    let count = |kind| springs.range(kind).len();
    let full = [
        (c - 1) * r + c * (r - 1),
        2 * (c - 1) * (r - 1),
        c.saturating_sub(2) * r + c * r.saturating_sub(2),
    ]
    .map(|count| count * pieces);
    [SpringKind::Stretch, SpringKind::Shear, SpringKind::Bend].map(count) == full
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;
    use crate::math::Vector;

    /// A grid cloth of `cols` × `rows` at `x(i)`, inverse masses `w(i)`,
    /// as a plan and lanes.
    fn setup(
        (cols, rows): (usize, usize),
        x: impl Fn(usize, Vector) -> Vector,
        w: impl Fn(usize) -> f32,
    ) -> (Cloth, GridPlan, Lanes) {
        let cloth = ClothBuilder::new(cols, rows).build().unwrap();
        let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
        let mut lanes = Lanes::default();
        lanes.resize(cols * rows);
        let [lx, ly, lz, sx, sy, sz, lw] = lanes.arrays_mut();
        for (i, &p) in cloth.positions().iter().enumerate() {
            let lane = plan.lanes_of(&(i..i + 1))[0] as usize;
            let q = x(i, p);
            (lx[lane], ly[lane], lz[lane]) = (q.x, q.y, q.z);
            (sx[lane], sy[lane], sz[lane]) = (p.x, p.y, p.z);
            lw[lane] = w(i);
        }
        (cloth, plan, lanes)
    }

    /// The lanes' positions in particle order.
    fn positions(plan: &GridPlan, lanes: &mut Lanes) -> Vec<Vector> {
        let n = lanes.arrays_mut()[0].len();
        let [x, y, z, ..] = lanes.arrays_mut();
        let lane = plan.lanes_of(&(0..n));
        lane.iter()
            .map(|&l| Vector::new(x[l as usize], y[l as usize], z[l as usize]))
            .collect()
    }

    /// Each stretch spring's length over its rest length, less 1.
    fn strains(cloth: &Cloth, x: &[Vector]) -> Vec<f32> {
        let s = cloth.springs();
        let (a, b) = s.endpoints();
        s.range(SpringKind::Stretch)
            .map(|k| (x[b[k] as usize] - x[a[k] as usize]).length() / s.rest_lengths()[k] - 1.0)
            .collect()
    }

    #[test]
    fn a_sheet_stretched_evenly_comes_back_to_rest_in_one_solve() {
        // Straight rows and columns, 10% too long, stiff springs, masses
        // that differ from row to row only (so that the columns' solve
        // moves every column alike and the rows stay straight): along a
        // straight chain the linearised system is the exact one, so one
        // solve of the rows and one of the columns put every stretch spring
        // at its rest length. (Gauss–Seidel would need about as many
        // sweeps as the chains have springs.)
        let stretched = |_, p: Vector| Vector::new(p.x * 1.1, p.y, p.z * 1.1);
        let (cloth, mut plan, mut lanes) = setup((13, 9), stretched, |i| 1.0 + (i / 13 % 3) as f32);
        let before = strains(&cloth, &positions(&plan, &mut lanes));
        assert!(before.iter().all(|&e| (e - 0.1).abs() < 1e-4), "{before:?}");
        ChainScratch::default().solve(&mut plan, &mut lanes, (0.0, 1), Team::ALONE);
        let after = strains(&cloth, &positions(&plan, &mut lanes));
        let worst = after.iter().fold(0.0f32, |m, e| m.max(e.abs()));
        assert!(worst < 1e-5, "a spring left {worst} off its rest length");
    }

    #[test]
    fn one_spring_moves_as_xpbd_says() {
        // A 2 × 2 grid: each row and column one spring. Along the first
        // row, a spring 0.1 m too long with ends of inverse masses 1 and 3
        // and compliance 2: Δλ = −C / (w_a + w_b + α) = −0.1 / 6, the ends
        // move by w Δλ along it.
        // The second row alike, so that the columns stay as they were.
        let moved = |i: usize, p: Vector| if i % 2 == 1 { p + Vector::X * 0.1 } else { p };
        let w = |i: usize| [1.0, 3.0, 1.0, 3.0][i];
        let (cloth, mut plan, mut lanes) = setup((2, 2), moved, w);
        let start = cloth.positions().to_vec();
        let spacing = (start[1] - start[0]).length();
        assert!(spacing > 0.1 && (start[1] - start[0]).dot(Vector::X) == spacing);
        ChainScratch::default().solve(&mut plan, &mut lanes, (2.0, 1), Team::ALONE);
        let x = positions(&plan, &mut lanes);
        let dl = -0.1f32 / 6.0;
        assert!(
            (x[0] - (start[0] - Vector::X * dl)).length() < 1e-6,
            "{:?}",
            x[0]
        );
        assert!(
            (x[1] - (start[1] + Vector::X * (0.1 + 3.0 * dl))).length() < 1e-6,
            "{:?}",
            x[1]
        );
        let first = plan.lanes_of(&(0..1))[0] as usize;
        let (_, [lambda_rows, _]) = plan.stretch_passes();
        assert!(
            (lambda_rows[first] - dl).abs() < 1e-7,
            "{}",
            lambda_rows[first]
        );
    }

    #[test]
    fn every_path_gives_the_same_bits() {
        // 21 columns and 70 rows, jittered, a few pinned: vectors and a
        // scalar tail along both directions, several chunks for threads.
        let jitter = |i: usize, p: Vector| {
            let j = (i as f32 * 0.37).sin() * 0.01;
            Vector::new(p.x * 1.08 + j, p.y - j, p.z * 1.05)
        };
        let w = |i: usize| if i.is_multiple_of(23) { 0.0 } else { 50.0 };
        let run = |simd: bool, threads: usize| {
            let (_, mut plan, mut lanes) = setup((21, 70), jitter, w);
            crate::parallel::on_threads(threads, |team| {
                let mut scratch = ChainScratch::default();
                scratch.solve_with(&mut plan, &mut lanes, (1.0e-3, 1), team, simd);
            });
            let (_, [rows, cols]) = plan.stretch_passes();
            let lambda: Vec<u32> = rows.iter().chain(&*cols).map(|v| v.to_bits()).collect();
            let x: Vec<[u32; 3]> = positions(&plan, &mut lanes)
                .iter()
                .map(|p| p.to_array().map(f32::to_bits))
                .collect();
            (x, lambda)
        };
        let one = run(false, 1);
        let (_, plan, mut lanes) = setup((21, 70), jitter, w);
        assert_ne!(one.0[5], {
            let p = positions(&plan, &mut lanes)[5];
            p.to_array().map(f32::to_bits)
        });
        assert_eq!(run(simd_available(), 1), one);
        assert_eq!(run(simd_available(), 2), one);
        assert_eq!(run(false, 2), one);
    }

    #[test]
    fn the_columns_from_both_ends_solve_what_one_end_does() {
        // The twisted solve eliminates towards the middle spring from both
        // ends: the same tridiagonal system, so the same multipliers and
        // positions as the Thomas algorithm from one end, to rounding. A
        // jittered grid with pinned particles, an odd and an even number
        // of rows (the middle spring falls differently), and 2 rows (the
        // middle spring is the only one).
        let jitter = |i: usize, p: Vector| {
            let j = (i as f32 * 0.37).sin() * 0.01;
            Vector::new(p.x * 1.08 + j, p.y - j, p.z * 1.05 + 0.5 * j)
        };
        let w = |i: usize| if i.is_multiple_of(23) { 0.0 } else { 50.0 };
        for rows in [2, 3, 16, 17, 70] {
            let run = |one_end: bool| {
                let (_, mut plan, mut lanes) = setup((21, rows), jitter, w);
                let mut scratch = ChainScratch {
                    columns_from_one_end: one_end,
                    ..Default::default()
                };
                scratch.solve(&mut plan, &mut lanes, (1.0e-3, 1), Team::ALONE);
                let cols = plan.stretch_passes().1[1].to_vec();
                (positions(&plan, &mut lanes), cols)
            };
            let (twisted, reference) = (run(false), run(true));
            let moved = reference.0.iter().zip(&twisted.0);
            let worst = moved.map(|(a, b)| (*a - *b).length()).fold(0.0, f32::max);
            assert!(worst < 1.0e-6, "{rows} rows: a particle {worst} m apart");
            let scale = reference.1.iter().fold(0.0f32, |m, l| m.max(l.abs()));
            assert!(scale > 0.0, "the columns' springs took no correction");
            for (a, b) in reference.1.iter().zip(&twisted.1) {
                assert!(
                    (a - b).abs() <= 1.0e-4 * scale,
                    "{rows} rows: multipliers {a} and {b}"
                );
            }
        }
    }

    #[test]
    fn the_chains_apply_to_whole_grids_only() {
        let grid = ClothBuilder::new(6, 5).build().unwrap();
        assert!(apply_to(&grid));
        let parts = Cloth::from_parts(
            grid.positions().to_vec(),
            grid.masses().to_vec(),
            grid.springs().iter().collect(),
            grid.triangles().to_vec(),
            grid.material.clone(),
        )
        .unwrap();
        assert!(!apply_to(&parts), "no grid");
    }
}
