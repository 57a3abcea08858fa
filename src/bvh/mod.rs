//! A bounding volume hierarchy over primitive bounds, and its traversals. The tree knows nothing
//! about spheres or triangles: it is built from boxes (and opaque tags that keep kinds apart in
//! leaves), and every traversal takes the leaf test as a closure that receives a range of
//! primitive indices (obvhs-style). Nodes are 32 bytes, depth first: an interior node's left
//! child follows it, its right child is named.
//!
//! Traversals: [`Bvh::closest_packet`] and [`Bvh::occluded_packet`] walk 8 rays at once (per-lane
//! entry distances, culling of subtrees no active lane can reach nearer than its current hit,
//! nearer child first by lane vote, any-hit stops when every lane is occluded);
//! [`Bvh::closest`] and [`Bvh::occluded`] walk a single ray. [`Bvh::closest_packet_probed`]
//! is the closest-hit packet walk reporting each node it visits to a [`TraversalProbe`] (the
//! cost heatmap's counter; the ordinary walk passes [`NoProbe`], which compiles away).

pub mod build;

use std::ops::Range;

use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{
    F32x8, LANES, Mask, Vec3x8, all, any, bitmask, from_lanes, le, lt, max, min, select,
};

/// The deepest a tree gets (the traversal stacks are sized by it).
pub const MAX_DEPTH: usize = 64;

/// Relative widening of the slab test's exit distance, so that rounding never culls a box a
/// ray touches (1 + 2 gamma(3), Pharr et al.).
const ROBUST: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (grows to anything).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Grows the box to hold `p`.
    #[inline]
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The centre.
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the surface area (the SAH only compares areas).
    #[inline]
    pub fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// True if `o` lies inside this box.
    pub fn contains(&self, o: &Aabb) -> bool {
        self.min.cmple(o.min).all() && self.max.cmpge(o.max).all()
    }
}

/// A node: its box and either a primitive range (leaf) or its right child (interior).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct BvhNode {
    pub min: [f32; 3],
    /// Leaf: first primitive; interior: index of the right child (the left one is next).
    pub first: u32,
    pub max: [f32; 3],
    /// Leaf: number of primitives (at least 1); interior: 0.
    pub count: u32,
}

/// Nodes store their box grown by this fraction of its size and of its coordinates' magnitude
/// on each axis, so a ray that only grazes a primitive's bounds (a tangent ray along a face,
/// with a zero direction component) still enters the node. A parent's padding is never smaller
/// than its children's.
const PAD: f32 = 1.0 / (1 << 20) as f32;

fn padded(b: &Aabb) -> Aabb {
    let pad = (b.max - b.min).max(Vec3::ZERO) * PAD + b.min.abs().max(b.max.abs()) * PAD;
    Aabb {
        min: b.min - pad,
        max: b.max + pad,
    }
}

impl BvhNode {
    fn leaf(b: &Aabb, first: u32, count: u32) -> BvhNode {
        let b = padded(b);
        BvhNode {
            min: b.min.to_array(),
            first,
            max: b.max.to_array(),
            count,
        }
    }

    fn interior(b: &Aabb, right: u32) -> BvhNode {
        let b = padded(b);
        BvhNode {
            min: b.min.to_array(),
            first: right,
            max: b.max.to_array(),
            count: 0,
        }
    }

    /// True for a leaf.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The primitive range of a leaf.
    #[inline(always)]
    pub fn prims(&self) -> Range<u32> {
        self.first..self.first + self.count
    }

    /// The node's box.
    pub fn aabb(&self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

/// A BVH: nodes depth first, root at 0. Empty when built over no primitive.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
}

/// Widens a distance by the relative rounding error of the slab test, in the direction that
/// keeps culling conservative (also for the negative distances of orthographic rays).
#[inline(always)]
fn widen(t: f32) -> f32 {
    t + t.abs() * (ROBUST - 1.0)
}

/// [`widen`] for 8 lanes.
#[inline(always)]
fn widen_packet(t: F32x8) -> F32x8 {
    t + t.abs() * F32x8::splat(ROBUST - 1.0)
}

/// Per-ray values the box test reuses: origin and reciprocal direction.
struct RaySlabs {
    origin: Vec3,
    inv: Vec3,
}

impl RaySlabs {
    #[inline(always)]
    fn new(ray: &Ray) -> RaySlabs {
        let safe = |d: f32| {
            1.0 / if d.abs() < 1e-30 {
                1e-30f32.copysign(d)
            } else {
                d
            }
        };
        RaySlabs {
            origin: ray.origin,
            inv: Vec3::new(safe(ray.dir.x), safe(ray.dir.y), safe(ray.dir.z)),
        }
    }

    /// The entry distance if the ray meets the box within `(tmin, tmax)`.
    #[inline(always)]
    fn test(&self, n: &BvhNode, tmin: f32, tmax: f32) -> Option<f32> {
        let lo = (Vec3::from(n.min) - self.origin) * self.inv;
        let hi = (Vec3::from(n.max) - self.origin) * self.inv;
        let near = lo.min(hi).max_element().max(tmin);
        let far = widen(lo.max(hi).min_element().min(tmax));
        (near <= far).then_some(near)
    }
}

/// [`RaySlabs`] for 8 rays: origins and reciprocal directions.
struct PacketSlabs {
    origin: Vec3x8,
    inv: Vec3x8,
}

impl PacketSlabs {
    #[inline(always)]
    fn new(rays: &RayPacket) -> PacketSlabs {
        let safe = |d: F32x8| {
            // A zero direction component would give 0 * inf = NaN in the slab test.
            let tiny = F32x8::splat(1e-30);
            let small = lt(d.abs(), tiny);
            F32x8::splat(1.0) / select(small, select(lt(d, F32x8::splat(0.0)), -tiny, tiny), d)
        };
        PacketSlabs {
            origin: rays.origin,
            inv: Vec3x8 {
                x: safe(rays.dir.x),
                y: safe(rays.dir.y),
                z: safe(rays.dir.z),
            },
        }
    }

    /// Lanes whose ray meets the box within `(tmin, tmax)`, and their entry distances.
    /// `(plane - origin) * inv` (not a fused `plane * inv - origin * inv`) keeps the error
    /// relative to the distance itself, which the widening by `ROBUST` then covers.
    #[inline(always)]
    fn test(&self, n: &BvhNode, tmin: F32x8, tmax: F32x8) -> (Mask, F32x8) {
        let slab = |lo: f32, hi: f32, o: F32x8, inv: F32x8| {
            let a = (F32x8::splat(lo) - o) * inv;
            let b = (F32x8::splat(hi) - o) * inv;
            (min(a, b), max(a, b))
        };
        let (x0, x1) = slab(n.min[0], n.max[0], self.origin.x, self.inv.x);
        let (y0, y1) = slab(n.min[1], n.max[1], self.origin.y, self.inv.y);
        let (z0, z1) = slab(n.min[2], n.max[2], self.origin.z, self.inv.z);
        let near = max(max(x0, y0), max(z0, tmin));
        let far = widen_packet(min(min(x1, y1), min(z1, tmax)));
        (le(near, far), near)
    }
}

thread_local! {
    /// The closest-hit packet traversal's stack (one per thread, reused by every call; the
    /// traversal never runs inside its own leaf test).
    static PACKET_STACK: std::cell::RefCell<Vec<Pending>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// A pending subtree of a packet traversal: the node and its lanes' entry distances.
#[derive(Clone, Copy)]
struct Pending {
    node: u32,
    near: [f32; LANES],
    lanes: [f32; LANES],
}

impl Pending {
    /// An entry from SIMD values (plain arrays keep the stack small and cheap to set up).
    #[inline(always)]
    fn new(node: u32, near: F32x8, lanes: Mask) -> Pending {
        Pending {
            node,
            near: crate::simd::lanes(near),
            lanes: crate::simd::lanes(lanes),
        }
    }
}

/// Told of every node a packet traversal visits, with the lanes that entered it (culled lanes
/// excluded): the hook behind the cost heatmap. Monomorphised, so [`NoProbe`] costs nothing.
pub trait TraversalProbe {
    fn node(&mut self, lanes: Mask);
}

/// The probe of ordinary traversals: does nothing.
pub struct NoProbe;

impl TraversalProbe for NoProbe {
    #[inline(always)]
    fn node(&mut self, _lanes: Mask) {}
}

impl Bvh {
    /// True when the tree has no node.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Single-ray twin of [`Bvh::closest_packet`]: `leaf(range, tmax)` lowers `tmax` on hits.
    pub fn closest(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: &mut f32,
        mut leaf: impl FnMut(Range<u32>, &mut f32),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let slabs = RaySlabs::new(ray);
        let Some(near) = slabs.test(&self.nodes[0], tmin, *tmax) else {
            return;
        };
        let mut stack = [(0u32, 0.0f32); MAX_DEPTH];
        stack[0] = (0, near);
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (mut node, near) = stack[top];
            if near > widen(*tmax) {
                continue;
            }
            loop {
                let n = &self.nodes[node as usize];
                if n.is_leaf() {
                    leaf(n.prims(), tmax);
                    break;
                }
                let (left, right) = (node + 1, n.first);
                let l = slabs.test(&self.nodes[left as usize], tmin, *tmax);
                let r = slabs.test(&self.nodes[right as usize], tmin, *tmax);
                match (l, r) {
                    (None, None) => break,
                    (Some(_), None) => node = left,
                    (None, Some(_)) => node = right,
                    (Some(nl), Some(nr)) => {
                        let (first, second) = if nl <= nr {
                            (left, (right, nr))
                        } else {
                            (right, (left, nl))
                        };
                        stack[top] = second;
                        top += 1;
                        node = first;
                    }
                }
            }
        }
    }

    /// Visits, for the active lanes of `rays`, every leaf one of them may hit nearer than its
    /// `tmax` lane; `leaf(range, rays, tmax)` tests the leaf's primitives for the packet's
    /// active lanes and lowers their `tmax` where it finds nearer hits. Nearer children go
    /// first so `tmax` shrinks early and culls more. The packet stays together to the leaves
    /// however few lanes remain (a switch to single rays measured slower: PERF.md).
    pub fn closest_packet(
        &self,
        rays: &RayPacket,
        tmax: &mut F32x8,
        leaf: impl FnMut(Range<u32>, &RayPacket, &mut F32x8),
    ) {
        self.closest_packet_probed(rays, tmax, leaf, &mut NoProbe);
    }

    /// [`Bvh::closest_packet`] reporting every node it visits to `probe`, with the lanes that
    /// entered it (the cost heatmap counts them); with [`NoProbe`] it is `closest_packet`.
    pub fn closest_packet_probed(
        &self,
        rays: &RayPacket,
        tmax: &mut F32x8,
        mut leaf: impl FnMut(Range<u32>, &RayPacket, &mut F32x8),
        probe: &mut impl TraversalProbe,
    ) {
        if self.nodes.is_empty() || !any(rays.active) {
            return;
        }
        let slabs = PacketSlabs::new(rays);
        let mut local = *rays;
        let (hit, near) = slabs.test(&self.nodes[0], rays.tmin, *tmax);
        // The stack lives with the thread: a fresh array per call cost a 4 KB memset.
        PACKET_STACK.with_borrow_mut(|stack| {
            stack.clear();
            stack.push(Pending::new(0, near, hit & rays.active));
            while let Some(entry) = stack.pop() {
                let mut node = entry.node;
                let (near, lanes) = (from_lanes(entry.near), from_lanes(entry.lanes));
                // cull: no lane of this subtree can hit nearer than its current hit
                let mut lanes = lanes & le(near, widen_packet(*tmax));
                if !any(lanes) {
                    continue;
                }
                loop {
                    let n = &self.nodes[node as usize];
                    probe.node(lanes);
                    if n.is_leaf() {
                        local.active = lanes;
                        leaf(n.prims(), &local, tmax);
                        break;
                    }
                    let (left, right) = (node + 1, n.first);
                    let (hl, nl) = slabs.test(&self.nodes[left as usize], rays.tmin, *tmax);
                    let (hr, nr) = slabs.test(&self.nodes[right as usize], rays.tmin, *tmax);
                    let (hl, hr) = (hl & lanes, hr & lanes);
                    match (any(hl), any(hr)) {
                        (false, false) => break,
                        (true, false) => (node, lanes) = (left, hl),
                        (false, true) => (node, lanes) = (right, hr),
                        (true, true) => {
                            // order: the child more lanes enter first goes first
                            let both = hl & hr;
                            let left_first = bitmask(both & lt(nl, nr)).count_ones() * 2
                                >= bitmask(both).count_ones();
                            let (first, second) = if left_first {
                                ((left, hl, nl), (right, hr, nr))
                            } else {
                                ((right, hr, nr), (left, hl, nl))
                            };
                            stack.push(Pending::new(second.0, second.2, second.1));
                            (node, lanes) = (first.0, first.1);
                        }
                    }
                }
            }
        });
    }

    /// Single-ray twin of [`Bvh::occluded_packet`]: stops at the first leaf that blocks.
    pub fn occluded(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        mut leaf: impl FnMut(Range<u32>) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let slabs = RaySlabs::new(ray);
        let mut stack = [0u32; MAX_DEPTH];
        let mut top = 0;
        if slabs.test(&self.nodes[0], tmin, tmax).is_none() {
            return false;
        }
        let mut node = 0;
        loop {
            let n = &self.nodes[node as usize];
            if n.is_leaf() {
                if leaf(n.prims()) {
                    return true;
                }
            } else {
                let (left, right) = (node + 1, n.first);
                let l = slabs.test(&self.nodes[left as usize], tmin, tmax).is_some();
                let r = slabs
                    .test(&self.nodes[right as usize], tmin, tmax)
                    .is_some();
                match (l, r) {
                    (true, true) => {
                        stack[top] = right;
                        top += 1;
                        node = left;
                        continue;
                    }
                    (true, false) => {
                        node = left;
                        continue;
                    }
                    (false, true) => {
                        node = right;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            if top == 0 {
                return false;
            }
            top -= 1;
            node = stack[top];
        }
    }

    /// The active lanes of `rays` that something blocks before their `tmax`: visits leaves
    /// until every active lane is occluded; `leaf(range, rays)` returns the lanes (of the
    /// packet's active ones) blocked by the leaf's primitives.
    pub fn occluded_packet(
        &self,
        rays: &RayPacket,
        tmax: F32x8,
        mut leaf: impl FnMut(Range<u32>, &RayPacket) -> Mask,
    ) -> Mask {
        let mut occluded = crate::simd::mask_none();
        if self.nodes.is_empty() || !any(rays.active) {
            return occluded;
        }
        let slabs = PacketSlabs::new(rays);
        let mut local = *rays;
        let mut stack = [(0u32, rays.active); MAX_DEPTH];
        let (hit, _) = slabs.test(&self.nodes[0], rays.tmin, tmax);
        stack[0] = (0, hit & rays.active);
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (mut node, lanes) = stack[top];
            let mut lanes = lanes & !occluded;
            if !any(lanes) {
                continue;
            }
            loop {
                let n = &self.nodes[node as usize];
                if n.is_leaf() {
                    local.active = lanes;
                    occluded |= leaf(n.prims(), &local);
                    // early exit: every active lane is blocked
                    if all(occluded | !rays.active) {
                        return occluded;
                    }
                    break;
                }
                let (left, right) = (node + 1, n.first);
                let (hl, _) = slabs.test(&self.nodes[left as usize], rays.tmin, tmax);
                let (hr, _) = slabs.test(&self.nodes[right as usize], rays.tmin, tmax);
                let (hl, hr) = (hl & lanes, hr & lanes);
                match (any(hl), any(hr)) {
                    (false, false) => break,
                    (true, false) => (node, lanes) = (left, hl),
                    (false, true) => (node, lanes) = (right, hr),
                    (true, true) => {
                        stack[top] = (right, hr);
                        top += 1;
                        (node, lanes) = (left, hl);
                    }
                }
            }
        }
        occluded
    }

    /// Checks the tree's invariants against the primitive bounds and tags it was built from
    /// (after reordering: primitive `i` of a leaf range is `bounds[i]`): every primitive in
    /// exactly one leaf, boxes nested, leaves hold their primitives and never mix tags,
    /// depth within [`MAX_DEPTH`].
    pub fn validate(&self, bounds: &[Aabb], tags: &[u8]) -> Result<(), String> {
        if bounds.is_empty() {
            return if self.nodes.is_empty() {
                Ok(())
            } else {
                Err("nodes without primitives".into())
            };
        }
        let mut seen = vec![false; bounds.len()];
        let mut stack = vec![(0u32, 0usize)];
        let mut visited = 0;
        while let Some((i, depth)) = stack.pop() {
            visited += 1;
            if depth >= MAX_DEPTH {
                return Err(format!("node {i} at depth {depth}"));
            }
            let n = self
                .nodes
                .get(i as usize)
                .ok_or_else(|| format!("node {i} out of range"))?;
            let b = n.aabb();
            if n.is_leaf() {
                let r = n.prims();
                if r.end as usize > bounds.len() {
                    return Err(format!("leaf {i} range {r:?} out of bounds"));
                }
                for p in r.clone() {
                    if std::mem::replace(&mut seen[p as usize], true) {
                        return Err(format!("primitive {p} in two leaves"));
                    }
                    if !b.contains(&bounds[p as usize]) {
                        return Err(format!("leaf {i} does not hold primitive {p}"));
                    }
                    if tags[p as usize] != tags[r.start as usize] {
                        return Err(format!("leaf {i} mixes tags"));
                    }
                }
            } else {
                let (l, r) = (i + 1, n.first);
                if r <= l || r as usize >= self.nodes.len() {
                    return Err(format!("interior node {i} has bad children {l}, {r}"));
                }
                for c in [l, r] {
                    if !b.contains(&self.nodes[c as usize].aabb()) {
                        return Err(format!("node {i} does not hold child {c}"));
                    }
                    stack.push((c, depth + 1));
                }
            }
        }
        if visited != self.nodes.len() {
            return Err(format!("{} nodes, {visited} reachable", self.nodes.len()));
        }
        match seen.iter().position(|s| !s) {
            Some(p) => Err(format!("primitive {p} in no leaf")),
            None => Ok(()),
        }
    }
}

const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);
