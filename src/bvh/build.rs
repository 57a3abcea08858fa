//! The binned SAH builder: primitive bounds in, a depth-first node array and the primitive
//! order out. Each node is split at the best of [`BINS`] bin boundaries on each axis by the
//! surface area heuristic, or made a leaf when that is cheaper (at most [`MAX_LEAF`]
//! primitives). Every primitive carries a tag (its kind, opaque here): a leaf never mixes tags,
//! so its primitives are one contiguous range of one SoA array once they are reordered.
//!
//! Speed: the builder works on an array of 32-byte primitive references (bounds, id, tag) that
//! it partitions in place, so every pass reads memory in order; one pass bins all three axes,
//! children get their bounds from the bins and their centroid bounds from the partition pass,
//! so no node ever re-scans its primitives for bounds (see PERF.md, "BVH build").

use glam::Vec4;

use super::{Aabb, Bvh, BvhNode, MAX_DEPTH};
use crate::simd::trunc3;

/// The most primitives a leaf holds.
pub const MAX_LEAF: usize = 4;
/// Bins per axis for big nodes (a power of two).
pub const BINS: usize = 16;
/// Cost of visiting a node relative to intersecting one primitive.
const TRAVERSAL_COST: f32 = 1.0;

/// A primitive reference: bounds with the id in `min.w` and the tag in `max.w` (as bits).
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

    /// Twice the centroid (the factor cancels out in binning).
    #[inline(always)]
    fn centroid2(&self) -> Vec4 {
        self.min + self.max
    }
}

/// Bounds as two `Vec4` (w ignored), for fast unions.
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
        let d = (self.max - self.min).max(Vec4::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.min.truncate(),
            max: self.max.truncate(),
        }
    }
}

/// Builds a BVH over primitives with the given bounds and tags. Returns the tree and the
/// primitive order: leaf ranges index into it.
pub fn build(bounds: &[Aabb], tags: &[u8]) -> (Bvh, Vec<u32>) {
    let n = bounds.len();
    let mut all = Box4::EMPTY;
    let mut centroids = Box4::EMPTY;
    let mut refs: Vec<PrimRef> = bounds
        .iter()
        .zip(tags)
        .enumerate()
        .map(|(i, (b, &tag))| {
            let r = PrimRef {
                min: b.min.extend(f32::from_bits(i as u32)),
                max: b.max.extend(f32::from_bits(tag as u32)),
            };
            all.grow(r.min, r.max);
            let c = r.centroid2();
            centroids.grow(c, c);
            r
        })
        .collect();
    let mut b = Builder {
        nodes: Vec::with_capacity(n.max(1)),
        bins: Bins::new(),
    };
    if n > 0 {
        b.node(&mut refs, 0, all, centroids, 0, true);
    }
    let order = refs.iter().map(PrimRef::id).collect();
    (Bvh { nodes: b.nodes }, order)
}

struct Builder {
    nodes: Vec<BvhNode>,
    bins: Bins,
}

/// The chosen split: axis, bin boundary, the two children's bounds, the left count and the
/// SAH cost of the children (area-weighted counts).
struct Split {
    axis: usize,
    boundary: usize,
    left: Box4,
    right: Box4,
    left_count: usize,
    cost: f32,
}

impl Builder {
    /// Builds the node over `refs` (which start at position `first` of the whole array);
    /// `bounds` and `centroids` are theirs. Returns the node's index.
    fn node(
        &mut self,
        refs: &mut [PrimRef],
        first: usize,
        bounds: Box4,
        centroids: Box4,
        depth: usize,
        parent_mixed: bool,
    ) -> u32 {
        let index = self.nodes.len() as u32;
        let count = refs.len();
        self.nodes
            .push(BvhNode::leaf(&bounds.aabb(), first as u32, count as u32));
        // Only a node whose parent mixed tags can itself mix them.
        let mixed = parent_mixed && refs.iter().any(|r| r.tag() != refs[0].tag());
        if count <= 1 && !mixed {
            return index;
        }
        let leaf_ok = count <= MAX_LEAF && !mixed;
        let split = if depth >= MAX_DEPTH - 1 {
            None
        } else {
            best_split(refs, &centroids, &mut self.bins)
        };
        let (mid, left, right) = match split {
            Some(s) => {
                let area = bounds.half_area().max(f32::MIN_POSITIVE);
                if leaf_ok && count as f32 <= TRAVERSAL_COST + s.cost / area {
                    return index;
                }
                let (mid, cl, cr) = partition_by_bin(refs, &s, &centroids);
                debug_assert_eq!(mid, s.left_count);
                (mid, (s.left, cl), (s.right, cr))
            }
            None if leaf_ok => return index,
            // No spatial split (every centroid coincides, or too deep): separate the kinds, or
            // halve the range.
            None => {
                let mid = if mixed {
                    partition_by_tag(refs)
                } else if depth >= MAX_DEPTH - 1 {
                    return index;
                } else {
                    count / 2
                };
                let (l, r) = refs.split_at(mid);
                (mid, bounds_of(l), bounds_of(r))
            }
        };
        let (left_refs, right_refs) = refs.split_at_mut(mid);
        let l = self.node(left_refs, first, left.0, left.1, depth + 1, mixed);
        debug_assert_eq!(l, index + 1);
        let r = self.node(right_refs, first + mid, right.0, right.1, depth + 1, mixed);
        self.nodes[index as usize] = BvhNode::interior(&bounds.aabb(), r);
        index
    }
}

/// Bounds and centroid bounds of some references.
fn bounds_of(refs: &[PrimRef]) -> (Box4, Box4) {
    let mut b = Box4::EMPTY;
    let mut c = Box4::EMPTY;
    for r in refs {
        b.grow(r.min, r.max);
        let cc = r.centroid2();
        c.grow(cc, cc);
    }
    (b, c)
}

/// Bins for a node of `count` primitives: [`BINS`] for big nodes, fewer for small ones, whose
/// cost would otherwise be setting up and sweeping empty bins (see PERF.md, "BVH build").
#[inline(always)]
fn bins_for(count: usize) -> usize {
    count.next_power_of_two().clamp(2, BINS)
}

/// Per-axis bin scale: `nb` bins span the centroid bounds (zero-extent axes get scale 0).
#[inline(always)]
fn bin_scale(centroids: &Box4, nb: usize) -> Vec4 {
    let extent = centroids.max - centroids.min;
    let s = Vec4::splat(nb as f32 * (1.0 - 1e-6)) / extent;
    Vec4::select(extent.cmpgt(Vec4::ZERO), s, Vec4::ZERO)
}

/// The bin of a (doubled) centroid on each axis.
#[inline(always)]
fn bin_index(c: Vec4, lo: Vec4, scale: Vec4, nb: usize) -> [usize; 3] {
    let b = ((c - lo) * scale).clamp(Vec4::ZERO, Vec4::splat((nb - 1) as f32));
    trunc3(b)
}

/// Bin counts and bounds per axis, kept by the builder so no node pays for setting up more
/// than the bins it uses.
struct Bins {
    counts: [[u32; BINS]; 3],
    boxes: [[Box4; BINS]; 3],
}

impl Bins {
    fn new() -> Bins {
        Bins {
            counts: [[0; BINS]; 3],
            boxes: [[Box4::EMPTY; BINS]; 3],
        }
    }
}

/// Bins every reference on all three axes in one pass and returns the cheapest split by SAH.
fn best_split(refs: &[PrimRef], centroids: &Box4, bins: &mut Bins) -> Option<Split> {
    let nb = bins_for(refs.len());
    let scale = bin_scale(centroids, nb);
    let lo = centroids.min;
    for axis in 0..3 {
        bins.counts[axis][..nb].fill(0);
        bins.boxes[axis][..nb].fill(Box4::EMPTY);
    }
    for r in refs {
        let b3 = bin_index(r.centroid2(), lo, scale, nb);
        for (axis, b) in b3.into_iter().enumerate() {
            // (the mask only tells the compiler the index is in range)
            let b = b & (BINS - 1);
            bins.counts[axis][b] += 1;
            bins.boxes[axis][b].grow(r.min, r.max);
        }
    }
    let mut best: Option<Split> = None;
    let mut right_box = [Box4::EMPTY; BINS];
    let mut right_count = [0u32; BINS];
    for axis in 0..3 {
        if scale[axis] == 0.0 {
            continue;
        }
        let (counts, boxes) = (&bins.counts[axis], &bins.boxes[axis]);
        // Sweep from the right: bounds and count of everything right of each boundary.
        let mut acc = Box4::EMPTY;
        let mut n = 0;
        for i in (1..nb).rev() {
            acc = acc.union(&boxes[i]);
            n += counts[i];
            right_box[i] = acc;
            right_count[i] = n;
        }
        let mut acc = Box4::EMPTY;
        let mut n = 0;
        for i in 1..nb {
            acc = acc.union(&boxes[i - 1]);
            n += counts[i - 1];
            if n == 0 || right_count[i] == 0 {
                continue;
            }
            let cost =
                acc.half_area() * n as f32 + right_box[i].half_area() * right_count[i] as f32;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split {
                    axis,
                    boundary: i,
                    left: acc,
                    right: right_box[i],
                    left_count: n as usize,
                    cost,
                });
            }
        }
    }
    best
}

/// Partitions by the split's bin boundary (the same bin arithmetic as [`best_split`]); returns
/// the split position and the two sides' centroid bounds, gathered on the way.
fn partition_by_bin(refs: &mut [PrimRef], s: &Split, centroids: &Box4) -> (usize, Box4, Box4) {
    let nb = bins_for(refs.len());
    let scale = bin_scale(centroids, nb);
    let lo = centroids.min;
    let (mut cl, mut cr) = (Box4::EMPTY, Box4::EMPTY);
    let mut i = 0;
    let mut j = refs.len();
    // Each reference is examined once, at position i; one that goes right is swapped with the
    // unexamined one at j - 1.
    while i < j {
        let c = refs[i].centroid2();
        if bin_index(c, lo, scale, nb)[s.axis] < s.boundary {
            cl.grow(c, c);
            i += 1;
        } else {
            cr.grow(c, c);
            j -= 1;
            refs.swap(i, j);
        }
    }
    (i, cl, cr)
}

/// Moves the references tagged like the first one to the front; returns their count.
fn partition_by_tag(refs: &mut [PrimRef]) -> usize {
    let tag = refs[0].tag();
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        if refs[i].tag() == tag {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    i
}
