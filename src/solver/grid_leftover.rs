//! The springs of a torn grid cloth that the grid's runs leave out: the
//! springs a split handed to a new particle (past the grid's), any that is
//! not one of the grid's six families, and those at a tear's edge
//! (`grid_sweep` says why). The grid keeps the thousands of others in
//! its vector runs, where the springs it lost are lanes at rest length 0,
//! which project nothing (`grid_sweep::project`). These few hundred are
//! swept after the runs, in the springs' stored order (kind by kind, colour
//! class by colour class, as `general_sweep.rs` takes them), on the same
//! lanes: a Gauss–Seidel sweep too, so the bits do not depend on the
//! threads.
//!
//! The springs of one colour class share no particle, so eight at a time
//! are gathered from the lanes, projected with AVX2 where the CPU has it,
//! and scattered back; the rest one at a time. Both make the same IEEE
//! operations for each spring (`project`), so the same bits.

use crate::cloth::SpringKind;
use crate::math::simd_available;

use super::grid_sweep::lanes::Lanes;
use super::grid_sweep::project::{project, Compliance, KindInSweep};

/// Springs one vector step takes: the 8 lanes of an AVX2 register.
const WIDTH: usize = 8;

/// The springs a torn grid's runs leave out, by their ends' lanes.
#[derive(Debug, Clone, Default)]
pub(crate) struct LeftoverSprings {
    /// Lane of each spring's first end.
    a: Vec<u32>,
    /// Lane of each spring's second end.
    b: Vec<u32>,
    /// Rest length (m) of each spring.
    rest: Vec<f32>,
    /// Kind of each spring ([`SpringKind::index`]).
    kind: Vec<u8>,
    /// Colour class of each spring whose class shares no particle.
    colour: Vec<Option<u32>>,
    /// Multiplier of each spring over the substep's sweeps (N·s²).
    lambda: Vec<f32>,
    /// Runs of consecutive springs of one kind and colour class, and
    /// whether they share no particle ([`LeftoverSprings::finish`]).
    groups: Vec<(std::ops::Range<usize>, bool)>,
    /// One more than the highest lane a spring reaches.
    lanes: usize,
}

impl LeftoverSprings {
    /// Adds the spring between lanes `a` and `b`, `rest` m long at rest, of
    /// `kind` and of the colour class `colour` (when that class's springs
    /// share no particle).
    pub fn push(
        &mut self,
        (a, b): (u32, u32),
        rest: f32,
        (kind, colour): (SpringKind, Option<u32>),
    ) {
        self.a.push(a);
        self.b.push(b);
        self.rest.push(rest);
        self.kind.push(kind.index() as u8);
        self.colour.push(colour);
        self.lambda.push(0.0);
        self.lanes = self.lanes.max(a.max(b) as usize + 1);
    }

    /// How many springs there are.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.a.len()
    }

    /// After the last [`Self::push`]: groups the springs into runs of one
    /// kind and colour class (a run of a class checked to share no particle
    /// may be swept eight at a time).
    pub fn finish(&mut self) {
        self.groups.clear();
        let mut seen = vec![u32::MAX; self.lanes];
        let mut start = 0;
        while start < self.a.len() {
            let key = (self.kind[start], self.colour[start]);
            let mut end = start + 1;
            while end < self.a.len() && (self.kind[end], self.colour[end]) == key {
                end += 1;
            }
            let mut disjoint = key.1.is_some();
            for s in start..end {
                for end_lane in [self.a[s], self.b[s]] {
                    let mark = &mut seen[end_lane as usize];
                    disjoint &= *mark != start as u32;
                    *mark = start as u32;
                }
            }
            self.groups.push((start..end, disjoint));
            start = end;
        }
    }

    /// Starts a substep: every multiplier back to zero.
    pub fn begin_substep(&mut self) {
        self.lambda.fill(0.0);
    }

    /// One Gauss–Seidel pass over the springs of the kinds `kinds` takes,
    /// with each kind's compliance terms, on `lanes`.
    pub fn sweep(
        &mut self,
        lanes: &mut Lanes,
        compliance: &[Compliance; 3],
        kinds: [KindInSweep; 3],
    ) {
        self.sweep_with(lanes, compliance, kinds, simd_available());
    }

    /// [`Self::sweep`], eight at a time only when `simd`.
    fn sweep_with(
        &mut self,
        lanes: &mut Lanes,
        compliance: &[Compliance; 3],
        kinds: [KindInSweep; 3],
        simd: bool,
    ) {
        if self.a.is_empty() {
            return;
        }
        let mut arrays = lanes.arrays_mut();
        // Once a sweep, for the unchecked loads and stores of every spring.
        assert!(
            arrays.iter().all(|v| v.len() >= self.lanes),
            "every spring's lanes within the lanes"
        );
        let arrays: [*mut f32; 7] = arrays.each_mut().map(|v| v.as_mut_ptr());
        for g in 0..self.groups.len() {
            let (range, disjoint) = self.groups[g].clone();
            let kind = self.kind[range.start] as usize;
            if !kinds[kind].on {
                continue;
            }
            let k = compliance[kind];
            let mut s = range.start;
            #[cfg(target_arch = "x86_64")]
            if simd && disjoint {
                // SAFETY: AVX2 is there (`simd`); the springs' lanes are
                // within the arrays (asserted) and share none in the group.
                s = unsafe { self.eights_avx2(range.clone(), arrays, k) };
            }
            let _ = (simd, disjoint);
            while s < range.end {
                // SAFETY: within the arrays (asserted).
                unsafe { self.chunk::<1>(s, arrays, k) };
                s += 1;
            }
        }
    }

    /// The springs of `range` eight at a time; returns the first left.
    ///
    /// # Safety
    /// AVX2 is available; as [`Self::chunk`], and the springs of `range`
    /// share no lane.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn eights_avx2(
        &mut self,
        range: std::ops::Range<usize>,
        arrays: [*mut f32; 7],
        k: Compliance,
    ) -> usize {
        let mut s = range.start;
        while s + WIDTH <= range.end {
            // SAFETY: the caller's promise.
            unsafe { self.chunk::<WIDTH>(s, arrays, k) };
            s += WIDTH;
        }
        s
    }

    /// Springs `s..s + M`, gathered from the lanes, projected and scattered
    /// back.
    ///
    /// # Safety
    /// `arrays` are the lanes' seven arrays (x, y, z, start x, y, z, w),
    /// borrowed for the call; every lane of the springs is within them;
    /// for `M > 1`, the springs share no lane.
    #[inline(always)]
    unsafe fn chunk<const M: usize>(&mut self, s: usize, arrays: [*mut f32; 7], k: Compliance) {
        let [x, y, z, sx, sy, sz, w] = arrays;
        let mut va = [[0.0f32; 3]; M];
        let mut vb = [[0.0f32; 3]; M];
        let mut motion = [[0.0f32; 3]; M];
        let mut wab = [[0.0f32; 2]; M];
        for c in 0..M {
            let (i, j) = (self.a[s + c] as usize, self.b[s + c] as usize);
            // SAFETY: within the arrays (the caller's promise).
            unsafe {
                va[c] = [*x.add(i), *y.add(i), *z.add(i)];
                vb[c] = [*x.add(j), *y.add(j), *z.add(j)];
                motion[c] = [
                    (vb[c][0] - *sx.add(j)) - (va[c][0] - *sx.add(i)),
                    (vb[c][1] - *sy.add(j)) - (va[c][1] - *sy.add(i)),
                    (vb[c][2] - *sz.add(j)) - (va[c][2] - *sz.add(i)),
                ];
                wab[c] = [*w.add(i), *w.add(j)];
            }
        }
        for c in 0..M {
            let lambda = &mut self.lambda[s + c];
            (va[c], vb[c]) = project(
                va[c],
                vb[c],
                motion[c],
                wab[c],
                (self.rest[s + c], lambda),
                k,
            );
        }
        for c in 0..M {
            let (i, j) = (self.a[s + c] as usize, self.b[s + c] as usize);
            // SAFETY: as above; no two springs of the chunk share a lane,
            // so no store is overwritten by another's.
            unsafe {
                (*x.add(i), *y.add(i), *z.add(i)) = (va[c][0], va[c][1], va[c][2]);
                (*x.add(j), *y.add(j), *z.add(j)) = (vb[c][0], vb[c][1], vb[c][2]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eight at a time or one at a time, the same bits: 21 springs of one
    /// class (two full steps and five alone) and three of another kind.
    #[test]
    fn eight_at_a_time_gives_the_bits_of_one_at_a_time() {
        let n = 64;
        let fill = |lanes: &mut Lanes| {
            lanes.resize(n);
            for (k, v) in lanes.arrays_mut().into_iter().enumerate() {
                for (i, x) in v.iter_mut().enumerate() {
                    let t = (i * 7 + k * 13) as f32;
                    *x = if k == 6 {
                        1.0 + (t * 0.1).sin().abs()
                    } else {
                        (t * 0.37).sin() * 0.1
                    };
                }
            }
        };
        let mut springs = LeftoverSprings::default();
        for s in 0..21u32 {
            springs.push((2 * s, 2 * s + 1), 0.05, (SpringKind::Stretch, Some(0)));
        }
        for s in 0..3u32 {
            springs.push((s, s + 50), 0.1, (SpringKind::Bend, Some(1)));
        }
        springs.finish();
        assert_eq!(springs.groups.len(), 2);
        assert!(
            springs.groups.iter().all(|g| g.1),
            "both classes share no particle"
        );
        let k = [Compliance {
            alpha: 1e-3,
            gamma: 0.1,
        }; 3];
        let on = KindInSweep {
            on: true,
            from_zero: false,
            kept: true,
        };
        let run = |simd: bool| {
            let (mut lanes, mut springs) = (Lanes::default(), springs.clone());
            fill(&mut lanes);
            springs.begin_substep();
            for _ in 0..3 {
                springs.sweep_with(&mut lanes, &k, [on; 3], simd);
            }
            let bits: Vec<u32> = lanes
                .arrays_mut()
                .iter()
                .flat_map(|v| v.iter().map(|x| x.to_bits()))
                .collect();
            (
                bits,
                springs
                    .lambda
                    .iter()
                    .map(|l| l.to_bits())
                    .collect::<Vec<_>>(),
            )
        };
        let (one, eight) = (run(false), run(simd_available()));
        assert_eq!(one, eight);
        // The sweep moved the lanes (the check can fail).
        let mut still = Lanes::default();
        fill(&mut still);
        let before: Vec<u32> = still
            .arrays_mut()
            .iter()
            .flat_map(|v| v.iter().map(|x| x.to_bits()))
            .collect();
        assert_ne!(one.0, before);
    }
}
