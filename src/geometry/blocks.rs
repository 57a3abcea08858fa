//! Leaf blocks: the BVH's leaves stored ready for intersection, contiguous per leaf and
//! structure of arrays inside (Embree's Triangle4 idea): a [`Triangle4`] holds `v0`, `e1`,
//! `e2` of 4 triangles coordinate by coordinate, a [`Sphere4`] the centres and squared radii of
//! 4 spheres, each with the geometry indices of its lanes. A leaf of `n` triangles is
//! `ceil(n / 4)` consecutive blocks; unused lanes hold a degenerate primitive that nothing hits.
//! Spheres under general transforms (rare) stay in their SoA array; their leaves list indices.
//!
//! The kernels here run one ray against a block (4 lanes, the ray splatted) or 8 rays against
//! each primitive of a block (the primitive splatted), with the same arithmetic
//! ([`triangle_lanes`], [`sphere_lanes`]) so both give the same bits. Closest-hit kernels break
//! ties in `t` towards the smaller geometry index, so the answer never depends on the order in
//! which a traversal meets the leaves.
//!
//! ```text
//! BVH builder --LeafSink::leaf(kind, sorted geometry indices)--> BlockSink
//!     --> Blocks { triangles: Vec<Triangle4>, spheres: Vec<Sphere4>, transformed: Vec<u32> }
//! ```

use super::{Geometry, PrimKind};
use crate::bvh::arena::Arena;
use crate::bvh::build::LeafSink;
use crate::intersect::sphere::{affine_packet, affine_point, affine_vector, sphere_lanes};
use crate::intersect::triangle::triangle_lanes;
use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{F32x4, F32x8, I32x8, Mask, Simd, Vec3x4, Vec3x8, gt, lt, select, select_i32};

/// Primitives per block.
pub const BLOCK: usize = 4;

/// A leaf visited by this many lanes of a packet or fewer is tested lane by lane with the
/// 4-wide block kernel rather than primitive by primitive on all 8 lanes (measured on the tori's
/// streams: PERF.md §10, "What was tried (figures from the branch's development)"; on the
/// spheres' incoherent packets 3 and 4 were slower, 0 and 1 within the noise: sitting 31).
pub const FEW_LANES: u32 = 2;

/// The geometry index of an unused lane.
const NO_PRIM: u32 = u32::MAX;

/// Four triangles: `v0`, `e1 = v1 - v0`, `e2 = v2 - v0` and the unnormalised normal
/// `ng = e1 x e2` as `[x; 4], [y; 4], [z; 4]`, and their geometry indices. 208 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Triangle4 {
    pub v0: [[f32; 4]; 3],
    pub e1: [[f32; 4]; 3],
    pub e2: [[f32; 4]; 3],
    pub ng: [[f32; 4]; 3],
    pub prim: [u32; 4],
}

/// Four spheres: centres as `[x; 4], [y; 4], [z; 4]`, squared radii, geometry indices.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Sphere4 {
    pub center: [[f32; 4]; 3],
    pub radius2: [f32; 4],
    pub prim: [u32; 4],
}

impl Triangle4 {
    /// A block of nothing: degenerate triangles (zero edges: no ray crosses them).
    const EMPTY: Triangle4 = Triangle4 {
        v0: [[0.0; 4]; 3],
        e1: [[0.0; 4]; 3],
        e2: [[0.0; 4]; 3],
        ng: [[0.0; 4]; 3],
        prim: [NO_PRIM; 4],
    };

    /// `(v0, e1, e2)` of lane `k`.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> (Vec3, Vec3, Vec3) {
        let v = |c: &[[f32; 4]; 3]| Vec3::new(c[0][k], c[1][k], c[2][k]);
        (v(&self.v0), v(&self.e1), v(&self.e2))
    }

    /// `ng = e1 x e2` of lane `k`.
    #[inline(always)]
    pub fn normal(&self, k: usize) -> Vec3 {
        let c = &self.ng;
        Vec3::new(c[0][k], c[1][k], c[2][k])
    }
}

impl Sphere4 {
    /// A block of nothing: negative squared radii (no real root).
    const EMPTY: Sphere4 = Sphere4 {
        center: [[0.0; 4]; 3],
        radius2: [-1.0; 4],
        prim: [NO_PRIM; 4],
    };

    /// Centre and squared radius of lane `k`.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> (Vec3, f32) {
        let c = &self.center;
        (Vec3::new(c[0][k], c[1][k], c[2][k]), self.radius2[k])
    }
}

/// The leaf storage of one BVH.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Blocks {
    pub triangles: Vec<Triangle4>,
    pub spheres: Vec<Sphere4>,
    /// Indices into the transformed-sphere array.
    pub transformed: Vec<u32>,
}

/// The sink the BVH builder hands leaves to: fills the block arenas from the geometry's SoA
/// arrays (in parallel, each leaf once).
pub struct BlockSink<'g> {
    geometry: &'g Geometry,
    triangles: Arena<Triangle4>,
    spheres: Arena<Sphere4>,
    transformed: Arena<u32>,
}

impl<'g> BlockSink<'g> {
    /// Arenas sized for the worst case (one primitive per leaf).
    pub fn new(geometry: &'g Geometry) -> BlockSink<'g> {
        BlockSink {
            geometry,
            triangles: Arena::with_capacity(geometry.triangles.len()),
            spheres: Arena::with_capacity(geometry.spheres.len()),
            transformed: Arena::with_capacity(geometry.transformed.len()),
        }
    }

    /// The filled blocks.
    pub fn finish(self) -> Blocks {
        Blocks {
            triangles: self.triangles.into_vec(),
            spheres: self.spheres.into_vec(),
            transformed: self.transformed.into_vec(),
        }
    }
}

impl LeafSink for BlockSink<'_> {
    fn leaf(&self, tag: u8, prims: &[u32]) -> u32 {
        let g = self.geometry;
        let kind = PrimKind::from_tag(tag);
        let base = g.base(kind) as u32;
        let blocks = prims.len().div_ceil(BLOCK);
        match kind {
            PrimKind::Triangle => {
                let first = self.triangles.alloc(blocks);
                for (b, chunk) in prims.chunks(BLOCK).enumerate() {
                    let mut t = Triangle4::EMPTY;
                    for (k, &p) in chunk.iter().enumerate() {
                        let (v0, e1, e2) = g.triangles.get((p - base) as usize);
                        let ng = e1.cross(e2);
                        for a in 0..3 {
                            t.v0[a][k] = v0[a];
                            t.e1[a][k] = e1[a];
                            t.e2[a][k] = e2[a];
                            t.ng[a][k] = ng[a];
                        }
                        t.prim[k] = p;
                    }
                    self.triangles.set(first + b, t);
                }
                first as u32
            }
            PrimKind::Sphere => {
                let first = self.spheres.alloc(blocks);
                for (b, chunk) in prims.chunks(BLOCK).enumerate() {
                    let mut s = Sphere4::EMPTY;
                    for (k, &p) in chunk.iter().enumerate() {
                        let i = (p - base) as usize;
                        let c = g.spheres.center(i);
                        for a in 0..3 {
                            s.center[a][k] = c[a];
                        }
                        s.radius2[k] = g.spheres.radius2[i];
                        s.prim[k] = p;
                    }
                    self.spheres.set(first + b, s);
                }
                first as u32
            }
            PrimKind::TransformedSphere => {
                let first = self.transformed.alloc(prims.len());
                for (k, &p) in prims.iter().enumerate() {
                    self.transformed.set(first + k, p - base);
                }
                first as u32
            }
            PrimKind::Plane => unreachable!("planes are not in the BVH"),
        }
    }
}

/// A closest hit so far: `t` and the geometry index (`-1`: none). A candidate replaces it when
/// nearer, or as near with a smaller index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Best {
    pub t: f32,
    pub prim: i32,
}

impl Best {
    #[inline(always)]
    pub(super) fn take(&mut self, t: f32, prim: i32) {
        if t < self.t || (t == self.t && prim < self.prim) {
            *self = Best { t, prim };
        }
    }
}

/// Takes the lanes `m` of candidate `(ti, id)` into `(t, prim)` where nearer, or as near with a
/// smaller index: [`Best::take`] lane by lane.
#[inline(always)]
pub(super) fn take_packet(m: Mask, ti: F32x8, id: I32x8, t: &mut F32x8, prim: &mut I32x8) {
    let smaller: Mask = bytemuck::cast(id.simd_lt(*prim));
    let hit = m & (lt(ti, *t) | (ti.simd_eq(*t) & smaller));
    *t = select(hit, ti, *t);
    *prim = select_i32(hit, id, *prim);
}

/// The lanes of a 4-lane candidate set that may beat `best`: no farther. The ties among them
/// go to [`take_lanes`], whose [`Best::take`] keeps the smaller index, so the answer is that of
/// the exact filter (nearer, or as near and a smaller index) without its index comparison in
/// every block (ties are rare; the filter runs once per block a ray visits).
#[inline(always)]
fn not_farther4(t: F32x4, best: &Best) -> F32x4 {
    t.le(F32x4::splat(best.t))
}

/// Takes the best of the hit lanes `hit` (bits) of a block into `best`, each by
/// [`Best::take`]: nearer, or as near and a smaller index.
#[inline(always)]
fn take_lanes(hit: u32, t: F32x4, prim: &[u32; 4], best: &mut Best) {
    let t = t.to_array();
    let mut m = hit;
    while m != 0 {
        let k = m.trailing_zeros() as usize;
        m &= m - 1;
        best.take(t[k], prim[k] as i32);
    }
}

/// One ray against a block of triangles: `(lanes hit inside (tmin, inf), t)`.
#[inline(always)]
fn triangle_block(b: &Triangle4, o: Vec3x4, d: Vec3x4, tmin: F32x4) -> (F32x4, F32x4) {
    let (inside, t) = triangle_lanes(
        Vec3x4::from_columns(&b.v0),
        Vec3x4::from_columns(&b.e1),
        Vec3x4::from_columns(&b.e2),
        Vec3x4::from_columns(&b.ng),
        o,
        d,
    );
    (inside & t.gt(tmin), t)
}

/// One ray against a block of spheres: real roots, and the two roots.
#[inline(always)]
fn sphere_block(b: &Sphere4, o: Vec3x4, d: Vec3x4) -> (F32x4, F32x4, F32x4) {
    sphere_lanes(Vec3x4::from_columns(&b.center), F32x4::new(b.radius2), o, d)
}

/// The roots of a transformed sphere for one ray (the unit sphere in its own space).
#[inline(always)]
fn transformed_roots(inv: &[f32; 12], ray: &Ray) -> (F32x4, F32x4, F32x4) {
    let o = Vec3x4::splat(affine_point(inv, ray.origin));
    let d = Vec3x4::splat(affine_vector(inv, ray.dir));
    sphere_lanes(Vec3x4::splat(Vec3::ZERO), F32x4::splat(1.0), o, d)
}

/// A sphere's nearer root past `tmin` in each lane (infinity where neither is), and the lanes
/// where one is.
#[inline(always)]
pub(super) fn nearer_root(real: Mask, t0: F32x8, t1: F32x8, tmin: F32x8) -> (F32x8, Mask) {
    let inf = F32x8::splat(f32::INFINITY);
    let (h0, h1) = (real & gt(t0, tmin), real & gt(t1, tmin));
    (select(h0, t0, select(h1, t1, inf)), h0 | h1)
}

/// Lowers `t` (and sets `prim`) in the `lanes` where one of `count` primitives is nearer, or
/// as near with a smaller index; `candidate(k)` is primitive `k`'s distance in each lane
/// (infinity where it is not hit), the lanes it hits and its index. Up to 8 candidates at a
/// time, none of them compared with the hit so far: their nearest by one minimum each, then
/// the smallest index among those hit at it, then that against `t`. The nearest (t, index)
/// whatever the order, as primitive by primitive, with no chain through `t` from one primitive
/// to the next.
#[inline(always)]
fn take_nearest(
    count: usize,
    lanes: Mask,
    t: &mut F32x8,
    prim: &mut I32x8,
    candidate: impl Fn(usize) -> (F32x8, Mask, u32),
) {
    let inf = F32x8::splat(f32::INFINITY);
    let none = I32x8::splat(i32::MAX);
    for chunk in (0..count).step_by(8) {
        let n = (count - chunk).min(8);
        let mut cand = [(inf, crate::simd::mask_none(), 0u32); 8];
        let mut best = inf;
        for (k, c) in cand.iter_mut().enumerate().take(n) {
            *c = candidate(chunk + k);
            best = crate::simd::min(best, c.0);
        }
        // (a lane no candidate hits keeps `none`, so an infinite `t` with an index is kept)
        let mut id = none;
        for &(c, hit, p) in cand.iter().take(n) {
            let at_best = crate::simd::eq(c, best) & hit;
            id = id.min(select_i32(at_best, I32x8::splat(p as i32), none));
        }
        take_packet(lanes, best, id, t, prim);
    }
}

impl Geometry {
    /// Starts fetching the first block of a leaf: every cache line of a 208-byte triangle
    /// block (16-byte aligned, so the four fields below reach each line it spans), the two or
    /// three of a sphere block.
    #[inline(always)]
    pub(super) fn prefetch_leaf(&self, leaf: crate::bvh::Leaf) {
        use crate::simd::prefetch;
        match PrimKind::from_tag(leaf.tag) {
            PrimKind::Triangle => {
                if let Some(b) = self.blocks.triangles.get(leaf.first as usize) {
                    // offsets 0, 64, 128 and 192
                    prefetch(&b.v0[0]);
                    prefetch(&b.e1[1]);
                    prefetch(&b.e2[2]);
                    prefetch(&b.prim);
                }
            }
            PrimKind::Sphere => {
                if let Some(b) = self.blocks.spheres.get(leaf.first as usize) {
                    prefetch(&b.center[0]);
                    prefetch(&b.prim);
                }
            }
            PrimKind::TransformedSphere | PrimKind::Plane => {}
        }
    }

    /// One ray against the primitives of a leaf: lowers `best` where they hit nearer. Sphere
    /// leaves are tested inline only when `SPHERES_INLINE`, else by a call
    /// ([`Geometry::closest_sphere_leaf`]): inlined into a single-ray walk, the sphere test's
    /// per-ray constants (the splatted ray, `1 / (d . d)`) were hoisted into the start of every
    /// walk, also of meshes without a sphere (PERF.md, sitting 27).
    #[inline(always)]
    pub(super) fn closest_leaf<const SPHERES_INLINE: bool>(
        &self,
        leaf: crate::bvh::Leaf,
        ray: &Ray,
        tmin: f32,
        best: &mut Best,
    ) {
        let (o, d) = (Vec3x4::splat(ray.origin), Vec3x4::splat(ray.dir));
        let tmin4 = F32x4::splat(tmin);
        let (first, blocks) = (leaf.first as usize, (leaf.count as usize).div_ceil(BLOCK));
        match PrimKind::from_tag(leaf.tag) {
            PrimKind::Triangle => {
                for b in &self.blocks.triangles[first..first + blocks] {
                    let (hit, t) = triangle_block(b, o, d, tmin4);
                    let hit = (hit & not_farther4(t, best)).bits();
                    if hit != 0 {
                        take_lanes(hit, t, &b.prim, best);
                    }
                }
            }
            _ if !SPHERES_INLINE => self.closest_sphere_leaf(leaf, ray, tmin, best),
            PrimKind::Sphere => {
                for b in &self.blocks.spheres[first..first + blocks] {
                    let (real, t0, t1) = sphere_block(b, o, d);
                    let a0 = real & t0.gt(tmin4) & not_farther4(t0, best);
                    let a1 = real & t1.gt(tmin4) & not_farther4(t1, best);
                    let hit = (a0 | a1).bits();
                    if hit != 0 {
                        take_lanes(hit, F32x4::pick(a0, t0, t1), &b.prim, best);
                    }
                }
            }
            PrimKind::TransformedSphere => {
                let base = self.base(PrimKind::TransformedSphere) as u32;
                for &i in &self.blocks.transformed[first..first + leaf.count as usize] {
                    let (real, t0, t1) =
                        transformed_roots(&self.transformed.inverse(i as usize), ray);
                    let prim = [base + i; 4];
                    let a0 = real & t0.gt(tmin4) & not_farther4(t0, best);
                    let a1 = real & t1.gt(tmin4) & not_farther4(t1, best);
                    let hit = (a0 | a1).bits() & 1;
                    if hit != 0 {
                        take_lanes(hit, F32x4::pick(a0, t0, t1), &prim, best);
                    }
                }
            }
            PrimKind::Plane => unreachable!("planes are not in the BVH"),
        }
    }

    /// [`Geometry::closest_leaf`] of a sphere leaf, out of line (the single-ray walks' call).
    #[inline(never)]
    fn closest_sphere_leaf(&self, leaf: crate::bvh::Leaf, ray: &Ray, tmin: f32, best: &mut Best) {
        self.closest_leaf::<true>(leaf, ray, tmin, best);
    }

    /// True if a primitive of the leaf lies on the ray in `(tmin, tmax)`.
    #[inline(always)]
    pub(super) fn occluded_leaf(
        &self,
        leaf: crate::bvh::Leaf,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
    ) -> bool {
        let (o, d) = (Vec3x4::splat(ray.origin), Vec3x4::splat(ray.dir));
        let (tmin4, tmax4) = (F32x4::splat(tmin), F32x4::splat(tmax));
        let (first, blocks) = (leaf.first as usize, (leaf.count as usize).div_ceil(BLOCK));
        let in_range = |t: F32x4| t.gt(tmin4) & t.lt(tmax4);
        match PrimKind::from_tag(leaf.tag) {
            PrimKind::Triangle => self.blocks.triangles[first..first + blocks]
                .iter()
                .any(|b| {
                    let (hit, t) = triangle_block(b, o, d, tmin4);
                    (hit & t.lt(tmax4)).bits() != 0
                }),
            PrimKind::Sphere => self.blocks.spheres[first..first + blocks].iter().any(|b| {
                let (real, t0, t1) = sphere_block(b, o, d);
                (real & (in_range(t0) | in_range(t1))).bits() != 0
            }),
            PrimKind::TransformedSphere => self.blocks.transformed
                [first..first + leaf.count as usize]
                .iter()
                .any(|&i| {
                    let (real, t0, t1) =
                        transformed_roots(&self.transformed.inverse(i as usize), ray);
                    (real & (in_range(t0) | in_range(t1))).bits() & 1 != 0
                }),
            PrimKind::Plane => unreachable!("planes are not in the BVH"),
        }
    }

    /// The `lanes` of a packet against the primitives of a leaf: lowers `t` (and sets `prim`)
    /// where they hit nearer, or as near with a smaller index. At most [`FEW_LANES`] lanes go
    /// one by one through the block kernel (4 primitives per pass, the same bits).
    #[inline(always)]
    pub(super) fn closest_leaf_packet(
        &self,
        leaf: crate::bvh::Leaf,
        rays: &RayPacket,
        lanes: Mask,
        t: &mut F32x8,
        prim: &mut I32x8,
    ) {
        let bits = lanes.bits();
        if bits.count_ones() <= FEW_LANES {
            let (mut ts, mut prims, tmin) = (t.to_array(), prim.to_array(), rays.tmin.to_array());
            let mut m = bits;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let mut best = Best {
                    t: ts[l],
                    prim: prims[l],
                };
                self.closest_leaf::<true>(leaf, &rays.ray(l), tmin[l], &mut best);
                (ts[l], prims[l]) = (best.t, best.prim);
            }
            (*t, *prim) = (F32x8::new(ts), I32x8::new(prims));
            return;
        }
        self.closest_leaf_lanes(leaf, rays, lanes, t, prim);
    }

    /// [`Geometry::closest_leaf_packet`] on all 8 lanes at once ([`take_nearest`]).
    #[inline(always)]
    fn closest_leaf_lanes(
        &self,
        leaf: crate::bvh::Leaf,
        rays: &RayPacket,
        lanes: Mask,
        t: &mut F32x8,
        prim: &mut I32x8,
    ) {
        let (first, count) = (leaf.first as usize, leaf.count as usize);
        match PrimKind::from_tag(leaf.tag) {
            // triangles one by one against the hit so far (through `take_nearest` the
            // torus scenes' primary and mirror rays ran 3% slower)
            PrimKind::Triangle => {
                for k in 0..count {
                    let b = &self.blocks.triangles[first + k / BLOCK];
                    let (v0, e1, e2) = b.lane(k % BLOCK);
                    let (inside, tt) = triangle_lanes(
                        Vec3x8::splat(v0),
                        Vec3x8::splat(e1),
                        Vec3x8::splat(e2),
                        Vec3x8::splat(b.normal(k % BLOCK)),
                        rays.origin,
                        rays.dir,
                    );
                    let id = I32x8::splat(b.prim[k % BLOCK] as i32);
                    take_packet(inside & gt(tt, rays.tmin) & lanes, tt, id, t, prim);
                }
            }
            PrimKind::Sphere => take_nearest(count, lanes, t, prim, |k| {
                let b = &self.blocks.spheres[first + k / BLOCK];
                let (c, r2) = b.lane(k % BLOCK);
                let (real, t0, t1) =
                    sphere_lanes(Vec3x8::splat(c), F32x8::splat(r2), rays.origin, rays.dir);
                let (near, hit) = nearer_root(real, t0, t1, rays.tmin);
                (near, hit, b.prim[k % BLOCK])
            }),
            PrimKind::TransformedSphere => {
                let base = self.base(PrimKind::TransformedSphere) as u32;
                let ids = &self.blocks.transformed[first..first + count];
                take_nearest(count, lanes, t, prim, |k| {
                    let i = ids[k];
                    let local = affine_packet(&self.transformed.inverse(i as usize), rays);
                    let (real, t0, t1) =
                        sphere_lanes(Vec3x8::zero(), F32x8::splat(1.0), local.origin, local.dir);
                    let (near, hit) = nearer_root(real, t0, t1, rays.tmin);
                    (near, hit, base + i)
                })
            }
            PrimKind::Plane => unreachable!("planes are not in the BVH"),
        }
    }

    /// The `lanes` of a packet that a primitive of the leaf blocks before `tmax`; at most
    /// [`FEW_LANES`] lanes go one by one through the block kernel.
    #[inline(always)]
    pub(super) fn occluded_leaf_packet(
        &self,
        leaf: crate::bvh::Leaf,
        rays: &RayPacket,
        lanes: Mask,
        tmax: F32x8,
    ) -> Mask {
        let bits = lanes.bits();
        if bits.count_ones() <= FEW_LANES {
            let (tmin, tmax) = (rays.tmin.to_array(), tmax.to_array());
            let (mut m, mut hit) = (bits, 0);
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                if self.occluded_leaf(leaf, &rays.ray(l), tmin[l], tmax[l]) {
                    hit |= 1 << l;
                }
            }
            return crate::simd::mask_from_byte(hit);
        }
        self.occluded_leaf_lanes(leaf, rays, lanes, tmax)
    }

    /// [`Geometry::occluded_leaf_packet`] on all 8 lanes at once.
    #[inline(always)]
    fn occluded_leaf_lanes(
        &self,
        leaf: crate::bvh::Leaf,
        rays: &RayPacket,
        lanes: Mask,
        tmax: F32x8,
    ) -> Mask {
        let (first, count) = (leaf.first as usize, leaf.count as usize);
        let in_range = |t: F32x8| gt(t, rays.tmin) & lt(t, tmax);
        let mut occluded = crate::simd::mask_none();
        match PrimKind::from_tag(leaf.tag) {
            PrimKind::Triangle => {
                for k in 0..count {
                    let b = &self.blocks.triangles[first + k / BLOCK];
                    let (v0, e1, e2) = b.lane(k % BLOCK);
                    let (inside, tt) = triangle_lanes(
                        Vec3x8::splat(v0),
                        Vec3x8::splat(e1),
                        Vec3x8::splat(e2),
                        Vec3x8::splat(b.normal(k % BLOCK)),
                        rays.origin,
                        rays.dir,
                    );
                    occluded |= inside & in_range(tt);
                    if (occluded | !lanes).bits() == 0xff {
                        break;
                    }
                }
            }
            PrimKind::Sphere => {
                for k in 0..count {
                    let b = &self.blocks.spheres[first + k / BLOCK];
                    let (c, r2) = b.lane(k % BLOCK);
                    let (real, t0, t1) =
                        sphere_lanes(Vec3x8::splat(c), F32x8::splat(r2), rays.origin, rays.dir);
                    occluded |= real & (in_range(t0) | in_range(t1));
                    if (occluded | !lanes).bits() == 0xff {
                        break;
                    }
                }
            }
            PrimKind::TransformedSphere => {
                for &i in &self.blocks.transformed[first..first + count] {
                    let local = affine_packet(&self.transformed.inverse(i as usize), rays);
                    let (real, t0, t1) =
                        sphere_lanes(Vec3x8::zero(), F32x8::splat(1.0), local.origin, local.dir);
                    occluded |= real & (in_range(t0) | in_range(t1));
                }
            }
            PrimKind::Plane => unreachable!("planes are not in the BVH"),
        }
        occluded & lanes
    }
}
