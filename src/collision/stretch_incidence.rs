//! The stretch springs at each particle, for the stretch hold
//! (`stretch_hold.rs`): after a hold moves a particle, the springs it must
//! look at again are those at that particle; and for the stretch limit's
//! weights near pins (`solver/pin_support.rs`), found by walking them.

use crate::cloth::{SpringKind, Springs};

/// The stretch springs at each particle, counted in spring order among the
/// stretch springs (a particle's in `springs[start[i]..start[i + 1]]`, in
/// ascending order).
#[derive(Debug, Default, Clone)]
pub(crate) struct StretchIncidence {
    start: Vec<u32>,
    springs: Vec<u32>,
    /// Scratch of the filling.
    fill: Vec<u32>,
    /// Made this step (for its springs and watch).
    pub built: bool,
    /// The springs the lists were made for: where they are, how many, the
    /// first and last rest lengths' bits, a checksum of the stretch
    /// springs' ends, and the particles (the lists are made again only
    /// when one changes: making them was 1.3% of the drape's frame at N =
    /// 64, and springs change only when a cloth tears).
    made_for: Option<(usize, usize, [u32; 2], u32, usize)>,
}

impl StretchIncidence {
    /// Lists the stretch `springs` at each of `n` particles, and marks the
    /// index built.
    pub fn build(&mut self, springs: &Springs, n: usize) {
        let stretch = springs.range(SpringKind::Stretch);
        self.built = true;
        let rest = springs.rest_lengths();
        let bits = |r: Option<&f32>| r.map_or(0, |r| r.to_bits());
        let (a, b) = springs.endpoints();
        let ends = a[stretch.clone()]
            .iter()
            .zip(&b[stretch.clone()])
            .enumerate()
            // A sum of mixed terms, not a chain: it runs as vectors.
            .map(|(k, (&a, &b))| (a.rotate_left(16) ^ b ^ k as u32).wrapping_mul(0x9E37_79B1))
            .fold(0u32, u32::wrapping_add);
        let key = (
            springs as *const Springs as usize,
            springs.len(),
            [bits(rest.first()), bits(rest.last())],
            ends,
            n,
        );
        if self.made_for == Some(key) {
            return;
        }
        self.made_for = Some(key);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloth::ClothBuilder;

    /// Each particle's list, by brute force: the stretch springs with an
    /// end there, counted among the stretch springs.
    fn expected(springs: &Springs, n: usize) -> Vec<Vec<u32>> {
        let (a, b) = springs.endpoints();
        let mut at = vec![Vec::new(); n];
        for (k, s) in springs.range(SpringKind::Stretch).enumerate() {
            at[a[s] as usize].push(k as u32);
            at[b[s] as usize].push(k as u32);
        }
        at
    }

    fn lists(index: &StretchIncidence, n: usize) -> Vec<Vec<u32>> {
        (0..n).map(|i| index.at(i).to_vec()).collect()
    }

    #[test]
    fn the_lists_follow_the_springs_they_are_made_for() {
        let small = ClothBuilder::new(4, 3).build().unwrap();
        let large = ClothBuilder::new(5, 4).build().unwrap();
        let mut index = StretchIncidence::default();
        for cloth in [&small, &small, &large, &small] {
            let n = cloth.particle_count();
            index.build(cloth.springs(), n);
            assert_eq!(lists(&index, n), expected(cloth.springs(), n));
        }
    }
}
