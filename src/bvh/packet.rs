//! Packet traversal of the 8-wide BVH: 8 rays together, one child at a time against all 8
//! lanes (per-lane entry distances, lanes culled where they cannot beat their current hit).
//! When the packet's rays share an octant, a frustum of them first tests all 8 children in one
//! pass (interval arithmetic over the packet's origins and reciprocal directions), so only
//! children some ray may enter get the per-lane test; children go nearest first by that bound.
//! Without one (rays of mixed octants), forward rays test each child by the single-ray test's
//! arithmetic, lane by lane in its own octant ([`Ray1x8`]).

use super::single::Ray1x8;
use super::stack::Stack;
use super::{
    Bvh8, HI, LO, Leaf, MAX_DEPTH, NoProbe, Node8, NodeRef, Plane, TraversalProbe, WIDTH,
    safe_inverse8, slab_octant, widen8,
};
use crate::packet::RayPacket;
use crate::simd::{
    F32x8, Mask, Vec3x8, all, any, bitmask, ge, lanes, le, lt, max, min, reduce_max, reduce_min,
    select,
};

/// Entries a packet stack may hold.
pub const PACKET_STACK_DEPTH: usize = (WIDTH - 1) * MAX_DEPTH + 1;

/// A packet prepared for box tests: origins and safe reciprocal directions.
#[derive(Clone, Copy)]
pub(super) struct Packet8 {
    pub org: Vec3x8,
    pub inv: Vec3x8,
}

impl Packet8 {
    /// A placeholder (no rays).
    pub(super) const EMPTY: Packet8 = Packet8 {
        org: Vec3x8 {
            x: F32x8::ZERO,
            y: F32x8::ZERO,
            z: F32x8::ZERO,
        },
        inv: Vec3x8 {
            x: F32x8::ZERO,
            y: F32x8::ZERO,
            z: F32x8::ZERO,
        },
    };

    #[inline(always)]
    pub(super) fn new(rays: &RayPacket) -> Packet8 {
        Packet8 {
            org: rays.origin,
            inv: Vec3x8 {
                x: safe_inverse8(rays.dir.x),
                y: safe_inverse8(rays.dir.y),
                z: safe_inverse8(rays.dir.z),
            },
        }
    }

    /// Lanes whose ray meets child `i`'s box within `(tmin, tmax)`, and their entry distances
    /// (`(plane - origin) * inv` lane by lane; the single-ray test's fused form errs to the same
    /// safe side, so both enter every box their ray meets).
    #[inline(always)]
    pub(super) fn test(&self, n: &Node8, i: usize, tmin: F32x8, tmax: F32x8) -> (Mask, F32x8) {
        self.test_planes(|k| n.bounds[k].as_array()[i], tmin, tmax)
    }

    /// [`Packet8::test`] for lanes that all share the octant of frustum `f`: each axis is
    /// entered through the frustum's entry plane, so the per-axis min/max of the general slab
    /// is not needed. For those lanes the same bits as [`Packet8::test`] (rounding is
    /// monotonic, so the min/max would pick the same distances).
    #[inline(always)]
    pub(super) fn test_octant(
        &self,
        n: &Node8,
        i: usize,
        f: &Frustum,
        tmin: F32x8,
        tmax: F32x8,
    ) -> (Mask, F32x8) {
        let (o, inv) = (
            [self.org.x, self.org.y, self.org.z],
            [self.inv.x, self.inv.y, self.inv.z],
        );
        let t =
            |k: Plane, a: usize| (F32x8::splat(n.bounds[k as usize].as_array()[i]) - o[a]) * inv[a];
        slab_octant::<false, false>(t, t, &f.near, &f.far, tmin, tmax)
    }

    /// [`Packet8::test`] for a box given as an [`Aabb`].
    #[inline(always)]
    pub(super) fn test_box(&self, b: &super::Aabb, tmin: F32x8, tmax: F32x8) -> (Mask, F32x8) {
        self.test_planes(
            |k| if k < HI { b.min[k - LO] } else { b.max[k - HI] },
            tmin,
            tmax,
        )
    }

    #[inline(always)]
    fn test_planes(&self, p: impl Fn(usize) -> f32, tmin: F32x8, tmax: F32x8) -> (Mask, F32x8) {
        let plane = |k: usize| F32x8::splat(p(k));
        let slab = |axis: usize, o: F32x8, inv: F32x8| {
            let a = (plane(LO + axis) - o) * inv;
            let b = (plane(HI + axis) - o) * inv;
            (min(a, b), max(a, b))
        };
        let (x0, x1) = slab(0, self.org.x, self.inv.x);
        let (y0, y1) = slab(1, self.org.y, self.inv.y);
        let (z0, z1) = slab(2, self.org.z, self.inv.z);
        let near = max(max(x0, y0), max(z0, tmin));
        let far = widen8(min(min(x1, y1), min(z1, tmax)));
        (le(near, far), near)
    }
}

/// A conservative frustum around rays that share an octant: the range of their origins and
/// reciprocal directions on each axis. Its box test bounds every ray's entry distance from
/// below and exit distance from above with the rays' own arithmetic (rounding is monotonic), so
/// a child it rejects is rejected by every ray's own test.
#[derive(Clone, Copy)]
pub(super) struct Frustum {
    /// The plane each axis is entered through (all rays share it) and left through.
    near: [Plane; 3],
    far: [Plane; 3],
    /// The origin bound that gives the smallest entry / largest exit difference.
    o_near: [F32x8; 3],
    o_far: [F32x8; 3],
    inv_lo: [F32x8; 3],
    inv_hi: [F32x8; 3],
    tmin: F32x8,
}

impl Frustum {
    /// The frustum of the `active` lanes of several prepared packets, or `None` when their
    /// directions do not share an octant (or no lane is active).
    pub(super) fn new<'a>(
        packets: impl Iterator<Item = (&'a Packet8, Mask, F32x8)>,
    ) -> Option<Frustum> {
        let (inf, ninf) = (F32x8::splat(f32::INFINITY), F32x8::splat(f32::NEG_INFINITY));
        let (mut o_lo, mut o_hi) = ([inf; 3], [ninf; 3]);
        let (mut i_lo, mut i_hi) = ([inf; 3], [ninf; 3]);
        let mut t_lo = inf;
        let mut any_lane = false;
        // per axis, whether some active ray goes down it and whether some goes up
        let (mut down, mut up) = ([false; 3], [false; 3]);
        for (p, active, tmin) in packets {
            any_lane |= any(active);
            let o = [p.org.x, p.org.y, p.org.z];
            let v = [p.inv.x, p.inv.y, p.inv.z];
            for a in 0..3 {
                down[a] |= any(active & lt(v[a], F32x8::ZERO));
                up[a] |= any(active & ge(v[a], F32x8::ZERO));
                o_lo[a] = min(o_lo[a], select(active, o[a], inf));
                o_hi[a] = max(o_hi[a], select(active, o[a], ninf));
                i_lo[a] = min(i_lo[a], select(active, v[a], inf));
                i_hi[a] = max(i_hi[a], select(active, v[a], ninf));
            }
            t_lo = min(t_lo, select(active, tmin, inf));
        }
        // no common octant: the test below would find it too, after twelve reductions
        if !any_lane || (0..3).any(|a| down[a] && up[a]) {
            return None;
        }
        let (mut o_near, mut o_far) = ([inf; 3], [inf; 3]);
        let (mut inv_lo, mut inv_hi) = ([inf; 3], [inf; 3]);
        for a in 0..3 {
            let (ilo, ihi) = (reduce_min(i_lo[a]), reduce_max(i_hi[a]));
            let (olo, ohi) = (reduce_min(o_lo[a]), reduce_max(o_hi[a]));
            let positive = ilo >= 0.0;
            if !positive && ihi >= 0.0 {
                return None;
            }
            down[a] = !positive;
            // Entry: the smallest (plane - origin) for rays going up the axis is from the
            // largest origin; going down, from the smallest. Exit: the opposite.
            o_near[a] = F32x8::splat(if positive { ohi } else { olo });
            o_far[a] = F32x8::splat(if positive { olo } else { ohi });
            inv_lo[a] = F32x8::splat(ilo);
            inv_hi[a] = F32x8::splat(ihi);
        }
        Some(Frustum {
            near: std::array::from_fn(|a| Plane::entry(a, down[a])),
            far: std::array::from_fn(|a| Plane::exit(a, down[a])),
            o_near,
            o_far,
            inv_lo,
            inv_hi,
            tmin: F32x8::splat(reduce_min(t_lo)),
        })
    }

    /// The children some ray of the frustum may enter before `tmax` (the largest of the rays'
    /// limits), and a lower bound of their entry distances.
    #[inline(always)]
    pub(super) fn test(&self, n: &Node8, tmax: F32x8) -> (u32, F32x8) {
        let zero = F32x8::splat(0.0);
        let entry = |a: usize| {
            let d = n.bounds[self.near[a] as usize] - self.o_near[a];
            d * select(ge(d, zero), self.inv_lo[a], self.inv_hi[a])
        };
        let exit = |a: usize| {
            let d = n.bounds[self.far[a] as usize] - self.o_far[a];
            d * select(ge(d, zero), self.inv_hi[a], self.inv_lo[a])
        };
        let near = max(max(entry(0), entry(1)), max(entry(2), self.tmin));
        let far = min(min(exit(0), exit(1)), min(exit(2), tmax));
        (bitmask(le(near, widen8(far))), near)
    }
}

/// The largest `tmax` among the `lanes`.
#[inline(always)]
pub(super) fn max_lane(t: F32x8, lanes_mask: Mask) -> F32x8 {
    F32x8::splat(reduce_max(select(
        lanes_mask,
        t,
        F32x8::splat(f32::NEG_INFINITY),
    )))
}

/// A pending subtree of a packet traversal: its lanes and their entry distances.
#[derive(Clone, Copy)]
struct Pending {
    node: NodeRef,
    lanes: Mask,
    near: F32x8,
}

/// A hit child while a node is processed: slot, lanes, their entry distances, sort key.
#[derive(Clone, Copy)]
struct HitChild {
    node: NodeRef,
    lanes: Mask,
    near: F32x8,
    key: f32,
}

/// The children of `n` that `lanes` enter, by `test(n, child, tmax)` (a child's lanes and
/// their entry distances), ordered nearest last (by the frustum's bound when there is one,
/// else by the nearest lane).
#[inline(always)]
fn hit_children(
    n: &Node8,
    frustum: Option<&Frustum>,
    test: &impl Fn(&Node8, usize, F32x8) -> (Mask, F32x8),
    lanes_mask: Mask,
    tmax: F32x8,
    out: &mut [HitChild; WIDTH],
) -> usize {
    let (mut cand, fnear) = match frustum {
        Some(f) => f.test(n, max_lane(tmax, lanes_mask)),
        None => ((1u32 << n.len()) - 1, F32x8::splat(0.0)),
    };
    let fnear = lanes(fnear);
    let mut count = 0;
    while cand != 0 {
        let i = cand.trailing_zeros() as usize;
        cand &= cand - 1;
        let (hit, near) = test(n, i, tmax);
        let hit = hit & lanes_mask;
        if !any(hit) {
            continue;
        }
        let key = if frustum.is_some() {
            fnear[i]
        } else {
            nearest_entry(hit, near)
        };
        out[count] = HitChild {
            node: n.child[i],
            lanes: hit,
            near,
            key,
        };
        count += 1;
    }
    sort_farthest_first(&mut out[..count]);
    count
}

/// [`hit_children`] without a frustum for a `test` that rejects an empty slot for every ray
/// ([`Ray1x8::test_child`]): all 8 slots tested before any child is taken, so no branch per
/// child waits on its test (the children some lane enters are few and vary from packet to
/// packet, so those branches were mispredicted). The same children in the same order.
#[inline(always)]
fn hit_children_all(
    n: &Node8,
    test: &impl Fn(&Node8, usize, F32x8) -> (Mask, F32x8),
    lanes_mask: Mask,
    tmax: F32x8,
    out: &mut [HitChild; WIDTH],
) -> usize {
    let mut hits = [(lanes_mask, tmax); WIDTH];
    let mut entered = 0u32;
    for (i, h) in hits.iter_mut().enumerate() {
        let (hit, near) = test(n, i, tmax);
        let hit = hit & lanes_mask;
        entered |= u32::from(any(hit)) << i;
        *h = (hit, near);
    }
    let mut count = 0;
    while entered != 0 {
        let i = entered.trailing_zeros() as usize;
        entered &= entered - 1;
        let (hit, near) = hits[i];
        out[count] = HitChild {
            node: n.child[i],
            lanes: hit,
            near,
            key: nearest_entry(hit, near),
        };
        count += 1;
    }
    sort_farthest_first(&mut out[..count]);
    count
}

/// The nearest entry distance among the lanes `hit`: a child's sort key without a frustum.
#[inline(always)]
fn nearest_entry(hit: Mask, near: F32x8) -> f32 {
    reduce_min(select(hit, near, F32x8::splat(f32::INFINITY)))
}

/// Orders hit children farthest first, so the nearest ends last.
#[inline(always)]
fn sort_farthest_first(out: &mut [HitChild]) {
    for i in 1..out.len() {
        let x = out[i];
        let mut j = i;
        while j > 0 && out[j - 1].key <= x.key {
            out[j] = out[j - 1];
            j -= 1;
        }
        out[j] = x;
    }
}

impl Bvh8 {
    /// Visits, for the active lanes of `rays`, every leaf one of them may hit nearer than its
    /// `tmax` lane; `leaf(leaf, rays, lanes, tmax)` tests the leaf's primitives for `lanes`
    /// (a subset of the active ones) and lowers their `tmax` where it finds nearer hits.
    pub fn closest_packet(
        &self,
        rays: &RayPacket,
        tmax: &mut F32x8,
        leaf: impl FnMut(Leaf, &RayPacket, Mask, &mut F32x8),
    ) {
        self.closest_packet_probed(rays, tmax, leaf, &mut NoProbe);
    }

    /// [`Bvh8::closest_packet`] reporting every node it visits to `probe`, with the lanes that
    /// entered it (the cost heatmap counts them); with [`NoProbe`] it is `closest_packet`.
    pub fn closest_packet_probed(
        &self,
        rays: &RayPacket,
        tmax: &mut F32x8,
        mut leaf: impl FnMut(Leaf, &RayPacket, Mask, &mut F32x8),
        probe: &mut impl TraversalProbe,
    ) {
        if self.is_empty() || !any(rays.active) {
            return;
        }
        let p = Packet8::new(rays);
        // the lanes that enter the tree's box (the heatmap counts the root for them only)
        let (enter, near) = p.test_box(&self.bounds, rays.tmin, *tmax);
        let enter = enter & rays.active;
        if !any(enter) {
            return;
        }
        if self.root.is_leaf() {
            probe.node(enter);
            leaf(self.root.as_leaf(), rays, enter, tmax);
            return;
        }
        let frustum = Frustum::new(std::iter::once((&p, rays.active, rays.tmin)));
        let tmin = rays.tmin;
        let root = Pending {
            node: self.root,
            lanes: enter,
            near,
        };
        // one walk for each child test, so the test is chosen once per packet
        match &frustum {
            Some(f) => {
                let test = |n: &Node8, i, tmax| p.test_octant(n, i, f, tmin, tmax);
                let children =
                    |n: &Node8, l, tmax, out: &mut _| hit_children(n, Some(f), &test, l, tmax, out);
                self.packet_walk(rays, tmax, root, &children, &mut leaf, probe);
            }
            // without a frustum (rays of mixed octants), forward rays test each child by the
            // single-ray test's fused arithmetic, lane by lane in its own octant: 4 operations
            // an axis instead of 6, and no widening after the minimum (PERF.md, sitting 20);
            // all 8 slots, as that test rejects an empty one, before any child is taken, so
            // no branch waits on a child's test (PERF.md, sitting 33)
            None if Ray1x8::all_forward(rays) => {
                let (o, i) = (p.org, p.inv);
                let r = Ray1x8::from_inverse([o.x, o.y, o.z], [i.x, i.y, i.z]);
                let test = |n: &Node8, i, tmax| r.test_child(n, i, tmin, tmax);
                let children =
                    |n: &Node8, l, tmax, out: &mut _| hit_children_all(n, &test, l, tmax, out);
                self.packet_walk(rays, tmax, root, &children, &mut leaf, probe);
            }
            None => {
                let test = |n: &Node8, i, tmax| p.test(n, i, tmin, tmax);
                let children =
                    |n: &Node8, l, tmax, out: &mut _| hit_children(n, None, &test, l, tmax, out);
                self.packet_walk(rays, tmax, root, &children, &mut leaf, probe);
            }
        }
    }

    /// The walk of [`Bvh8::closest_packet_probed`] from `root`, testing children by `test`
    /// (the frustum's when there is one, which also picks the candidates).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn packet_walk(
        &self,
        rays: &RayPacket,
        tmax: &mut F32x8,
        root: Pending,
        children: &impl Fn(&Node8, Mask, F32x8, &mut [HitChild; WIDTH]) -> usize,
        leaf: &mut impl FnMut(Leaf, &RayPacket, Mask, &mut F32x8),
        probe: &mut impl TraversalProbe,
    ) {
        let mut stack: Stack<Pending, PACKET_STACK_DEPTH> = Stack::new();
        stack.push(root);
        let mut hits = [HitChild {
            node: NodeRef::EMPTY,
            lanes: F32x8::splat(0.0),
            near: F32x8::splat(0.0),
            key: 0.0,
        }; WIDTH];
        while let Some(e) = stack.pop() {
            // cull: no lane of this subtree can hit nearer than its current hit
            let mut lanes_mask = e.lanes & le(e.near, widen8(*tmax));
            if !any(lanes_mask) {
                continue;
            }
            let mut node = e.node;
            loop {
                probe.node(lanes_mask);
                if node.is_leaf() {
                    leaf(node.as_leaf(), rays, lanes_mask, tmax);
                    break;
                }
                let n = &self.nodes[node.index()];
                let count = children(n, lanes_mask, *tmax, &mut hits);
                if count == 0 {
                    break;
                }
                for h in &hits[..count - 1] {
                    stack.push(Pending {
                        node: h.node,
                        lanes: h.lanes,
                        near: h.near,
                    });
                }
                let nearest = hits[count - 1];
                (node, lanes_mask) = (nearest.node, nearest.lanes);
            }
        }
    }

    /// The active lanes of `rays` that something blocks before their `tmax`: visits leaves
    /// until every active lane is occluded; `leaf(leaf, rays, lanes)` returns the lanes (of
    /// `lanes`) blocked by the leaf's primitives.
    pub fn occluded_packet(
        &self,
        rays: &RayPacket,
        tmax: F32x8,
        mut leaf: impl FnMut(Leaf, &RayPacket, Mask) -> Mask,
    ) -> Mask {
        let mut occluded = crate::simd::mask_none();
        if self.is_empty() || !any(rays.active) {
            return occluded;
        }
        if self.root.is_leaf() {
            return leaf(self.root.as_leaf(), rays, rays.active) & rays.active;
        }
        let p = Packet8::new(rays);
        let frustum = Frustum::new(std::iter::once((&p, rays.active, rays.tmin)));
        let tmax_all = max_lane(tmax, rays.active);
        let mut stack: Stack<(NodeRef, Mask), PACKET_STACK_DEPTH> = Stack::new();
        stack.push((self.root, rays.active));
        while let Some((mut node, lanes_mask)) = stack.pop() {
            let mut lanes_mask = lanes_mask & !occluded;
            if !any(lanes_mask) {
                continue;
            }
            loop {
                if node.is_leaf() {
                    occluded |= leaf(node.as_leaf(), rays, lanes_mask) & lanes_mask;
                    // early exit: every active lane is blocked
                    if all(occluded | !rays.active) {
                        return occluded;
                    }
                    break;
                }
                let n = &self.nodes[node.index()];
                let mut cand = match &frustum {
                    Some(f) => f.test(n, tmax_all).0,
                    None => (1u32 << n.len()) - 1,
                };
                // highest slot first, so the first (largest) child is visited first
                let mut next: Option<(NodeRef, Mask)> = None;
                while cand != 0 {
                    let i = 31 - cand.leading_zeros() as usize;
                    cand &= !(1 << i);
                    let (hit, _) = match &frustum {
                        Some(f) => p.test_octant(n, i, f, rays.tmin, tmax),
                        None => p.test(n, i, rays.tmin, tmax),
                    };
                    let hit = hit & lanes_mask;
                    if any(hit) {
                        if let Some(prev) = next.replace((n.child[i], hit)) {
                            stack.push(prev);
                        }
                    }
                }
                match next {
                    Some((c, l)) => (node, lanes_mask) = (c, l),
                    None => break,
                }
            }
        }
        occluded
    }
}

#[cfg(test)]
mod tests {
    use super::{Frustum, Packet8};
    use crate::bvh::{Aabb, Node8, NodeRef};
    use crate::math::{Ray, Vec3};
    use crate::packet::RayPacket;
    use crate::simd::{LANES, bitmask, lanes, mask_first};
    use crate::test_rng::Rng;

    /// For rays sharing an octant, the octant test gives the general slab test's bits (mask
    /// and entry distances) for every child and every count of active lanes, directions
    /// along an axis and boxes the rays start inside included.
    #[test]
    fn octant_test_equals_the_general_slab_test() {
        let mut rng = Rng(0x9e37_79b9);
        for case in 0..400 {
            let children: Vec<(NodeRef, Aabb)> = (0..1 + case % 8)
                .map(|_| {
                    let (a, b) = (rng.vec(-4.0, 4.0), rng.vec(-4.0, 4.0));
                    (
                        NodeRef::EMPTY,
                        Aabb {
                            min: a.min(b),
                            max: a.max(b),
                        },
                    )
                })
                .collect();
            let n = Node8::new(&children);
            let sign = Vec3::new(
                if case & 1 == 0 { 1.0 } else { -1.0 },
                if case & 2 == 0 { 1.0 } else { -1.0 },
                if case & 4 == 0 { 1.0 } else { -1.0 },
            );
            let rays: [Ray; LANES] = std::array::from_fn(|l| {
                let mut d = rng.vec(0.0, 1.0) * sign;
                if l == 3 {
                    d = Vec3::new(0.0, 0.0, 1.0) * sign; // a signed zero keeps the octant
                }
                Ray::new(rng.vec(-6.0, 6.0), d.normalize_or(Vec3::Z * sign.z))
            });
            let active_lanes = 1 + case % LANES;
            let mut packet = RayPacket::from_rays(&rays, 1e-3);
            packet.active = mask_first(active_lanes);
            let p = Packet8::new(&packet);
            let f = Frustum::new(std::iter::once((&p, packet.active, packet.tmin)))
                .expect("one octant");
            let tmax = crate::simd::from_lanes(std::array::from_fn(|_| rng.range(0.5, 12.0)));
            for i in 0..children.len() {
                let (m0, near0) = p.test(&n, i, packet.tmin, tmax);
                let (m1, near1) = p.test_octant(&n, i, &f, packet.tmin, tmax);
                let active = (1u32 << active_lanes) - 1;
                assert_eq!(
                    bitmask(m0) & active,
                    bitmask(m1) & active,
                    "case {case} child {i}"
                );
                for l in 0..active_lanes {
                    assert_eq!(lanes(near0)[l].to_bits(), lanes(near1)[l].to_bits());
                }
            }
        }
    }

    /// Rays going both ways along an axis have no frustum.
    #[test]
    fn mixed_octants_have_no_frustum() {
        let rays: [Ray; LANES] = std::array::from_fn(|l| {
            let x = if l == 5 { -1.0 } else { 1.0 };
            Ray::new(Vec3::ZERO, Vec3::new(x, 0.5, 0.5).normalize())
        });
        let mut packet = RayPacket::from_rays(&rays, 1e-3);
        let p = Packet8::new(&packet);
        assert!(Frustum::new(std::iter::once((&p, packet.active, packet.tmin))).is_none());
        // without the one lane going down x, they share an octant
        packet.active = crate::simd::mask_from_bits(0xff & !(1 << 5));
        assert!(Frustum::new(std::iter::once((&p, packet.active, packet.tmin))).is_some());
    }
}
