//! Arrays of one length in one allocation, each starting at its own offset
//! modulo 4 KiB. The grid sweep reads and writes a dozen arrays at the same
//! index; allocated one after another they started 16 bytes apart modulo
//! 4 KiB (measured), where the CPU mistakes a load from one for a load of
//! what was just stored to another (4K aliasing) and waits. Each array here
//! starts [`STAGGER`] floats after the one before, modulo 4 KiB.

/// Floats (192 bytes) between the starts of consecutive arrays, modulo 4 KiB:
/// room for 21 arrays before the offsets come round.
const STAGGER: usize = 48;

/// Floats in 4 KiB.
const PAGE: usize = 1024;

/// `count` arrays of `len` floats, array `k` starting at offset
/// `(first + k) · STAGGER` floats modulo 4 KiB from the allocation.
#[derive(Debug, Clone, Default)]
pub(crate) struct Staggered {
    buf: Vec<f32>,
    len: usize,
    stride: usize,
    first: usize,
    count: usize,
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
        self.buf
            .resize(self.first * STAGGER + self.count * self.stride, 0.0);
    }

    /// Array `k`.
    pub fn get(&self, k: usize) -> &[f32] {
        let at = self.first * STAGGER + k * self.stride;
        &self.buf[at..at + self.len]
    }

    /// Array `k`, to write.
    pub fn get_mut(&mut self, k: usize) -> &mut [f32] {
        let at = self.first * STAGGER + k * self.stride;
        &mut self.buf[at..at + self.len]
    }

    /// Every array, to write at once.
    pub fn all_mut(&mut self) -> impl Iterator<Item = &mut [f32]> {
        let len = self.len;
        self.buf[self.first * STAGGER..]
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
            let base = s.buf.as_ptr() as usize;
            offsets.push((a.as_ptr() as usize - base) % 4096);
        }
        offsets.sort();
        offsets.dedup();
        assert_eq!(offsets.len(), 7, "two arrays at one offset modulo 4 KiB");
    }
}
