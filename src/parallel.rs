//! Work split over threads with the bits of one thread: mutable slices that
//! threads share by taking disjoint ranges of them, and a [`Team`] that runs
//! loops of independent work items on the threads of rayon's pool (with the
//! `parallel` feature) or in order. Each item computes what it would on one
//! thread; only sums of integers cross items, so the result never depends
//! on the thread count.
//!
//! Why a team rather than a `par_iter` per loop: a substep runs a dozen such
//! loops with short stretches of one-thread work between them, and rayon's
//! idle workers fall asleep within tens of microseconds; waking them took
//! longer than the loops (measured: 8 items of 5 µs after 50 µs of serial
//! work took 40 µs on 2 threads, the time of one). For one step the team's
//! helpers wait for work spinning (a moment, then yielding the CPU), as
//! Box2D v3's workers wait between the stages of its solver, and leave when
//! the step ends.

use std::marker::PhantomData;
use std::ops::Range;

/// A mutable slice shared by threads that each take a disjoint range of it.
pub(crate) struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _slice: PhantomData<&'a mut [T]>,
}

impl<T> Clone for Disjoint<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Disjoint<'_, T> {}

// SAFETY: a `Disjoint` hands out its elements only through `range`, whose
// callers promise that the ranges in use at once do not overlap; each
// element is then reached from one thread at a time, as through `&mut [T]`.
unsafe impl<T: Send> Send for Disjoint<'_, T> {}
// SAFETY: as above.
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}

impl<'a, T> Disjoint<'a, T> {
    /// Shares `slice` (borrowed mutably for as long as the `Disjoint` lives).
    pub(crate) fn new(slice: &'a mut [T]) -> Self {
        Disjoint {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _slice: PhantomData,
        }
    }

    /// The elements `range` (panics when it is not within the slice).
    ///
    /// # Safety
    /// No other slice taken from this `Disjoint` that overlaps `range` may
    /// be in use while the returned one is.
    pub(crate) unsafe fn range(self, range: Range<usize>) -> &'a mut [T] {
        assert!(
            range.start <= range.end && range.end <= self.len,
            "a range within the slice"
        );
        // SAFETY: in bounds (asserted); exclusive by the caller's promise;
        // alive for 'a, for which the slice is borrowed.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(range.start), range.len()) }
    }

    /// The slice's length.
    pub(crate) fn len(self) -> usize {
        self.len
    }

    /// The slice's first element, for kernels that step through it with
    /// strides (reading or writing through it is `unsafe`: in bounds, and
    /// only elements no other thread uses meanwhile).
    pub(crate) fn as_ptr(self) -> *mut T {
        self.ptr
    }
}

/// The threads working together through one step: hand it loops of
/// independent items ([`Team::sum_count`]). `Team::ALONE` runs them in order
/// on this thread.
#[derive(Clone, Copy)]
pub(crate) struct Team<'a> {
    #[cfg(feature = "parallel")]
    shared: Option<&'a TeamShared>,
    #[cfg(not(feature = "parallel"))]
    shared: PhantomData<&'a ()>,
}

impl Team<'static> {
    /// No helpers: every loop runs in order on the calling thread.
    pub(crate) const ALONE: Team<'static> = Team {
        #[cfg(feature = "parallel")]
        shared: None,
        #[cfg(not(feature = "parallel"))]
        shared: PhantomData,
    };
}

impl<'a> Team<'a> {
    /// True when the loops run in order on the calling thread.
    pub(crate) fn is_alone(self) -> bool {
        #[cfg(feature = "parallel")]
        return self.shared.is_none();
        #[cfg(not(feature = "parallel"))]
        true
    }

    /// This team for a loop of `work` items, or [`Team::ALONE`] below
    /// `least` of them: handing out a short loop costs more than it saves.
    pub(crate) fn for_work(self, work: usize, least: usize) -> Team<'a> {
        if work >= least {
            self
        } else {
            Team::ALONE
        }
    }

    /// Runs `f` on every item and sums what it returns.
    pub(crate) fn sum_over<I: Sync>(self, items: &[I], f: impl Fn(&I) -> u32 + Sync) -> u32 {
        self.sum_count(items.len(), |k| f(&items[k]))
    }

    /// Runs `f` on `0..count` cut into chunks of `chunk` (on the team's
    /// threads from two chunks on) and returns the largest of what it
    /// returns, taken as non-negative: the same whatever the order.
    pub(crate) fn largest_over_chunks(
        self,
        (count, chunk): (usize, usize),
        f: impl Fn(Range<usize>) -> f32 + Sync,
    ) -> f32 {
        let largest = std::sync::atomic::AtomicU32::new(0);
        let chunks = count.div_ceil(chunk);
        self.for_work(count, 2 * chunk).sum_count(chunks, |c| {
            let got = f(c * chunk..((c + 1) * chunk).min(count));
            // Non-negative floats order as their bits do.
            largest.fetch_max(got.max(0.0).to_bits(), std::sync::atomic::Ordering::Relaxed);
            0
        });
        f32::from_bits(largest.into_inner())
    }

    /// Runs `f` on `0..count` and sums what it returns: on the team's
    /// threads, in whatever order they take the items, or in order alone.
    /// Each member runs its own share of the items (the same data on the
    /// same core, loop after loop), unless another's has stalled: for
    /// items of about one cost each.
    pub(crate) fn sum_count(self, count: usize, f: impl Fn(usize) -> u32 + Sync) -> u32 {
        self.sum_count_as(count, f, Taking::Stalled)
    }

    /// [`Self::sum_count`] for items whose costs differ widely (a
    /// self-collision look's blocks of triangles, a collision pass's
    /// blocks of particles near an obstacle or not): a member whose own
    /// share is done takes another's items at once (the self-collision
    /// look so, on two threads: `stack` 19.3 → 18.9 ms a frame, `fold`
    /// 3.25 → 3.2).
    pub(crate) fn sum_count_uneven(self, count: usize, f: impl Fn(usize) -> u32 + Sync) -> u32 {
        self.sum_count_as(count, f, Taking::AtOnce)
    }

    /// [`Self::sum_count`], taking others' items as `taking` says.
    fn sum_count_as(self, count: usize, f: impl Fn(usize) -> u32 + Sync, taking: Taking) -> u32 {
        #[cfg(feature = "parallel")]
        if let Some(shared) = self.shared {
            if count > 1 {
                return shared.run(count, &f, taking);
            }
        }
        let _ = taking;
        (0..count).map(f).sum()
    }
}

/// When a member whose own share of a loop is done takes items of
/// another's share.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Taking {
    /// Once that share's owner has stalled (`team::STALL`).
    Stalled,
    /// At once.
    AtOnce,
}

/// Runs `body` with a team of the threads of rayon's current pool when
/// `threads` (and the `parallel` feature) and the pool has more than one;
/// otherwise with [`Team::ALONE`].
pub(crate) fn with_team<R>(threads: bool, body: impl FnOnce(Team) -> R) -> R {
    #[cfg(feature = "parallel")]
    if threads && rayon::current_num_threads() > 1 {
        let members = rayon::current_num_threads();
        let shared = TeamShared::new(members);
        return rayon::in_place_scope(|scope| {
            for me in 1..members {
                let shared = &shared;
                scope.spawn(move |_| shared.help(me));
            }
            // The helpers leave when the body ends, even by a panic.
            let _leave = Leave(&shared);
            body(Team {
                shared: Some(&shared),
            })
        });
    }
    let _ = threads;
    body(Team::ALONE)
}

#[cfg(feature = "parallel")]
pub(crate) use team::TeamShared;

#[cfg(feature = "parallel")]
mod team {
    use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicU32, AtomicU64, Ordering};
    use std::time::{Duration, Instant};

    use super::Taking;

    /// A loop of work items as the helpers see it.
    type Job<'f> = &'f (dyn Fn(usize) -> u32 + Sync);

    /// The low half of a ticket or cursor: an item count or index; the high
    /// half numbers the loops.
    const LOW: u64 = u32::MAX as u64;

    /// Spins a moment, then gives the CPU away each time: a thread that
    /// waits long (its partner descheduled, or sharing its CPU with it)
    /// must not hold the CPU the partner needs.
    fn pause(waited: &mut u32) {
        if *waited < SPINS {
            *waited += 1;
            std::hint::spin_loop();
        } else {
            std::thread::yield_now();
        }
    }

    /// Spins before a waiting thread yields: some tens of microseconds, about
    /// the serial stretches between a substep's loops.
    const SPINS: u32 = 1 << 12;

    /// How long a member that has run its own share of a loop waits on
    /// another's share that has not moved before it takes an item of it.
    /// The items are each member's own so that the same data stay on the
    /// same core; taken whenever a member ran out of its own, they moved
    /// from core to core, and the data with them: a member whose item was
    /// taken found its data on the other core next time, took longer, and
    /// had more taken (two threads at N = 128: the chain solves' items of
    /// the second thread took three times those of the first). A member
    /// that has stopped (its thread descheduled) still has its items taken.
    const STALL: Duration = Duration::from_micros(100);

    /// One member's next item, alone on its cache line (a member whose
    /// own share is done claims items of a stalled member's).
    #[derive(Default)]
    #[repr(align(128))]
    struct Cursor(AtomicU64);

    /// The items one member has finished, loop after loop, and the sum of
    /// what they returned (both wrapping): written by that member alone,
    /// alone on its cache lines (as [`Cursor`]). Counters every member
    /// updated after each item sent their line from core to core: a loop
    /// of 8 items took 1.25 µs on two threads, of 2 items 0.6; so, 0.7
    /// and 0.45.
    #[derive(Default)]
    #[repr(align(128))]
    struct Finished {
        done: AtomicU32,
        sum: AtomicU32,
    }

    impl Finished {
        /// One more item finished, which returned `value`.
        fn add(&self, value: u32) {
            let sum = self.sum.load(Ordering::Relaxed).wrapping_add(value);
            self.sum.store(sum, Ordering::Relaxed);
            let done = self.done.load(Ordering::Relaxed).wrapping_add(1);
            self.done.store(done, Ordering::Release);
        }
    }

    /// What the team's threads share.
    pub(crate) struct TeamShared {
        /// The current loop's number and item count.
        ticket: AtomicU64,
        /// Per member: the loop's number and the next item of its share.
        /// Member `m` of `M` owns items `⌈m·count/M⌉ .. ⌈(m+1)·count/M⌉`: the
        /// same items, hence the same data, on the same thread loop after
        /// loop (measured: handing items out first come first served cost
        /// the cache misses that ate most of what a second thread gave).
        cursors: Vec<Cursor>,
        /// Points to the current loop's [`Job`] (on the stack of `run`).
        job: AtomicPtr<()>,
        /// Whether the current loop's items are taken from a share only
        /// once its owner has stalled ([`Taking`]).
        patient: AtomicBool,
        /// Per member: the items it finished and the sum of what they
        /// returned, since the team began.
        finished: Vec<Finished>,
        /// An item panicked.
        panicked: AtomicBool,
        /// The step is over: helpers leave.
        pub(super) quit: AtomicBool,
    }

    impl TeamShared {
        /// Shared state of a team of `members` threads (the caller is member 0).
        pub(super) fn new(members: usize) -> TeamShared {
            TeamShared {
                ticket: AtomicU64::new(0),
                cursors: (0..members.max(1)).map(|_| Cursor::default()).collect(),
                job: AtomicPtr::new(std::ptr::null_mut()),
                patient: AtomicBool::new(true),
                finished: (0..members.max(1)).map(|_| Finished::default()).collect(),
                panicked: AtomicBool::new(false),
                quit: AtomicBool::new(false),
            }
        }

        /// The first item of member `m`'s share of `count`: rounded up,
        /// so that the caller (member 0), which starts a loop first, has
        /// the larger share of an odd count (the stretch limit's loops of
        /// seven regions on two threads: 3.11 → 3.03 ms a frame at
        /// N = 128).
        fn share_start(&self, m: usize, count: u64) -> u64 {
            let members = self.cursors.len() as u64;
            (count * m as u64).div_ceil(members)
        }

        /// Runs `f` on `0..count` with the helpers, taking others' items
        /// as `taking` says; returns the sum.
        pub(super) fn run(
            &self,
            count: usize,
            f: &(dyn Fn(usize) -> u32 + Sync),
            taking: Taking,
        ) -> u32 {
            assert!(count as u64 <= LOW, "at most 2^32 - 1 items in a loop");
            let job: Job = f;
            let count = count as u64;
            // No member runs an item between loops.
            let before = self.finished_so_far();
            self.job
                .store(&job as *const Job as *mut (), Ordering::Relaxed);
            // Shares far apart (one of two items, two of three) are
            // balanced by taking at once: the `fold`'s three bands of rows
            // on two threads, 3.3 ms a frame so, 3.5 waiting for the
            // caller's two. Four against three (the limit's seven
            // boundaries) wait: 2.98 against 3.05 ms at N = 128.
            // (Rounded up, the shares are the count over the members,
            // rounded down or up.)
            let members = self.cursors.len() as u64;
            let (least, most) = (count / members, count.div_ceil(members));
            let near = 3 * least >= 2 * most;
            self.patient
                .store(taking == Taking::Stalled && near, Ordering::Relaxed);
            let number = (self.ticket.load(Ordering::Relaxed) >> 32) + 1;
            for (m, cursor) in self.cursors.iter().enumerate() {
                let start = self.share_start(m, count);
                cursor.0.store((number << 32) | start, Ordering::Relaxed);
            }
            // Publishes the loop: a helper that reads this ticket sees the above.
            self.ticket.store((number << 32) | count, Ordering::Release);
            self.work(0, number, count);
            // Helpers may still be on their last items; `job` must live until
            // they finish (no item is claimed once all are).
            let mut waited = 0u32;
            let sum = loop {
                let (done, sum) = self.finished_so_far();
                if u64::from(done.wrapping_sub(before.0)) >= count {
                    break sum.wrapping_sub(before.1);
                }
                pause(&mut waited);
            };
            assert!(
                !self.panicked.load(Ordering::Relaxed),
                "a cloth thread panicked"
            );
            sum
        }

        /// The items the members have finished and the sum of what they
        /// returned, since the team began (wrapping).
        fn finished_so_far(&self) -> (u32, u32) {
            self.finished.iter().fold((0u32, 0u32), |(done, sum), f| {
                // The count first: an item's value is stored before it.
                let d = f.done.load(Ordering::Acquire);
                (
                    done.wrapping_add(d),
                    sum.wrapping_add(f.sum.load(Ordering::Relaxed)),
                )
            })
        }

        /// Member `me` claims and runs items of loop `number` of `count`
        /// items: its own share first, then what is left of the others'
        /// (in a patient loop, of those whose owners have stalled:
        /// [`STALL`]).
        fn work(&self, me: usize, number: u64, count: u64) {
            let members = self.cursors.len();
            // Published with the loop (stored before its ticket).
            let patient = self.patient.load(Ordering::Relaxed);
            for (k, m) in (0..members).map(|k| (k, (me + k) % members)) {
                let end = self.share_start(m + 1, count);
                let cursor = &self.cursors[m].0;
                // Another's share: the cursor as last seen, and since when.
                let mut seen: Option<(u64, Instant)> = None;
                loop {
                    let c = cursor.load(Ordering::Acquire);
                    // A later loop (this one is done), or the share done.
                    if c >> 32 != number || c & LOW >= end {
                        break;
                    }
                    let at = c & LOW;
                    if k > 0 && patient {
                        // Its owner is getting through it: leave it be.
                        match seen {
                            Some((before, since)) if before == c => {
                                if since.elapsed() < STALL {
                                    std::hint::spin_loop();
                                    continue;
                                }
                            }
                            _ => {
                                seen = Some((c, Instant::now()));
                                continue;
                            }
                        }
                    }
                    if cursor
                        .compare_exchange_weak(c, c + 1, Ordering::AcqRel, Ordering::Relaxed)
                        .is_err()
                    {
                        continue;
                    }
                    let value = self.run_item(at as usize);
                    self.finished[me].add(value);
                }
            }
        }

        /// Runs claimed item `at` of the current loop; returns what it
        /// returned (0 if it panicked).
        fn run_item(&self, at: usize) -> u32 {
            // SAFETY: the item is claimed and not done, so `run` of its
            // loop has not returned: its `job` is alive, and the pointer
            // (stored before the loop was published, read after it was)
            // points to it.
            let job: Job = unsafe { *(self.job.load(Ordering::Acquire) as *const Job) };
            // A panic is carried to `run`, which must not unwind while
            // other threads still use `job`.
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| job(at))) {
                Ok(v) => v,
                Err(_) => {
                    self.panicked.store(true, Ordering::Relaxed);
                    0
                }
            }
        }

        /// Helper `me` (1 or more): waits for loops, spinning, and works on
        /// them, until the step ends.
        pub(super) fn help(&self, me: usize) {
            let mut seen = 0;
            let mut idle = 0u32;
            while !self.quit.load(Ordering::Acquire) {
                let ticket = self.ticket.load(Ordering::Acquire);
                let number = ticket >> 32;
                if number != seen {
                    self.work(me, number, ticket & LOW);
                    seen = number;
                    idle = 0;
                } else {
                    pause(&mut idle);
                }
            }
        }
    }
}

/// Tells the helpers to leave when dropped.
#[cfg(feature = "parallel")]
struct Leave<'a>(&'a TeamShared);

#[cfg(feature = "parallel")]
impl Drop for Leave<'_> {
    fn drop(&mut self) {
        self.0
            .quit
            .store(true, std::sync::atomic::Ordering::Release);
    }
}

/// Runs `body` with a team of `threads` on a pool of its own (the tests
/// that compare the bits of one thread and of several).
#[cfg(test)]
pub(crate) fn on_threads<R: Send>(threads: usize, body: impl FnOnce(Team) -> R + Send) -> R {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    pool.install(|| with_team(threads > 1, body))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alone_the_items_run_in_order() {
        let order = std::sync::Mutex::new(Vec::new());
        let sum = Team::ALONE.sum_count(5, |k| {
            order.lock().unwrap().push(k);
            k as u32
        });
        assert_eq!(sum, 10);
        assert_eq!(*order.lock().unwrap(), [0, 1, 2, 3, 4]);
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn a_team_runs_every_item_of_every_loop_once() {
        use std::sync::atomic::{AtomicU32, Ordering};
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let runs: Vec<AtomicU32> = (0..64).map(|_| AtomicU32::new(0)).collect();
        let helped = AtomicU32::new(0);
        pool.install(|| {
            let caller = std::thread::current().id();
            with_team(true, |team| {
                // Many short loops back to back, of every size up to 64:
                // a helper late for one loop must not run items of the next.
                for round in 0..20_000 {
                    let count = round % 65;
                    let sum = team.sum_count(count, |k| {
                        runs[k].fetch_add(1, Ordering::Relaxed);
                        if std::thread::current().id() != caller {
                            helped.fetch_add(1, Ordering::Relaxed);
                        }
                        k as u32
                    });
                    assert_eq!(sum as usize, count * count.saturating_sub(1) / 2);
                }
            });
        });
        for (k, r) in runs.iter().enumerate() {
            // Item k is in the loops of count k + 1 ..= 64.
            let loops = (0..20_000).filter(|r| r % 65 > k).count() as u32;
            assert_eq!(r.load(Ordering::Relaxed), loops, "item {k}");
        }
        assert!(
            helped.load(Ordering::Relaxed) > 0,
            "the helpers took no item"
        );
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn a_member_runs_its_own_share_unless_its_owner_has_stalled() {
        use std::sync::Mutex;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        // Eight items: the caller's share 0..4, the helper's 4..8.
        let ran_by = |stall: bool, uneven: bool| {
            let who = Mutex::new(vec![None; 8]);
            pool.install(|| {
                let caller = std::thread::current().id();
                with_team(true, |team| {
                    // A few loops first, so that the helper is waiting.
                    for _ in 0..100 {
                        team.sum_count(8, |_| 0);
                    }
                    let item = |k: usize| {
                        if stall && k == 4 {
                            // The helper's first item holds it up for
                            // far longer than a stall.
                            std::thread::sleep(std::time::Duration::from_millis(20));
                        } else if uneven && k >= 4 {
                            // The helper's items take a while (less than
                            // a stall), so that the caller, done with its
                            // own, finds some of them still to take: with
                            // empty items a helper may finish its share
                            // first every time on a busy machine (seen in
                            // CI while another build ran).
                            let start = std::time::Instant::now();
                            while start.elapsed() < std::time::Duration::from_micros(20) {
                                std::hint::spin_loop();
                            }
                        }
                        let me = std::thread::current().id() == caller;
                        who.lock().unwrap()[k] = Some(me);
                        0
                    };
                    if uneven {
                        team.sum_count_uneven(8, item);
                    } else {
                        team.sum_count(8, item);
                    }
                });
            });
            who.into_inner().unwrap()
        };
        // Unhindered, each runs its own: the caller, done with its four
        // empty items long before the helper is, does not take the
        // helper's (taken at once, as they were, it ran most of them). Not
        // every time: a test run elsewhere may hold the helper up.
        let shares = [true, true, true, true, false, false, false, false];
        // Each property must show at least once; on a busy machine (the
        // other tests, another build) a run may go either way, so runs are
        // tried until it shows, for up to half a minute.
        let shows = |uneven: bool, property: &dyn Fn(&[bool]) -> bool| {
            let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
            loop {
                let mine: Vec<bool> = ran_by(false, uneven)
                    .iter()
                    .map(|w| w.expect("ran"))
                    .collect();
                if property(&mine) {
                    return true;
                }
                if std::time::Instant::now() > deadline {
                    return false;
                }
            }
        };
        assert!(
            shows(false, &|mine| mine == shares),
            "the caller took the helper's items every time"
        );
        // Items of uneven costs are taken at once.
        assert!(
            shows(true, &|mine| mine[4..].contains(&true)),
            "the caller never took the helper's uneven items"
        );
        // Whoever is held up in item 4 (the helper, unless the helper was
        // late and the caller took it), the other runs the rest of that
        // share: a stalled member's items are still taken.
        let mine: Vec<bool> = ran_by(true, false)
            .iter()
            .map(|w| w.expect("ran"))
            .collect();
        assert!(mine[5..].iter().all(|&m| m != mine[4]), "{mine:?}");
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn a_panic_in_an_item_reaches_the_caller_and_the_helpers_leave() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let out = pool.install(|| {
            std::panic::catch_unwind(|| {
                with_team(true, |team| {
                    team.sum_count(8, |k| if k == 6 { panic!("item {k}") } else { 1 })
                })
            })
        });
        assert!(out.is_err());
        // The pool is free again: the helper left.
        assert_eq!(
            pool.install(|| with_team(true, |team| team.sum_count(4, |_| 1))),
            4
        );
    }
}
