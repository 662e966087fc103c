//! A batch's array of up to `N` values, filled from the front: the slots past its length are
//! never written or read. Initialising a whole `[(u8, Scatter); 16]` from a constant took 16
//! `memcpy` calls of 160 bytes per batch, and two such arrays were 2.6 % of a vertex-normal
//! render's samples.

use std::mem::MaybeUninit;

pub(super) struct Slots<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Slots<T, N> {
    pub(super) fn new() -> Self {
        Slots {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// Appends `value` and returns its slot. Panics when all `N` are taken.
    #[inline]
    pub(super) fn push(&mut self, value: T) -> &mut T {
        let slot = self.items[self.len].write(value);
        self.len += 1;
        slot
    }

    #[inline]
    pub(super) fn as_slice(&self) -> &[T] {
        // SAFETY: the first `len` items were written by `push`, and MaybeUninit<T> has T's
        // layout.
        unsafe { std::slice::from_raw_parts(self.items.as_ptr().cast::<T>(), self.len) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pushed_values_read_back_in_order() {
        let mut s = Slots::<(u8, [f32; 3]), 4>::new();
        assert!(s.as_slice().is_empty());
        s.push((1, [1.0; 3]));
        s.push((2, [0.0; 3])).1[2] = 5.0;
        assert_eq!(s.as_slice(), &[(1, [1.0; 3]), (2, [0.0, 0.0, 5.0])]);
    }

    #[test]
    #[should_panic]
    fn a_full_array_takes_no_more() {
        let mut s = Slots::<u8, 1>::new();
        s.push(1);
        s.push(2);
    }
}
