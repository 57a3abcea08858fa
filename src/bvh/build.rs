//! The binned SAH builder: primitive bounds in, a depth-first node array and the primitive
//! order out. Each node is split at the best of 16 bin boundaries on each axis by the surface
//! area heuristic, or made a leaf when that is cheaper (at most [`MAX_LEAF`] primitives). Every
//! primitive carries a tag (its kind, opaque here): a leaf never mixes tags, so its primitives
//! are one contiguous range of one SoA array once they are reordered.

use super::{Aabb, Bvh, BvhNode, MAX_DEPTH};

/// The most primitives a leaf holds.
pub const MAX_LEAF: usize = 8;
const BINS: usize = 16;
/// Cost of visiting a node relative to intersecting one primitive.
const TRAVERSAL_COST: f32 = 1.0;

/// Builds a BVH over primitives with the given bounds and tags. Returns the tree and the
/// primitive order: leaf ranges index into it.
pub fn build(bounds: &[Aabb], tags: &[u8]) -> (Bvh, Vec<u32>) {
    let n = bounds.len();
    let mut b = Builder {
        centroid: bounds
            .iter()
            .map(Aabb::center)
            .map(|c| c.to_array())
            .collect(),
        bounds,
        tags,
        order: (0..n as u32).collect(),
        nodes: Vec::with_capacity(n),
    };
    if n > 0 {
        b.node(0, n, 0);
    }
    (Bvh { nodes: b.nodes }, b.order)
}

struct Builder<'a> {
    bounds: &'a [Aabb],
    centroid: Vec<[f32; 3]>,
    tags: &'a [u8],
    order: Vec<u32>,
    nodes: Vec<BvhNode>,
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

impl Builder<'_> {
    /// Builds the node for `order[first..first + count]`; returns its index.
    fn node(&mut self, first: usize, count: usize, depth: usize) -> u32 {
        let index = self.nodes.len() as u32;
        let range = &self.order[first..first + count];
        let mut bounds = Aabb::EMPTY;
        let mut cbounds = Aabb::EMPTY;
        for &p in range {
            bounds = bounds.union(&self.bounds[p as usize]);
            cbounds.grow(self.centroid[p as usize].into());
        }
        self.nodes
            .push(BvhNode::leaf(&bounds, first as u32, count as u32));
        let mixed = range
            .iter()
            .any(|&p| self.tags[p as usize] != self.tags[range[0] as usize]);
        let split = if count <= 1 && !mixed {
            None
        } else {
            self.split(first, count, &bounds, &cbounds, mixed, depth)
        };
        if let Some(mid) = split {
            let left = self.node(first, mid - first, depth + 1);
            debug_assert_eq!(left, index + 1);
            let right = self.node(mid, first + count - mid, depth + 1);
            self.nodes[index as usize] = BvhNode::interior(&bounds, right);
        }
        index
    }

    /// Partitions `order[first..first + count]` and returns the split position, or `None` to
    /// make a leaf.
    fn split(
        &mut self,
        first: usize,
        count: usize,
        bounds: &Aabb,
        cbounds: &Aabb,
        mixed: bool,
        depth: usize,
    ) -> Option<usize> {
        let leaf_ok = count <= MAX_LEAF && !mixed;
        if depth >= MAX_DEPTH - 1 {
            // Too deep: only a tag split is allowed, else a (possibly large) leaf.
            return mixed.then(|| self.partition_by_tag(first, count));
        }
        let extent = cbounds.max - cbounds.min;
        let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bin boundary)
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let scale = BINS as f32 / extent[axis];
            let lo = cbounds.min[axis];
            let mut bins = [Bin {
                bounds: Aabb::EMPTY,
                count: 0,
            }; BINS];
            for &p in &self.order[first..first + count] {
                let b = bin_of(self.centroid[p as usize][axis], lo, scale);
                bins[b].count += 1;
                bins[b].bounds = bins[b].bounds.union(&self.bounds[p as usize]);
            }
            // Sweep: area and count of everything right of each boundary.
            let mut right_area = [0.0f32; BINS];
            let mut right_count = [0u32; BINS];
            let mut acc = Aabb::EMPTY;
            let mut n = 0;
            for i in (1..BINS).rev() {
                acc = acc.union(&bins[i].bounds);
                n += bins[i].count;
                right_area[i] = acc.half_area();
                right_count[i] = n;
            }
            let mut acc = Aabb::EMPTY;
            let mut n = 0;
            for i in 1..BINS {
                acc = acc.union(&bins[i - 1].bounds);
                n += bins[i - 1].count;
                if n == 0 || right_count[i] == 0 {
                    continue;
                }
                let cost = acc.half_area() * n as f32 + right_area[i] * right_count[i] as f32;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, i));
                }
            }
        }
        let parent_area = bounds.half_area().max(f32::MIN_POSITIVE);
        let leaf_cost = count as f32;
        match best {
            Some((cost, axis, boundary)) => {
                let split_cost = TRAVERSAL_COST + cost / parent_area;
                if leaf_ok && leaf_cost <= split_cost {
                    return None;
                }
                let lo = cbounds.min[axis];
                let scale = BINS as f32 / extent[axis];
                let centroid = &self.centroid;
                let mid = partition(&mut self.order[first..first + count], |p| {
                    bin_of(centroid[p as usize][axis], lo, scale) < boundary
                });
                Some(first + mid)
            }
            // All centroids coincide: no spatial split exists.
            None if leaf_ok => None,
            None if mixed => Some(self.partition_by_tag(first, count)),
            None => Some(first + count / 2),
        }
    }

    /// Moves the primitives tagged like the first one to the front; returns the split position.
    fn partition_by_tag(&mut self, first: usize, count: usize) -> usize {
        let tags = self.tags;
        let tag = tags[self.order[first] as usize];
        first
            + partition(&mut self.order[first..first + count], |p| {
                tags[p as usize] == tag
            })
    }
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// Stable-free in-place partition: elements satisfying `left` first; returns their count.
fn partition(items: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = items.len();
    while i < j {
        if left(items[i]) {
            i += 1;
        } else {
            j -= 1;
            items.swap(i, j);
        }
    }
    i
}
