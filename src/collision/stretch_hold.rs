//! The stretch limit held against the contacts. The solvers shorten every
//! stretch spring to the material's limit before the contacts, and the
//! contacts win where the two disagree. But a contact pushes a particle out
//! along the obstacle's normal, which at a box's corner or edge points away
//! from its neighbours: cloth draped over a table's corner ended 6%
//! stretched under a 4.5% limit (measured), though it could lie
//! within the limit outside the table. This pass shortens the stretch
//! springs with an end near an obstacle once more, moving only the ends
//! near one (an end away from the obstacles has springs this pass does not
//! look at: moving it stretched those, 5.09% on the 128 × 128 drape's
//! landing against 4.81% so), then pushes every particle it moved back out
//! of the obstacles; a few rounds let the neighbours slide round the
//! corner to where both hold.

use super::contact_set::NONE;
use super::obstacle::Obstacle;
use super::stage::CollisionStage;
use crate::cloth::{Particles, SpringKind, Springs};
use crate::math::Vector;
use crate::parallel::{Disjoint, Team};

/// Rounds of shortening and pushing out at most; they stop when no spring
/// near an obstacle is over the limit.
const ROUNDS: usize = 4;

/// Words of due marks (64 stretch springs each) one work item of the
/// first round's search finds.
const HOLD_WORDS: usize = 32;

/// How far over its limit, as a share of it, a spring may be and count as
/// within it, in every stretch limit (this hold, the solvers' limit after
/// a substep and the grid's): a spring shortened to its limit measures a
/// few parts in 10⁷ either side of it, and without a slack the passes
/// would chase the rounding.
pub(crate) const LIMIT_SLACK: f32 = 1.0e-4;

impl CollisionStage {
    /// Shortens to `factor` times their rest length the stretch `springs`
    /// with an end near an obstacle (the watched ones, when `watched`), each
    /// end near an obstacle moving by its inverse mass (the other held) and
    /// the ends losing the velocity that still stretches the spring; then
    /// moves each particle it moved back out to `thickness` of the
    /// obstacles. Returns the springs shortened.
    pub(super) fn hold_stretch_limit(
        &mut self,
        particles: &mut Particles,
        springs: &Springs,
        obstacles: &[Obstacle],
        (factor, thickness, watched): (f32, f32, bool),
        team: Team,
    ) -> u32 {
        if !factor.is_finite() {
            return 0;
        }
        let stretch = springs.range(SpringKind::Stretch);
        // The watched springs are in spring order, stretch first.
        let count = if watched {
            self.edge_watch
                .partition_point(|&s| (s as usize) < stretch.end)
        } else {
            stretch.len()
        };
        if !self.stretch_at.built {
            self.index_stretch_springs(springs, particles.len());
        }
        let mut shortened = 0;
        for round in 0..ROUNDS {
            self.moved.clear();
            // A spring is shortened only when it is over the limit, and
            // can come to be only when the round moves an end before its
            // turn. So the due springs are those over it as the round
            // begins, and as the round moves a particle its springs
            // further on in spring order; taken in spring order, they give
            // the bits of a look at every spring in order (a round shortens
            // a few springs of thousands). In the first round those over
            // are found on the team's threads; after it, only springs at
            // the particles the last round moved can be (the others kept
            // the length that round found within the limit).
            if round == 0 {
                if count > 0 {
                    self.mark_over(particles, springs, (factor, watched), team);
                } else {
                    self.hold_due.fill(0);
                }
            } else {
                self.hold_due.fill(0);
                for k in 0..self.held_before.len() {
                    let i = self.held_before[k] as usize;
                    self.mark_due(i, 0, watched);
                }
            }
            let mut word = 0;
            while word < self.hold_due.len() {
                let bits = self.hold_due[word];
                if bits == 0 {
                    word += 1;
                    continue;
                }
                self.hold_due[word] = bits & (bits - 1);
                let k = word * 64 + bits.trailing_zeros() as usize;
                let s = stretch.start + k;
                let before = self.moved.len();
                shortened += self.hold_spring(particles, springs, s, factor) as u32;
                for m in before..self.moved.len() {
                    let i = self.moved[m] as usize;
                    self.mark_due(i, k + 1, watched);
                }
            }
            // The last round's marks give way to this one's.
            self.forget_held();
            if self.moved.is_empty() {
                break;
            }
            // The contacts still win: every particle moved ends outside.
            let held = std::mem::take(&mut self.moved);
            for &i in &held {
                let i = i as usize;
                self.edge_moved[i] = false;
                self.held_moved[i] = true;
                let (x, v) = (&mut particles.x[i], &mut particles.v[i]);
                self.move_out(x, Some(v), obstacles, thickness);
            }
            // This round's list becomes the last round's; the emptied one
            // collects the next.
            self.moved = std::mem::replace(&mut self.held_before, held);
        }
        self.forget_held();
        shortened
    }

    /// Holds stretch spring `s` to `factor` times its rest length if an end
    /// is near an obstacle, moving only such ends (an end away from them has
    /// other springs, which this pass does not look at and must not
    /// stretch: it is held like a pin here), and lists the particles it
    /// moved for the first time this round in `moved`. Returns whether it
    /// shortened the spring.
    fn hold_spring(
        &mut self,
        particles: &mut Particles,
        springs: &Springs,
        s: usize,
        factor: f32,
    ) -> bool {
        let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
        if self.nearest[a] == NONE && self.nearest[b] == NONE {
            return false;
        }
        let Particles { x, v, inv_mass, .. } = &mut *particles;
        let near = |i: usize| self.nearest[i] != NONE;
        let wa = if near(a) { inv_mass[a] } else { 0.0 };
        let wb = if near(b) { inv_mass[b] } else { 0.0 };
        let w = wa + wb;
        let d = x[b] - x[a];
        let limit = springs.rest[s] * factor;
        let len2 = d.length_squared();
        if !over_limit(len2, limit) || w == 0.0 {
            return false;
        }
        let len = len2.sqrt();
        let n = d / len;
        let step = n * ((len - limit) / w);
        x[a] += step * wa;
        x[b] -= step * wb;
        stop_separating(v, (a, b), n, (wa, wb));
        for (i, wi) in [(a, wa), (b, wb)] {
            if wi != 0.0 && !self.edge_moved[i] {
                self.edge_moved[i] = true;
                self.moved.push(i as u32);
            }
        }
        true
    }

    /// Marks due the stretch springs the hold looks at (the watched ones,
    /// when `watched`) that are over `factor` times their rest length by
    /// more than the slack with an end near an obstacle, and no others:
    /// the springs [`Self::hold_spring`] would shorten as things stand. On
    /// the team's threads, 64 springs to a word and [`HOLD_WORDS`] words to
    /// an item.
    fn mark_over(
        &mut self,
        particles: &Particles,
        springs: &Springs,
        (factor, watched): (f32, bool),
        team: Team,
    ) {
        let stretch = springs.range(SpringKind::Stretch);
        let (nearest, watch, x) = (&self.nearest, &self.hold_watch, &particles.x);
        let words = self.hold_due.len();
        let due = Disjoint::new(&mut self.hold_due[..]);
        team.sum_count_uneven(words.div_ceil(HOLD_WORDS), |item| {
            let first = item * HOLD_WORDS;
            let last = (first + HOLD_WORDS).min(words);
            // SAFETY: item `item` alone writes these words.
            let due = unsafe { due.range(first..last) };
            for (word, bits) in (first..last).zip(due) {
                let mut looked = if watched { watch[word] } else { u64::MAX };
                let end = ((word + 1) * 64).min(stretch.len());
                if word * 64 + 64 > end {
                    looked &= (1u64 << (end - word * 64)) - 1;
                }
                *bits = 0;
                while looked != 0 {
                    let bit = looked.trailing_zeros() as usize;
                    looked &= looked - 1;
                    let s = stretch.start + word * 64 + bit;
                    let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
                    if nearest[a] == NONE && nearest[b] == NONE {
                        continue;
                    }
                    // As in `hold_spring` (a spring due for nothing would
                    // be looked at for nothing: the same bits).
                    let limit = springs.rest[s] * factor;
                    if over_limit((x[b] - x[a]).length_squared(), limit) {
                        *bits |= 1 << bit;
                    }
                }
            }
            0
        });
    }

    /// Marks due, for the hold's next look, the stretch springs at particle
    /// `i` from the `from`th on (counted in spring order among the stretch
    /// springs), those the hold looks at (the watched ones, when `watched`).
    fn mark_due(&mut self, i: usize, from: usize, watched: bool) {
        for &k in self.stretch_at.at(i) {
            let k = k as usize;
            if k >= from && (!watched || self.hold_watch[k / 64] >> (k % 64) & 1 != 0) {
                self.hold_due[k / 64] |= 1 << (k % 64);
            }
        }
    }

    /// Lists the stretch springs at each particle (of `n`), counted in
    /// spring order among the stretch springs, and which of them the edge
    /// watch holds; sizes the due marks. Once a step, when the watch is made
    /// ([`CollisionStage::cache_candidates`]), or at the hold's first look
    /// in a step without one.
    pub(super) fn index_stretch_springs(&mut self, springs: &Springs, n: usize) {
        let stretch = springs.range(SpringKind::Stretch);
        let words = stretch.len().div_ceil(64);
        self.hold_due.clear();
        self.hold_due.resize(words, 0);
        self.hold_watch.clear();
        self.hold_watch.resize(words, 0);
        for &s in &self.edge_watch {
            let s = s as usize;
            if stretch.contains(&s) {
                let k = s - stretch.start;
                self.hold_watch[k / 64] |= 1 << (k % 64);
            }
        }
        self.stretch_at.build(springs, n);
    }

    /// Clears the marks of the particles the stretch hold's last round moved.
    fn forget_held(&mut self) {
        for &i in &self.held_before {
            self.held_moved[i as usize] = false;
        }
        self.held_before.clear();
    }
}

/// Whether some stretch spring of `springs` at positions `x` is over
/// `factor` times its rest length by more than the slack: what this hold
/// would shorten, over every stretch spring rather than those near an
/// obstacle (so false means it would shorten none). Blocks of springs on
/// the `team`, each one pass with no early exit (the loop stays
/// branch-free).
pub(crate) fn any_stretch_over_limit(
    springs: &Springs,
    x: &[Vector],
    factor: f32,
    team: Team,
) -> bool {
    if !factor.is_finite() {
        return false;
    }
    let stretch = springs.range(SpringKind::Stretch);
    let blocks = stretch.len().div_ceil(OVER_BLOCK);
    let over = team.sum_count(blocks, |k| {
        let block =
            stretch.start + k * OVER_BLOCK..(stretch.start + (k + 1) * OVER_BLOCK).min(stretch.end);
        let (a, b, rest) = (
            &springs.a[block.clone()],
            &springs.b[block.clone()],
            &springs.rest[block],
        );
        let mut over = false;
        for ((&a, &b), &rest) in a.iter().zip(b).zip(rest) {
            let len2 = (x[b as usize] - x[a as usize]).length_squared();
            // A length that is not a number counts as over: the hold's own
            // test skips it, but nothing is then known of it.
            over |= over_limit(len2, rest * factor) || len2.is_nan();
        }
        u32::from(over)
    });
    over > 0
}

/// Stretch springs a block of [`any_stretch_over_limit`] takes.
const OVER_BLOCK: usize = 8192;

/// Whether a spring of squared length `len2` (m²) is over its `limit` (m)
/// by more than the slack every limit allows (false for a length that is
/// not a number).
#[inline]
fn over_limit(len2: f32, limit: f32) -> bool {
    let slack = limit * (1.0 + LIMIT_SLACK);
    len2 > slack * slack
}

/// Takes away the velocity with which particles `a` and `b` (inverse
/// masses `wa`, `wb`, not both zero) still separate along the unit vector
/// `n` from `a` to `b`, each by its inverse mass: an inelastic stop, which
/// keeps their momentum and never adds energy.
#[inline]
pub(crate) fn stop_separating(
    v: &mut [Vector],
    (a, b): (usize, usize),
    n: Vector,
    (wa, wb): (f32, f32),
) {
    let separating = (v[b] - v[a]).dot(n);
    if separating > 0.0 {
        let dv = n * (separating / (wa + wb));
        v[a] += dv * wa;
        v[b] -= dv * wb;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// The check says what the hold would do: nothing for a cloth at rest
    /// or with a spring within the slack of its limit, something for one
    /// a hair past it or with a length that is not a number.
    #[test]
    fn a_spring_counts_as_over_its_limit_only_past_the_slack() {
        let cloth = ClothBuilder::new(4, 4).build().unwrap();
        let springs = cloth.springs();
        let mut x = cloth.positions().to_vec();
        let factor = 1.05;
        assert!(!any_stretch_over_limit(springs, &x, factor, Team::ALONE));
        // The first stretch spring, stretched along itself.
        let s = springs.range(SpringKind::Stretch).start;
        let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
        let rest = springs.rest[s];
        let along = (x[b] - x[a]).normalize();
        let xa = x[a];
        let at = |stretch: f32| xa + along * (rest * stretch);
        x[b] = at(factor * (1.0 + 0.5 * LIMIT_SLACK));
        assert!(!any_stretch_over_limit(springs, &x, factor, Team::ALONE));
        x[b] = at(factor * (1.0 + 2.0 * LIMIT_SLACK));
        assert!(any_stretch_over_limit(springs, &x, factor, Team::ALONE));
        // No limit: nothing to hold.
        assert!(!any_stretch_over_limit(
            springs,
            &x,
            f32::INFINITY,
            Team::ALONE
        ));
        x[b] = Vector::splat(f32::NAN);
        assert!(any_stretch_over_limit(springs, &x, factor, Team::ALONE));
    }

    /// The check's blocks of springs cover them all: the last stretch
    /// spring of a cloth with two blocks' worth is found over, on one
    /// thread and on a team.
    #[test]
    fn the_check_looks_at_every_block_of_springs() {
        let cloth = ClothBuilder::new(70, 70).build().unwrap();
        let springs = cloth.springs();
        let stretch = springs.range(SpringKind::Stretch);
        assert!(stretch.len() > OVER_BLOCK);
        let mut x = cloth.positions().to_vec();
        let s = stretch.end - 1;
        let (a, b) = (springs.a[s] as usize, springs.b[s] as usize);
        let check = |x: &[Vector], team: Team| any_stretch_over_limit(springs, x, 1.05, team);
        let at_rest = x.clone();
        x[b] = x[a] + (x[b] - x[a]) * 1.2;
        let answers = |team: Team| [check(&at_rest, team), check(&x, team)];
        assert_eq!(answers(Team::ALONE), [false, true]);
        let on_two = crate::parallel::on_threads(2, answers);
        assert_eq!(on_two, [false, true]);
    }
}
