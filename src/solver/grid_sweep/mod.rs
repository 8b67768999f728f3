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

pub(crate) mod lanes;
mod limit;
mod plan;
pub(crate) mod project;
mod sweep;

pub(crate) use self::lanes::Lanes;
pub(crate) use self::limit::{limit_stretch, limit_stretch_again, LanePlanes};
pub(crate) use self::plan::GridPlan;
pub(crate) use self::project::{Compliance, KindInSweep};
pub(crate) use self::sweep::sweep;

#[cfg(test)]
mod tests;
