//! The grid sweep's and the stretch limit's tests: against the springs one
//! at a time, the plan's layout and their bits.

use super::lanes::*;
use super::limit::*;
use super::plan::*;
use super::project::{Compliance, KindInSweep};
use super::sweep::*;
use crate::cloth::{Cloth, ClothBuilder};
use crate::cloth::{Grid, LaneGrid, SpringKind};
use crate::collision::LIMIT_SLACK;
use crate::math::simd_available;
use crate::parallel::Team;
use std::sync::atomic::{AtomicU32, Ordering};

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
