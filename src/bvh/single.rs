//! Single-ray traversal of the 8-wide BVH, for incoherent rays: one 8-lane pass tests all of a
//! node's children against the ray (box planes chosen by the ray's octant, so no per-axis
//! min/max), hit children are visited nearest first (closest hit) or in slot order (any hit).

use super::stack::Stack;
use super::{
    Bvh8, Leaf, MAX_DEPTH, Node8, NodeRef, Plane, WIDTH, safe_inverse, slab_octant, widen,
};
use crate::math::Ray;
use crate::simd::{F32x8, bitmask};

/// Entries a single-ray stack may hold: each level pushes at most `WIDTH - 1` children more
/// than it pops.
pub(super) const STACK: usize = (WIDTH - 1) * MAX_DEPTH + 1;

/// One ray prepared for 8-wide box tests: splatted origin and reciprocal direction, and the
/// box planes it enters (`near`) and leaves (`far`) through on each axis.
pub(super) struct Ray1 {
    org: [F32x8; 3],
    inv: [F32x8; 3],
    near: [Plane; 3],
    far: [Plane; 3],
}

impl Ray1 {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Ray1 {
        Ray1::from_parts(ray.origin.to_array(), ray.dir.to_array().map(safe_inverse))
    }

    /// From an origin and the safe reciprocal direction ([`safe_inverse`]).
    #[inline(always)]
    pub(super) fn from_parts(o: [f32; 3], inv: [f32; 3]) -> Ray1 {
        let down = inv.map(|i| i < 0.0);
        Ray1 {
            org: o.map(F32x8::splat),
            inv: inv.map(F32x8::splat),
            near: std::array::from_fn(|a| Plane::entry(a, down[a])),
            far: std::array::from_fn(|a| Plane::exit(a, down[a])),
        }
    }

    /// The children the ray enters within `(tmin, tmax)` (bit `i` = child `i`) and their entry
    /// distances. `(plane - origin) * inv`, not a fused `plane * inv - origin * inv`, keeps the
    /// error relative to the distance itself, which the widening of the exit distance covers.
    #[inline(always)]
    pub(super) fn test(&self, n: &Node8, tmin: F32x8, tmax: F32x8) -> (u32, F32x8) {
        let t = |plane: Plane, axis: usize| {
            (n.bounds[plane as usize] - self.org[axis]) * self.inv[axis]
        };
        let (enter, near) = slab_octant(t, &self.near, &self.far, tmin, tmax);
        (bitmask(enter), near)
    }
}

impl Bvh8 {
    /// The closest hit of one ray: visits every leaf the ray may hit nearer than `tmax`,
    /// nearest child first; `leaf(leaf, tmax)` tests the leaf's primitives and lowers `tmax`
    /// where it finds a nearer hit.
    #[inline(always)]
    pub fn closest(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: &mut f32,
        mut leaf: impl FnMut(Leaf, &mut f32),
    ) {
        if self.root.is_empty() {
            return;
        }
        let r = Ray1::new(ray);
        let tmin8 = F32x8::splat(tmin);
        let mut stack: Stack<(NodeRef, f32), STACK> = Stack::new();
        let mut cur = self.root;
        loop {
            let next = if cur.is_leaf() {
                leaf(cur.as_leaf(), tmax);
                None
            } else {
                let node = &self.nodes[cur.index()];
                self.descend(&r, node, tmin8, *tmax, &mut stack, &|_| {})
            };
            cur = match next {
                Some(c) => c,
                None => match pop_nearer(&mut stack, *tmax) {
                    Some(c) => c,
                    None => return,
                },
            };
        }
    }

    /// One step down from interior node `n` for a closest-hit walk: the nearest child the ray
    /// enters before `tmax`, the other entered children pushed farthest first; `None` when it
    /// enters none. Pushed interior nodes are prefetched here, pushed leaves by `touch`.
    #[inline(always)]
    pub(super) fn descend(
        &self,
        r: &Ray1,
        n: &Node8,
        tmin8: F32x8,
        tmax: f32,
        stack: &mut Stack<(NodeRef, f32), STACK>,
        touch: &impl Fn(Leaf),
    ) -> Option<NodeRef> {
        let (mask, near) = r.test(n, tmin8, F32x8::splat(tmax));
        if mask == 0 {
            return None;
        }
        let c0 = mask.trailing_zeros() as usize;
        let rest = mask & (mask - 1);
        if rest == 0 {
            return Some(n.child[c0]);
        }
        let near = near.to_array();
        let c1 = rest.trailing_zeros() as usize;
        let rest = rest & (rest - 1);
        if rest == 0 {
            // two: the farther waits on the stack
            let (a, b) = ((n.child[c0], near[c0]), (n.child[c1], near[c1]));
            let (first, second) = if a.1 <= b.1 { (a, b) } else { (b, a) };
            self.prefetch(second.0, touch);
            stack.push(second);
            return Some(first.0);
        }
        // three or more: sort them farthest first, push all but the nearest
        let mut hits = [(NodeRef::EMPTY, 0.0f32); WIDTH];
        hits[0] = (n.child[c0], near[c0]);
        hits[1] = (n.child[c1], near[c1]);
        let mut count = 2;
        let mut m = rest;
        while m != 0 {
            let j = m.trailing_zeros() as usize;
            m &= m - 1;
            hits[count] = (n.child[j], near[j]);
            count += 1;
        }
        sort_farthest_first(&mut hits[..count]);
        for h in &hits[..count - 1] {
            self.prefetch(h.0, touch);
            stack.push(*h);
        }
        Some(hits[count - 1].0)
    }

    /// Single-ray any hit: true as soon as `leaf(leaf)` reports a blocker before `tmax`.
    #[inline(always)]
    pub fn occluded(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        mut leaf: impl FnMut(Leaf) -> bool,
    ) -> bool {
        if self.root.is_empty() {
            return false;
        }
        let r = Ray1::new(ray);
        let (tmin8, tmax8) = (F32x8::splat(tmin), F32x8::splat(tmax));
        let mut stack: Stack<NodeRef, STACK> = Stack::new();
        let mut cur = self.root;
        loop {
            if cur.is_leaf() {
                if leaf(cur.as_leaf()) {
                    return true;
                }
            } else {
                let n = &self.nodes[cur.index()];
                let (mut mask, _) = r.test(n, tmin8, tmax8);
                if mask != 0 {
                    let i = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    while mask != 0 {
                        let j = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        stack.push(n.child[j]);
                    }
                    cur = n.child[i];
                    continue;
                }
            }
            match stack.pop() {
                Some(c) => cur = c,
                None => return false,
            }
        }
    }
}

/// Pops entries until one the ray may still enter before `tmax`.
#[inline(always)]
pub(super) fn pop_nearer(stack: &mut Stack<(NodeRef, f32), STACK>, tmax: f32) -> Option<NodeRef> {
    loop {
        match stack.pop() {
            None => return None,
            Some((c, near)) if near <= widen(tmax) => return Some(c),
            Some(_) => {}
        }
    }
}

/// Insertion sort of a few stack entries by entry distance, largest first (ties keep slot
/// order reversed, so the lower slot ends on top).
#[inline(always)]
fn sort_farthest_first(s: &mut [(NodeRef, f32)]) {
    for i in 1..s.len() {
        let x = s[i];
        let mut j = i;
        while j > 0 && s[j - 1].1 <= x.1 {
            s[j] = s[j - 1];
            j -= 1;
        }
        s[j] = x;
    }
}
