//! The lanes: the grid's particles as structure-of-arrays in the plan's order,
//! the compliance terms of a kind, and the views the sweep and the limit take
//! of them.

use crate::parallel::Disjoint;
use crate::solver::staggered::Staggered;

/// Structure-of-arrays positions (m), positions at the substep's start (m) and
/// inverse masses (1/kg), in the plan's lane order
/// ([`GridPlan::lane`](super::plan::GridPlan::lane)): x, y, z, start x, y, z,
/// w, staggered ([`Staggered`]).
#[derive(Debug)]
pub(crate) struct Lanes(pub(super) Staggered);

/// Stagger slots: the lanes' 7 arrays, then the passes' multipliers, then
/// their rest lengths, all read at the same index by the sweep.
pub(super) const LANE_SLOT: usize = 0;

pub(super) const LAMBDA_SLOT: usize = 7;

pub(super) const REST_SLOT: usize = 13;

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
    pub(crate) fn arrays_mut(&mut self) -> [&mut [f32]; 7] {
        let mut arrays = self.0.all_mut();
        std::array::from_fn(|_| arrays.next().expect("seven arrays"))
    }
}

/// The lanes and the passes' multipliers, shared by the regions of one
/// phase, which touch disjoint lanes.
#[derive(Clone, Copy)]
pub(super) struct SharedLanes<'a> {
    pub(super) x: Disjoint<'a, f32>,
    pub(super) y: Disjoint<'a, f32>,
    pub(super) z: Disjoint<'a, f32>,
    pub(super) sx: &'a [f32],
    pub(super) sy: &'a [f32],
    pub(super) sz: &'a [f32],
    pub(super) w: &'a [f32],
    pub(super) lambda: [Disjoint<'a, f32>; 6],
}

/// The lanes of one region: positions to update, substep-start positions and
/// inverse masses to read, indexed from the region's first lane.
pub(super) struct View<'a> {
    pub(super) x: &'a mut [f32],
    pub(super) y: &'a mut [f32],
    pub(super) z: &'a mut [f32],
    pub(super) sx: &'a [f32],
    pub(super) sy: &'a [f32],
    pub(super) sz: &'a [f32],
    pub(super) w: &'a [f32],
}

impl View<'_> {
    /// How many lanes the view has (each of its arrays that many).
    #[inline(always)]
    pub(super) fn len(&self) -> usize {
        self.x.len()
    }

    /// The positions at lanes `at..at + M`: x, y, z.
    ///
    /// # Safety
    /// `at + M <= self.len()`.
    #[inline(always)]
    pub(super) unsafe fn positions<const M: usize>(&self, at: usize) -> [[f32; M]; 3] {
        // SAFETY: in bounds by the caller's promise; the arrays are of one length.
        unsafe { [load(self.x, at), load(self.y, at), load(self.z, at)] }
    }

    /// Writes positions `p` (x, y, z) to lanes `at..at + M`.
    ///
    /// # Safety
    /// As for [`View::positions`].
    #[inline(always)]
    pub(super) unsafe fn set_positions<const M: usize>(
        &mut self,
        at: usize,
        [x, y, z]: [[f32; M]; 3],
    ) {
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
pub(super) unsafe fn load<const M: usize>(v: &[f32], at: usize) -> [f32; M] {
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
pub(super) unsafe fn store<const M: usize>(v: &mut [f32], at: usize, value: [f32; M]) {
    debug_assert!(at + M <= v.len());
    // SAFETY: as for `load`.
    unsafe { v.as_mut_ptr().add(at).cast::<[f32; M]>().write(value) }
}

impl<'a> SharedLanes<'a> {
    /// `lanes` and the passes' multipliers `lambda`, all of one length.
    pub(super) fn new(lanes: &'a mut Lanes, lambda: &'a mut Staggered) -> SharedLanes<'a> {
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
    pub(super) unsafe fn view(self, range: std::ops::Range<usize>) -> View<'a> {
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
    pub(super) unsafe fn lambda(self, p: usize, range: std::ops::Range<usize>) -> &'a mut [f32] {
        // SAFETY: exclusive by the caller's promise.
        unsafe { self.lambda[p].range(range) }
    }
}

/// Springs handled by one vector step: the 8 lanes of an AVX2 register.
pub(super) const WIDTH: usize = 8;

/// True when lanes `a..a + len` and `b..b + len` do not overlap.
pub(super) fn apart(a: u32, b: u32, len: u32) -> bool {
    a + len <= b || b + len <= a
}
