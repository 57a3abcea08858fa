//! Closest hits of many incoherent rays at once, one ray at a time through the tree but
//! several walks in flight: each turn advances every walk by one node or one leaf. A single
//! walk is one long chain of dependent loads and compares (node, box test, child, next node);
//! interleaving independent walks lets the processor overlap their chains.

use super::single::{Ray1, Ray1x8, STACK, pop_nearer};
use super::stack::Stack;
use super::{Bvh8, Leaf, NodeRef};
use crate::simd::F32x8;

/// Walks in flight (measured: PERF.md, "Single rays").
pub const IN_FLIGHT: usize = 2;

/// One ray's walk: its prepared ray, limits, current node and stack.
struct Walk {
    ray: Ray1,
    tmin: F32x8,
    tmax: f32,
    cur: NodeRef,
    index: usize,
    stack: Stack<(NodeRef, f32), STACK>,
}

impl Bvh8 {
    /// The closest hits of rays `0..n`, `ray(i)` giving ray `i` as `(packet, lane, tmin, tmax)`:
    /// lane `lane` of `packets[packet]`, a forward ray (`tmin >= 0`), whose walk is
    /// [`Bvh8::closest_lane`]'s, with [`IN_FLIGHT`] walks interleaved. `leaf(i, leaf, tmax)`
    /// tests the leaf's primitives for ray `i` and lowers its `tmax` on hits; `touch(leaf)`
    /// starts fetching a leaf's primitives when a walk pushes it for later (measured: PERF.md,
    /// "Prefetching pushed leaves"). Each ray's walk is exactly its single-ray walk, so the
    /// results are the same.
    pub fn closest_many(
        &self,
        packets: &[Ray1x8],
        n: usize,
        ray: impl Fn(usize) -> (usize, usize, f32, f32),
        mut leaf: impl FnMut(usize, Leaf, &mut f32),
        touch: impl Fn(Leaf),
    ) {
        if self.root.is_empty() || n == 0 {
            return;
        }
        let start = |i: usize| {
            let (p, l, tmin, tmax) = ray(i);
            debug_assert!(tmin >= 0.0);
            Walk {
                ray: packets[p].lane(l),
                tmin: F32x8::splat(tmin),
                tmax,
                cur: self.root,
                index: i,
                stack: Stack::new(),
            }
        };
        // a walk's next ray reuses its storage: a new `Walk` moved in would copy the stack
        let restart = |w: &mut Walk, i: usize| {
            let (p, l, tmin, tmax) = ray(i);
            debug_assert!(tmin >= 0.0);
            w.ray = packets[p].lane(l);
            w.tmin = F32x8::splat(tmin);
            w.tmax = tmax;
            w.cur = self.root;
            w.index = i;
            w.stack.clear();
        };
        let mut next = 0;
        let mut walks: [Option<Walk>; IN_FLIGHT] = std::array::from_fn(|_| {
            (next < n).then(|| {
                next += 1;
                start(next - 1)
            })
        });
        let mut running = walks.iter().filter(|w| w.is_some()).count();
        while running > 0 {
            for slot in walks.iter_mut() {
                let Some(w) = slot else {
                    continue;
                };
                let step = if w.cur.is_leaf() {
                    leaf(w.index, w.cur.as_leaf(), &mut w.tmax);
                    None
                } else {
                    let node = &self.nodes[w.cur.index()];
                    self.descend::<true>(&w.ray, node, w.tmin, w.tmax, &mut w.stack, &touch)
                };
                match step.or_else(|| pop_nearer(&mut w.stack, w.tmax)) {
                    Some(c) => w.cur = c,
                    None if next < n => {
                        restart(w, next);
                        next += 1;
                    }
                    None => {
                        *slot = None;
                        running -= 1;
                    }
                }
            }
        }
    }
}
