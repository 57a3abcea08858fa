//! An 8-wide bounding volume hierarchy over primitive bounds, and its traversals. The tree
//! knows nothing about spheres or triangles: it is built from boxes and opaque tags (a leaf never
//! mixes tags), its leaves are whatever the caller's [`build::LeafSink`] stored for a group of
//! primitives, and every traversal takes the leaf test as a closure that receives a [`Leaf`]
//! (obvhs-style).
//!
//! A [`Node8`] holds the boxes of its up to 8 children structure of arrays (one `F32x8` per
//! box plane, lane `i` = child `i`) and a [`NodeRef`] per child, 256 bytes in all: one 8-lane
//! pass tests all children against one ray. Unused slots come last and hold an inverted box that
//! no ray enters.
//!
//! ```text
//! primitive bounds + tags --build (binned SAH, 8-wide, parallel)--> Bvh8 { nodes, root }
//!                                     '--LeafSink::leaf(tag, primitives)--> caller's leaf blocks
//! traversals (leaf test as a closure):
//!     single.rs  one ray, all 8 children per pass, nearest first     (incoherent rays;
//!                [`Ray1x8`] prepares a packet's 8 rays for their walks at once)
//!     packet.rs  8 rays, child by child, per-lane entry distances     (small coherent groups;
//!                [`Bvh8::closest_packet_probed`] reports each node to a [`TraversalProbe`],
//!                the cost heatmap's counter)
//!     stream.rs  several packets sharing one frustum                  (camera and shadow rays)
//!     lists.rs   many rays going down together as lists of ray ids,   (incoherent rays of
//!                each node splitting its list among its children       big trees)
//! ```

pub mod arena;
pub mod build;
mod lists;
mod packet;
mod single;
mod stack;
mod stream;

pub use lists::ListScratch;
pub use packet::PACKET_STACK_DEPTH;
pub use single::{Entered, ListRay, Ray1x8};
pub use stream::{MAX_STREAM, StreamMasks};

use crate::math::Vec3;
use crate::simd::F32x8;

/// Children per node.
pub const WIDTH: usize = 8;

/// Told of every node a packet traversal visits, with the lanes that entered it (culled lanes
/// excluded): the hook behind the cost heatmap. Monomorphised, so [`NoProbe`] costs nothing.
pub trait TraversalProbe {
    fn node(&mut self, lanes: crate::simd::Mask);
}

/// The probe of ordinary traversals: does nothing.
pub struct NoProbe;

impl TraversalProbe for NoProbe {
    #[inline(always)]
    fn node(&mut self, _lanes: crate::simd::Mask) {}
}

/// The deepest a tree gets, in nodes from the root (the traversal stacks are sized by it; the
/// builder makes leaves there).
pub const MAX_DEPTH: usize = 40;

/// Relative widening of the slab test's exit distance, so that rounding never culls a box a
/// ray touches: a distance carries at most three relative roundings (reciprocal, difference,
/// product; the fused single-ray form two), which the entry may err up and the exit down, and
/// the widening itself rounds twice, so `1 + 2 gamma(4)` (Pharr et al.'s `gamma(n)` =
/// `n u / (1 - n u)`; `1 + 2 gamma(3)` alone left the widening's own rounding uncovered). The
/// forward single-ray test, which folds the widening into its exit reciprocal, spends five of
/// those eight roundings: two on the entry, three on the exit (reciprocal, the folded
/// reciprocal, the fused difference).
const ROBUST: f32 = 1.0 + 2.0 * (4.0 * f32::EPSILON * 0.5) / (1.0 - 4.0 * f32::EPSILON * 0.5);

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

/// Nodes store their children's boxes grown by this fraction of the box's size and of its
/// coordinates' magnitude on each axis, so a ray that only grazes a primitive's bounds (a tangent
/// ray along a face, with a zero direction component) still enters the node.
const PAD: f32 = 1.0 / (1 << 20) as f32;

fn padded(b: &Aabb) -> Aabb {
    let pad = (b.max - b.min).max(Vec3::ZERO) * PAD + b.min.abs().max(b.max.abs()) * PAD;
    Aabb {
        min: b.min - pad,
        max: b.max + pad,
    }
}

/// What a [`NodeRef`] names when it is a leaf: the tag of its primitives, and the `first`
/// index and `count` the [`build::LeafSink`] chose for them (what they index is the sink's
/// business).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Leaf {
    pub tag: u8,
    pub first: u32,
    pub count: u32,
}

/// A child reference: an interior node, a leaf, or an empty slot. Bit 63 marks a leaf; a leaf
/// keeps its tag in bits 56..63, its count in bits 32..56 and its first index in bits 0..32. An
/// interior node's reference is its byte offset in the tree's node array (its index times the
/// 256 bytes of a [`Node8`]), so that a single-ray walk reaches its planes with one addressing
/// mode ([`NodeRef::offset`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeRef(u64);

const LEAF_BIT: u64 = 1 << 63;

/// An interior node's reference is its index shifted by this: the size of a [`Node8`].
const NODE_SHIFT: u32 = 8;

impl NodeRef {
    /// An unused child slot.
    pub const EMPTY: NodeRef = NodeRef(u64::MAX);

    /// The most primitives one leaf may name.
    pub const MAX_LEAF_COUNT: u32 = (1 << 24) - 1;

    /// The interior node at `index`.
    #[inline(always)]
    pub fn node(index: u32) -> NodeRef {
        NodeRef((index as u64) << NODE_SHIFT)
    }

    /// A leaf.
    #[inline(always)]
    pub fn leaf(leaf: Leaf) -> NodeRef {
        debug_assert!(leaf.count <= Self::MAX_LEAF_COUNT && leaf.tag < 0x7f);
        NodeRef(LEAF_BIT | (leaf.tag as u64) << 56 | (leaf.count as u64) << 32 | leaf.first as u64)
    }

    /// True for a leaf (or the empty slot).
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.0 & LEAF_BIT != 0
    }

    /// True for the empty slot.
    #[inline(always)]
    pub fn is_empty(self) -> bool {
        self == Self::EMPTY
    }

    /// The interior node's index.
    #[inline(always)]
    pub fn index(self) -> usize {
        (self.0 >> NODE_SHIFT) as usize
    }

    /// The interior node's byte offset in its tree's node array.
    #[inline(always)]
    pub fn offset(self) -> usize {
        self.0 as usize
    }

    /// The leaf's contents.
    #[inline(always)]
    pub fn as_leaf(self) -> Leaf {
        Leaf {
            tag: (self.0 >> 56) as u8 & 0x7f,
            first: self.0 as u32,
            count: (self.0 >> 32) as u32 & Self::MAX_LEAF_COUNT,
        }
    }
}

/// Box planes in a node's `bounds`: the lower x, y, z planes, then the upper ones.
const LO: usize = 0;
const HI: usize = 3;

/// An index into [`Node8::bounds`] whose range the compiler knows (six values), so the box
/// tests pick a ray's entry and exit planes by it without a bounds check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
enum Plane {
    LoX,
    LoY,
    LoZ,
    HiX,
    HiY,
    HiZ,
}

impl Plane {
    /// `[down][axis]`: the plane a ray enters through on `axis`, `down` when its direction
    /// component is negative.
    const ENTRY: [[Plane; 3]; 2] = [
        [Plane::LoX, Plane::LoY, Plane::LoZ],
        [Plane::HiX, Plane::HiY, Plane::HiZ],
    ];

    /// `[octant][axis]`: the planes a ray enters through, bit `axis` of `octant` set when its
    /// direction component on `axis` is negative (`octant ^ 7` gives the exit planes).
    const ENTRY_OF_OCTANT: [[Plane; 3]; 8] = {
        let mut t = [[Plane::LoX; 3]; 8];
        let mut octant = 0;
        while octant < 8 {
            let mut axis = 0;
            while axis < 3 {
                t[octant][axis] = Self::ENTRY[(octant >> axis) & 1][axis];
                axis += 1;
            }
            octant += 1;
        }
        t
    };

    /// The plane a ray enters its boxes through on `axis`.
    #[inline(always)]
    fn entry(axis: usize, down: bool) -> Plane {
        Self::ENTRY[usize::from(down)][axis]
    }

    /// The plane it leaves them through (the entry plane's opposite).
    #[inline(always)]
    fn exit(axis: usize, down: bool) -> Plane {
        Self::ENTRY[usize::from(!down)][axis]
    }
}

/// The slab test of rays that enter every box through planes `near` and leave through `far`
/// (one octant): `entry(plane, axis)` and `exit(plane, axis)` give the distances to an entry and
/// an exit plane, in error by at most the relative rounding the widening covers ([`ROBUST`]).
/// Returns the lanes that enter within `(tmin, tmax)` (the exit widened by that error,
/// [`widen_exit`]) and their entry distances. Shared by the single-ray test (lanes = children)
/// and the packet's octant test (lanes = rays). `FORWARD` promises `tmin >= 0` in every lane;
/// then the maximum, the minimum and the comparison of the two take the bits as integers
/// ([`crate::simd::max_bits`], [`crate::simd::le_bits`]: one cycle each on the walk's chain of
/// dependent operations, as in Embree; a float comparison takes four on Intel's cores): the
/// entry maximum includes `tmin >= 0`, so it is the float one, and the exit minimum is the
/// float one where every exit is at least 0 and negative otherwise, as the float one is, which
/// culls the lane (a negative exit, `-0` included, leaves nothing after `tmin`; the float
/// comparison kept a box left at exactly `-0`). `WIDENED` says
/// the exit distances and `tmax` come already widened (the forward single-ray test folds the
/// widening into its exit planes), so none is applied here.
#[inline(always)]
fn slab_octant<const FORWARD: bool, const WIDENED: bool>(
    entry: impl Fn(Plane, usize) -> F32x8,
    exit: impl Fn(Plane, usize) -> F32x8,
    near: &[Plane; 3],
    far: &[Plane; 3],
    tmin: F32x8,
    tmax: F32x8,
) -> (crate::simd::Mask, F32x8) {
    use crate::simd::{le, le_bits, max, max_bits, min, min_bits};
    type Pick = fn(F32x8, F32x8) -> F32x8;
    let (max, min): (Pick, Pick) = if FORWARD {
        (max_bits, min_bits)
    } else {
        (max, min)
    };
    let t0 = max(
        max(entry(near[0], 0), entry(near[1], 1)),
        max(entry(near[2], 2), tmin),
    );
    let t1 = min(
        min(exit(far[0], 0), exit(far[1], 1)),
        min(exit(far[2], 2), tmax),
    );
    let t1 = if WIDENED {
        t1
    } else {
        widen_exit::<FORWARD>(t1)
    };
    if FORWARD {
        (le_bits(t0, t1), t0)
    } else {
        (le(t0, t1), t0)
    }
}

/// An interior node: its children's boxes structure of arrays and their references. Children
/// occupy slots `0..n`; the other slots are [`NodeRef::EMPTY`] with the inverted box
/// (`lo = +inf`, `hi = -inf`), which the slab test rejects for every ray direction.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node8 {
    /// `[lo_x, lo_y, lo_z, hi_x, hi_y, hi_z]`, lane `i` = child `i`.
    pub bounds: [F32x8; 6],
    pub child: [NodeRef; WIDTH],
}

const _: () = assert!(std::mem::size_of::<Node8>() == 1 << NODE_SHIFT);

impl Node8 {
    /// A node over `children` (at most [`WIDTH`]) and their (unpadded) boxes.
    pub fn new(children: &[(NodeRef, Aabb)]) -> Node8 {
        assert!(children.len() <= WIDTH);
        let mut planes = [[f32::INFINITY; WIDTH]; 6];
        for p in &mut planes[HI..] {
            *p = [f32::NEG_INFINITY; WIDTH];
        }
        let mut child = [NodeRef::EMPTY; WIDTH];
        for (i, (r, b)) in children.iter().enumerate() {
            let b = padded(b);
            for axis in 0..3 {
                planes[LO + axis][i] = b.min[axis];
                planes[HI + axis][i] = b.max[axis];
            }
            child[i] = *r;
        }
        Node8 {
            bounds: planes.map(F32x8::new),
            child,
        }
    }

    /// The number of children.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.child.iter().take_while(|c| !c.is_empty()).count()
    }

    /// True when the node has no child (never, in a built tree).
    pub fn is_empty(&self) -> bool {
        self.child[0].is_empty()
    }

    /// The (padded) box of child `i`.
    pub fn child_box(&self, i: usize) -> Aabb {
        let p = |k: usize| self.bounds[k].as_array()[i];
        Aabb {
            min: Vec3::new(p(LO), p(LO + 1), p(LO + 2)),
            max: Vec3::new(p(HI), p(HI + 1), p(HI + 2)),
        }
    }
}

/// An 8-wide BVH: interior nodes and the root reference (a leaf when everything fits in one).
/// Empty when built over no primitive.
///
/// Every interior reference of a tree (the root and each node's children) names one of its
/// nodes: the builder makes only such trees and checks it once more before handing one out
/// (`Bvh8::check_references`), and the fields are private, so nothing changes a tree
/// afterwards. The single-ray walks read nodes by that promise, without bounds checks.
#[derive(Clone, Debug)]
pub struct Bvh8 {
    nodes: Vec<Node8>,
    root: NodeRef,
    /// The box of everything (padded like a child's).
    pub bounds: Aabb,
}

impl Default for Bvh8 {
    fn default() -> Bvh8 {
        Bvh8 {
            nodes: Vec::new(),
            root: NodeRef::EMPTY,
            bounds: Aabb::EMPTY,
        }
    }
}

impl PartialEq for Bvh8 {
    fn eq(&self, o: &Bvh8) -> bool {
        self.root == o.root
            && self.nodes.len() == o.nodes.len()
            && self.nodes.iter().zip(&o.nodes).all(|(a, b)| {
                a.child == b.child
                    && a.bounds.iter().zip(&b.bounds).all(|(x, y)| {
                        x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits)
                    })
            })
    }
}

/// Widens a distance by the relative rounding error of the slab test, in the direction that
/// keeps culling conservative (also for the negative distances of orthographic rays).
#[inline(always)]
fn widen(t: f32) -> f32 {
    t + t.abs() * (ROBUST - 1.0)
}

/// [`widen`] for 8 lanes, in one multiplication's latency: `t * ROBUST` for `t >= 0`, `t * (2 -
/// ROBUST)` below, the larger of the two. `ROBUST - 1` is a power of two, so for normal `t`
/// both products round to the same value as [`widen`]'s sum (its scaled term is exact).
#[inline(always)]
fn widen8(t: F32x8) -> F32x8 {
    crate::simd::max(t * F32x8::splat(ROBUST), t * F32x8::splat(2.0 - ROBUST))
}

/// The widened exit distance of a slab test, where `FORWARD` promises entry distances of at
/// least 0 (`tmin >= 0`, every ray but an orthographic camera's): there a negative exit culls
/// the box however it is widened, so `t * ROBUST`, [`widen8`]'s product for `t >= 0`, decides
/// the same lanes in one multiplication (the exit widening is on the walk's chain of dependent
/// operations: PERF.md, "Widening in one product").
#[inline(always)]
fn widen_exit<const FORWARD: bool>(t: F32x8) -> F32x8 {
    if FORWARD {
        t * F32x8::splat(ROBUST)
    } else {
        widen8(t)
    }
}

/// The reciprocal of a direction component, with zero replaced by a tiny value of the same
/// sign (a zero would give `0 * inf = NaN` in the slab test).
#[inline(always)]
fn safe_inverse(d: f32) -> f32 {
    1.0 / if d.abs() < 1e-30 {
        1e-30f32.copysign(d)
    } else {
        d
    }
}

/// [`safe_inverse`] for 8 lanes (the same bits in every lane).
#[inline(always)]
fn safe_inverse8(d: F32x8) -> F32x8 {
    use crate::simd::{copysign, lt, select};
    let tiny = F32x8::splat(1e-30);
    let small = lt(d.abs(), tiny);
    F32x8::splat(1.0) / select(small, copysign(tiny, d), d)
}

impl Bvh8 {
    /// Starts fetching a child a walk pushes for later: an interior node's bounds (the first
    /// three of its four cache lines), or a leaf's primitives by `touch` (the tree does not
    /// know what its leaves index).
    #[inline(always)]
    fn prefetch(&self, r: NodeRef, touch: &impl Fn(Leaf)) {
        if r.is_leaf() {
            touch(r.as_leaf());
        } else if let Some(n) = self.nodes.get(r.index()) {
            for k in [0, 2, 4] {
                crate::simd::prefetch(&n.bounds[k]);
            }
        }
    }

    /// The interior nodes.
    pub fn nodes(&self) -> &[Node8] {
        &self.nodes
    }

    /// The root reference: a leaf (or the empty slot) when the tree has no interior node.
    pub fn root(&self) -> NodeRef {
        self.root
    }

    /// Asserts that every interior reference names a node of the array: what
    /// [`Bvh8::node_at`] relies on. One pass over the child references (the builder's last
    /// step); a failure is a bug in the builder.
    fn check_references(&self) {
        let inside = |r: &NodeRef| r.is_leaf() || r.index() < self.nodes.len();
        assert!(
            inside(&self.root) && self.nodes.iter().all(|n| n.child.iter().all(inside)),
            "a BVH node references a node outside its tree"
        );
    }

    /// The interior node `r`, read without a bounds check.
    ///
    /// # Safety
    ///
    /// `r` is an interior reference of this tree: its root, or a child reference read from one
    /// of its nodes ([`Bvh8::check_references`] has proved every such reference in bounds).
    #[inline(always)]
    unsafe fn node_at(&self, r: NodeRef) -> &Node8 {
        debug_assert!(!r.is_leaf() && r.index() < self.nodes.len());
        // SAFETY: `r.offset()` is `r.index()` nodes into the array, which holds that node
        unsafe {
            &*self
                .nodes
                .as_ptr()
                .cast::<u8>()
                .add(r.offset())
                .cast::<Node8>()
        }
    }

    /// True when the tree holds nothing.
    pub fn is_empty(&self) -> bool {
        self.root.is_empty()
    }

    /// Interior nodes and leaves.
    pub fn counts(&self) -> (usize, usize) {
        let leaves = self
            .nodes
            .iter()
            .flat_map(|n| n.child.iter())
            .filter(|c| c.is_leaf() && !c.is_empty())
            .count();
        let root_leaf = usize::from(self.root.is_leaf() && !self.root.is_empty());
        (self.nodes.len(), leaves + root_leaf)
    }

    /// Checks the tree's invariants against the primitive bounds and tags it was built over;
    /// `leaf_prims(leaf)` lists the primitives a leaf holds: every primitive in exactly one
    /// leaf, every node reached exactly once within [`MAX_DEPTH`], every child's box inside its
    /// parent's and holding its primitives, children packed first with inverted boxes in the
    /// unused slots, at least two children per node, no leaf mixing tags.
    pub fn validate(
        &self,
        bounds: &[Aabb],
        tags: &[u8],
        leaf_prims: impl Fn(Leaf) -> Vec<u32>,
    ) -> Result<(), String> {
        if bounds.is_empty() {
            return if self.is_empty() && self.nodes.is_empty() {
                Ok(())
            } else {
                Err("a tree without primitives".into())
            };
        }
        if self.is_empty() {
            return Err(format!("no tree over {} primitives", bounds.len()));
        }
        let mut seen = vec![false; bounds.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut check_leaf = |leaf: Leaf, b: &Aabb| -> Result<(), String> {
            let prims = leaf_prims(leaf);
            if prims.is_empty() || prims.len() != leaf.count as usize {
                return Err(format!("leaf {leaf:?} holds {} primitives", prims.len()));
            }
            for p in prims {
                let p = p as usize;
                if p >= bounds.len() {
                    return Err(format!(
                        "leaf {leaf:?} names primitive {p} of {}",
                        bounds.len()
                    ));
                }
                if std::mem::replace(&mut seen[p], true) {
                    return Err(format!("primitive {p} in two leaves"));
                }
                if !b.contains(&bounds[p]) {
                    return Err(format!("leaf {leaf:?}'s box does not hold primitive {p}"));
                }
                if tags[p] != leaf.tag {
                    return Err(format!(
                        "leaf {leaf:?} holds primitive {p} tagged {}",
                        tags[p]
                    ));
                }
            }
            Ok(())
        };
        if self.root.is_leaf() {
            if !self.nodes.is_empty() {
                return Err("a leaf root with interior nodes".into());
            }
            check_leaf(self.root.as_leaf(), &self.bounds)?;
        } else {
            let mut stack = vec![(self.root, self.bounds, 1usize)];
            while let Some((r, b, depth)) = stack.pop() {
                if depth > MAX_DEPTH {
                    return Err(format!("node {} at depth {depth}", r.index()));
                }
                let i = r.index();
                let n = self
                    .nodes
                    .get(i)
                    .ok_or_else(|| format!("node {i} out of range"))?;
                if std::mem::replace(&mut reached[i], true) {
                    return Err(format!("node {i} reached twice"));
                }
                let count = n.len();
                if count < 2 {
                    return Err(format!("node {i} has {count} children"));
                }
                for slot in 0..WIDTH {
                    let (c, cb) = (n.child[slot], n.child_box(slot));
                    if slot >= count {
                        let inverted = cb.min.cmpeq(Vec3::INFINITY).all()
                            && cb.max.cmpeq(Vec3::NEG_INFINITY).all();
                        if !c.is_empty() || !inverted {
                            return Err(format!("node {i}: slot {slot} after the last child"));
                        }
                        continue;
                    }
                    if !b.contains(&cb) {
                        return Err(format!("node {i}'s box does not hold child {slot}"));
                    }
                    if c.is_leaf() {
                        check_leaf(c.as_leaf(), &cb)?;
                    } else {
                        stack.push((c, cb, depth + 1));
                    }
                }
            }
            if let Some(i) = reached.iter().position(|r| !r) {
                return Err(format!("node {i} is not reachable"));
            }
        }
        match seen.iter().position(|s| !s) {
            Some(p) => Err(format!("primitive {p} in no leaf")),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Aabb, Bvh8, Node8, NodeRef, ROBUST, widen, widen8};
    use crate::simd::{F32x8, lanes};
    use crate::test_rng::Rng;

    /// The 8-lane widening (two products and a max) gives the scalar one's value (a sum) for
    /// every sign and scale of distance down to 1e-30 (below, the scalar's scaled term is no
    /// longer exact), zero and `+inf`: the packet, stream and single-ray tests keep culling
    /// what they culled; and at every scale it widens by the relative amount it promises.
    #[test]
    fn the_8_lane_widening_equals_the_scalar_one() {
        assert_eq!(
            (ROBUST - 1.0).to_bits() & 0x007f_ffff,
            0,
            "ROBUST - 1 is a power of two"
        );
        let mut rng = Rng(0x9e37_79b9);
        let mut ts = vec![
            0.0,
            1.0,
            -1.0,
            f32::MAX,
            -f32::MAX,
            f32::MIN_POSITIVE,
            f32::INFINITY,
        ];
        ts.extend((0..40_000).map(|_| {
            let t = 10f64.powf(rng.range64(-37.0, 38.0)) as f32;
            if rng.range64(0.0, 1.0) < 0.5 { -t } else { t }
        }));
        for chunk in ts.chunks(8) {
            let mut t = [0.0f32; 8];
            t[..chunk.len()].copy_from_slice(chunk);
            for (x, w) in t.iter().zip(lanes(widen8(F32x8::new(t)))) {
                assert!(w >= *x, "{x:e} widened to {w:e}");
                if x.abs() >= 1e-30 || *x == 0.0 {
                    assert_eq!(w, widen(*x), "{x:e}");
                }
                // one rounding (half a unit, 2^-24 relative) of the exact product: at least 7/8 of it
                let (x64, c) = (f64::from(*x), f64::from(ROBUST - 1.0));
                if x.is_finite() {
                    assert!(f64::from(w) >= x64 + x64.abs() * c * (7.0 / 8.0), "{x:e}");
                }
            }
        }
    }

    /// A node's reference is its index shifted to a byte offset, both ways, for every index a
    /// builder can hand out.
    #[test]
    fn a_node_reference_is_its_byte_offset() {
        for i in [0, 1, 2, 255, 256, 70_263, u32::MAX - 1, u32::MAX] {
            let r = NodeRef::node(i);
            assert!(!r.is_leaf() && !r.is_empty());
            assert_eq!(r.index(), i as usize);
            assert_eq!(r.offset(), i as usize * size_of::<Node8>());
        }
    }

    /// The check the walks' unchecked reads rest on refuses a tree whose node names a node past
    /// the array's end, or whose root does.
    #[test]
    fn a_reference_outside_the_tree_is_refused() {
        let unit = Aabb {
            min: crate::math::Vec3::ZERO,
            max: crate::math::Vec3::ONE,
        };
        let tree = |child: NodeRef, root: NodeRef| Bvh8 {
            nodes: vec![Node8::new(&[(child, unit)])],
            root,
            bounds: unit,
        };
        let checked = |t: Bvh8| std::panic::catch_unwind(move || t.check_references()).is_ok();
        assert!(checked(tree(NodeRef::EMPTY, NodeRef::node(0))));
        assert!(!checked(tree(NodeRef::node(1), NodeRef::node(0))));
        assert!(!checked(tree(NodeRef::EMPTY, NodeRef::node(1))));
    }
}
