//! The geometry's ray queries: closest hit and any hit, for one ray (through the BVH one ray at
//! a time, 8 children per pass, leaf blocks 4 primitives per pass), for an 8-ray packet, for a
//! stream of packets that share one frustum, and (closest hit) for many rays going down the tree
//! together as lists; plus [`Geometry::closest_hit_batch`] and [`Geometry::occluded_batch`],
//! which pick among them per group of packets by how coherent the rays are and how big the tree
//! is ([`Geometry::choose_path`], the rule the wavefront and `whitted bench` use). Planes are
//! tested after the BVH.
//!
//! Every closest-hit query reports the nearest hit in `(tmin, tmax)`, ties in `t` going to the
//! smaller geometry index, so single rays, packets, streams and lists give the same
//! `(t, prim)` bit for bit. Packet queries never touch inactive lanes.

use super::blocks::{Best, nearer_root, take_packet};
use super::{Geometry, PrimKind};
use crate::bvh::{Entered, ListRay, ListScratch, MAX_STREAM, Ray1x8};
use crate::intersect::sphere::affine_packet;
use crate::intersect::sphere::sphere_lanes;
use crate::intersect::{
    intersect_plane, intersect_plane_packet, intersect_transformed_sphere,
    intersect_transformed_sphere_packet, intersect_triangle, intersect_triangle_packet,
};
use crate::math::{Ray, Vec3};
use crate::packet::{HitPacket, RayPacket};
use crate::simd::{
    F32x4, F32x8, I32x8, LANES, Mask, Simd, Vec3x4, Vec3x8, any, bitmask, ge, lanes, mask_none,
};

/// How a group of packets is traced (see [`Geometry::closest_hit_batch`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// Packets of the group together, one frustum ([`Geometry::closest_hit_stream`]).
    Stream,
    /// Packet by packet ([`Geometry::closest_hit_packet`]).
    Packet,
    /// Ray by ray, one walk at a time ([`Geometry::closest_hit`]).
    Single,
    /// The rays of every group on this path in one batch together, as lists of rays that go
    /// down the tree breadth first ([`Geometry::closest_hit_lists`]; any-hit rays go ray by
    /// ray, as [`Path::Single`]).
    Lists,
}

impl Path {
    /// Every path, for tests that hold them to one another.
    pub const ALL: [Path; 4] = [Path::Stream, Path::Packet, Path::Single, Path::Lists];
}

/// The packets of [`Path::Lists`] that wait for one another before they go down the tree
/// together (32,768 rays): the more rays a list starts with, the more of them share each node
/// and leaf (PERF.md, sitting 32).
pub const LIST_PACKETS: usize = 4096;

thread_local! {
    /// Each thread's [`ListBatch`], grown by its first batches and reused (taken out while in
    /// use, so that a batch traced from inside another gets one of its own).
    static LISTS: std::cell::Cell<ListBatch> = std::cell::Cell::default();
}

/// The groups of packets waiting for [`Path::Lists`] ([`Geometry::closest_hit_group`]), and the
/// buffers of a run of the lists: each thread has one, lent by [`ListBatch::with`].
#[derive(Default)]
pub struct ListBatch {
    /// The packets waiting, the hits they start from, and the caller's index of each.
    rays: Vec<RayPacket>,
    hits: Vec<HitPacket>,
    at: Vec<usize>,
    /// Those of them the lists trace (forward rays), prepared; ray `id` of the lists is
    /// `prepared[id]`, lane `id % 8` of the waiting packet `packet[id / 8]`.
    prepared: Vec<ListRay>,
    packet: Vec<usize>,
    /// Each prepared lane's hit so far (by id), active or not.
    t: Vec<f32>,
    prim: Vec<i32>,
    /// The ids of the active lanes.
    ids: Vec<u32>,
    scratch: ListScratch,
}

impl ListBatch {
    /// Runs `f` with this thread's batch, empty (its buffers as the last run left them).
    pub fn with<R>(f: impl FnOnce(&mut ListBatch) -> R) -> R {
        let mut lists = LISTS.take();
        lists.clear();
        let r = f(&mut lists);
        LISTS.set(lists);
        r
    }

    /// True when [`LIST_PACKETS`] packets or more wait: time for
    /// [`Geometry::closest_hit_waiting`].
    pub fn is_full(&self) -> bool {
        self.rays.len() >= LIST_PACKETS
    }

    fn clear(&mut self) {
        self.rays.clear();
        self.hits.clear();
        self.at.clear();
    }
}

/// The smallest cosine between a group's ray directions and their mean at which the group
/// counts as coherent and is traced as a stream. Camera rays of a 32x2 strip: 1.000; shadow rays
/// towards a point light: above 0.999; mirror rays off the torus: above 0.96 for 90% of groups;
/// diffuse rays: about 0. Measured: PERF.md §10, "What was tried (figures from the branch's
/// development)", "Path per group".
pub const COHERENT_COS: f32 = 0.9;

/// Trees with fewer interior nodes than this are small enough that even incoherent packets
/// share most of the nodes and leaves they visit: their incoherent groups stay packets
/// (spheres4096, ~150 nodes: packets 2x faster than single rays), bigger trees trace them as
/// lists (torus1m diffuse: single rays 1.3x faster than packets, PERF.md §10, "What was tried
/// (figures from the branch's development)", "Path per group"; lists faster than single rays,
/// sitting 32).
pub const SMALL_TREE_NODES: usize = 1024;

/// Whether the active directions of `rays` all lie within `acos(cos)` of their mean (`cos` in
/// `(0, 1]`; true when no lane is active): each direction `d` has `d . m >= cos |d|` for the
/// unit mean `m`. Compared squared (no square root, no division), and the packets after the
/// first with a lane outside are not looked at: an incoherent group (diffuse rays) is told
/// after its first packet. Only the speed of a path depends on it, never the hits.
pub fn coherent(rays: &[RayPacket], cos: f32) -> bool {
    let mut sum = Vec3x8::zero();
    for r in rays {
        sum = sum + Vec3x8::select(r.active, r.dir, Vec3x8::zero());
    }
    let mean = Vec3::new(
        lanes(sum.x).iter().sum(),
        lanes(sum.y).iter().sum(),
        lanes(sum.z).iter().sum(),
    )
    .normalize_or_zero();
    let m = Vec3x8::splat(mean);
    let cos2 = F32x8::splat(cos * cos);
    let zero = F32x8::splat(0.0);
    rays.iter().all(|r| {
        let along = r.dir.dot(m);
        let inside = ge(along, zero) & ge(along * along, cos2 * r.dir.length_squared());
        bitmask(r.active) & !bitmask(inside) == 0
    })
}

impl Geometry {
    fn planes_range(&self) -> std::ops::Range<usize> {
        0..self.planes.len()
    }

    /// The closest hit of one ray in `(tmin, tmax)`: `(t, geometry index)`.
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, u32)> {
        let mut best = Best { t: tmax, prim: -1 };
        self.closest_one(ray, tmin, &mut best);
        (best.prim >= 0).then_some((best.t, best.prim as u32))
    }

    /// Lowers `best` to the closest hit of one ray among every primitive nearer than `best.t`:
    /// the BVH's (or all of them, brute force, without one), then the planes.
    #[inline(always)]
    fn closest_one(&self, ray: &Ray, tmin: f32, best: &mut Best) {
        if self.bvh.is_empty() {
            self.closest_brute(ray, tmin, best);
        } else {
            self.closest_bvh(ray, tmin, best);
        }
        self.closest_planes(ray, tmin, best);
    }

    /// Lowers `best` to the closest hit of one ray among the planes (which no BVH holds).
    #[inline(always)]
    fn closest_planes(&self, ray: &Ray, tmin: f32, best: &mut Best) {
        let base = self.base(PrimKind::Plane) as i32;
        for k in self.planes_range() {
            let (pn, d) = (self.planes.normal(k), self.planes.offset[k]);
            if let Some(t) = intersect_plane(pn, d, ray, tmin, f32::INFINITY) {
                best.take(t, base + k as i32);
            }
        }
    }

    /// Lowers `best` to the closest hit of one ray among the BVH's primitives nearer than
    /// `best.t` (one walk; the leaves it pushes are prefetched).
    #[inline(always)]
    fn closest_bvh(&self, ray: &Ray, tmin: f32, best: &mut Best) {
        let mut limit = best.t;
        self.bvh.closest(
            ray,
            tmin,
            &mut limit,
            // inlined into the walk, as are the single-ray any-hit and the any-hit stream's
            // leaf tests below (the packet walks' and the closest-hit stream's stay calls,
            // which measured faster): called, it made the walk save and reload seven vector
            // registers around each leaf, about 40 instructions (PERF.md, sitting 20)
            #[inline(always)]
            |leaf, limit| {
                self.closest_leaf::<false>(leaf, ray, tmin, best);
                *limit = best.t;
            },
            |leaf| self.prefetch_leaf(leaf),
        );
    }

    /// [`Geometry::closest_bvh`] for lane `l` of a packet prepared by [`Ray1x8::new`] (`ray`
    /// is that lane, its `tmin` at least 0).
    #[inline(always)]
    fn closest_bvh_lane(
        &self,
        (rays, root): &(Ray1x8, Option<Entered>),
        l: usize,
        ray: &Ray,
        tmin: f32,
        best: &mut Best,
    ) {
        let mut limit = best.t;
        self.bvh.closest_lane(
            rays,
            root.as_ref(),
            l,
            tmin,
            &mut limit,
            #[inline(always)]
            |leaf, limit| {
                self.closest_leaf::<false>(leaf, ray, tmin, best);
                *limit = best.t;
            },
            |leaf| self.prefetch_leaf(leaf),
        );
    }

    /// Updates `hit` with the closest hits of the packet's active lanes; inactive lanes of `hit`
    /// are left untouched.
    pub fn closest_hit_packet(&self, rays: &RayPacket, hit: &mut HitPacket) {
        let HitPacket { t, prim } = hit;
        if self.bvh.is_empty() {
            self.closest_brute_packet(rays, t, prim);
        } else {
            // a call: inlined, it cost spheres4096's incoherent packets about 3% (PERF.md,
            // sitting 20)
            self.bvh.closest_packet(rays, t, |leaf, rays, lanes, t| {
                self.closest_leaf_packet(leaf, rays, lanes, t, prim)
            });
        }
        self.closest_planes_packet(rays, t, prim);
    }

    /// [`Geometry::closest_hit_packet`] that also adds to `cost` each lane's traversal work:
    /// BVH nodes it entered plus primitives tested for it (planes included). The heatmap's
    /// counter; the same packet traversal, in the same order, as [`Geometry::closest_hit_packet`].
    pub fn closest_hit_packet_counted(
        &self,
        rays: &RayPacket,
        hit: &mut HitPacket,
        cost: &mut [u32; LANES],
    ) {
        let (mut nodes, mut prims) = (LaneCounter::default(), LaneCounter::default());
        let HitPacket { t, prim } = hit;
        if self.bvh.is_empty() {
            prims.add(rays.active, self.base(PrimKind::Plane) as u32);
            self.closest_brute_packet(rays, t, prim);
        } else {
            let leaf = |leaf: crate::bvh::Leaf, rays: &RayPacket, lanes: Mask, t: &mut F32x8| {
                prims.add(lanes, leaf.count);
                self.closest_leaf_packet(leaf, rays, lanes, t, prim);
            };
            self.bvh.closest_packet_probed(rays, t, leaf, &mut nodes);
        }
        prims.add(rays.active, self.planes.len() as u32);
        self.closest_planes_packet(rays, t, prim);
        for (lane, c) in cost.iter_mut().enumerate() {
            *c += nodes.0[lane] + prims.0[lane];
        }
    }

    /// [`Geometry::closest_hit_packet`] for a stream of at most [`MAX_STREAM`] packets traced
    /// together (coherent rays: camera rays, shadow rays towards a point light).
    pub fn closest_hit_stream(&self, rays: &[RayPacket], hits: &mut [HitPacket]) {
        assert!(rays.len() <= MAX_STREAM && hits.len() == rays.len());
        if self.bvh.is_empty() {
            for (r, h) in rays.iter().zip(hits) {
                self.closest_hit_packet(r, h);
            }
            return;
        }
        let mut t = [F32x8::splat(0.0); MAX_STREAM];
        let mut prim = [I32x8::splat(0); MAX_STREAM];
        for (k, h) in hits.iter().enumerate() {
            (t[k], prim[k]) = (h.t, h.prim);
        }
        let n = rays.len();
        self.bvh.closest_stream(
            rays,
            &mut t[..n],
            |leaf, p, rays, lanes, t| self.closest_leaf_packet(leaf, rays, lanes, t, &mut prim[p]),
            |leaf| self.prefetch_leaf(leaf),
        );
        for (k, (r, h)) in rays.iter().zip(hits).enumerate() {
            (h.t, h.prim) = (t[k], prim[k]);
            self.closest_planes_packet(r, &mut h.t, &mut h.prim);
        }
    }

    /// The path for a group of packets: a stream when their directions are coherent
    /// ([`COHERENT_COS`]), otherwise packets in a small tree ([`SMALL_TREE_NODES`]) and lists
    /// in a bigger one. (Two walks interleaved, once the path of trees of 16,384 nodes or more,
    /// fell behind one walk at a time on torus1m when single rays came to be prepared a packet
    /// at a time, and were removed: PERF.md, sitting 20.)
    pub fn choose_path(&self, rays: &[RayPacket]) -> Path {
        let nodes = self.bvh.nodes().len();
        if coherent(rays, COHERENT_COS) {
            Path::Stream
        } else if nodes < SMALL_TREE_NODES {
            Path::Packet
        } else {
            Path::Lists
        }
    }

    /// Closest hits of any number of packets, each group of [`MAX_STREAM`] traced by the path
    /// [`Geometry::choose_path`] picks for it ([`Geometry::closest_hit_group`]): the groups on
    /// [`Path::Lists`] together, [`LIST_PACKETS`] packets at a time.
    pub fn closest_hit_batch(&self, rays: &[RayPacket], hits: &mut [HitPacket]) {
        assert_eq!(rays.len(), hits.len());
        ListBatch::with(|lists| {
            for first in (0..rays.len()).step_by(MAX_STREAM) {
                let group = first..(first + MAX_STREAM).min(rays.len());
                let (r, h) = (&rays[group.clone()], &mut hits[group]);
                if !self.closest_hit_group(first, r, h, lists) && lists.is_full() {
                    self.closest_hit_waiting(lists, |k, hit| hits[k] = hit);
                }
            }
            self.closest_hit_waiting(lists, |k, hit| hits[k] = hit);
        });
    }

    /// The closest hits of a group of up to [`MAX_STREAM`] packets, the caller's `first..`, by
    /// the path [`Geometry::choose_path`] picks for it: true when traced (`hits` updated), false
    /// when on [`Path::Lists`], where it waits in `lists` (copied) for
    /// [`Geometry::closest_hit_waiting`], which the caller runs when `lists` is full
    /// ([`ListBatch::is_full`]) and after its last group. The wavefront's and `whitted
    /// bench`'s entry, group by group as they make the packets.
    pub fn closest_hit_group(
        &self,
        first: usize,
        rays: &[RayPacket],
        hits: &mut [HitPacket],
        lists: &mut ListBatch,
    ) -> bool {
        match self.choose_path(rays) {
            Path::Lists => {
                lists.rays.extend_from_slice(rays);
                lists.hits.extend_from_slice(hits);
                lists.at.extend(first..first + rays.len());
                false
            }
            path => {
                self.closest_hit_path(path, rays, hits);
                true
            }
        }
    }

    /// Traces the packets waiting in `lists` together ([`Geometry::closest_hit_lists`]) and
    /// hands each one's hits to `hit(k, hits)`, `k` the index its group gave it; `lists` is
    /// empty after.
    pub fn closest_hit_waiting(
        &self,
        lists: &mut ListBatch,
        mut hit: impl FnMut(usize, HitPacket),
    ) {
        self.trace_lists(lists);
        for (&k, h) in lists.at.iter().zip(&lists.hits) {
            hit(k, *h);
        }
        lists.clear();
    }

    /// Closest hits of up to [`MAX_STREAM`] packets by the given path (any number on
    /// [`Path::Lists`]).
    pub fn closest_hit_path(&self, path: Path, rays: &[RayPacket], hits: &mut [HitPacket]) {
        match path {
            Path::Stream => self.closest_hit_stream(rays, hits),
            Path::Packet => {
                for (r, h) in rays.iter().zip(hits) {
                    self.closest_hit_packet(r, h);
                }
            }
            Path::Single => self.closest_hit_singles(rays, hits),
            Path::Lists => self.closest_hit_lists(rays, hits),
        }
    }

    /// Closest hits of any number of packets by breadth-first lists
    /// ([`crate::bvh::Bvh8::closest_lists`]): all their rays go down the tree together, each
    /// node splitting the list of rays that reach it among its children. Packets with a lane
    /// that is not a forward ray (`tmin < 0`: an orthographic camera's) go ray by ray. The same
    /// answers as [`Geometry::closest_hit`]; inactive lanes are left untouched.
    pub fn closest_hit_lists(&self, rays: &[RayPacket], hits: &mut [HitPacket]) {
        ListBatch::with(|lists| {
            lists.rays.extend_from_slice(rays);
            lists.hits.extend_from_slice(hits);
            self.trace_lists(lists);
            hits.copy_from_slice(&lists.hits);
        });
    }

    /// Traces the packets waiting in `lists` ([`Geometry::closest_hit_lists`]), their hits
    /// left in `lists.hits`.
    fn trace_lists(&self, lists: &mut ListBatch) {
        let ListBatch {
            rays,
            hits,
            prepared,
            packet,
            t,
            prim,
            ids,
            scratch,
            ..
        } = lists;
        prepared.clear();
        packet.clear();
        t.clear();
        prim.clear();
        ids.clear();
        for (p, (r, h)) in rays.iter().zip(hits.iter_mut()).enumerate() {
            if !Ray1x8::all_forward(r) || self.bvh.is_empty() {
                self.closest_hit_singles(std::slice::from_ref(r), std::slice::from_mut(h));
                continue;
            }
            let first = prepared.len() as u32;
            Ray1x8::new(r).list_rays(r, prepared);
            packet.push(p);
            t.extend_from_slice(&lanes(h.t));
            prim.extend_from_slice(&crate::simd::lanes_i32(h.prim));
            let mut active = bitmask(r.active);
            while active != 0 {
                ids.push(first + active.trailing_zeros());
                active &= active - 1;
            }
        }
        if ids.is_empty() {
            return;
        }
        self.bvh.closest_lists(
            prepared,
            ids,
            t,
            scratch,
            |leaf, ids, tmax| {
                for &id in ids {
                    let id = id as usize;
                    let r = &prepared[id];
                    let mut best = Best {
                        t: tmax[id],
                        prim: prim[id],
                    };
                    self.closest_leaf::<false>(leaf, &r.ray(), r.tmin(), &mut best);
                    (tmax[id], prim[id]) = (best.t, best.prim);
                }
            },
            |leaf| self.prefetch_leaf(leaf),
        );
        for (k, &p) in packet.iter().enumerate() {
            let lanes_of = k * LANES..(k + 1) * LANES;
            let h = &mut hits[p];
            h.t = F32x8::new(t[lanes_of.clone()].try_into().expect("8 lanes"));
            h.prim = I32x8::new(prim[lanes_of].try_into().expect("8 lanes"));
            self.closest_planes_packet(&rays[p], &mut h.t, &mut h.prim);
        }
    }

    /// Closest hits of up to [`MAX_STREAM`] packets ray by ray, one walk at a time: the same
    /// answers as [`Geometry::closest_hit`]. Each packet's lanes are walked in place (gathering
    /// a group's rays into arrays and scattering their hits back cost 5% of torus100k's diffuse
    /// instructions; PERF.md, sitting 19), forward rays (every `tmin >= 0`, all but an
    /// orthographic camera's) prepared for their walks all 8 at once ([`Ray1x8`]), and the root
    /// tested for all 8 at once too ([`crate::bvh::Bvh8::enter_root`]): the first step of
    /// every lane's walk.
    fn closest_hit_singles(&self, rays: &[RayPacket], hits: &mut [HitPacket]) {
        for (r, h) in rays.iter().zip(hits.iter_mut()) {
            let (mut t, mut prim) = (lanes(h.t), crate::simd::lanes_i32(h.prim));
            let tmin = r.tmin.as_array();
            let mut active = bitmask(r.active);
            let prepared = (Ray1x8::all_forward(r) && !self.bvh.is_empty()).then(|| {
                let p = Ray1x8::new(r);
                let root = self.bvh.enter_root(&p, r.tmin, h.t);
                (p, root)
            });
            if let Some((_, Some(root))) = &prepared
                && self.planes.is_empty()
            {
                // a lane that enters none of the root's children hits nothing: no walk to start
                active &= root.lanes();
            }
            while active != 0 {
                let l = active.trailing_zeros() as usize;
                active &= active - 1;
                let ray = r.ray(l);
                let mut b = Best {
                    t: t[l],
                    prim: prim[l],
                };
                match &prepared {
                    Some(p) => {
                        self.closest_bvh_lane(p, l, &ray, tmin[l], &mut b);
                        self.closest_planes(&ray, tmin[l], &mut b);
                    }
                    None => self.closest_one(&ray, tmin[l], &mut b),
                }
                (t[l], prim[l]) = (b.t, b.prim);
            }
            (h.t, h.prim) = (F32x8::new(t), I32x8::new(prim));
        }
    }

    /// True if anything lies on the ray in `(tmin, tmax)`.
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        let bounded = if self.bvh.is_empty() {
            self.occluded_brute(ray, tmin, tmax)
        } else {
            self.bvh.occluded(
                ray,
                tmin,
                tmax,
                #[inline(always)]
                |leaf| self.occluded_leaf(leaf, ray, tmin, tmax),
            )
        };
        bounded
            || self.planes_range().any(|i| {
                let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
                intersect_plane(n, d, ray, tmin, tmax).is_some()
            })
    }

    /// The active lanes with something in `(tmin, tmax)`; stops as soon as every active lane is
    /// occluded.
    pub fn occluded_packet(&self, rays: &RayPacket, tmax: F32x8) -> Mask {
        let occluded = if self.bvh.is_empty() {
            self.occluded_brute_packet(rays, tmax)
        } else {
            self.bvh.occluded_packet(rays, tmax, |leaf, rays, lanes| {
                self.occluded_leaf_packet(leaf, rays, lanes, tmax)
            })
        };
        occluded | self.occluded_planes_packet(rays, !occluded & rays.active, tmax)
    }

    /// [`Geometry::occluded_packet`] for a stream of at most [`MAX_STREAM`] packets traced
    /// together: `occluded[p]` gets packet `p`'s blocked lanes.
    pub fn occluded_stream(&self, rays: &[RayPacket], tmax: &[F32x8], occluded: &mut [Mask]) {
        assert!(rays.len() <= MAX_STREAM && tmax.len() == rays.len());
        if self.bvh.is_empty() {
            for ((r, t), o) in rays.iter().zip(tmax).zip(occluded) {
                *o = self.occluded_packet(r, *t);
            }
            return;
        }
        self.bvh.occluded_stream(
            rays,
            tmax,
            occluded,
            #[inline(always)]
            |leaf, p, rays, lanes| self.occluded_leaf_packet(leaf, rays, lanes, tmax[p]),
            |leaf| self.prefetch_leaf(leaf),
        );
        for ((r, t), o) in rays.iter().zip(tmax).zip(occluded) {
            *o |= self.occluded_planes_packet(r, !*o & r.active, *t);
        }
    }

    /// Occlusion of any number of packets, each group of [`MAX_STREAM`] traced by the path
    /// [`Geometry::choose_path`] picks for it.
    pub fn occluded_batch(&self, rays: &[RayPacket], tmax: &[F32x8], occluded: &mut [Mask]) {
        let groups = rays
            .chunks(MAX_STREAM)
            .zip(tmax.chunks(MAX_STREAM))
            .zip(occluded.chunks_mut(MAX_STREAM));
        for ((r, t), o) in groups {
            self.occluded_path(self.choose_path(r), r, t, o);
        }
    }

    /// Occlusion of up to [`MAX_STREAM`] packets by the given path.
    pub fn occluded_path(&self, path: Path, rays: &[RayPacket], tmax: &[F32x8], out: &mut [Mask]) {
        match path {
            Path::Stream => self.occluded_stream(rays, tmax, out),
            Path::Packet => {
                for ((r, t), o) in rays.iter().zip(tmax).zip(out) {
                    *o = self.occluded_packet(r, *t);
                }
            }
            // the lists are a closest-hit path: shadow rays come in coherent groups (towards a
            // point light, or along one direction), and the others go ray by ray
            Path::Single | Path::Lists => {
                for ((r, t), o) in rays.iter().zip(tmax).zip(out) {
                    let (tmin, tmax, active) = (lanes(r.tmin), lanes(*t), bitmask(r.active));
                    let mut bits = 0;
                    for l in 0..LANES {
                        if active >> l & 1 == 1 && self.occluded(&r.ray(l), tmin[l], tmax[l]) {
                            bits |= 1 << l;
                        }
                    }
                    *o = crate::simd::mask_from_byte(bits);
                }
            }
        }
    }

    /// Planes against the packet's active lanes, closest hit.
    #[inline(always)]
    fn closest_planes_packet(&self, rays: &RayPacket, t: &mut F32x8, prim: &mut I32x8) {
        let base = self.base(PrimKind::Plane);
        for i in self.planes_range() {
            let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
            let (m, ti) = intersect_plane_packet(n, d, rays, F32x8::splat(f32::INFINITY));
            take_packet(m, ti, I32x8::splat((base + i) as i32), t, prim);
        }
    }

    /// Planes against `lanes` of a packet, any hit.
    #[inline(always)]
    fn occluded_planes_packet(&self, rays: &RayPacket, lanes_mask: Mask, tmax: F32x8) -> Mask {
        let mut occluded = mask_none();
        if !any(lanes_mask) {
            return occluded;
        }
        for i in self.planes_range() {
            let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
            occluded |= intersect_plane_packet(n, d, rays, tmax).0;
        }
        occluded & lanes_mask
    }

    /// Brute-force closest hit over every bounded primitive (no BVH built).
    fn closest_brute(&self, ray: &Ray, tmin: f32, best: &mut Best) {
        for i in 0..self.triangles.len() {
            let (v0, e1, e2) = self.triangles.get(i);
            if let Some(t) = intersect_triangle(v0, e1, e2, ray, tmin, f32::INFINITY) {
                best.take(t, i as i32);
            }
        }
        let base = self.base(PrimKind::Sphere);
        for i in 0..self.spheres.len() {
            let (real, t0, t1) = sphere_lanes(
                Vec3x4::splat(self.spheres.center(i)),
                F32x4::splat(self.spheres.radius2[i]),
                Vec3x4::splat(ray.origin),
                Vec3x4::splat(ray.dir),
            );
            take_roots(real, t0, t1, tmin, (base + i) as i32, best);
        }
        let base = self.base(PrimKind::TransformedSphere);
        for i in 0..self.transformed.len() {
            let inv = self.transformed.inverse(i);
            let o = crate::intersect::sphere::affine_point(&inv, ray.origin);
            let d = crate::intersect::sphere::affine_vector(&inv, ray.dir);
            let (real, t0, t1) = sphere_lanes(
                Vec3x4::zero(),
                F32x4::splat(1.0),
                Vec3x4::splat(o),
                Vec3x4::splat(d),
            );
            take_roots(real, t0, t1, tmin, (base + i) as i32, best);
        }
    }

    /// Brute-force closest hits of a packet over every bounded primitive (no BVH built).
    fn closest_brute_packet(&self, rays: &RayPacket, t: &mut F32x8, prim: &mut I32x8) {
        let inf = F32x8::splat(f32::INFINITY);
        for i in 0..self.triangles.len() {
            let (v0, e1, e2) = self.triangles.get(i);
            let (m, ti) = intersect_triangle_packet(v0, e1, e2, rays, inf);
            take_packet(m, ti, I32x8::splat(i as i32), t, prim);
        }
        let base = self.base(PrimKind::Sphere);
        for i in 0..self.spheres.len() {
            let (real, t0, t1) = sphere_lanes(
                Vec3x8::splat(self.spheres.center(i)),
                F32x8::splat(self.spheres.radius2[i]),
                rays.origin,
                rays.dir,
            );
            take_roots_packet(
                real & rays.active,
                t0,
                t1,
                rays.tmin,
                (base + i) as i32,
                t,
                prim,
            );
        }
        let base = self.base(PrimKind::TransformedSphere);
        for i in 0..self.transformed.len() {
            let local = affine_packet(&self.transformed.inverse(i), rays);
            let (real, t0, t1) =
                sphere_lanes(Vec3x8::zero(), F32x8::splat(1.0), local.origin, local.dir);
            take_roots_packet(
                real & rays.active,
                t0,
                t1,
                rays.tmin,
                (base + i) as i32,
                t,
                prim,
            );
        }
    }

    /// Brute-force any hit over every bounded primitive.
    fn occluded_brute(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        (0..self.triangles.len()).any(|i| {
            let (v0, e1, e2) = self.triangles.get(i);
            intersect_triangle(v0, e1, e2, ray, tmin, tmax).is_some()
        }) || (0..self.spheres.len()).any(|i| {
            let (c, r2) = (self.spheres.center(i), self.spheres.radius2[i]);
            crate::intersect::intersect_sphere(c, r2, ray, tmin, tmax).is_some()
        }) || (0..self.transformed.len()).any(|i| {
            intersect_transformed_sphere(&self.transformed.inverse(i), ray, tmin, tmax).is_some()
        })
    }

    /// Brute-force any hit of a packet over every bounded primitive.
    fn occluded_brute_packet(&self, rays: &RayPacket, tmax: F32x8) -> Mask {
        let mut occluded = mask_none();
        for i in 0..self.triangles.len() {
            let (v0, e1, e2) = self.triangles.get(i);
            occluded |= intersect_triangle_packet(v0, e1, e2, rays, tmax).0;
        }
        for i in 0..self.spheres.len() {
            let (c, r2) = (self.spheres.center(i), self.spheres.radius2[i]);
            occluded |= crate::intersect::intersect_sphere_packet(c, r2, rays, tmax).0;
        }
        for i in 0..self.transformed.len() {
            occluded |=
                intersect_transformed_sphere_packet(&self.transformed.inverse(i), rays, tmax).0;
        }
        occluded & rays.active
    }
}

/// Counts per lane, for the heatmap: the BVH's probe (one per node a lane enters) and the
/// primitive tests of the leaves a lane reaches.
#[derive(Default)]
struct LaneCounter([u32; LANES]);

impl LaneCounter {
    fn add(&mut self, lanes: Mask, n: u32) {
        let bits = bitmask(lanes);
        for (lane, c) in self.0.iter_mut().enumerate() {
            if bits >> lane & 1 == 1 {
                *c += n;
            }
        }
    }
}

impl crate::bvh::TraversalProbe for LaneCounter {
    fn node(&mut self, lanes: Mask) {
        self.add(lanes, 1);
    }
}

/// The root rule of the sphere kernels with the tie rule, one ray (lane 0 of splatted roots).
#[inline(always)]
fn take_roots(real: F32x4, t0: F32x4, t1: F32x4, tmin: f32, id: i32, best: &mut Best) {
    if real.bits() & 1 == 0 {
        return;
    }
    let (t0, t1) = (t0.to_array()[0], t1.to_array()[0]);
    let closer = |t: f32| t < best.t || (t == best.t && id < best.prim);
    if t0 > tmin && closer(t0) {
        best.take(t0, id);
    } else if t1 > tmin && closer(t1) {
        best.take(t1, id);
    }
}

/// [`take_roots`] for the lanes `real` of a packet.
#[inline(always)]
fn take_roots_packet(
    real: Mask,
    t0: F32x8,
    t1: F32x8,
    tmin: F32x8,
    id: i32,
    t: &mut F32x8,
    prim: &mut I32x8,
) {
    // the nearer root past `tmin`: a farther one never beats the hit where the nearer does not
    let (near, hit) = nearer_root(real, t0, t1, tmin);
    take_packet(hit, near, I32x8::splat(id), t, prim);
}

#[cfg(test)]
mod tests {
    use super::{RayPacket, coherent};
    use crate::math::{Ray, Vec3};

    /// The rule by its definition: the smallest cosine between an active direction and the
    /// unit mean of the active directions (1 with none).
    fn smallest_cos(rays: &[RayPacket]) -> f32 {
        let active: Vec<Vec3> = rays
            .iter()
            .flat_map(|p| {
                (0..8)
                    .filter(|&l| p.active.to_array()[l] != 0.0)
                    .map(|l| p.ray(l).dir)
            })
            .collect();
        let mean = active
            .iter()
            .fold(Vec3::ZERO, |a, &d| a + d)
            .normalize_or_zero();
        active
            .iter()
            .map(|d| d.dot(mean) / d.length())
            .fold(1.0, f32::min)
    }

    #[test]
    fn a_group_is_coherent_when_its_smallest_cosine_to_the_mean_reaches_the_bound() {
        let mut s = 12345u32;
        let mut rnd = move || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1 << 24) as f32
        };
        let (mut yes, mut no) = (0, 0);
        for case in 0..4000 {
            let spread = [0.0, 0.05, 0.2, 0.5, 2.0][case % 5];
            let base = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or_zero();
            let packets = 1 + case % 8;
            let group: Vec<RayPacket> = (0..packets)
                .map(|_| {
                    let lanes = (rnd() * 9.0) as usize;
                    let rays: Vec<Ray> = (0..lanes.min(8))
                        .map(|_| {
                            let jitter = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                            // not unit length: the rule must not assume it
                            let length = 0.5 + 2.0 * rnd();
                            Ray::new(Vec3::ZERO, (base + spread * jitter) * length)
                        })
                        .collect();
                    RayPacket::from_rays(&rays, 0.0)
                })
                .collect();
            for cos in [0.5, 0.9, 0.99] {
                let smallest = smallest_cos(&group);
                if (smallest - cos).abs() < 1e-4 {
                    continue; // rounding may fall either way at the bound
                }
                assert_eq!(
                    coherent(&group, cos),
                    smallest >= cos,
                    "case {case}, cos {cos}"
                );
                if smallest >= cos { yes += 1 } else { no += 1 }
            }
        }
        assert!(yes > 1000 && no > 1000, "both answers drawn: {yes} / {no}");
    }
}
