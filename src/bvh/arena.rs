//! A pre-sized arena that parallel builder tasks fill: each task claims slots with one atomic
//! add and writes them, the finished arena becomes a `Vec`. The builder allocates nodes from
//! one, the geometry its leaf blocks from others. Its capacity must bound what is ever claimed
//! (it is only reserved address space until written: pages that are never touched cost no
//! memory). Every claimed slot must be written before [`Arena::into_vec`]; builds with debug
//! assertions (the tests) count the writes and check it.

use std::cell::UnsafeCell;
use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Slots of `T`, claimed and written by any thread, each exactly once.
pub struct Arena<T: Copy> {
    slots: Box<[UnsafeCell<MaybeUninit<T>>]>,
    next: AtomicUsize,
    #[cfg(debug_assertions)]
    written: AtomicUsize,
}

// SAFETY: a slot is written only by the task that claimed it (`alloc` hands out every index
// once) and read only in `into_vec`, which owns the arena.
unsafe impl<T: Copy + Send> Sync for Arena<T> {}

impl<T: Copy> Arena<T> {
    /// An arena of `capacity` slots.
    pub fn with_capacity(capacity: usize) -> Arena<T> {
        let mut v = Vec::with_capacity(capacity);
        // SAFETY: UnsafeCell<MaybeUninit<T>> needs no initialisation.
        unsafe { v.set_len(capacity) };
        Arena {
            slots: v.into_boxed_slice(),
            next: AtomicUsize::new(0),
            #[cfg(debug_assertions)]
            written: AtomicUsize::new(0),
        }
    }

    /// Claims `n` consecutive slots; returns the first. Panics past the capacity.
    #[inline]
    pub fn alloc(&self, n: usize) -> usize {
        let first = self.next.fetch_add(n, Ordering::Relaxed);
        assert!(
            first + n <= self.slots.len(),
            "arena of {} slots overflows",
            self.slots.len()
        );
        first
    }

    /// Writes slot `i`, which the caller claimed with [`Arena::alloc`] and writes once.
    #[inline]
    pub fn set(&self, i: usize, value: T) {
        let slot = &self.slots[i];
        // SAFETY: `i` was claimed by this caller alone (see `alloc`), so nobody else touches it.
        unsafe { (*slot.get()).write(value) };
        #[cfg(debug_assertions)]
        self.written.fetch_add(1, Ordering::Relaxed);
    }

    /// The claimed slots as a vector, in slot order, keeping the arena's (untouched) capacity
    /// (with debug assertions: panics if a claimed slot was never written).
    pub fn into_vec(self) -> Vec<T> {
        let len = self.next.load(Ordering::Relaxed);
        #[cfg(debug_assertions)]
        assert_eq!(
            self.written.load(Ordering::Relaxed),
            len,
            "arena slots claimed but not written"
        );
        let mut slots = std::mem::ManuallyDrop::new(self.slots);
        let cap = slots.len();
        let ptr = slots.as_mut_ptr().cast::<T>();
        // SAFETY: the boxed slice's allocation holds `cap` slots of UnsafeCell<MaybeUninit<T>>,
        // which have T's layout; the first `len` are written (checked above, each index is
        // claimed once) and the rest are uninitialised memory a Vec may own as spare capacity.
        // No shrink_to_fit: the spare capacity was never touched, so it holds no memory, and
        // shrinking an over-aligned vector (nodes: 64 bytes) copies it (10 ms for torus1m).
        unsafe { Vec::from_raw_parts(ptr, len, cap) }
    }
}

#[cfg(test)]
mod tests {
    use super::Arena;
    use rayon::prelude::*;

    #[test]
    fn parallel_claims_fill_every_slot_once() {
        let a: Arena<u64> = Arena::with_capacity(10_000);
        (0..1000u64).into_par_iter().for_each(|k| {
            let first = a.alloc(3);
            for j in 0..3 {
                a.set(first + j, k * 3 + j as u64);
            }
        });
        let mut v = a.into_vec();
        assert_eq!(v.len(), 3000);
        v.sort_unstable();
        assert!(v.iter().enumerate().all(|(i, &x)| x == i as u64));
    }

    #[test]
    #[cfg(debug_assertions)]
    #[should_panic]
    fn claimed_but_unwritten_slots_are_refused() {
        let a: Arena<u32> = Arena::with_capacity(4);
        a.alloc(2);
        a.set(0, 7);
        a.into_vec();
    }

    #[test]
    #[should_panic]
    fn overflow_is_refused() {
        let a: Arena<u8> = Arena::with_capacity(4);
        a.alloc(5);
    }
}
