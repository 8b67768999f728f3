//! The copies of a grid's lanes into a transposed scratch and back, for the
//! chain solves along rows (`grid_chains.rs`), where a row's chain must be
//! a lane of the scratch. Pure data movement: blocks of 8 × 8 transposed in
//! AVX2 registers where the CPU has it, element by element elsewhere and
//! at the edges, the same values either way. Element by element, the
//! copies were 7% of the drape's frame at N = 128 (perf, one thread).

/// Rows a thread takes at a time, both ways: a multiple of [`BLOCK`], and
/// the chains a thread takes at a time along rows (`grid_chains::CHUNK`),
/// so that a row is copied in, solved and copied back on one thread.
pub(super) const CHUNK: usize = 32;

/// Side of the blocks transposed in registers (AVX2's 8 `f32`).
const BLOCK: usize = 8;

/// The floats a scratch of a grid of `shape` (columns, rows) takes: its
/// rows padded to whole chunks ([`scratch_at`]).
pub(super) fn scratch_len((cols, rows): (usize, usize)) -> usize {
    rows.div_ceil(CHUNK) * CHUNK * cols
}

/// Where the scratch holds column `c` of row `r` of a grid of `cols`
/// columns: by chunks of [`CHUNK`] rows, each chunk column by column
/// (`CHUNK` floats of a column side by side). A chunk's rows are one
/// thread's, in one stretch of memory: with the whole scratch column by
/// column (`c · rows + r`), each thread's rows were a quarter of every
/// 512 bytes at N = 128, and the CPU's prefetchers, fetching the lines
/// next to those a core touched, took the other core's lines away from
/// it (two threads writing alternate 256 bytes of an array took four
/// times as long as one writing all of it; measured).
#[inline(always)]
pub(super) fn scratch_at(c: usize, r: usize, cols: usize) -> usize {
    (r / CHUNK) * CHUNK * cols + c * CHUNK + r % CHUNK
}

/// An array copied into another, as raw pointers to their first elements
/// (the copies of different chunks of rows run at once on different
/// threads, each in its own part of both).
pub(super) type Pair = (*const f32, *mut f32);

/// Which way a transpose copies: lanes into the scratch, or back.
#[derive(Clone, Copy)]
pub(super) enum Way {
    In,
    Out,
}

/// Checks, once a transpose, what its unchecked copies rely on: `lens`,
/// the lengths of each pair's arrays (from, to), hold the whole grid as
/// lanes and as scratch ([`scratch_len`]), and each lane of a row has its
/// column.
pub(super) fn assert_within(
    lens: &[(usize, usize)],
    column: &[u32],
    (cols, rows): (usize, usize),
    way: Way,
) {
    let (n, padded) = (cols * rows, scratch_len((cols, rows)));
    let (from, to) = match way {
        Way::In => (n, padded),
        Way::Out => (padded, n),
    };
    assert!(lens.iter().all(|&(a, b)| a >= from && b >= to) && column.len() == cols);
    assert!(column.iter().all(|&c| (c as usize) < cols));
}

/// Copies the rows `part` (a chunk of [`CHUNK`], the last maybe shorter)
/// of each pair's lanes (row-major, `shape` = (columns, rows), lanes of a
/// row in the plan's order) into its scratch (lane `p` of row `r` to
/// [`scratch_at`]`(column[p], r)`) going in, or back coming out; in
/// registers when `simd` (only where the CPU has AVX2).
///
/// # Safety
/// The pairs passed [`assert_within`] for `way`; `part` is within the
/// grid; no other thread uses these rows of the arrays written, nor
/// writes those of the arrays read, meanwhile.
pub(super) unsafe fn copy_rows(
    pairs: &[Pair],
    column: &[u32],
    shape: (usize, usize),
    part: std::ops::Range<usize>,
    (way, simd): (Way, bool),
) {
    for &(from, to) in pairs {
        let copy = Copy {
            from,
            to,
            column,
            shape,
        };
        // SAFETY: the caller's promise.
        unsafe { copy_chunk(&copy, part.clone(), way, simd) };
    }
}

/// One chunk of one array's transpose, in AVX2 registers when `simd`.
///
/// # Safety
/// As for [`in_chunk`]; `simd` only where the CPU has AVX2.
unsafe fn copy_chunk(copy: &Copy, part: std::ops::Range<usize>, way: Way, simd: bool) {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: the caller's promise.
        unsafe {
            match way {
                Way::In => in_chunk_avx2(copy, part),
                Way::Out => out_chunk_avx2(copy, part),
            }
        };
        return;
    }
    let _ = simd;
    // SAFETY: the caller's promise.
    unsafe {
        match way {
            Way::In => in_chunk(copy, part, false),
            Way::Out => out_chunk(copy, part, false),
        }
    }
}

/// One array's copy: from, to, the column of each lane of a row, and the
/// grid's (columns, rows).
struct Copy<'a> {
    from: *const f32,
    to: *mut f32,
    column: &'a [u32],
    shape: (usize, usize),
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn in_chunk_avx2(copy: &Copy, rows: std::ops::Range<usize>) {
    // SAFETY: the caller's promise.
    unsafe { in_chunk(copy, rows, true) };
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn out_chunk_avx2(copy: &Copy, rows: std::ops::Range<usize>) {
    // SAFETY: the caller's promise.
    unsafe { out_chunk(copy, rows, true) };
}

/// Rows `rows` of the lanes into the scratch: blocks of 8 lanes and 8
/// rows in registers when `simd`, the rest element by element (the mirror
/// of [`out_chunk`]).
///
/// # Safety
/// Every element read and written is within the arrays (the caller
/// asserted the shape), and this chunk's alone; `simd` only within an
/// AVX2 function.
#[inline(always)]
unsafe fn in_chunk(c: &Copy, rows: std::ops::Range<usize>, simd: bool) {
    let cols = c.shape.0;
    let col = |p: usize| c.column[p] as usize;
    let at = |p: usize, r: usize| scratch_at(col(p), r, cols);
    #[cfg_attr(not(target_arch = "x86_64"), allow(unused_mut))]
    let mut p0 = 0;
    #[cfg(target_arch = "x86_64")]
    while simd && p0 + BLOCK <= cols {
        let mut r0 = rows.start;
        while r0 + BLOCK <= rows.end {
            // SAFETY: rows `r0..r0 + 8` of lanes `p0..p0 + 8`, to the
            // scratch rows of their columns at `r0..r0 + 8`: in bounds.
            unsafe {
                block(
                    std::array::from_fn(|i| c.from.add((r0 + i) * cols + p0)),
                    std::array::from_fn(|j| c.to.add(at(p0 + j, r0))),
                )
            };
            r0 += BLOCK;
        }
        for p in p0..p0 + BLOCK {
            for r in r0..rows.end {
                // SAFETY: in bounds, as above.
                unsafe { *c.to.add(at(p, r)) = *c.from.add(r * cols + p) };
            }
        }
        p0 += BLOCK;
    }
    let _ = simd;
    for p in p0..cols {
        for r in rows.clone() {
            // SAFETY: in bounds, as above.
            unsafe { *c.to.add(at(p, r)) = *c.from.add(r * cols + p) };
        }
    }
}

/// Rows `rows` of the scratch back into the lanes: blocks of 8 lanes and
/// 8 rows in registers when `simd`, the rest element by element.
///
/// # Safety
/// As for [`in_chunk`].
#[inline(always)]
unsafe fn out_chunk(c: &Copy, rows: std::ops::Range<usize>, simd: bool) {
    let cols = c.shape.0;
    let col = |p: usize| c.column[p] as usize;
    let at = |p: usize, r: usize| scratch_at(col(p), r, cols);
    #[cfg_attr(not(target_arch = "x86_64"), allow(unused_mut))]
    let mut p0 = 0;
    #[cfg(target_arch = "x86_64")]
    while simd && p0 + BLOCK <= cols {
        let mut r0 = rows.start;
        while r0 + BLOCK <= rows.end {
            // SAFETY: the scratch rows of lanes `p0..p0 + 8` at `r0..r0 +
            // 8`, to rows `r0..r0 + 8` of those lanes: in bounds.
            unsafe {
                block(
                    std::array::from_fn(|j| c.from.add(at(p0 + j, r0))),
                    std::array::from_fn(|i| c.to.add((r0 + i) * cols + p0)),
                )
            };
            r0 += BLOCK;
        }
        for r in r0..rows.end {
            for p in p0..p0 + BLOCK {
                // SAFETY: in bounds, as above.
                unsafe { *c.to.add(r * cols + p) = *c.from.add(at(p, r)) };
            }
        }
        p0 += BLOCK;
    }
    let _ = simd;
    for p in p0..cols {
        for r in rows.clone() {
            // SAFETY: in bounds, as above.
            unsafe { *c.to.add(r * cols + p) = *c.from.add(at(p, r)) };
        }
    }
}

/// Transposes an 8 × 8 block: element `j` of the 8 floats at `from[i]`
/// goes to element `i` of the 8 floats at `to[j]`. Unpacks, shuffles and
/// lane swaps, 24 in all, in registers.
///
/// # Safety
/// Each pointer has 8 floats to read or write; within an AVX2 function.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn block(from: [*const f32; 8], to: [*mut f32; 8]) {
    use std::arch::x86_64::*;
    // SAFETY: the caller's promise (unaligned loads and stores).
    unsafe {
        let r = [
            _mm256_loadu_ps(from[0]),
            _mm256_loadu_ps(from[1]),
            _mm256_loadu_ps(from[2]),
            _mm256_loadu_ps(from[3]),
            _mm256_loadu_ps(from[4]),
            _mm256_loadu_ps(from[5]),
            _mm256_loadu_ps(from[6]),
            _mm256_loadu_ps(from[7]),
        ];
        // Pairs of rows interleaved: t0 = r0₀ r1₀ r0₁ r1₁ | r0₄ r1₄ r0₅ r1₅, …
        let t0 = _mm256_unpacklo_ps(r[0], r[1]);
        let t1 = _mm256_unpackhi_ps(r[0], r[1]);
        let t2 = _mm256_unpacklo_ps(r[2], r[3]);
        let t3 = _mm256_unpackhi_ps(r[2], r[3]);
        let t4 = _mm256_unpacklo_ps(r[4], r[5]);
        let t5 = _mm256_unpackhi_ps(r[4], r[5]);
        let t6 = _mm256_unpacklo_ps(r[6], r[7]);
        let t7 = _mm256_unpackhi_ps(r[6], r[7]);
        // Quads: s0 = r0₀ r1₀ r2₀ r3₀ | r0₄ r1₄ r2₄ r3₄, …
        let s0 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let s1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
        let s2 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let s3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
        let s4 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let s5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
        let s6 = _mm256_shuffle_ps::<0x44>(t5, t7);
        let s7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
        // Halves joined: column j of the block.
        _mm256_storeu_ps(to[0], _mm256_permute2f128_ps::<0x20>(s0, s4));
        _mm256_storeu_ps(to[1], _mm256_permute2f128_ps::<0x20>(s1, s5));
        _mm256_storeu_ps(to[2], _mm256_permute2f128_ps::<0x20>(s2, s6));
        _mm256_storeu_ps(to[3], _mm256_permute2f128_ps::<0x20>(s3, s7));
        _mm256_storeu_ps(to[4], _mm256_permute2f128_ps::<0x31>(s0, s4));
        _mm256_storeu_ps(to[5], _mm256_permute2f128_ps::<0x31>(s1, s5));
        _mm256_storeu_ps(to[6], _mm256_permute2f128_ps::<0x31>(s2, s6));
        _mm256_storeu_ps(to[7], _mm256_permute2f128_ps::<0x31>(s3, s7));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::simd_available;

    /// A grid's arrays transposed in and out, with `simd` or not, on
    /// `threads`, a chunk of rows an item: (the scratch, the lanes back).
    fn round_trip(
        (cols, rows): (usize, usize),
        column: &[u32],
        simd: bool,
        threads: usize,
    ) -> (Vec<f32>, Vec<f32>) {
        let n = cols * rows;
        let shape = (cols, rows);
        let lanes: Vec<f32> = (0..n).map(|i| i as f32 * 0.5 - 7.0).collect();
        // Finite (the padding compares equal), and no lane's value.
        let mut scratch = vec![f32::MAX; scratch_len(shape)];
        let mut back = vec![f32::NAN; n];
        let (into, out) = (
            [(lanes.as_ptr(), scratch.as_mut_ptr())],
            [(scratch.as_ptr(), back.as_mut_ptr())],
        );
        assert_within(&[(n, scratch.len())], column, shape, Way::In);
        assert_within(&[(scratch.len(), n)], column, shape, Way::Out);
        // Raw pointers, shared by the items (each copies its own rows).
        struct Shared([Pair; 1], [Pair; 1]);
        // SAFETY: the items use disjoint rows.
        unsafe impl Sync for Shared {}
        let shared = &Shared(into, out);
        crate::parallel::on_threads(threads, |team| {
            for way in [Way::In, Way::Out] {
                team.sum_count(rows.div_ceil(CHUNK), |q| {
                    let part = q * CHUNK..((q + 1) * CHUNK).min(rows);
                    let pairs = match way {
                        Way::In => &shared.0,
                        Way::Out => &shared.1,
                    };
                    // SAFETY: checked above; each item its own rows.
                    unsafe { copy_rows(pairs, column, shape, part, (way, simd)) };
                    0
                });
            }
        });
        assert_eq!(back, lanes, "the round trip gives the lanes back");
        (scratch, back)
    }

    #[test]
    fn the_blocks_in_registers_copy_what_the_elements_do() {
        // Columns and rows that leave tails past the blocks and past the
        // chunks, columns permuted as a plan's blocks store them.
        for (cols, rows) in [(43, 70), (64, 16), (5, 9), (8, 8), (37, 41)] {
            let blocks = 4;
            let column: Vec<u32> = {
                let mut c: Vec<u32> = (0..cols as u32).collect();
                c.sort_by_key(|&c| (c % blocks, c / blocks));
                c
            };
            let (scratch, _) = round_trip((cols, rows), &column, false, 1);
            for (p, &c) in column.iter().enumerate() {
                for r in 0..rows {
                    let lane = (r * cols + p) as f32 * 0.5 - 7.0;
                    let at = scratch_at(c as usize, r, cols);
                    assert_eq!(scratch[at], lane, "lane {p} row {r}");
                }
            }
            for threads in [1, 2] {
                let simd = round_trip((cols, rows), &column, simd_available(), threads);
                assert_eq!(simd.0, scratch, "{cols} × {rows} on {threads} threads");
            }
        }
    }
}
