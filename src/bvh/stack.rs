//! The traversal stacks: a fixed-capacity stack living in the traversal's own stack frame,
//! left uninitialised until pushed (a zeroed array of a few kilobytes per ray cost a `memset`
//! per call, more than a short traversal). The only `unsafe` of the traversals, kept here.

use std::mem::MaybeUninit;

/// At most `N` entries of `T`.
pub struct Stack<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    /// An empty stack (no initialisation of its storage).
    #[inline(always)]
    pub fn new() -> Self {
        Stack {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }

    /// Pushes `item`; panics when full (the callers size `N` by the tree's depth bound).
    #[inline(always)]
    pub fn push(&mut self, item: T) {
        self.items[self.len] = MaybeUninit::new(item);
        self.len += 1;
    }

    /// Pops the last item.
    #[inline(always)]
    pub fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every slot below `len` was written by `push` and `T: Copy`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

#[cfg(test)]
mod tests {
    use super::Stack;

    #[test]
    fn push_pop_in_order() {
        let mut s: Stack<(u32, f32), 4> = Stack::new();
        assert!(s.pop().is_none());
        for i in 0..4 {
            s.push((i, i as f32));
        }
        assert_eq!(s.pop(), Some((3, 3.0)));
        assert_eq!(s.pop(), Some((2, 2.0)));
        assert_eq!(s.pop(), Some((1, 1.0)));
        assert_eq!(s.pop(), Some((0, 0.0)));
        assert_eq!(s.pop(), None);
    }

    #[test]
    #[should_panic]
    fn overflow_panics() {
        let mut s: Stack<u8, 2> = Stack::new();
        for i in 0..3 {
            s.push(i);
        }
    }
}
