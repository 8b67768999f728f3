//! The stretch springs at each particle, for the stretch hold
//! (`stretch_hold.rs`): after a hold moves a particle, the springs it must
//! look at again are those at that particle.

use crate::cloth::{SpringKind, Springs};

/// The stretch springs at each particle, counted in spring order among the
/// stretch springs (a particle's in `springs[start[i]..start[i + 1]]`, in
/// ascending order).
#[derive(Debug, Default)]
pub(super) struct StretchIncidence {
    start: Vec<u32>,
    springs: Vec<u32>,
    /// Scratch of the filling.
    fill: Vec<u32>,
    /// Made this step (for its springs and watch).
    pub built: bool,
}

impl StretchIncidence {
    /// Lists the stretch `springs` at each of `n` particles, and marks the
    /// index built.
    pub fn build(&mut self, springs: &Springs, n: usize) {
        let stretch = springs.range(SpringKind::Stretch);
        self.built = true;
        self.start.clear();
        self.start.resize(n + 1, 0);
        for s in stretch.clone() {
            for e in [springs.a[s], springs.b[s]] {
                self.start[e as usize + 1] += 1;
            }
        }
        for i in 0..n {
            self.start[i + 1] += self.start[i];
        }
        self.springs.clear();
        self.springs.resize(2 * stretch.len(), 0);
        // Filled in spring order: each particle's list ascends.
        let mut next = std::mem::take(&mut self.fill);
        next.clear();
        next.extend_from_slice(&self.start[..n]);
        for (k, s) in stretch.enumerate() {
            for e in [springs.a[s] as usize, springs.b[s] as usize] {
                self.springs[next[e] as usize] = k as u32;
                next[e] += 1;
            }
        }
        self.fill = next;
    }

    /// The stretch springs at particle `i`, counted among the stretch
    /// springs, ascending.
    #[inline]
    pub fn at(&self, i: usize) -> &[u32] {
        &self.springs[self.start[i] as usize..self.start[i + 1] as usize]
    }
}
