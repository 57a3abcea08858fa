//! Coherent-stream traversal of the 8-wide BVH: several packets (up to [`MAX_STREAM`], 64 rays)
//! share one frustum and one walk of the tree (Embree's coherent stream, after Overbeck et al.
//! 2008 and Fuetterling et al. 2015). The rays a subtree may concern are a 64-bit mask (bit
//! `8 p + l` = lane `l` of packet `p`). At each node one 8-lane frustum test picks the children
//! some ray may enter and bounds their entry distance; then one representative ray (the first
//! of the mask) is tested against all children at once. Interior children it enters inherit
//! the whole mask untested (a conservative guess, refined further down); the others, and every
//! leaf, get the exact per-packet test, so a leaf only ever sees the lanes that enter its box.
//! Children go nearest first by the frustum's bound.

use super::packet::{Frustum, Packet8, max_lane};
use super::single::Ray1;
use super::stack::Stack;
use super::{Bvh8, Leaf, MAX_DEPTH, Node8, NodeRef, WIDTH, widen};
use crate::packet::RayPacket;
use crate::simd::{F32x8, LANES, Mask, bitmask, lanes, mask_from_byte};

/// The most packets one stream traverses together.
pub const MAX_STREAM: usize = 8;

/// A set of a stream's rays: bit `8 p + l` is lane `l` of packet `p`.
pub type StreamMasks = u64;

const STACK: usize = (WIDTH - 1) * MAX_DEPTH + 1;

/// A stream's rays prepared for box tests.
struct Stream<'r> {
    rays: &'r [RayPacket],
    packets: &'r [Packet8],
    frustum: Frustum,
}

/// The lanes of packet `p` in `mask`.
#[inline(always)]
fn byte(mask: StreamMasks, p: usize) -> u32 {
    (mask >> (LANES * p)) as u32 & 0xff
}

impl Stream<'_> {
    /// The rays of `mask` that enter child `i` of `n` within their own `(tmin, tmax)`.
    #[inline(always)]
    fn exact(&self, n: &Node8, i: usize, mask: StreamMasks, tmax: &[F32x8]) -> StreamMasks {
        let mut out = 0;
        let mut m = mask;
        while m != 0 {
            let p = m.trailing_zeros() as usize / LANES;
            m &= !(0xff << (LANES * p));
            let (hit, _) =
                self.packets[p].test_octant(n, i, &self.frustum, self.rays[p].tmin, tmax[p]);
            let bits = bitmask(hit) & byte(mask, p);
            out |= (bits as u64) << (LANES * p);
        }
        out
    }

    /// The first ray of `mask` as a single ray.
    #[inline(always)]
    fn first_ray(&self, mask: StreamMasks) -> (Ray1, usize, usize) {
        let k = mask.trailing_zeros() as usize;
        let (p, l) = (k / LANES, k % LANES);
        let pk = &self.packets[p];
        let lane = |v: F32x8| v.as_array()[l];
        let o = [lane(pk.org.x), lane(pk.org.y), lane(pk.org.z)];
        let inv = [lane(pk.inv.x), lane(pk.inv.y), lane(pk.inv.z)];
        (Ray1::from_parts::<false>(o, inv), p, l)
    }

    /// The largest `tmax` of any active ray.
    #[inline(always)]
    fn tmax_all(&self, tmax: &[F32x8]) -> F32x8 {
        let ninf = F32x8::splat(f32::NEG_INFINITY);
        let mut m = ninf;
        for (p, t) in self.rays.iter().zip(tmax) {
            m = crate::simd::max(m, crate::simd::select(p.active, *t, ninf));
        }
        max_lane(m, crate::simd::mask_first(LANES))
    }

    /// The children of `n` the rays of `mask` may enter, with their ray masks and the
    /// frustum's entry bound, farthest first (the nearest ends last).
    #[inline(always)]
    fn children(
        &self,
        n: &Node8,
        mask: StreamMasks,
        tmax: &[F32x8],
        tmax_all: F32x8,
        out: &mut [(NodeRef, StreamMasks, f32); WIDTH],
    ) -> usize {
        let (mut cand, fnear) = self.frustum.test(n, tmax_all);
        if cand == 0 {
            return 0;
        }
        let (ray, p, l) = self.first_ray(mask);
        let tl = |v: F32x8| F32x8::splat(v.as_array()[l]);
        let (first_hits, _) = ray.test::<false>(n, tl(self.rays[p].tmin), tl(tmax[p]));
        let fnear = lanes(fnear);
        let mut count = 0;
        while cand != 0 {
            let i = cand.trailing_zeros() as usize;
            cand &= cand - 1;
            let child = n.child[i];
            let m = if !child.is_leaf() && first_hits >> i & 1 == 1 {
                mask
            } else {
                self.exact(n, i, mask, tmax)
            };
            if m == 0 {
                continue;
            }
            let x = (child, m, fnear[i]);
            let mut j = count;
            while j > 0 && out[j - 1].2 <= x.2 {
                out[j] = out[j - 1];
                j -= 1;
            }
            out[j] = x;
            count += 1;
        }
        count
    }
}

impl Bvh8 {
    /// The closest hits of a stream of packets (at most [`MAX_STREAM`]): visits, for the
    /// active lanes, every leaf one of them may hit nearer than its `tmax` lane;
    /// `leaf(leaf, p, rays[p], lanes, tmax[p])` tests the leaf's primitives for `lanes` of
    /// packet `p` and lowers their `tmax` where it finds nearer hits. Every child pushed for
    /// later is prefetched: an interior node here, a leaf's primitives by `touch(leaf)`
    /// (measured: PERF.md, "Prefetching pushed leaves"). Packets whose directions do not share
    /// an octant are traversed one by one ([`Bvh8::closest_packet`]).
    pub fn closest_stream(
        &self,
        rays: &[RayPacket],
        tmax: &mut [F32x8],
        mut leaf: impl FnMut(Leaf, usize, &RayPacket, Mask, &mut F32x8),
        touch: impl Fn(Leaf),
    ) {
        assert!(rays.len() <= MAX_STREAM && tmax.len() == rays.len());
        let mut packets = [Packet8::EMPTY; MAX_STREAM];
        let Some(s) = self.stream(rays, &mut packets) else {
            for (p, (r, t)) in rays.iter().zip(tmax.iter_mut()).enumerate() {
                self.closest_packet(r, t, |l, r, m, t| leaf(l, p, r, m, t));
            }
            return;
        };
        let active = active_mask(rays);
        let mut stack: Stack<(NodeRef, StreamMasks, f32), STACK> = Stack::new();
        stack.push((self.root, active, f32::NEG_INFINITY));
        let mut hits = [(NodeRef::EMPTY, 0, 0.0); WIDTH];
        let mut tmax_all = s.tmax_all(tmax);
        while let Some((mut node, mut mask, dist)) = stack.pop() {
            if dist > widen(tmax_all.as_array()[0]) {
                continue;
            }
            loop {
                if node.is_leaf() {
                    let l = node.as_leaf();
                    let mut m = mask;
                    while m != 0 {
                        let p = m.trailing_zeros() as usize / LANES;
                        m &= !(0xff << (LANES * p));
                        leaf(l, p, &rays[p], mask_from_byte(byte(mask, p)), &mut tmax[p]);
                    }
                    tmax_all = s.tmax_all(tmax);
                    break;
                }
                let n = &self.nodes[node.index()];
                let count = s.children(n, mask, tmax, tmax_all, &mut hits);
                if count == 0 {
                    break;
                }
                for h in &hits[..count - 1] {
                    self.prefetch(h.0, &touch);
                    stack.push(*h);
                }
                (node, mask) = (hits[count - 1].0, hits[count - 1].1);
            }
        }
    }

    /// The occluded lanes of a stream of packets (at most [`MAX_STREAM`]), each before its
    /// `tmax` lane: `occluded[p]` gets the lanes of packet `p` that something blocks.
    /// `leaf(leaf, p, rays[p], lanes)` returns the lanes (of `lanes`) blocked by the leaf's
    /// primitives; the walk ends once every active ray is blocked. Pushed children are
    /// prefetched as in [`Bvh8::closest_stream`].
    pub fn occluded_stream(
        &self,
        rays: &[RayPacket],
        tmax: &[F32x8],
        occluded: &mut [Mask],
        mut leaf: impl FnMut(Leaf, usize, &RayPacket, Mask) -> Mask,
        touch: impl Fn(Leaf),
    ) {
        assert!(rays.len() <= MAX_STREAM && tmax.len() == rays.len());
        assert!(occluded.len() == rays.len());
        let mut packets = [Packet8::EMPTY; MAX_STREAM];
        let Some(s) = self.stream(rays, &mut packets) else {
            for (p, (r, t)) in rays.iter().zip(tmax).enumerate() {
                occluded[p] = self.occluded_packet(r, *t, |l, r, m| leaf(l, p, r, m));
            }
            return;
        };
        let active = active_mask(rays);
        let mut blocked: StreamMasks = 0;
        let tmax_all = s.tmax_all(tmax);
        let mut stack: Stack<(NodeRef, StreamMasks), STACK> = Stack::new();
        stack.push((self.root, active));
        let mut hits = [(NodeRef::EMPTY, 0, 0.0); WIDTH];
        'walk: while let Some((mut node, mask)) = stack.pop() {
            let mut mask = mask & !blocked;
            if mask == 0 {
                continue;
            }
            loop {
                if node.is_leaf() {
                    let l = node.as_leaf();
                    let mut m = mask;
                    while m != 0 {
                        let p = m.trailing_zeros() as usize / LANES;
                        m &= !(0xff << (LANES * p));
                        let lanes_p = mask_from_byte(byte(mask, p));
                        let b = bitmask(leaf(l, p, &rays[p], lanes_p) & lanes_p);
                        blocked |= (b as u64) << (LANES * p);
                    }
                    if blocked == active {
                        break 'walk;
                    }
                    break;
                }
                let n = &self.nodes[node.index()];
                let count = s.children(n, mask, tmax, tmax_all, &mut hits);
                if count == 0 {
                    break;
                }
                for h in &hits[..count - 1] {
                    self.prefetch(h.0, &touch);
                    stack.push((h.0, h.1));
                }
                (node, mask) = (hits[count - 1].0, hits[count - 1].1);
            }
        }
        for (p, o) in occluded.iter_mut().enumerate() {
            *o = mask_from_byte(byte(blocked, p));
        }
    }

    /// The stream's prepared rays, or `None` (traverse packet by packet) when the tree is a
    /// single leaf or nothing, or the rays share no octant.
    #[inline(always)]
    fn stream<'r>(
        &self,
        rays: &'r [RayPacket],
        packets: &'r mut [Packet8; MAX_STREAM],
    ) -> Option<Stream<'r>> {
        if self.root.is_leaf() || active_mask(rays) == 0 {
            return None;
        }
        for (p, r) in packets.iter_mut().zip(rays) {
            *p = Packet8::new(r);
        }
        let packets = &packets[..rays.len()];
        let frustum = Frustum::new(packets.iter().zip(rays).map(|(p, r)| (p, r.active, r.tmin)))?;
        Some(Stream {
            rays,
            packets,
            frustum,
        })
    }
}

/// The active lanes of every packet as one mask.
fn active_mask(rays: &[RayPacket]) -> StreamMasks {
    rays.iter()
        .enumerate()
        .fold(0, |m, (p, r)| m | (bitmask(r.active) as u64) << (LANES * p))
}
