//! Breadth-first ray lists (Barringer and Akenine-Möller 2014, dynamic ray stream traversal):
//! many incoherent rays go down the 8-wide BVH together as a list of ray ids. A node tests each
//! ray of its list against its 8 children (one 8-lane pass per ray, [`ListRay::test`]) and
//! splits the list into one list per child the rays enter; a leaf hands its list to the caller's
//! leaf test, which lowers the rays' `tmax`. A node or leaf is then fetched once for all the rays
//! that reach it together, where single-ray walks fetch it once per ray, and the rays' tests at
//! a node do not wait on one another, where a walk's steps each wait on the one before.
//!
//! A node's children are visited nearest first by the smallest entry distance among the rays
//! that enter each (the rays of a list point every way, so no order is nearest first for all
//! of them; this one puts first the child around the rays' origins, where many of them hit).
//! The closest hit does not depend on the order (ties go to the smaller geometry index).
//! `geometry::query` decides which rays take this path.
//!
//! ```text
//! rays prepared (ListRay, one cache line each), ray id = index, tmax per id
//!   --> root: every id --> node: one list per entered child --> ... --> leaf(leaf, ids, tmax)
//! ```

use super::{Bvh8, Leaf, ListRay, NodeRef, WIDTH};
use crate::simd::{F32x8, LANES, bitmask, compact_lanes, min, select};

/// Buffers of [`Bvh8::closest_lists`], kept by the caller from one call to the next so that a
/// call allocates nothing once they have grown.
#[derive(Debug, Default)]
pub struct ListScratch {
    /// The lists, one after another: a node's list, then the lists it hands down. Only
    /// `..top` of it is in use; it never shrinks, so growing it zeroes memory only once.
    ids: Vec<u32>,
    /// Lists waiting for their node: the node, where its list starts in `ids`, how long it is.
    waiting: Vec<(NodeRef, u32, u32)>,
    /// The children each ray of the list being split enters (bit `i` = child `i`), zeros after
    /// the list up to a multiple of 8.
    masks: Vec<u8>,
}

impl Bvh8 {
    /// The closest hits of forward rays (`tmin >= 0`), traced together by breadth-first lists:
    /// ray `id` is `rays[id]` (made by [`super::Ray1x8::list_rays`]); `ids` names the rays to
    /// trace, and `tmax[id]` bounds each one's hit. `leaf(leaf, ids, tmax)` tests a leaf's
    /// primitives for the rays it lists and lowers their `tmax` where it finds nearer hits;
    /// every ray reaches every leaf it may hit nearer than its `tmax`.
    /// `touch(leaf)` starts fetching a leaf handed a list (the lists handed down are visited
    /// after their siblings' subtrees, so every entered child is fetched while those run).
    ///
    /// # Panics
    ///
    /// If an id names a ray outside `rays` or `tmax`.
    pub fn closest_lists(
        &self,
        rays: &[ListRay],
        ids: &[u32],
        tmax: &mut [f32],
        s: &mut ListScratch,
        mut leaf: impl FnMut(Leaf, &[u32], &mut [f32]),
        touch: impl Fn(Leaf),
    ) {
        if self.root.is_empty() || ids.is_empty() {
            return;
        }
        s.grow(ids.len() + LANES);
        s.ids[..ids.len()].copy_from_slice(ids);
        s.waiting.clear();
        s.waiting.push((self.root, 0, ids.len() as u32));
        while let Some((r, start, len)) = s.waiting.pop() {
            let list = start as usize..(start + len) as usize;
            if r.is_leaf() {
                leaf(r.as_leaf(), &s.ids[list], tmax);
                continue;
            }
            // the lists after this one were handed down by nodes already done with
            let top = list.end;
            // SAFETY: `r` is the root or a child reference read from this tree's nodes
            let n = unsafe { self.node_at(r) };
            // each ray's children, against `tmin` 0, not its own (one array less to read: a
            // child entered between 0 and `tmin` is visited for nothing, and no hit changes),
            // and each child's nearest entry among the rays that enter it
            let inf = F32x8::splat(f32::INFINITY);
            let mut nearest = inf;
            let entered = s.test_list(list.clone(), |id| {
                let id = id as usize;
                let (m, near) = rays[id].test(n, 0.0, tmax[id]);
                nearest = min(nearest, select(m, near, inf));
                bitmask(m)
            });
            let (order, k) = farthest_first(entered, nearest.to_array());
            let mut at = top;
            for &c in &order[..k] {
                let end = s.hand_down(list.clone(), c, at);
                self.prefetch(n.child[c], &touch);
                s.waiting.push((n.child[c], at as u32, (end - at) as u32));
                at = end;
            }
        }
    }
}

/// The children set in `entered` (bit `i` = child `i`) by `key[i]`, largest first (of equal
/// keys the higher slot first), and how many: the order the lists are handed down in, so that
/// the child some ray enters nearest is taken back first, and of equal keys the lower slot, as
/// the packet walk visits them (`packet::sort_farthest_first`).
#[inline(always)]
fn farthest_first(entered: u32, key: [f32; WIDTH]) -> ([usize; WIDTH], usize) {
    let mut order = [0; WIDTH];
    let mut k = 0;
    let mut e = entered;
    while e != 0 {
        let c = e.trailing_zeros() as usize;
        e &= e - 1;
        let mut j = k;
        while j > 0 && key[order[j - 1]] <= key[c] {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = c;
        k += 1;
    }
    (order, k)
}

impl ListScratch {
    /// Makes `ids` at least `len` long.
    fn grow(&mut self, len: usize) {
        if self.ids.len() < len {
            self.ids.resize(len, 0);
        }
    }

    /// Tests each ray of `ids[list]` by `test` (its entered children, bit `i` = child `i`),
    /// keeps the masks for [`ListScratch::hand_down`], and returns every child some ray enters.
    #[inline(always)]
    fn test_list(&mut self, list: std::ops::Range<usize>, mut test: impl FnMut(u32) -> u32) -> u32 {
        let len = list.len();
        self.masks.clear();
        self.masks.resize(len.next_multiple_of(LANES), 0);
        let mut entered = 0;
        for (m, &id) in self.masks.iter_mut().zip(&self.ids[list]) {
            let bits = test(id);
            *m = bits as u8;
            entered |= bits;
        }
        entered
    }

    /// Writes, from `at` on, the ids of `ids[list]` whose mask has bit `child` (in list order),
    /// 8 rays at a time; returns where the new list ends. Each store of 8 may write up to 7
    /// ids past the new list, where the next list (or nothing) goes.
    #[inline(always)]
    fn hand_down(&mut self, list: std::ops::Range<usize>, child: usize, at: usize) -> usize {
        // room for a list as long as this one, the 8-lane stores past its end, and the reads
        // of the last 8 rays past the list's end (their masks are zero)
        self.grow(at + list.len() + LANES);
        let mut end = at;
        for (k, m) in self.masks.chunks_exact(LANES).enumerate() {
            // bit `child` of each of the 8 masks, gathered into one byte (bit j = ray j)
            let x = u64::from_le_bytes(m.try_into().expect("8 masks"));
            let bits = (((x >> child) & 0x0101_0101_0101_0101).wrapping_mul(0x0102_0408_1020_4080)
                >> 56) as u32;
            if bits != 0 {
                let from = list.start + k * LANES;
                let rays: [u32; LANES] = self.ids[from..from + LANES].try_into().expect("8 ids");
                self.ids[end..end + LANES].copy_from_slice(&compact_lanes(rays, bits));
                end += bits.count_ones() as usize;
            }
        }
        end
    }
}

#[cfg(test)]
mod tests {
    use super::{WIDTH, farthest_first};

    /// Every set of entered children, with keys of few values (so many ties): the entered
    /// slots, each once, keys never rising, and of equal keys the higher slot first.
    #[test]
    fn lists_are_handed_down_farthest_first_ties_higher_slot_first() {
        for entered in 0..1u32 << WIDTH {
            for seed in 0..4u32 {
                let key: [f32; WIDTH] = std::array::from_fn(|i| {
                    [0.0, 1.5, f32::INFINITY][(i as u32 * 7 + seed * 3) as usize % 3]
                });
                let (order, k) = farthest_first(entered, key);
                assert_eq!(k, entered.count_ones() as usize);
                let mut seen = 0u32;
                for &c in &order[..k] {
                    assert_eq!(entered >> c & 1, 1);
                    seen |= 1 << c;
                }
                assert_eq!(seen, entered);
                for w in order[..k].windows(2) {
                    let (a, b) = (w[0], w[1]);
                    assert!(
                        key[a] > key[b] || (key[a] == key[b] && a > b),
                        "{order:?} {key:?}"
                    );
                }
            }
        }
    }
}
