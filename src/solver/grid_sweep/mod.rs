//! The spring sweep of the small-steps solver specialised to grid cloth:
//! springs of one kind and direction are the lanes of a row, so that rows of
//! one parity class are independent and each row is one vectorised loop over
//! structure-of-arrays positions (8 springs per AVX2 instruction, no
//! gathers). Chosen at run time: AVX2 where the CPU has it, else the same
//! loops with the baseline's 4 lanes; both give the same bits (no fused
//! multiply-add, the same IEEE operations in the same order per lane).
//!
//! Threads: the rows are cut into bands of at least
//! [`BAND_ROWS`](plan::BAND_ROWS) rows (their number depends only on the grid).
//! A sweep runs the bands, each with all its families of springs in turn, then
//! the boundaries between them (the springs that cross from one band into the
//! next), likewise. Bands share no particle, nor do boundaries, so each of the
//! two phases may run its regions on any threads in any order: the bits are
//! those of one thread. One handout to the threads a sweep, not one per family
//! and phase (twelve: at N = 64 the handshakes had cost more than the second
//! thread saved): a band's item runs the boundaries beside it once their other
//! band is done too ([`bands_and_boundaries`](sweep::bands_and_boundaries)),
//! and a boundary touches only its two bands. The boundary springs then lag
//! their band's families by a sweep: before the stretch limit this order landed
//! the drape at N = 128 0.3% more stretched; with it, the peak over every frame
//! went 4.61 → 4.65% (N = 64: 4.50 → 4.56%).
//!
//! A torn grid ([`GridPlan::torn`]) keeps the runs: the springs it lost
//! are lanes at rest length 0, which project nothing, its new particles
//! lanes past the grid's, and the springs the runs cannot hold are swept
//! after them (`grid_leftover.rs`).

mod limit;
mod plan;
mod sweep;
#[cfg(test)]
mod tests;

pub(crate) use self::limit::{limit_stretch, limit_stretch_again, LanePlanes};
pub(crate) use self::plan::GridPlan;
pub(crate) use self::sweep::{project, sweep, KindInSweep};

use super::staggered::Staggered;
use crate::parallel::Disjoint;

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
