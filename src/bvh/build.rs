//! The binned SAH builder, 8-wide and parallel: primitive bounds and tags in, a [`Bvh8`] out,
//! each leaf stored by the caller's [`LeafSink`] as it is made (the one pass that reorders the
//! primitives into leaf blocks). Embree's recipe (`BVHBuilderBinnedSAH`):
//!
//! - the builder works on 32-byte primitive references (bounds, index, tag) that it partitions
//!   in place, every pass reading memory in order;
//! - one pass bins the centroids on all three axes at once (SSE), with as many bins as the node
//!   deserves (`4 + n / 20`, at most [`MAX_BINS`]); the children's bounds come from the bins
//!   and their centroid bounds and tags from the partition pass, so nothing is scanned twice;
//! - the SAH prices a leaf in blocks of the leaf width ([`BuildSettings::block`]), as the
//!   leaves are stored;
//! - a node opens up to 8 children by splitting, again and again, the child with the largest
//!   area (children sorted by area, largest first);
//! - nodes come from one pre-sized [`Arena`]; big nodes bin and partition in parallel chunks,
//!   and subtrees over many primitives are built in parallel (rayon), so no phase is serial.
//!
//! Every primitive carries a tag (its kind, opaque here): a leaf never mixes tags. The tree
//! does not depend on the thread count: binning and partitioning are by value, and leaves list
//! their primitives sorted.

use glam::{BVec4A, Vec4};
use rayon::prelude::*;

use super::arena::Arena;
use super::{Aabb, Bvh8, Leaf, MAX_DEPTH, Node8, NodeRef, WIDTH, padded};
use crate::simd::{F32x8, join_halves, min, split_halves, trunc3};

/// The most bins per axis.
pub const MAX_BINS: usize = 32;

/// Subtrees over more primitives than this are built in parallel.
const PARALLEL_SUBTREE: usize = 4096;

/// Nodes over more primitives than this bin and partition in parallel chunks of this size (and
/// the references are made and first bounded so); on one thread, the size of every pass's chunks.
const PARALLEL_PASS: usize = 1 << 16;

/// With more than one thread, the references are made and first bounded, and nodes bin and
/// partition, in chunks of this size: the top node of a mesh of tens of thousands of triangles
/// (the course's 40k bunny) is then shared out too, not only the subtrees below it. One thread
/// keeps [`PARALLEL_PASS`]: these chunks cost it 2–4% of a torus build (the partition's swaps
/// across the chunks; PERF.md, sitting 21). The tree is the same either way, as binning and
/// partitioning are by value.
const PARALLEL_PASS_SHARED: usize = 1 << 12;

/// Where the builder puts leaves: the caller turns a group of primitives into its leaf storage.
pub trait LeafSink: Sync {
    /// Stores the primitives `prims` (all tagged `tag`, sorted ascending) as one leaf and
    /// returns the leaf's first index ([`Leaf::first`]; its `count` is `prims.len()`).
    fn leaf(&self, tag: u8, prims: &[u32]) -> u32;
}

/// The builder's knobs (see PERF.md for how they were chosen).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildSettings {
    /// The leaf width: the SAH prices a leaf of `n` primitives as `ceil(n / block)` blocks.
    pub block: usize,
    /// Primitives at or below this count (of one tag) always make a leaf.
    pub min_leaf: usize,
    /// The most primitives a leaf holds, unless no split separates them.
    pub max_leaf: usize,
    /// Cost of visiting a node relative to intersecting one block.
    pub traversal_cost: f32,
    /// Bins per axis for big nodes (at most [`MAX_BINS`]).
    pub max_bins: usize,
}

impl Default for BuildSettings {
    fn default() -> BuildSettings {
        BuildSettings {
            block: 4,
            min_leaf: 4,
            max_leaf: 12,
            traversal_cost: 2.0,
            max_bins: MAX_BINS,
        }
    }
}

/// A primitive reference: bounds with the index in `min.w` and the tag in `max.w` (as bits).
///
/// As floats those bits are denormal (or zero), and arithmetic on denormals is slow on some
/// CPUs (AMD Zen 5 takes a microcode assist: the whole build ran 1.6-3x slower). So the w
/// lanes take part in `min`/`max` only, never in arithmetic: [`PrimRef::centroid2`] and
/// [`Box4::half_area`] clear them first ([`XYZ`]).
#[derive(Clone, Copy)]
struct PrimRef {
    min: Vec4,
    max: Vec4,
}

impl PrimRef {
    #[inline(always)]
    fn id(&self) -> u32 {
        self.min.w.to_bits()
    }

    #[inline(always)]
    fn tag(&self) -> u32 {
        self.max.w.to_bits()
    }

    /// Twice the centroid (the factor cancels out in binning), w = 0.
    #[inline(always)]
    fn centroid2(&self) -> Vec4 {
        xyz(self.min) + xyz(self.max)
    }
}

/// The lanes that hold coordinates.
const XYZ: BVec4A = BVec4A::new(true, true, true, false);

/// `v` with w = 0 (one blend): what arithmetic may read of a [`PrimRef`] or [`Box4`] lane.
#[inline(always)]
fn xyz(v: Vec4) -> Vec4 {
    Vec4::select(XYZ, v, Vec4::ZERO)
}

/// Bounds as two `Vec4` (w ignored, and not read by arithmetic: it may hold a reference's
/// index and tag bits), for fast unions.
#[derive(Clone, Copy)]
struct Box4 {
    min: Vec4,
    max: Vec4,
}

impl Box4 {
    const EMPTY: Box4 = Box4 {
        min: Vec4::splat(f32::INFINITY),
        max: Vec4::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, min: Vec4, max: Vec4) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
    }

    #[inline(always)]
    fn union(&self, o: &Box4) -> Box4 {
        Box4 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    fn half_area(&self) -> f32 {
        let d = (xyz(self.max) - xyz(self.min)).max(Vec4::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.min.truncate(),
            max: self.max.truncate(),
        }
    }

    /// The box a bin holds ([`bin_bounds`] undone).
    #[inline(always)]
    fn of_bin(b: F32x8) -> Box4 {
        let (min, neg_max) = split_halves(b);
        Box4 { min, max: -neg_max }
    }
}

/// Bounds as a bin holds them: the minimum in lanes 0–3 and the negated maximum in lanes 4–7,
/// so that the union of two is one 8-lane `min` (the empty box: [`empty_bin`]).
/// Negation flips sign bits only: exact, and no arithmetic on the w lanes' index and tag bits
/// ([`PrimRef`]), so [`Box4::of_bin`] gives back the very bounds.
#[inline(always)]
fn bin_bounds(min: Vec4, max: Vec4) -> F32x8 {
    join_halves(min, -max)
}

/// The empty box as a bin holds it: [`Box4::EMPTY`] through [`bin_bounds`] (+infinity in
/// every lane).
#[inline(always)]
fn empty_bin() -> F32x8 {
    bin_bounds(Box4::EMPTY.min, Box4::EMPTY.max)
}

/// What a node's builder knows of its primitives: bounds, centroid bounds (doubled), and the
/// set of tags (bit `t` = tag `t` present).
#[derive(Clone, Copy)]
struct Record {
    bounds: Box4,
    centroids: Box4,
    tags: u32,
}

impl Record {
    const EMPTY: Record = Record {
        bounds: Box4::EMPTY,
        centroids: Box4::EMPTY,
        tags: 0,
    };

    /// Adds a reference; its bounds only if `BOUNDS` (a split already knows its sides'
    /// bounds from the bins).
    #[inline(always)]
    fn add<const BOUNDS: bool>(&mut self, r: &PrimRef) {
        if BOUNDS {
            self.bounds.grow(r.min, r.max);
        }
        let c = r.centroid2();
        self.centroids.grow(c, c);
        self.tags |= 1 << r.tag();
    }

    fn merge(mut self, o: &Record) -> Record {
        self.bounds = self.bounds.union(&o.bounds);
        self.centroids = self.centroids.union(&o.centroids);
        self.tags |= o.tags;
        self
    }

    /// The record of `refs`, over more than `pass` of them in parallel chunks of `pass` (the
    /// same record either way: bounds and tags do not depend on the order they are met in).
    fn of(refs: &[PrimRef], pass: usize) -> Record {
        if refs.len() > pass {
            return refs
                .par_chunks(pass)
                .map(|c| Record::of(c, pass))
                .reduce(|| Record::EMPTY, |a, b| a.merge(&b));
        }
        let mut r = Record::EMPTY;
        for p in refs {
            r.add::<true>(p);
        }
        r
    }
}

/// Builds a BVH over `n` primitives, primitive `i` having bounds and tag `prim(i)` (tags below
/// 32); `sink` stores the leaves.
pub fn build(
    n: usize,
    prim: impl Fn(usize) -> (Aabb, u8) + Sync,
    settings: &BuildSettings,
    sink: &impl LeafSink,
) -> Bvh8 {
    assert!(n < u32::MAX as usize, "too many primitives for one BVH");
    if n == 0 {
        return Bvh8::default();
    }
    let make = |i: usize| {
        let (b, tag) = prim(i);
        assert!(tag < 32, "primitive tags are below 32");
        PrimRef {
            min: b.min.extend(f32::from_bits(i as u32)),
            max: b.max.extend(f32::from_bits(tag as u32)),
        }
    };
    let pass = if rayon::current_num_threads() > 1 {
        PARALLEL_PASS_SHARED
    } else {
        PARALLEL_PASS
    };
    let mut refs: Vec<PrimRef> = if n > pass {
        (0..n)
            .into_par_iter()
            .with_min_len(PARALLEL_PASS_SHARED)
            .map(make)
            .collect()
    } else {
        (0..n).map(make).collect()
    };
    let rec = Record::of(&refs, pass);
    // A tree over n primitives has fewer than n interior nodes (each has two children or more).
    let builder = Builder {
        settings: BuildSettings {
            max_bins: settings.max_bins.clamp(2, MAX_BINS),
            block: settings.block.max(1),
            ..*settings
        },
        nodes: Arena::with_capacity(n),
        sink,
        ordered: in_spatial_order(&refs, &rec),
        pass,
    };
    let root = builder.subtree(&mut refs, rec, 1, &mut Search::new());
    let tree = Bvh8 {
        nodes: builder.nodes.into_vec(),
        root,
        bounds: padded(&rec.bounds.aabb()),
    };
    tree.check_references();
    tree
}

/// A child being opened: its references' range and record; `open` until it is known not to
/// split further.
#[derive(Clone, Copy)]
struct Child {
    start: usize,
    len: usize,
    rec: Record,
    open: bool,
}

impl Child {
    fn new(start: usize, len: usize, rec: Record) -> Child {
        Child {
            start,
            len,
            rec,
            open: true,
        }
    }
}

struct Builder<'s, S: LeafSink> {
    settings: BuildSettings,
    nodes: Arena<Node8>,
    sink: &'s S,
    /// The references came in spatial order ([`in_spatial_order`]): partitions may branch.
    ordered: bool,
    /// Nodes over more references than this bin and partition in parallel chunks of this size
    /// ([`PARALLEL_PASS`] on one thread, [`PARALLEL_PASS_SHARED`] on more).
    pass: usize,
}

/// A split: the axis and bin boundary (everything in a lower bin goes left), the children's
/// bounds and the left count, and the SAH cost of the children (area times blocks).
#[derive(Clone, Copy)]
struct Split {
    axis: usize,
    boundary: usize,
    mapping: Mapping,
    cost: f32,
    left: Box4,
    right: Box4,
}

/// How centroids map to bins: `nb` bins spanning the centroid bounds on each axis.
#[derive(Clone, Copy)]
struct Mapping {
    nb: usize,
    lo: Vec4,
    scale: Vec4,
}

impl Mapping {
    fn new(centroids: &Box4, n: usize, max_bins: usize) -> Mapping {
        let nb = (4 + n / 20).min(max_bins);
        let extent = centroids.max - centroids.min;
        let s = Vec4::splat(nb as f32 * (1.0 - 1e-6)) / extent;
        Mapping {
            nb,
            lo: centroids.min,
            scale: Vec4::select(extent.cmpgt(Vec4::ZERO), s, Vec4::ZERO),
        }
    }

    /// The bin of a (doubled) centroid on each axis.
    #[inline(always)]
    fn bins(&self, c: Vec4) -> [usize; 3] {
        let b = ((c - self.lo) * self.scale).clamp(Vec4::ZERO, Vec4::splat((self.nb - 1) as f32));
        trunc3(b)
    }
}

/// Bin counts and bounds per axis, the bounds as [`bin_bounds`] gives them: growing a bin by a
/// reference is one `min` and one store, not two of each.
#[derive(Clone)]
struct Bins {
    counts: [[u32; MAX_BINS]; 3],
    boxes: [[F32x8; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Bins {
        Bins {
            counts: [[0; MAX_BINS]; 3],
            boxes: [[empty_bin(); MAX_BINS]; 3],
        }
    }

    fn clear(&mut self, nb: usize) {
        for axis in 0..3 {
            self.counts[axis][..nb].fill(0);
            self.boxes[axis][..nb].fill(empty_bin());
        }
    }

    /// Adds every reference on each axis the centroids span, two at a time (independent
    /// updates overlap). An axis where every centroid coincides (scale 0: the sweep skips it)
    /// is not binned: all its references would land in one bin, one dependent update after
    /// another. The loop is instantiated for each set of axes, so it does not ask per
    /// reference which axes to bin.
    #[inline(always)]
    fn add_all(&mut self, refs: &[PrimRef], m: &Mapping) {
        match m.scale.truncate().cmpne(glam::Vec3::ZERO).bitmask() {
            0b111 => self.add_axes::<0b111>(refs, m),
            0b101 => self.add_axes::<0b101>(refs, m),
            0b011 => self.add_axes::<0b011>(refs, m),
            0b110 => self.add_axes::<0b110>(refs, m),
            0b001 => self.add_axes::<0b001>(refs, m),
            0b010 => self.add_axes::<0b010>(refs, m),
            0b100 => self.add_axes::<0b100>(refs, m),
            _ => {}
        }
    }

    /// [`Bins::add_all`] on the axes of `LIVE` (bit `axis`).
    #[inline(always)]
    fn add_axes<const LIVE: u32>(&mut self, refs: &[PrimRef], m: &Mapping) {
        let mut add = |r: &PrimRef, b: [usize; 3]| {
            let bounds = bin_bounds(r.min, r.max);
            for (axis, b) in b.into_iter().enumerate() {
                if LIVE >> axis & 1 == 0 {
                    continue;
                }
                // (the mask only tells the compiler the index is in range)
                let b = b & (MAX_BINS - 1);
                self.counts[axis][b] += 1;
                self.boxes[axis][b] = min(self.boxes[axis][b], bounds);
            }
        };
        let mut pairs = refs.chunks_exact(2);
        for pair in &mut pairs {
            let (a, b) = (&pair[0], &pair[1]);
            let (ba, bb) = (m.bins(a.centroid2()), m.bins(b.centroid2()));
            add(a, ba);
            add(b, bb);
        }
        for r in pairs.remainder() {
            add(r, m.bins(r.centroid2()));
        }
    }

    fn merge(&mut self, o: &Bins, nb: usize) {
        for axis in 0..3 {
            for b in 0..nb {
                self.counts[axis][b] += o.counts[axis][b];
                self.boxes[axis][b] = min(self.boxes[axis][b], o.boxes[axis][b]);
            }
        }
    }
}

/// What one thread's split searches reuse from node to node: the bins, and the SAH sweep's
/// arrays (kept here so that a search does not first fill a kilobyte of stack).
struct Search {
    bins: Bins,
    /// Area times blocks of everything right of each boundary (one axis at a time).
    right_cost: [f32; MAX_BINS],
    /// The bounds of everything right of each boundary (one axis at a time).
    right_box: [Box4; MAX_BINS],
}

impl Search {
    fn new() -> Search {
        Search {
            bins: Bins::new(),
            right_cost: [0.0; MAX_BINS],
            right_box: [Box4::EMPTY; MAX_BINS],
        }
    }
}

impl<S: LeafSink> Builder<'_, S> {
    /// Blocks a leaf of `n` primitives takes.
    #[inline(always)]
    fn blocks(&self, n: u32) -> f32 {
        blocks_of(n, self.settings.block as u32) as f32
    }

    /// The cheapest binned split of `refs` by SAH, or `None` when every centroid coincides.
    fn find(&self, refs: &[PrimRef], rec: &Record, search: &mut Search) -> Option<Split> {
        let m = Mapping::new(&rec.centroids, refs.len(), self.settings.max_bins);
        if m.scale.truncate() == glam::Vec3::ZERO {
            return None;
        }
        let nb = m.nb;
        let Search {
            bins,
            right_cost,
            right_box,
        } = search;
        if refs.len() > self.pass {
            *bins = refs
                .par_chunks(self.pass)
                .map(|chunk| {
                    let mut b = Bins::new();
                    b.add_all(chunk, &m);
                    b
                })
                .reduce(Bins::new, |mut a, b| {
                    a.merge(&b, nb);
                    a
                });
        } else {
            bins.clear(nb);
            bins.add_all(refs, &m);
        }
        let mut best: Option<Split> = None;
        for axis in 0..3 {
            if m.scale[axis] == 0.0 {
                continue;
            }
            let (counts, boxes) = (&bins.counts[axis], &bins.boxes[axis]);
            // Sweep from the right: area times blocks of everything right of each boundary.
            let mut acc = Box4::EMPTY;
            let mut n = 0;
            for i in (1..nb).rev() {
                acc = acc.union(&Box4::of_bin(boxes[i]));
                n += counts[i];
                right_box[i] = acc;
                right_cost[i] = if n == 0 {
                    f32::INFINITY
                } else {
                    acc.half_area() * self.blocks(n)
                };
            }
            let mut acc = Box4::EMPTY;
            let mut n = 0;
            for i in 1..nb {
                acc = acc.union(&Box4::of_bin(boxes[i - 1]));
                n += counts[i - 1];
                // an empty right side costs infinity
                let cost = acc.half_area() * self.blocks(n) + right_cost[i];
                if n > 0 && cost < f32::INFINITY && best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Split {
                        axis,
                        boundary: i,
                        mapping: m,
                        cost,
                        left: acc,
                        right: right_box[i],
                    });
                }
            }
        }
        best
    }

    /// Partitions `refs` by `split` (or, without one, by tag or into halves); returns the
    /// position of the first right reference and the two sides' records.
    fn partition(
        &self,
        refs: &mut [PrimRef],
        rec: &Record,
        split: Option<&Split>,
    ) -> (usize, Record, Record) {
        let mid_rec = |refs: &[PrimRef], mid: usize| {
            let (l, r) = refs.split_at(mid);
            (mid, Record::of(l, self.pass), Record::of(r, self.pass))
        };
        match split {
            Some(s) => {
                // `m.bins(c)[axis] < boundary`, the bin's index below the boundary, without
                // the clamp and the conversion: for a boundary in 1..nb the scaled centroid is
                // below it exactly when its clamped integer part is (the same decisions). In
                // the vector lanes, not read out as a scalar: the same centroid serves the
                // side's record, and no lane is picked by a run-time index (PERF.md, sitting 20)
                let (axis, m) = (s.axis, s.mapping);
                debug_assert!((1..m.nb).contains(&s.boundary));
                let boundary = Vec4::splat(s.boundary as f32);
                let goes_left = |r: &PrimRef| {
                    ((r.centroid2() - m.lo) * m.scale).cmplt(boundary).bitmask() >> axis & 1 == 1
                };
                let (mid, mut l, mut r) =
                    partition_by::<false>(refs, &goes_left, self.ordered, self.pass);
                (l.bounds, r.bounds) = (s.left, s.right);
                (mid, l, r)
            }
            None if rec.tags.count_ones() > 1 => {
                let tag = rec.tags.trailing_zeros();
                partition_by::<true>(refs, &|r: &PrimRef| r.tag() == tag, self.ordered, self.pass)
            }
            None => {
                // Every centroid coincides: halves, in index order so the tree is the same
                // whatever order the parallel passes left the references in.
                refs.sort_unstable_by_key(PrimRef::id);
                let mid = refs.len() / 2;
                mid_rec(refs, mid)
            }
        }
    }

    /// Builds the subtree over `refs` as a node at `depth` (the root is at 1), or a leaf.
    fn subtree(
        &self,
        refs: &mut [PrimRef],
        rec: Record,
        depth: usize,
        search: &mut Search,
    ) -> NodeRef {
        let n = refs.len();
        let single = rec.tags.count_ones() == 1;
        if single && (n <= self.settings.min_leaf || depth > MAX_DEPTH || n == 1) {
            return self.leaf(refs);
        }
        // A leaf that costs no more than a node's traversal alone beats every split (whose
        // cost adds its children's, at least 0, to that traversal): the leaf the comparison
        // below would make, without binning for it first.
        if single
            && n <= self.settings.max_leaf
            && self.blocks(n as u32) <= self.settings.traversal_cost
        {
            return self.leaf(refs);
        }
        // at the depth limit only kinds are separated
        let split = if depth >= MAX_DEPTH {
            None
        } else {
            self.find(refs, &rec, search)
        };
        if single && n <= self.settings.max_leaf {
            let area = rec.bounds.half_area();
            let leaf_cost = area * self.blocks(n as u32);
            let split_cost = split.map_or(f32::INFINITY, |s| {
                self.settings.traversal_cost * area + s.cost
            });
            if leaf_cost <= split_cost {
                return self.leaf(refs);
            }
        }
        if single && depth >= MAX_DEPTH {
            return self.leaf(refs);
        }
        // Open up to WIDTH children: split the first, then the largest splittable child.
        let mut children = [Child {
            start: 0,
            len: 0,
            rec: Record::EMPTY,
            open: false,
        }; WIDTH];
        let (mid, l, r) = self.partition(refs, &rec, split.as_ref());
        children[0] = Child::new(0, mid, l);
        children[1] = Child::new(mid, n - mid, r);
        let mut count = 2;
        while count < WIDTH {
            let mut pick = None;
            let mut best_area = f32::NEG_INFINITY;
            for (k, c) in children[..count].iter().enumerate() {
                let splittable = c.len > self.settings.min_leaf || c.rec.tags.count_ones() > 1;
                if c.open && splittable && c.rec.bounds.half_area() > best_area {
                    (pick, best_area) = (Some(k), c.rec.bounds.half_area());
                }
            }
            let Some(k) = pick else {
                break;
            };
            let Child {
                start,
                len,
                rec: crec,
                ..
            } = children[k];
            let part = &mut refs[start..start + len];
            // at the depth limit only kinds are separated
            let s = if depth >= MAX_DEPTH {
                None
            } else {
                self.find(part, &crec, search)
            };
            if s.is_none()
                && crec.tags.count_ones() == 1
                && (len <= self.settings.max_leaf || depth >= MAX_DEPTH)
            {
                children[k].open = false;
                continue;
            }
            let (m, cl, cr) = self.partition(part, &crec, s.as_ref());
            children[k] = Child::new(start, m, cl);
            children[count] = Child::new(start + m, len - m, cr);
            count += 1;
        }
        let children = &mut children[..count];
        let index = self.nodes.alloc(1);
        // Largest child first (Embree: faster any-hit traversal).
        children.sort_unstable_by(|a, b| {
            b.rec
                .bounds
                .half_area()
                .total_cmp(&a.rec.bounds.half_area())
        });
        let mut kids = [(NodeRef::EMPTY, Aabb::EMPTY); WIDTH];
        if n > PARALLEL_SUBTREE {
            // disjoint slices of the references, one per child, for parallel subtrees
            let mut order: Vec<usize> = (0..count).collect();
            order.sort_by_key(|&i| children[i].start);
            let mut slices: Vec<(usize, &mut [PrimRef])> = Vec::with_capacity(count);
            let mut rest = &mut refs[..];
            let mut at = 0;
            for &i in &order {
                let Child { start, len, .. } = children[i];
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(start - at + len);
                slices.push((i, &mut head[start - at..]));
                rest = tail;
                at = start + len;
            }
            let built: Vec<(usize, NodeRef)> = slices
                .into_par_iter()
                .map(|(i, s)| {
                    (
                        i,
                        self.subtree(s, children[i].rec, depth + 1, &mut Search::new()),
                    )
                })
                .collect();
            for (i, r) in built {
                kids[i] = (r, children[i].rec.bounds.aabb());
            }
        } else {
            for (kid, c) in kids.iter_mut().zip(children.iter()) {
                let part = &mut refs[c.start..c.start + c.len];
                *kid = (
                    self.subtree(part, c.rec, depth + 1, search),
                    c.rec.bounds.aabb(),
                );
            }
        }
        self.nodes.set(index, Node8::new(&kids[..count]));
        NodeRef::node(index as u32)
    }

    /// A leaf over `refs` (one tag), stored by the sink.
    fn leaf(&self, refs: &[PrimRef]) -> NodeRef {
        assert!(
            refs.len() <= NodeRef::MAX_LEAF_COUNT as usize,
            "{} coincident primitives in one leaf",
            refs.len()
        );
        let tag = refs[0].tag() as u8;
        let mut small = [0u32; 16];
        let mut big = Vec::new();
        let ids: &mut [u32] = if refs.len() <= small.len() {
            &mut small[..refs.len()]
        } else {
            big.resize(refs.len(), 0);
            &mut big
        };
        for (id, r) in ids.iter_mut().zip(refs) {
            *id = r.id();
        }
        ids.sort_unstable();
        let first = self.sink.leaf(tag, ids);
        NodeRef::leaf(Leaf {
            tag,
            first,
            count: refs.len() as u32,
        })
    }
}

/// `n.div_ceil(block)` (`block` at least 1), by a shift for the usual widths: the SAH sweep
/// prices every bin boundary, and its `div` there showed in a profile of the build (PERF.md,
/// sitting 41, gives what the shift was measured to save).
#[inline(always)]
fn blocks_of(n: u32, block: u32) -> u32 {
    if block.is_power_of_two() {
        (n >> block.trailing_zeros()) + u32::from(n & (block - 1) != 0)
    } else {
        n.div_ceil(block)
    }
}

/// Partitions `refs` so those `goes_left` come first; returns the split position and the two
/// sides' records (gathered on the way; their bounds only if `BOUNDS`). Ranges over `pass`
/// references partition in parallel chunks of `pass`, then swap the misplaced references across
/// the split position.
fn partition_by<const BOUNDS: bool>(
    refs: &mut [PrimRef],
    goes_left: &(impl Fn(&PrimRef) -> bool + Sync),
    ordered: bool,
    pass: usize,
) -> (usize, Record, Record) {
    if refs.len() <= pass {
        return partition_serial::<BOUNDS>(refs, goes_left, ordered);
    }
    let parts: Vec<(usize, Record, Record)> = refs
        .par_chunks_mut(pass)
        .map(|c| partition_serial::<BOUNDS>(c, goes_left, ordered))
        .collect();
    let mid: usize = parts.iter().map(|p| p.0).sum();
    let (mut l, mut r) = (Record::EMPTY, Record::EMPTY);
    // Right references left of `mid` and left references right of it, chunk by chunk.
    let mut wrong_right = Vec::new();
    let mut wrong_left = Vec::new();
    for (k, p) in parts.iter().enumerate() {
        l = l.merge(&p.1);
        r = r.merge(&p.2);
        let start = k * pass;
        let end = (start + pass).min(refs.len());
        let split = start + p.0;
        if split < mid {
            wrong_right.push(split..end.min(mid));
        }
        if start.max(mid) < split {
            wrong_left.push(start.max(mid)..split);
        }
    }
    let a = wrong_right.into_iter().flatten();
    let b = wrong_left.into_iter().flatten();
    for (i, j) in a.zip(b) {
        refs.swap(i, j);
    }
    (mid, l, r)
}

/// [`partition_by`] on one thread, by the scheme [`in_spatial_order`] chose for the build.
/// Both give the same two sets.
fn partition_serial<const BOUNDS: bool>(
    refs: &mut [PrimRef],
    goes_left: &impl Fn(&PrimRef) -> bool,
    ordered: bool,
) -> (usize, Record, Record) {
    if ordered {
        partition_branchy::<BOUNDS>(refs, goes_left)
    } else {
        partition_branchless::<BOUNDS>(refs, goes_left)
    }
}

/// How many references, from the first, [`in_spatial_order`] looks at.
const ORDER_SAMPLE: usize = 256;

/// Whether the references come in spatial order: whether at least 3 in 4 of the first
/// [`ORDER_SAMPLE`] are within 1/16 of the centroids' extent (on every axis) of the one before.
/// Then a branch on each reference's side is well predicted and [`partition_branchy`] is the
/// fastest partition (generated meshes, grids of spheres: spheres4096 builds 12% faster than
/// with the other). Where they come in no order, as in the course's meshes, that branch
/// mispredicts on every other reference and [`partition_branchless`] is 1.7x faster
/// (the 40,000-triangle bunny: 11.0–11.4 against 6.5–6.6 ms). One choice per build, as sampling at every
/// node cost as much as it saved.
///
/// Fewer than [`ORDER_SAMPLE`] references count as ordered: too few to tell, and a build that
/// small takes microseconds either way (spheres64, 66 references a little apart: 4.2 µs
/// branchy, 4.8 µs without the branch).
fn in_spatial_order(refs: &[PrimRef], rec: &Record) -> bool {
    if refs.len() < ORDER_SAMPLE {
        return true;
    }
    let extent = xyz(rec.centroids.max - rec.centroids.min).max_element();
    let reach = extent / 16.0;
    let near = refs[..ORDER_SAMPLE]
        .windows(2)
        .filter(|w| (w[1].centroid2() - w[0].centroid2()).abs().max_element() <= reach)
        .count();
    4 * near >= 3 * (ORDER_SAMPLE - 1)
}

/// From both ends: only misplaced pairs are swapped, the records gathered on the way.
fn partition_branchy<const BOUNDS: bool>(
    refs: &mut [PrimRef],
    goes_left: &impl Fn(&PrimRef) -> bool,
) -> (usize, Record, Record) {
    let (mut l, mut r) = (Record::EMPTY, Record::EMPTY);
    let mut i = 0;
    let mut j = refs.len();
    loop {
        while i < j && goes_left(&refs[i]) {
            l.add::<BOUNDS>(&refs[i]);
            i += 1;
        }
        while i < j && !goes_left(&refs[j - 1]) {
            r.add::<BOUNDS>(&refs[j - 1]);
            j -= 1;
        }
        if i >= j {
            return (i, l, r);
        }
        // refs[i] goes right and refs[j - 1] left
        r.add::<BOUNDS>(&refs[i]);
        l.add::<BOUNDS>(&refs[j - 1]);
        refs.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// With no branch on a reference's side: each reference is swapped to the end of the left
/// part, which grows by one when it goes left (Lomuto's scheme, the side taken as an integer);
/// the two sides' records are gathered afterwards, one straight pass over each.
fn partition_branchless<const BOUNDS: bool>(
    refs: &mut [PrimRef],
    goes_left: &impl Fn(&PrimRef) -> bool,
) -> (usize, Record, Record) {
    let mut mid = 0;
    for k in 0..refs.len() {
        let left = goes_left(&refs[k]);
        // refs[mid..k] all go right: swapping one of them to k keeps that true
        refs.swap(mid, k);
        mid += usize::from(left);
    }
    let (l, r) = refs.split_at(mid);
    let (mut lr, mut rr) = (Record::EMPTY, Record::EMPTY);
    for p in l {
        lr.add::<BOUNDS>(p);
    }
    for p in r {
        rr.add::<BOUNDS>(p);
    }
    (mid, lr, rr)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reference to primitive `id` (tag 3) with the given bounds: its w lanes hold denormals.
    fn prim_ref(id: u32, min: [f32; 3], max: [f32; 3]) -> PrimRef {
        PrimRef {
            min: Vec4::from((glam::Vec3::from(min), f32::from_bits(id))),
            max: Vec4::from((glam::Vec3::from(max), f32::from_bits(3))),
        }
    }

    /// A sink that keeps each leaf's primitives.
    #[derive(Default)]
    struct RecordingSink(std::sync::Mutex<Vec<Vec<u32>>>);

    impl RecordingSink {
        fn leaves(self) -> Vec<Vec<u32>> {
            self.0.into_inner().unwrap()
        }
    }

    impl LeafSink for RecordingSink {
        fn leaf(&self, _tag: u8, prims: &[u32]) -> u32 {
            let mut v = self.0.lock().unwrap();
            v.push(prims.to_vec());
            v.len() as u32 - 1
        }
    }

    /// `n` unit boxes, the first ones along a line in x (spatial order), or shuffled.
    fn line_of_refs(n: usize, shuffled: bool) -> Vec<PrimRef> {
        let mut refs: Vec<PrimRef> = (0..n)
            .map(|i| {
                let x = i as f32;
                prim_ref(i as u32, [x, 0.0, 0.0], [x + 1.0, 1.0, 1.0])
            })
            .collect();
        if shuffled {
            let mut rng = crate::test_rng::Rng(0x9e37_79b9);
            for i in (1..n).rev() {
                let j = (rng.range(0.0, 1.0) * (i + 1) as f32) as usize;
                refs.swap(i, j.min(i));
            }
        }
        refs
    }

    /// A record's fields as plain values, to compare two records.
    fn record_key(r: &Record) -> ([[f32; 4]; 4], u32) {
        let v = |a: Vec4| xyz(a).to_array();
        let (b, c) = (&r.bounds, &r.centroids);
        ([v(b.min), v(b.max), v(c.min), v(c.max)], r.tags)
    }

    #[test]
    fn bins_hold_boxes_exactly_and_unite_them_by_one_min() {
        let boxes = [
            prim_ref(3, [-1.0, 0.0, 2.0], [1.0, 0.5, 3.0]),
            prim_ref(9, [-0.0, -4.0, 1.0], [0.0, -1.0, 8.0]),
            prim_ref(1, [2.0, -2.0, -6.0], [2.5, 7.0, -5.0]),
        ];
        let bits = |b: &Box4| {
            let v = |a: Vec4| xyz(a).to_array().map(f32::to_bits);
            (v(b.min), v(b.max))
        };
        let mut united = Box4::EMPTY;
        let mut bin = empty_bin();
        assert_eq!(bits(&Box4::of_bin(bin)), bits(&Box4::EMPTY));
        for r in &boxes {
            let b = Box4::of_bin(bin_bounds(r.min, r.max));
            assert_eq!(
                bits(&b),
                bits(&Box4 {
                    min: r.min,
                    max: r.max
                })
            );
            united.grow(r.min, r.max);
            bin = min(bin, bin_bounds(r.min, r.max));
            assert_eq!(bits(&Box4::of_bin(bin)), bits(&united));
        }
        assert_eq!(Box4::of_bin(bin).aabb(), united.aabb());
    }

    #[test]
    fn blocks_of_is_the_rounded_up_quotient_for_every_width() {
        let counts = (0..200).chain([u32::MAX - 1, u32::MAX, 1 << 31, (1 << 31) + 1]);
        for n in counts {
            for block in 1..=17 {
                assert_eq!(
                    blocks_of(n, block),
                    n.div_ceil(block),
                    "n {n}, block {block}"
                );
            }
        }
    }

    #[test]
    fn both_partition_schemes_give_the_same_sides_and_records() {
        for n in [0, 1, 2, 3, 17, 64, 129, 1000] {
            for shuffled in [false, true] {
                for cut in [0.0, 0.3, 0.5, 0.9, 2.0] {
                    let boundary = cut * n as f32;
                    let goes_left = |r: &PrimRef| r.min.x < boundary;
                    let mut a = line_of_refs(n, shuffled);
                    let mut b = a.clone();
                    let (ma, la, ra) = partition_branchy::<true>(&mut a, &goes_left);
                    let (mb, lb, rb) = partition_branchless::<true>(&mut b, &goes_left);
                    let case = format!("n {n}, shuffled {shuffled}, cut {cut}");
                    assert_eq!(ma, mb, "{case}");
                    assert!(a[..ma].iter().all(goes_left), "{case}");
                    assert!(!b[mb..].iter().any(goes_left), "{case}");
                    let ids = |s: &[PrimRef]| {
                        let mut v: Vec<u32> = s.iter().map(PrimRef::id).collect();
                        v.sort_unstable();
                        v
                    };
                    assert_eq!(ids(&a[..ma]), ids(&b[..mb]), "{case}");
                    assert_eq!(ids(&a[ma..]), ids(&b[mb..]), "{case}");
                    if ma > 0 && ma < n {
                        assert_eq!(record_key(&la), record_key(&lb), "{case}");
                        assert_eq!(record_key(&ra), record_key(&rb), "{case}");
                    }
                }
            }
        }
    }

    #[test]
    fn spatial_order_is_told_from_no_order() {
        for n in [300, 5000] {
            let ordered = line_of_refs(n, false);
            assert!(
                in_spatial_order(&ordered, &Record::of(&ordered, PARALLEL_PASS)),
                "n {n}"
            );
            let shuffled = line_of_refs(n, true);
            assert!(
                !in_spatial_order(&shuffled, &Record::of(&shuffled, PARALLEL_PASS)),
                "n {n}"
            );
        }
    }

    #[test]
    fn the_tree_is_the_same_whichever_partition_scheme_runs() {
        // the same boxes, in order and shuffled: the builder takes each scheme once
        let trees: Vec<String> = [false, true]
            .into_iter()
            .map(|shuffled| {
                let refs = line_of_refs(3000, shuffled);
                assert_eq!(
                    in_spatial_order(&refs, &Record::of(&refs, PARALLEL_PASS)),
                    !shuffled
                );
                let order: Vec<(u32, f32)> = refs.iter().map(|r| (r.id(), r.min.y)).collect();
                let sink = RecordingSink::default();
                let bvh = build(
                    order.len(),
                    |i| {
                        let (id, y) = order[i];
                        let x = id as f32;
                        (
                            Aabb {
                                min: glam::Vec3::new(x, y, 0.0),
                                max: glam::Vec3::new(x + 1.0, y + 1.0, 1.0),
                            },
                            0,
                        )
                    },
                    &BuildSettings::default(),
                    &sink,
                );
                // leaves as sets of the boxes' own ids, so the input order does not show
                let mut leaves: Vec<Vec<u32>> = sink
                    .leaves()
                    .into_iter()
                    .map(|l| {
                        let mut v: Vec<u32> = l.iter().map(|&i| order[i as usize].0).collect();
                        v.sort_unstable();
                        v
                    })
                    .collect();
                leaves.sort();
                format!("{} nodes, leaves {leaves:?}", bvh.nodes.len())
            })
            .collect();
        assert_eq!(trees[0], trees[1]);
    }

    /// A tree as text, from the root down: every node's planes as bits, every leaf's primitives
    /// (as the sink recorded them); independent of the order nodes and leaves were stored in.
    fn tree_text(bvh: &Bvh8, leaves: &[Vec<u32>], r: NodeRef, out: &mut String) {
        use std::fmt::Write;
        if r.is_leaf() {
            let _ = write!(out, "leaf{:?} ", leaves[r.as_leaf().first as usize]);
            return;
        }
        let n = &bvh.nodes[r.index()];
        let bits: Vec<u32> = n
            .bounds
            .iter()
            .flat_map(|b| b.to_array().map(f32::to_bits))
            .collect();
        let _ = write!(out, "node{bits:?}( ");
        for c in n.child.iter().filter(|c| !c.is_empty()) {
            tree_text(bvh, leaves, *c, out);
        }
        out.push_str(") ");
    }

    /// Two threads bin and partition the big nodes in smaller chunks than one
    /// ([`PARALLEL_PASS_SHARED`]), and build the same tree: every plane, every leaf, bit for
    /// bit, over 20,000 boxes in order and shuffled (the two partition schemes), and over
    /// 70,000 (past [`PARALLEL_PASS`] too).
    #[test]
    fn the_tree_is_the_same_on_one_thread_and_on_two() {
        for (n, shuffled) in [(20_000, false), (20_000, true), (70_000, true)] {
            let mut rng = crate::test_rng::Rng(0x2545_f491);
            let boxes: Vec<Aabb> = line_of_refs(n, shuffled)
                .iter()
                .map(|r| {
                    // scattered in all three axes, of several sizes
                    let x = r.min.x;
                    let p = glam::Vec3::new(x, rng.range(0.0, 300.0), rng.range(0.0, 300.0));
                    Aabb {
                        min: p,
                        max: p + glam::Vec3::splat(rng.range(0.1, 20.0)),
                    }
                })
                .collect();
            let tree = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let sink = RecordingSink::default();
                let bvh =
                    pool.install(|| build(n, |i| (boxes[i], 0), &BuildSettings::default(), &sink));
                let mut text = String::new();
                tree_text(&bvh, &sink.leaves(), bvh.root, &mut text);
                text
            };
            let one = tree(1);
            let leaves = one.matches("leaf").count();
            let max_leaf = BuildSettings::default().max_leaf;
            assert!(
                leaves >= n / max_leaf,
                "{n} boxes: a tree of {leaves} leaves"
            );
            assert!(
                tree(2) == one,
                "{n} boxes, shuffled {shuffled}: 2 threads built another tree"
            );
        }
    }

    #[test]
    fn arithmetic_never_reads_the_index_and_tag_bits() {
        let r = prim_ref(12345, [0.0, 1.0, 2.0], [2.0, 3.0, 6.0]);
        assert!(r.min.w.is_subnormal() && r.max.w.is_subnormal());
        assert_eq!(r.centroid2().to_array(), [2.0, 4.0, 8.0, 0.0]);
        let mut rec = Record::EMPTY;
        rec.add::<true>(&r);
        rec.add::<true>(&prim_ref(7, [1.0, 1.0, 1.0], [4.0, 2.0, 2.0]));
        // the w lanes of the record's boxes still hold bits; what is computed from them does not
        assert_eq!(rec.bounds.half_area(), 4.0 * 2.0 + 2.0 * 5.0 + 5.0 * 4.0);
        assert_eq!(rec.centroids.min.w, 0.0);
        let m = Mapping::new(&rec.centroids, 2, MAX_BINS);
        assert_eq!(m.scale.w, 0.0);
        assert_eq!((r.id(), r.tag()), (12345, 3));
    }

    /// `validate` fails, with the matching message, on each kind of broken tree it promises to
    /// catch: a tree built over random boxes passes, and one change at a time breaks it.
    #[test]
    fn validate_rejects_each_broken_invariant() {
        use super::super::{HI, LO};
        use crate::simd::F32x8;
        let mut rng = crate::test_rng::Rng(0x51ed_270b);
        let boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c: [f32; 3] = std::array::from_fn(|_| rng.range64(-10.0, 10.0) as f32);
                let c = glam::Vec3::from_array(c);
                Aabb {
                    min: c - glam::Vec3::splat(0.1),
                    max: c + glam::Vec3::splat(0.2),
                }
            })
            .collect();
        let tags = vec![0u8; boxes.len()];
        let sink = RecordingSink::default();
        let bvh = build(
            boxes.len(),
            |i| (boxes[i], 0),
            &BuildSettings::default(),
            &sink,
        );
        let lists = sink.leaves();
        let leaf_prims = |l: Leaf| lists[l.first as usize].clone();
        let check = |b: &Bvh8| b.validate(&boxes, &tags, leaf_prims);
        check(&bvh).unwrap();
        // a node of 3 to 7 children, and one whose first child is a leaf
        let partial = bvh
            .nodes
            .iter()
            .position(|n| (3..WIDTH).contains(&n.len()))
            .unwrap();
        let with_leaf = bvh.nodes.iter().position(|n| n.child[0].is_leaf()).unwrap();
        let expect = |b: Bvh8, what: &str| {
            let e = check(&b).expect_err(what);
            assert!(e.contains(what), "expected '{what}', got '{e}'");
        };
        // an empty slot before a child (the last child moved one slot on)
        let mut b = bvh.clone();
        let n = &mut b.nodes[partial];
        let last = n.len();
        n.child.swap(last - 1, last);
        for k in 0..6 {
            let mut p = n.bounds[k].to_array();
            p.swap(last - 1, last);
            n.bounds[k] = F32x8::new(p);
        }
        expect(b, "after the last child");
        // a child box that does not hold its primitives
        let mut b = bvh.clone();
        let n = &mut b.nodes[with_leaf];
        for k in HI..HI + 3 {
            let mut p = n.bounds[k].to_array();
            p[0] = n.bounds[k - HI + LO].to_array()[0];
            n.bounds[k] = F32x8::new(p);
        }
        expect(b, "does not hold primitive");
        // a node reached twice (and so another never)
        let mut b = bvh.clone();
        let inner =
            |n: &Node8| -> Vec<usize> { (0..n.len()).filter(|&k| !n.child[k].is_leaf()).collect() };
        let i = (0..b.nodes.len())
            .find(|&i| inner(&b.nodes[i]).len() >= 2)
            .unwrap();
        let k = inner(&b.nodes[i]);
        let n = &mut b.nodes[i];
        n.child[k[1]] = n.child[k[0]];
        for plane in &mut n.bounds {
            let mut p = plane.to_array();
            p[k[1]] = p[k[0]];
            *plane = F32x8::new(p);
        }
        expect(b, "reached twice");
        // a leaf whose count is not the number of primitives it lists
        let mut b = bvh.clone();
        let n = &mut b.nodes[with_leaf];
        let mut l = n.child[0].as_leaf();
        l.count += 1;
        n.child[0] = NodeRef::leaf(l);
        expect(b, "holds");
    }
}
