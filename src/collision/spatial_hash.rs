//! A spatial hash of points (Teschner et al. 2003, "Optimized spatial
//! hashing for collision detection of deformable objects", in the dense
//! layout of Müller's "Ten minute physics"): cubic cells of one size,
//! hashed into a table of about twice as many buckets as points, each
//! bucket's points stored contiguously in point order. Built in O(n)
//! whenever the points move; allocates nothing once warmed up.

use crate::math::{simd_available, Vector};

/// Points by cell, for "which points lie in this box" queries.
#[derive(Debug, Default, Clone)]
pub(crate) struct SpatialHash {
    /// 1 / cell size, in 1/m.
    inv_cell: f32,
    /// Per bucket: where its points start in `entries`; one more entry
    /// than buckets, the last being the point count.
    start: Vec<u32>,
    /// Point indices, bucket by bucket, ascending within a bucket.
    entries: Vec<u32>,
    /// Per point: its cell.
    cells: Vec<[i32; 3]>,
    /// Per entry: its point's cell and position (m), coordinate by
    /// coordinate, so that a query reads a bucket's points from one
    /// stretch of memory (the self-collision look went to loading them
    /// point by point from wherever they were), eight at a time where the
    /// CPU has AVX2. [`PAD`] entries longer than the points, so that eight
    /// lanes read from a bucket's last entry stay inside.
    entry_cells: [Vec<i32>; 3],
    entry_points: [Vec<f32>; 3],
    /// The CPU has AVX2.
    simd: bool,
}

/// Lanes of the AVX2 scan, and the padding past the last entry that its
/// loads may read.
const PAD: usize = 8;

/// Cells a query may visit before it visits every point instead (a box
/// over a cloth that has flown apart would otherwise take forever).
const MAX_QUERY_CELLS: i64 = 4096;

impl SpatialHash {
    /// Hashes `points` into cells of `cell` metres (> 0).
    pub fn build(&mut self, points: &[Vector], cell: f32) {
        let n = points.len();
        self.inv_cell = if cell > 0.0 && cell.is_finite() {
            1.0 / cell
        } else {
            1.0
        };
        let buckets = (2 * n).next_power_of_two().max(1);
        self.start.clear();
        self.start.resize(buckets + 1, 0);
        self.entries.clear();
        self.entries.resize(n, 0);
        self.cells.clear();
        for &p in points {
            let c = self.cell_of(p);
            self.cells.push(c);
            let b = self.bucket(c);
            self.start[b] += 1;
        }
        // Running sums: `start[b]` is then where bucket b ends.
        let mut sum = 0;
        for s in self.start.iter_mut() {
            sum += *s;
            *s = sum;
        }
        // Filled from the last point down, so each bucket ends ascending and
        // `start[b]` where it begins.
        for i in (0..n).rev() {
            let b = self.bucket(self.cells[i]);
            self.start[b] -= 1;
            self.entries[self.start[b] as usize] = i as u32;
        }
        for (cells, coordinates) in self.entry_cells.iter_mut().zip(&mut self.entry_points) {
            cells.clear();
            cells.resize(n + PAD, 0);
            coordinates.clear();
            coordinates.resize(n + PAD, 0.0);
        }
        // One pass over the entries for all six arrays (a pass each, by
        // `extend`, read each point's cell and position six times).
        let [cx, cy, cz] = &mut self.entry_cells;
        let [px, py, pz] = &mut self.entry_points;
        let (cx, cy, cz) = (&mut cx[..n], &mut cy[..n], &mut cz[..n]);
        let (px, py, pz) = (&mut px[..n], &mut py[..n], &mut pz[..n]);
        for (k, &i) in self.entries.iter().enumerate() {
            let (c, p) = (self.cells[i as usize], points[i as usize]);
            (cx[k], cy[k], cz[k]) = (c[0], c[1], c[2]);
            (px[k], py[k], pz[k]) = (p.x, p.y, p.z);
        }
        self.simd = simd_available();
    }

    /// The position (m) of entry `k`.
    fn entry_point(&self, k: usize) -> Vector {
        let [x, y, z] = &self.entry_points;
        Vector::new(x[k], y[k], z[k])
    }

    /// Calls `f` with the index and position (m) of every point inside the
    /// box `min..=max` (metres; a point that is not a number is in no box),
    /// each once: the points [`SpatialHash::for_each_in`] visits, less
    /// those outside the box, tested here without a call each.
    pub fn for_each_inside(&self, min: Vector, max: Vector, mut f: impl FnMut(u32, Vector)) {
        let inside = |p: Vector| p.cmpge(min).all() && p.cmple(max).all();
        let (lo, hi) = (self.cell_of(min), self.cell_of(max));
        let span = |a: usize| (hi[a] as i64 - lo[a] as i64 + 1).max(0);
        if span(0) * span(1) * span(2) > MAX_QUERY_CELLS {
            for k in 0..self.entries.len() {
                let p = self.entry_point(k);
                if inside(p) {
                    f(self.entries[k], p);
                }
            }
            return;
        }
        let mut hand = |k: usize| f(self.entries[k], self.entry_point(k));
        for_cells((lo, hi), |c| {
            let b = self.bucket(c);
            let bucket = self.start[b] as usize..self.start[b + 1] as usize;
            #[cfg(target_arch = "x86_64")]
            if self.simd {
                // SAFETY: `simd` only when the CPU has AVX2.
                unsafe { self.scan_avx2(bucket, c, (min, max), &mut hand) };
                return;
            }
            for k in bucket {
                // Another cell may share the bucket; each point is visited
                // from its own cell only.
                let cell = self.entry_cells.each_ref().map(|cells| cells[k]);
                if cell == c && inside(self.entry_point(k)) {
                    hand(k);
                }
            }
        });
    }

    /// The entries `bucket` of cell `c` inside the box `min..=max`, eight
    /// at a time, handed to `hand` in entry order: the portable loop's
    /// tests (ordered compares: a point that is not a number is outside).
    ///
    /// # Safety
    /// The CPU has AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn scan_avx2(
        &self,
        bucket: std::ops::Range<usize>,
        c: [i32; 3],
        (min, max): (Vector, Vector),
        hand: &mut impl FnMut(usize),
    ) {
        use std::arch::x86_64::*;
        // Eight lanes from any entry of the bucket stay inside the arrays.
        let n = self.entries.len();
        assert!(bucket.end <= n);
        assert!(self.entry_cells.iter().all(|v| v.len() == n + PAD));
        assert!(self.entry_points.iter().all(|v| v.len() == n + PAD));
        // Written out, not mapped: a closure would not be compiled for AVX2.
        let cell = [
            _mm256_set1_epi32(c[0]),
            _mm256_set1_epi32(c[1]),
            _mm256_set1_epi32(c[2]),
        ];
        let lo = [
            _mm256_set1_ps(min.x),
            _mm256_set1_ps(min.y),
            _mm256_set1_ps(min.z),
        ];
        let hi = [
            _mm256_set1_ps(max.x),
            _mm256_set1_ps(max.y),
            _mm256_set1_ps(max.z),
        ];
        let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
        let mut k = bucket.start;
        while k < bucket.end {
            // Lanes past the bucket's end read the next bucket or the pad,
            // and are masked off.
            let left = _mm256_set1_epi32((bucket.end - k).min(PAD) as i32);
            let mut keep = _mm256_castsi256_ps(_mm256_cmpgt_epi32(left, lane));
            for a in 0..3 {
                let cells = self.entry_cells[a].as_ptr().add(k) as *const __m256i;
                let same = _mm256_cmpeq_epi32(_mm256_loadu_si256(cells), cell[a]);
                let at = _mm256_loadu_ps(self.entry_points[a].as_ptr().add(k));
                let within = _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GE_OQ>(at, lo[a]),
                    _mm256_cmp_ps::<_CMP_LE_OQ>(at, hi[a]),
                );
                keep = _mm256_and_ps(keep, _mm256_and_ps(_mm256_castsi256_ps(same), within));
            }
            let mut bits = _mm256_movemask_ps(keep) as u32;
            while bits != 0 {
                hand(k + bits.trailing_zeros() as usize);
                bits &= bits - 1;
            }
            k += PAD;
        }
    }

    /// Calls `f` once for every point whose cell meets the box `min..=max`
    /// (metres): every point inside the box, and some near it.
    pub fn for_each_in(&self, min: Vector, max: Vector, mut f: impl FnMut(u32)) {
        let (lo, hi) = (self.cell_of(min), self.cell_of(max));
        let span = |a: usize| (hi[a] as i64 - lo[a] as i64 + 1).max(0);
        if span(0) * span(1) * span(2) > MAX_QUERY_CELLS {
            for i in 0..self.cells.len() {
                let c = self.cells[i];
                if (0..3).all(|a| lo[a] <= c[a] && c[a] <= hi[a]) {
                    f(i as u32);
                }
            }
            return;
        }
        for_cells((lo, hi), |c| {
            let b = self.bucket(c);
            let (s, e) = (self.start[b] as usize, self.start[b + 1] as usize);
            for &i in &self.entries[s..e] {
                // Another cell may share the bucket; each point is visited
                // from its own cell only.
                if self.cells[i as usize] == c {
                    f(i);
                }
            }
        });
    }

    fn cell_of(&self, p: Vector) -> [i32; 3] {
        cell_of(p, self.inv_cell)
    }

    fn bucket(&self, c: [i32; 3]) -> usize {
        bucket(c, self.start.len() - 1)
    }
}

/// Calls `f` on every cell of the inclusive range `lo..=hi`.
fn for_cells((lo, hi): ([i32; 3], [i32; 3]), mut f: impl FnMut([i32; 3])) {
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                f([x, y, z]);
            }
        }
    }
}

/// The cell of `p` for cells of `1 / inv` metres.
fn cell_of(p: Vector, inv: f32) -> [i32; 3] {
    let s = p * inv;
    [floor_to_i32(s.x), floor_to_i32(s.y), floor_to_i32(s.z)]
}

/// `v.floor() as i32` (saturating, NaN to 0: no panic on a wild point)
/// without a call: the baseline x86-64 has no rounding instruction, and
/// `floorf` was a call a coordinate, 1.3% of the `fold`'s instructions.
/// Truncation rounds toward zero; a negative `v` with a fraction is then
/// one above its floor (exact: below 2²⁴ in size an `i32` is an exact
/// `f32`, above it every `f32` is whole).
#[inline]
fn floor_to_i32(v: f32) -> i32 {
    let t = v as i32;
    if (t as f32) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// The bucket of cell `c` among `buckets` (a power of two).
fn bucket([x, y, z]: [i32; 3], buckets: usize) -> usize {
    let h = x.wrapping_mul(92_837_111) ^ y.wrapping_mul(689_287_499) ^ z.wrapping_mul(283_923_481);
    (h as u32 as usize) & (buckets - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cell index is the floor's, wild values included.
    #[test]
    fn floor_to_i32_is_the_floor_cast() {
        let mut values = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1.0e-30,
            16_777_215.5,
            -16_777_215.5,
            16_777_216.0,
            -16_777_217.0,
            2_147_483_520.0,
            -2_147_483_648.0,
            2_147_483_648.0,
            -2_147_483_904.0,
            1.0e30,
            -1.0e30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
        ];
        values.extend((-2000..2000).map(|i| i as f32 * 0.37));
        for v in values {
            assert_eq!(floor_to_i32(v), v.floor() as i32, "{v}");
        }
    }

    /// Every point in a query box is visited exactly once, and none whose
    /// cell lies outside the box's cells.
    #[test]
    fn box_queries_visit_each_point_inside_once() {
        let mut points = Vec::new();
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        for _ in 0..2000 {
            points.push(Vector::new(rnd() * 2.0 - 1.0, rnd(), rnd() * 0.5));
        }
        let mut hash = SpatialHash::default();
        hash.build(&points, 0.07);
        for (min, max) in [
            (Vector::new(-0.2, 0.1, 0.0), Vector::new(0.1, 0.4, 0.2)),
            (Vector::splat(-5.0), Vector::splat(5.0)),
            (Vector::new(0.3, 0.3, 0.3), Vector::new(0.31, 0.31, 0.31)),
        ] {
            let mut seen = vec![0u32; points.len()];
            hash.for_each_in(min, max, |i| seen[i as usize] += 1);
            for (i, p) in points.iter().enumerate() {
                let inside = p.cmpge(min).all() && p.cmple(max).all();
                assert!(seen[i] <= 1, "point {i} visited {} times", seen[i]);
                if inside {
                    assert_eq!(
                        seen[i], 1,
                        "point {i} at {p:?} inside {min:?}..{max:?} missed"
                    );
                }
                if seen[i] == 1 {
                    let near = p.cmpge(min - Vector::splat(0.07)).all()
                        && p.cmple(max + Vector::splat(0.07)).all();
                    assert!(near, "point {i} at {p:?} is a cell away from the box");
                }
            }
        }
    }

    /// The box query hands out exactly the points inside the box, each once
    /// with its position, on both of its paths (few cells, and a box over
    /// more than `MAX_QUERY_CELLS`); a point that is not a number is in none.
    #[test]
    fn box_queries_hand_out_the_points_inside_once() {
        let mut points: Vec<Vector> = (0..1500)
            .map(|i| {
                let f =
                    |k: u32| ((i as u32).wrapping_mul(2_654_435_761).rotate_left(k) % 1000) as f32;
                Vector::new(f(0) * 1e-3, f(9) * 5e-4, f(17) * 2e-3 - 1.0)
            })
            .collect();
        points[7] = Vector::new(f32::NAN, 0.2, 0.0);
        let mut hash = SpatialHash::default();
        hash.build(&points, 0.05);
        // Both scans: AVX2's (where the CPU has it) and the portable one.
        let portable = SpatialHash {
            simd: false,
            ..hash.clone()
        };
        for (hash, (min, max)) in [&hash, &portable].into_iter().flat_map(|h| {
            [
                (Vector::new(0.2, 0.1, -0.5), Vector::new(0.4, 0.3, 0.1)),
                (Vector::splat(-10.0), Vector::splat(10.0)),
                (Vector::new(0.9, 0.9, 0.9), Vector::new(0.8, 1.0, 1.0)),
            ]
            .map(|b| (h, b))
        }) {
            let mut seen = vec![0u32; points.len()];
            hash.for_each_inside(min, max, |i, p| {
                assert_eq!(
                    p.to_array().map(f32::to_bits),
                    points[i as usize].to_array().map(f32::to_bits)
                );
                seen[i as usize] += 1;
            });
            let mut inside = 0;
            for (i, p) in points.iter().enumerate() {
                let want = p.cmpge(min).all() && p.cmple(max).all();
                inside += u32::from(want);
                assert_eq!(
                    seen[i],
                    u32::from(want),
                    "point {i} at {p:?}, box {min:?}..{max:?}"
                );
            }
            // The boxes hold some points but the empty one.
            assert_eq!(inside == 0, min.x > max.x, "{min:?}..{max:?}");
        }
    }
}
