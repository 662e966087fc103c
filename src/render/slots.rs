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

    /// Appends `value`. Panics when all `N` are taken.
    #[inline]
    pub(super) fn push(&mut self, value: T) {
        self.items[self.len].write(value);
        self.len += 1;
    }

    /// Appends the value `init` writes into the slot itself, and returns the slot's reference
    /// (which `MaybeUninit::write` gives): a value built elsewhere and moved in is a `memcpy`
    /// call past 128 bytes. Panics when all `N` are taken, or when `init` returns another
    /// reference than its slot's.
    #[inline]
    pub(super) fn push_with(&mut self, init: impl FnOnce(&mut MaybeUninit<T>) -> &mut T) {
        let slot = &mut self.items[self.len];
        let at = slot.as_ptr();
        let written: *const T = init(slot);
        assert!(std::ptr::eq(written, at), "the slot's own value, written");
        self.len += 1;
    }

    #[inline]
    pub(super) fn as_slice(&self) -> &[T] {
        // SAFETY: the first `len` items were written by `push` or `push_with` (a reference to
        // its slot's T is had only from `MaybeUninit::write`, or by an unsafe promise), and
        // MaybeUninit<T> has T's layout.
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
        s.push((2, [0.0, 0.0, 5.0]));
        assert_eq!(s.as_slice(), &[(1, [1.0; 3]), (2, [0.0, 0.0, 5.0])]);
    }

    #[test]
    fn values_written_in_place_read_back() {
        let mut s = Slots::<[u32; 40], 3>::new();
        s.push_with(|slot| slot.write([7; 40]));
        s.push_with(|slot| {
            let v = slot.write([1; 40]);
            v[39] = 9;
            v
        });
        assert_eq!(s.as_slice().len(), 2);
        assert_eq!(s.as_slice()[0], [7; 40]);
        assert_eq!(s.as_slice()[1][..2], [1, 1]);
        assert_eq!(s.as_slice()[1][39], 9);
    }

    #[test]
    #[should_panic(expected = "the slot's own value")]
    fn another_reference_than_the_slot_is_refused() {
        let mut s = Slots::<u8, 2>::new();
        // (a leaked box stands for any reference that is not the slot's)
        s.push_with(|_| Box::leak(Box::new(3u8)));
    }

    #[test]
    #[should_panic]
    fn a_full_array_takes_no_more() {
        let mut s = Slots::<u8, 1>::new();
        s.push(1);
        s.push(2);
    }
}
