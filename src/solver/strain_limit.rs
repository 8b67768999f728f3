//! The material's stretch limit (Provot 1995, "Deformation constraints in a
//! mass-spring model"): after a substep, every stretch spring longer than
//! the limit allows is shortened to it, both ends moving by their inverse
//! masses, in a few Gauss–Seidel passes. The small-steps solver takes its
//! velocities from the positions afterwards; for the others the ends of a
//! shortened spring lose the part of their relative velocity that still
//! stretches it (an inelastic constraint: it takes energy away, never adds
//! it, unlike a correction of the move over the substep, which kicked fast
//! mass-spring's one-step-a-frame curtain into divergence). The springs give the cloth its
//! elasticity below the limit; the limit stops what a spring soft enough to
//! step cheaply would let through under a sudden load. Done after the
//! solve, not inside it: projected once inside a sweep, a chain of hard
//! limits leaves some springs longer than before (measured: a row stretched
//! 30% and limited to 5% ended with a spring at 53%).

use super::pin_support::PinSupport;
use crate::cloth::{SpringKind, Springs};
use crate::collision::StretchIncidence;
use crate::collision::{stop_separating, LIMIT_SLACK};
use crate::math::Vector;

/// Gauss–Seidel passes at most; they stop as soon as none is over the limit.
pub(crate) const PASSES: usize = 4;

/// Passes at most of [`limit_stretch_relaxed`]: the small-steps solver's
/// limit on a cloth without a grid plan (a mesh, a torn sheet), and every
/// other integrator's within its stability limit for every 1/960 s of its
/// substep ([`relaxed_passes`]). A mesh
/// hung from a few points hangs on long runs of springs at the limit,
/// which plain passes carry a pin's correction along a spring or two at a
/// time: a 64 × 64 quad mesh of cotton hung by two corners peaked at 24%
/// stretch with 4 plain passes (weighted by mass). Measured, peak over
/// every frame and ms a frame (BENCHMARKS.md, thirty-seventh session),
/// over-relaxed passes weighted by the pins' support: 48², 64² and 96²
/// hung by two corners 7.1%, 7.8%, 8.8% with 20 passes; 4.8%, 5.3%, 5.8%
/// with 40; 4.51%, 4.73%, 4.91% with 80 (5.6 → 6.5, 13.6 → 18–19, 44 →
/// 79 ms); by four corners at 64 4.51% with 20 (14.0% before). The passes stop
/// once none shortens a spring, so a cloth within its limit pays one.
pub(crate) const RELAXED_PASSES: usize = 80;

/// The passes at most of [`limit_stretch_relaxed`] after a substep of `h`
/// seconds: [`RELAXED_PASSES`] for every 1/960 s of it, rounded (at least
/// one lot, at most 32: a 30 Hz frame in one step). The limit's work then
/// goes by the time simulated, as the substeps' does: an integrator taking
/// one step a 60 Hz frame (implicit Euler, fast mass-spring) gets 1280
/// passes where one taking a hundred substeps gets 80 after each. The
/// passes stop once none shortens a spring. Measured on the `pins` sheet
/// hung by two corners, peak stretch over 120 frames, fast mass-spring /
/// implicit Euler with 80, 160, 320, 640 and 1280 passes: at N = 48 9.9 /
/// 6.0%, 6.6 / 4.6%, 4.85 / 4.51%, 4.51 / 4.51%, 4.51 / 4.51%; at N = 64
/// 16.8 / 20.6% with 80, 4.56 / 4.51% with 1280, at the same time a frame
/// (BENCHMARKS.md, thirty-eighth session). The small-steps solver's
/// substeps are a twelfth of a frame or shorter: 80.
pub(crate) fn relaxed_passes(h: f32) -> usize {
    let lots = (h * 960.0).round();
    if lots.is_finite() {
        RELAXED_PASSES * (lots.clamp(1.0, 32.0) as usize)
    } else {
        RELAXED_PASSES
    }
}

/// How far past its limit a pass of [`limit_stretch_relaxed`] shortens a
/// spring: 1.9 times its excess, as the grid's limit does
/// (`grid_sweep::LIMIT_OVER_RELAXATION`, which says why). With exact
/// projections the 80 passes seldom settle: the 48² and 64² meshes hung by
/// two corners peaked at 5.7% in three to four times the frame (20.7 and
/// 60.8 ms against 6.5 and 19.0 at 1.9).
const OVER_RELAXATION: f32 = 1.9;

/// Holds every stretch spring to at most `factor` times its rest length,
/// moving the free particles' positions `x` (m); with velocities `v`
/// (m/s), takes away the ends' relative velocity that stretches a
/// shortened spring, each pass after the first looking only at the springs
/// whose ends moved (`scratch`, [`DirtySprings`]). Returns the springs
/// shortened.
pub(crate) fn limit_stretch(
    scratch: &mut LimitScratch,
    (springs, inv_mass): (&Springs, &[f32]),
    (x, v): (&mut [Vector], Option<&mut [Vector]>),
    factor: f32,
) -> u32 {
    scratch.dirty.begin(springs, x.len(), false);
    plain_passes(scratch, (springs, inv_mass), (x, v), factor)
}

/// [`limit_stretch`] after a stage that moved some particles of a cloth
/// whose every stretch spring was within the limit before it (by the
/// limit's own test, as the grid's limit leaves it when it settles):
/// the first pass looks only at the springs at a particle whose position
/// differs from `before`, every other spring being still within. The same
/// bits as [`limit_stretch`] then: that pass would find those within too.
/// Positions `before` of another length: every spring.
pub(crate) fn limit_stretch_after_moves(
    scratch: &mut LimitScratch,
    (springs, inv_mass): (&Springs, &[f32]),
    (x, v): (&mut [Vector], Option<&mut [Vector]>),
    factor: f32,
    before: &[Vector],
) -> u32 {
    if before.len() != x.len() {
        return limit_stretch(scratch, (springs, inv_mass), (x, v), factor);
    }
    let dirty = &mut scratch.dirty;
    dirty.begin_none(springs, x.len());
    for (i, (now, was)) in x.iter().zip(before).enumerate() {
        if now.to_array().map(f32::to_bits) != was.to_array().map(f32::to_bits) {
            dirty.moved(i);
        }
    }
    plain_passes(scratch, (springs, inv_mass), (x, v), factor)
}

/// Up to [`PASSES`] plain passes over the springs the scratch's dirty bits
/// (begun for this call) give.
fn plain_passes(
    scratch: &mut LimitScratch,
    (springs, inv_mass): (&Springs, &[f32]),
    (x, v): (&mut [Vector], Option<&mut [Vector]>),
    factor: f32,
) -> u32 {
    let dirty = Some(&mut scratch.dirty);
    limit_passes(springs, inv_mass, (x, v), factor, (PASSES, 1.0), dirty)
}

/// Scratch of the limit's passes ([`limit_stretch`],
/// [`limit_stretch_supported`]): the pins' weights, and the springs the
/// next pass looks at ([`DirtySprings`]).
#[derive(Debug, Default, Clone)]
pub(crate) struct LimitScratch {
    support: PinSupport,
    dirty: DirtySprings,
}

impl LimitScratch {
    /// Makes the scratch for the stretch `springs` of `particles` (found
    /// again only when they change), so that a later call allocates
    /// nothing.
    pub(crate) fn prepare(&mut self, springs: &Springs, particles: usize) {
        self.dirty.begin(springs, particles, false);
    }

    /// Notes that particle `i` moved since the last call, between calls
    /// that carry on (`contact_follow.rs`: the obstacles' push between its
    /// rounds).
    pub(crate) fn moved(&mut self, i: usize) {
        self.dirty.moved(i);
    }
}

/// The stretch springs a pass of the limit looks at: those with an end
/// that moved since the last pass looked at them. The others were found
/// within the limit then (or they would have moved their ends) and still
/// are, so passing over them gives the bits of looking again. A pass
/// takes them in spring order, as Gauss–Seidel does: a spring whose end
/// the pass moves is looked at later in the same pass if it comes after
/// the mover, in the next if not.
#[derive(Debug, Default, Clone)]
struct DirtySprings {
    /// The stretch springs at each particle.
    at: StretchIncidence,
    /// Bits by stretch spring (counted from the first): this pass's, and
    /// the next pass's.
    now: Vec<u64>,
    next: Vec<u64>,
    /// The stretch springs and particles the bits are of.
    of: (usize, usize),
}

impl DirtySprings {
    /// Before a call's passes over the stretch `springs` of `particles`:
    /// every spring, unless `carry` (then those the last call left, and
    /// those at the particles noted since) for the same springs.
    fn begin(&mut self, springs: &Springs, particles: usize, carry: bool) {
        let count = springs.count(SpringKind::Stretch);
        if carry && self.of == (count, particles) {
            // The springs at each particle too: the last call's cloth.
            return;
        }
        self.at.build(springs, particles);
        self.of = (count, particles);
        let words = count.div_ceil(64);
        self.now.clear();
        self.now.resize(words, u64::MAX);
        if !count.is_multiple_of(64) {
            self.now[words - 1] = (1 << (count % 64)) - 1;
        }
        self.next.clear();
        self.next.resize(words, 0);
    }

    /// Before a call's passes over the stretch `springs` of `particles`
    /// that looks at none but those at the particles noted afterwards
    /// ([`Self::moved`]): [`Self::begin`], whose lists of the springs at
    /// each particle are made again whenever the springs change (another
    /// cloth of as many springs and particles too), with no spring marked.
    fn begin_none(&mut self, springs: &Springs, particles: usize) {
        self.begin(springs, particles, false);
        self.now.fill(0);
    }

    /// Notes that particle `i` moved after every look so far.
    fn moved(&mut self, i: usize) {
        if i < self.of.1 {
            for &k in self.at.at(i) {
                self.now[k as usize / 64] |= 1 << (k % 64);
            }
        }
    }

    /// Notes that spring `k`'s look moved particle `i`.
    #[inline]
    fn moved_by(&mut self, k: u32, i: usize) {
        for &t in self.at.at(i) {
            let set = if t > k { &mut self.now } else { &mut self.next };
            set[t as usize / 64] |= 1 << (t % 64);
        }
    }
}

/// The limit after a substep that did not hold it itself (every
/// integrator but the small-steps solver, and that one on a cloth without
/// a grid plan, which takes its velocities from the positions afterwards
/// and passes none): as [`limit_stretch`], each end moved by its `weight`
/// (1/kg: the inverse mass, or less near a pin, `pin_support.rs`),
/// over-relaxed ([`OVER_RELAXATION`]), in up to `passes` passes
/// ([`RELAXED_PASSES`], or [`relaxed_passes`] by the substep).
fn limit_stretch_relaxed(
    springs: &Springs,
    weight: &[f32],
    (x, v): (&mut [Vector], Option<&mut [Vector]>),
    factor: f32,
    (passes, dirty): (usize, &mut DirtySprings),
) -> u32 {
    let passes = (passes, OVER_RELAXATION);
    limit_passes(springs, weight, (x, v), factor, passes, Some(dirty))
}

/// [`limit_stretch_relaxed`] over every spring, each end moved by its
/// `weight` (1/kg; 0 holds a particle where it is): a stage between steps
/// that placed particles and lets the cloth around follow them.
pub(crate) fn limit_stretch_weighted(
    scratch: &mut LimitScratch,
    (springs, weight): (&Springs, &[f32]),
    x: &mut [Vector],
    factor: f32,
) -> u32 {
    let dirty = &mut scratch.dirty;
    dirty.begin(springs, x.len(), false);
    limit_stretch_relaxed(springs, weight, (x, None), factor, (RELAXED_PASSES, dirty))
}

/// [`limit_stretch_relaxed`] weighted by the pins' `support` for the
/// particles' inverse masses `inv_mass` (found again only when the cloth's
/// mass `revision` changed): the limit after a substep of every integrator
/// that does not hold it itself, of the small-steps solver on a cloth
/// without a grid plan, and of the cloth following its contacts. With
/// `carry`, the call goes on from the last one's passes (the same cloth,
/// `factor` and weights), every particle moved since noted with
/// [`LimitScratch::moved`].
pub(crate) fn limit_stretch_supported(
    scratch: &mut LimitScratch,
    (springs, inv_mass, revision): (&Springs, &[f32], u64),
    (x, v): (&mut [Vector], Option<&mut [Vector]>),
    factor: f32,
    (passes, carry): (usize, bool),
) -> u32 {
    let LimitScratch { support, dirty } = scratch;
    support.update(inv_mass, springs, |i| i, revision);
    let weight = support.weights(inv_mass.len()).unwrap_or(inv_mass);
    dirty.begin(springs, x.len(), carry);
    limit_stretch_relaxed(springs, weight, (x, v), factor, (passes, dirty))
}

/// Up to `passes.0` Gauss–Seidel passes of the limit, each spring over it
/// shortened by `passes.1` times its excess; with `dirty` (begun for this
/// call), each pass over those springs only ([`DirtySprings`]), the same
/// bits. The passes after a first over every spring then cost what the
/// springs near those still over do. The `hammock`'s boxes landing spend
/// most of such a frame in the rounds after the contacts
/// (`contact_follow.rs`), which carry on from round to round: in its
/// worst frame, 480 000 looks at a spring before, 385 000 of them the
/// rounds' first passes.
fn limit_passes(
    springs: &Springs,
    inv_mass: &[f32],
    (x, mut v): (&mut [Vector], Option<&mut [Vector]>),
    factor: f32,
    (passes, relaxation): (usize, f32),
    mut dirty: Option<&mut DirtySprings>,
) -> u32 {
    if !factor.is_finite() {
        return 0;
    }
    let (a, b) = springs.endpoints();
    let rest = springs.rest_lengths();
    let stretch = springs.range(SpringKind::Stretch);
    // Spring `s` looked at: shortened to the limit when over it, and
    // whether it was.
    let mut look = |s: usize, x: &mut [Vector]| -> bool {
        let (i, j) = (a[s] as usize, b[s] as usize);
        let w = inv_mass[i] + inv_mass[j];
        let d = x[j] - x[i];
        let len = d.length();
        let limit = rest[s] * factor;
        let excess = len - limit;
        if excess.is_nan() || excess <= limit * LIMIT_SLACK || w == 0.0 {
            return false;
        }
        let step = d * (relaxation * excess / (w * len));
        let (di, dj) = (step * inv_mass[i], -step * inv_mass[j]);
        x[i] += di;
        x[j] += dj;
        if let Some(v) = v.as_deref_mut() {
            stop_separating(v, (i, j), d / len, (inv_mass[i], inv_mass[j]));
        }
        true
    };
    let mut shortened = 0;
    for _ in 0..passes {
        let mut over = 0;
        match dirty.as_deref_mut() {
            None => {
                for s in stretch.clone() {
                    over += look(s, x) as u32;
                }
            }
            Some(dirty) => {
                for w in 0..dirty.now.len() {
                    // Read again after each look: it may add later springs
                    // of this word.
                    while dirty.now[w] != 0 {
                        let word = dirty.now[w];
                        dirty.now[w] = word & (word - 1);
                        let k = (w * 64) as u32 + word.trailing_zeros();
                        let s = stretch.start + k as usize;
                        if look(s, x) {
                            over += 1;
                            dirty.moved_by(k, a[s] as usize);
                            dirty.moved_by(k, b[s] as usize);
                        }
                    }
                }
                // Every bit of this pass is taken: the next pass's come in.
                std::mem::swap(&mut dirty.now, &mut dirty.next);
            }
        }
        shortened += over;
        if over == 0 {
            break;
        }
    }
    shortened
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// After some particles of a cloth within its limit moved, the limit
    /// that looks at their springs alone gives the bits of the limit over
    /// every spring; given positions that are not the cloth's, it looks at
    /// every spring.
    #[test]
    fn the_limit_at_moved_particles_gives_the_bits_of_the_whole_limit() {
        let cloth = ClothBuilder::new(9, 7).build().unwrap();
        let springs = cloth.springs().clone();
        let inv_mass = cloth.inverse_masses().to_vec();
        // Within the limit: each particle a little off its rest place.
        let before: Vec<Vector> = cloth
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| *p + Vector::new(0.0, 0.004 * ((i * 7 % 5) as f32 - 2.0), 0.0))
            .collect();
        let mut scratch = LimitScratch::default();
        let mut within = before.clone();
        assert_eq!(
            limit_stretch(
                &mut scratch,
                (&springs, &inv_mass),
                (&mut within, None),
                1.05
            ),
            0,
            "the cloth starts within its limit"
        );
        // Three particles pushed out of the sheet, two of them neighbours.
        let mut moved = before.clone();
        for (i, dy) in [(10, 0.06), (11, -0.05), (40, 0.07)] {
            moved[i].y += dy;
        }
        let v0: Vec<Vector> = (0..moved.len())
            .map(|i| Vector::new(0.0, 0.1 * i as f32, 0.0))
            .collect();
        let (mut x_all, mut v_all) = (moved.clone(), v0.clone());
        let all = limit_stretch(
            &mut scratch,
            (&springs, &inv_mass),
            (&mut x_all, Some(&mut v_all)),
            1.05,
        );
        assert!(all > 0, "the pushes stretched springs past the limit");
        for wrong in [false, true] {
            let (mut x, mut v) = (moved.clone(), v0.clone());
            let from = if wrong { &before[1..] } else { &before[..] };
            let n = limit_stretch_after_moves(
                &mut LimitScratch::default(),
                (&springs, &inv_mass),
                (&mut x, Some(&mut v)),
                1.05,
                from,
            );
            assert_eq!(n, all);
            let bits = |p: &[Vector]| -> Vec<[u32; 3]> {
                p.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            assert_eq!(bits(&x), bits(&x_all));
            assert_eq!(bits(&v), bits(&v_all));
        }
    }

    #[test]
    fn a_pulled_particle_is_brought_back_within_the_limit() {
        let mut cloth = ClothBuilder::new(6, 6).build().unwrap();
        let mut x = cloth.positions().to_vec();
        // One particle pulled 40% of a spacing out of the sheet.
        x[14] += Vector::new(0.0, 0.4 * 0.2, 0.0);
        let springs = cloth.springs().clone();
        let inv_mass = cloth.inverse_masses().to_vec();
        let pulled = x[14];
        let mut v = vec![Vector::ZERO; x.len()];
        v[14] = Vector::new(0.0, 1.0, 0.0);
        let mut scratch = LimitScratch::default();
        let n = limit_stretch(
            &mut scratch,
            (&springs, &inv_mass),
            (&mut x, Some(&mut v)),
            1.05,
        );
        assert!(n > 0);
        for (i, p) in x.iter().enumerate() {
            cloth.set_position(i, *p).unwrap();
        }
        let worst = cloth.max_strain(SpringKind::Stretch);
        assert!(worst <= 0.0501, "a stretch spring at {worst}");
        // The pulled particle moved back towards the sheet, and no longer
        // moves away from it as fast: the limit took speed, added none.
        assert!(x[14].y < pulled.y, "{:?}", x[14]);
        assert!(v[14].y < 1.0 && v[14].y >= 0.0, "{:?}", v[14]);
        assert!(v.iter().all(|v| v.length() <= 1.0));
        // Without a limit nothing moves.
        let before = x.clone();
        let limits = (&springs, &inv_mass[..]);
        let none = limit_stretch(&mut scratch, limits, (&mut x, None), f32::INFINITY);
        assert_eq!((none, x), (0, before));
    }

    /// The passes over the springs whose ends moved give the bits of the
    /// passes over every spring: from scratch, and carried on after moves
    /// noted between calls, with passes enough to settle and too few,
    /// over-relaxed and plain.
    #[test]
    fn passes_over_the_moved_springs_give_the_bits_of_passes_over_all() {
        let cloth = ClothBuilder::new(12, 12).build().unwrap();
        let springs = cloth.springs().clone();
        let mut w = cloth.inverse_masses().to_vec();
        w[0] = 0.0;
        // A crumple: every particle moved by up to 40% of a spacing.
        let mut seed = 7u32;
        let mut jitter = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5
        };
        let spacing = 1.0 / 11.0;
        let mut x = cloth.positions().to_vec();
        for p in &mut x {
            *p += Vector::new(jitter(), jitter(), jitter()) * (0.8 * spacing);
        }
        let v = vec![Vector::new(0.0, -1.0, 0.5); x.len()];
        for (passes, relaxation) in [(3, OVER_RELAXATION), (80, OVER_RELAXATION), (PASSES, 1.0)] {
            let (mut xa, mut va) = (x.clone(), v.clone());
            let (mut xb, mut vb) = (x.clone(), v.clone());
            let mut dirty = DirtySprings::default();
            let run = |x: &mut [Vector], v: &mut [Vector], dirty: Option<&mut DirtySprings>| {
                limit_passes(
                    &springs,
                    &w,
                    (x, Some(v)),
                    1.05,
                    (passes, relaxation),
                    dirty,
                )
            };
            for call in 0..3 {
                let plain = run(&mut xa, &mut va, None);
                dirty.begin(&springs, xb.len(), call > 0);
                let skipping = run(&mut xb, &mut vb, Some(&mut dirty));
                assert!(plain > 0, "passes {passes}, call {call}");
                assert_eq!(plain, skipping, "passes {passes}, call {call}");
                let bits = |p: &[Vector]| -> Vec<[u32; 3]> {
                    p.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
                };
                assert_eq!(bits(&xa), bits(&xb), "passes {passes}, call {call}");
                assert_eq!(bits(&va), bits(&vb), "passes {passes}, call {call}");
                // Between calls, a few particles pushed (as the obstacles
                // push them between the rounds), and noted.
                for i in [5, 40, 77, 130] {
                    let push = Vector::new(0.0, 0.5 * spacing, 0.0);
                    xa[i] += push;
                    xb[i] += push;
                    dirty.moved(i);
                }
            }
        }
    }
}
