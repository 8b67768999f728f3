//! Arrays of one length in one allocation, each starting at its own offset
//! modulo 4 KiB. The grid sweep reads and writes a dozen arrays at the same
//! index; allocated one after another they started 16 bytes apart modulo
//! 4 KiB (measured), where the CPU mistakes a load from one for a load of
//! what was just stored to another (4K aliasing) and waits. Each array here
//! starts [`STAGGER`] floats after the one before, modulo 4 KiB.
//!
//! Every array starts on a cache line. A large allocation starts 16 bytes
//! past a page (the allocator's header), so the lanes a thread's chunk
//! ends on shared a line with the next chunk's, another thread's: the
//! chain solves, whose two threads walk the same rows at once, took three
//! times their one-thread time on two (their samples 1019 → 3136 at
//! N = 128), the line going back and forth between the cores every row.

/// Floats (192 bytes) between the starts of consecutive arrays, modulo 4 KiB:
/// room for 21 arrays before the offsets come round.
const STAGGER: usize = 48;

/// Floats in 4 KiB.
const PAGE: usize = 1024;

/// Floats in a cache line (64 bytes).
const LINE: usize = 16;

/// `count` arrays of `len` floats, array `k` starting at offset
/// `(first + k) · STAGGER` floats modulo 4 KiB from the first cache line
/// of the allocation.
#[derive(Debug, Default)]
pub(crate) struct Staggered {
    buf: Vec<f32>,
    /// Floats from the start of `buf` to its first cache line.
    origin: usize,
    len: usize,
    stride: usize,
    first: usize,
    count: usize,
}

impl Clone for Staggered {
    /// The same arrays, laid out from the clone's own first cache line.
    fn clone(&self) -> Staggered {
        let mut c = Staggered::new(self.count, self.len, self.first);
        for (k, a) in c.all_mut().enumerate() {
            a.copy_from_slice(self.get(k));
        }
        c
    }
}

impl Staggered {
    /// `count` arrays of `len` zeros, the first at stagger slot `first`
    /// (give arrays read together distinct slots).
    pub fn new(count: usize, len: usize, first: usize) -> Staggered {
        let mut s = Staggered {
            first,
            count,
            ..Default::default()
        };
        s.resize(len);
        s
    }

    /// Every array at `len` floats (new ones zero; the contents otherwise
    /// unspecified after a change of length).
    pub fn resize(&mut self, len: usize) {
        if len == self.len && !self.buf.is_empty() {
            return;
        }
        self.len = len;
        self.stride = len.next_multiple_of(PAGE) + STAGGER;
        self.buf.clear();
        let size = self.first * STAGGER + self.count * self.stride;
        // A line more than the arrays need, to start them on one.
        self.buf.resize(size + LINE, 0.0);
        self.origin = self.buf.as_ptr().align_offset(LINE * 4).min(LINE);
    }

    /// Where array `k` starts in `buf`.
    fn start(&self, k: usize) -> usize {
        self.origin + self.first * STAGGER + k * self.stride
    }

    /// Array `k`.
    pub fn get(&self, k: usize) -> &[f32] {
        let at = self.start(k);
        &self.buf[at..at + self.len]
    }

    /// Array `k`, to write.
    pub fn get_mut(&mut self, k: usize) -> &mut [f32] {
        let at = self.start(k);
        &mut self.buf[at..at + self.len]
    }

    /// Every array, to write at once.
    pub fn all_mut(&mut self) -> impl Iterator<Item = &mut [f32]> {
        let len = self.len;
        let at = self.start(0);
        self.buf[at..]
            .chunks_mut(self.stride)
            .take(self.count)
            .map(move |c| &mut c[..len])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_start_apart_modulo_4k_and_do_not_overlap() {
        let mut s = Staggered::new(7, 16384, 2);
        for (k, a) in s.all_mut().enumerate() {
            a.fill(k as f32);
        }
        let mut offsets = Vec::new();
        for k in 0..7 {
            let a = s.get(k);
            assert_eq!(a.len(), 16384);
            assert!(a.iter().all(|&v| v == k as f32), "array {k} overwritten");
            let base = s.buf.as_ptr() as usize + 4 * s.origin;
            offsets.push((a.as_ptr() as usize - base) % 4096);
            assert_eq!(a.as_ptr() as usize % 64, 0, "array {k} off a cache line");
        }
        let copy = s.clone();
        for k in 0..7 {
            assert_eq!(copy.get(k), s.get(k), "array {k} of the copy");
            assert_eq!(copy.get(k).as_ptr() as usize % 64, 0, "copy's array {k}");
        }
        offsets.sort();
        offsets.dedup();
        assert_eq!(offsets.len(), 7, "two arrays at one offset modulo 4 KiB");
    }
}
