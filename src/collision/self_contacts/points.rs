//! A particle array as the parts of a pass share it.

use crate::math::Vector;
use crate::parallel::Disjoint;

/// A particle array as the parts of a pass share it
/// ([`SelfContacts::resolve`](super::SelfContacts::resolve)): each part reads
/// and writes only particles no other part running at the same time touches.
pub(super) struct Points<'a> {
    pub(super) ptr: *mut Vector,
    pub(super) len: usize,
    pub(super) _array: std::marker::PhantomData<&'a mut [Vector]>,
}

impl<'a> Points<'a> {
    /// The array `of`, for one part.
    ///
    /// # Safety
    /// While this lives, no other user of the array touches a particle
    /// this one does.
    pub(super) unsafe fn new(of: Disjoint<'a, Vector>) -> Points<'a> {
        Points {
            ptr: of.as_ptr(),
            len: of.len(),
            _array: std::marker::PhantomData,
        }
    }
}

impl std::ops::Index<usize> for Points<'_> {
    type Output = Vector;
    #[inline(always)]
    fn index(&self, i: usize) -> &Vector {
        assert!(i < self.len);
        // SAFETY: in bounds; no other part touches particle `i` (`new`).
        unsafe { &*self.ptr.add(i) }
    }
}

impl std::ops::IndexMut<usize> for Points<'_> {
    #[inline(always)]
    fn index_mut(&mut self, i: usize) -> &mut Vector {
        assert!(i < self.len);
        // SAFETY: as for `index`.
        unsafe { &mut *self.ptr.add(i) }
    }
}
