//! The kernels `whitted bench` times, each a [`Kernel`]: the closest hit and the any hit
//! (occlusion) of a queue, one ray at a time and 8 rays at a time, on the calling thread or
//! spread over a rayon pool. They trace the queues of `queues.rs` against a [`Geometry`] and
//! are counted into a [`Tally`] for the report; `mod.rs` times them.
//!
//! A new kernel (another traversal, a stream of packets) is one more type implementing
//! [`Kernel`] here and one call of `trace_queue` in `mod.rs`; [`trace`] spreads any kernel over
//! threads the same way.

use rayon::ThreadPool;
use rayon::prelude::*;

use super::queues::{BenchPacket, BenchRay, PacketQueue, RayQueue};
use crate::bvh::MAX_STREAM;
use crate::geometry::{Geometry, ListBatch};
use crate::packet::{HitPacket, NO_HIT, RayPacket};
use crate::simd::{F32x8, Mask, bitmask, lanes, lanes_i32, mask_none, prefetch_all};

/// Queue entries (rays or packets) per rayon task when tracing on several threads (a multiple
/// of [`MAX_STREAM`]).
const CHUNK: usize = 64;

/// One way of tracing a queue: the entry it traces in one step, the result it writes for it,
/// and how results are counted.
pub trait Kernel {
    /// What one step traces: a [`BenchRay`] or a [`BenchPacket`].
    type Item: Sync;
    /// What one step answers; reset to [`Kernel::fresh`] before every repetition.
    type Result: Send;
    /// The suffix of the kernel's `CSV,` rows: `_scalar` for single rays, empty for packets.
    const SUFFIX: &'static str;
    /// Whether hits have distances, whose sum is printed as a checksum (not for any-hit).
    const CHECKSUM: bool;
    /// The result before tracing `item`.
    fn fresh(item: &Self::Item) -> Self::Result;
    /// Traces `item` into `result`.
    fn trace(geometry: &Geometry, item: &Self::Item, result: &mut Self::Result);
    /// Traces consecutive `items` into their `results` (kernels that trace several entries
    /// together, such as packet streams, override it).
    #[inline(always)]
    fn trace_many(geometry: &Geometry, items: &[Self::Item], results: &mut [Self::Result]) {
        for (item, result) in items.iter().zip(results) {
            Self::trace(geometry, item, result);
        }
    }
    /// Adds the hits of `result` to `tally`.
    fn count(result: &Self::Result, tally: &mut Tally);
}

/// Hits counted over a queue's results, and the sum of their distances.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    pub hits: usize,
    /// The sum of the hit distances, in queue order (0 for any-hit kernels).
    pub t_sum: f64,
}

impl Tally {
    /// Counts one hit at distance `t`.
    pub fn hit(&mut self, t: f32) {
        self.hits += 1;
        self.t_sum += t as f64;
    }
}

/// The closest hit of one ray: `(t, geometry index)` or `None`.
pub struct Closest;

impl Kernel for Closest {
    type Item = BenchRay;
    type Result = Option<(f32, u32)>;
    const SUFFIX: &'static str = "_scalar";
    const CHECKSUM: bool = true;
    fn fresh(_: &BenchRay) -> Self::Result {
        None
    }
    #[inline(always)]
    fn trace(geometry: &Geometry, r: &BenchRay, hit: &mut Self::Result) {
        *hit = geometry.closest_hit(&r.ray, 0.0, r.tmax);
    }
    fn count(hit: &Self::Result, tally: &mut Tally) {
        if let Some((t, _)) = hit {
            tally.hit(*t);
        }
    }
}

/// Starts fetching group `g` of [`MAX_STREAM`] packets (if any) while the one before it is
/// traced: the gather reads a group's 36 cache lines at once, and the misses stalled it (8% of
/// spheres4096's diffuse rays on Zen 5; Embree's harness has no such copy in its timed loop).
#[inline(always)]
fn prefetch_group(items: &[BenchPacket], g: usize) {
    let start = (g * MAX_STREAM).min(items.len());
    prefetch_all(&items[start..(start + MAX_STREAM).min(items.len())]);
}

/// The rays of up to [`MAX_STREAM`] consecutive packets, gathered for a stream query.
#[inline(always)]
fn gather(packets: &[BenchPacket]) -> ([RayPacket; MAX_STREAM], [F32x8; MAX_STREAM]) {
    let mut rays = [packets[0].rays; MAX_STREAM];
    let mut tmax = [packets[0].tmax; MAX_STREAM];
    for (k, p) in packets.iter().enumerate() {
        (rays[k], tmax[k]) = (p.rays, p.tmax);
    }
    (rays, tmax)
}

/// The closest hits of 8 rays, the path the renderer uses: [`Geometry::closest_hit_group`]
/// (groups of [`MAX_STREAM`] packets as streams where the rays are coherent, the incoherent
/// groups of big trees together as lists).
pub struct ClosestPacket;

impl Kernel for ClosestPacket {
    type Item = BenchPacket;
    type Result = HitPacket;
    const SUFFIX: &'static str = "";
    const CHECKSUM: bool = true;
    fn fresh(p: &BenchPacket) -> HitPacket {
        HitPacket::with_tmax(p.tmax)
    }
    #[inline(always)]
    fn trace(geometry: &Geometry, p: &BenchPacket, hit: &mut HitPacket) {
        geometry.closest_hit_batch(std::slice::from_ref(&p.rays), std::slice::from_mut(hit));
    }
    #[inline(always)]
    fn trace_many(geometry: &Geometry, items: &[BenchPacket], hits: &mut [HitPacket]) {
        ListBatch::with(|lists| {
            for first in (0..items.len()).step_by(MAX_STREAM) {
                prefetch_group(items, first / MAX_STREAM + 1);
                let group = first..(first + MAX_STREAM).min(items.len());
                let (rays, _) = gather(&items[group.clone()]);
                let (rays, h) = (&rays[..group.len()], &mut hits[group]);
                if !geometry.closest_hit_group(first, rays, h, lists) && lists.is_full() {
                    geometry.closest_hit_waiting(lists, |k, hit| hits[k] = hit);
                }
            }
            geometry.closest_hit_waiting(lists, |k, hit| hits[k] = hit);
        });
    }
    fn count(hit: &HitPacket, tally: &mut Tally) {
        for (t, prim) in lanes(hit.t).into_iter().zip(lanes_i32(hit.prim)) {
            if prim != NO_HIT {
                tally.hit(t);
            }
        }
    }
}

/// Whether anything lies on one ray before its `tmax` (shadow rays).
pub struct Any;

impl Kernel for Any {
    type Item = BenchRay;
    type Result = bool;
    const SUFFIX: &'static str = "_scalar";
    const CHECKSUM: bool = false;
    fn fresh(_: &BenchRay) -> bool {
        false
    }
    #[inline(always)]
    fn trace(geometry: &Geometry, r: &BenchRay, occluded: &mut bool) {
        *occluded = geometry.occluded(&r.ray, 0.0, r.tmax);
    }
    fn count(occluded: &bool, tally: &mut Tally) {
        tally.hits += usize::from(*occluded);
    }
}

/// The occluded lanes of 8 rays (shadow rays), the path the renderer uses: groups of up to
/// [`MAX_STREAM`] packets through [`Geometry::occluded_batch`].
pub struct AnyPacket;

impl Kernel for AnyPacket {
    type Item = BenchPacket;
    type Result = Mask;
    const SUFFIX: &'static str = "";
    const CHECKSUM: bool = false;
    fn fresh(_: &BenchPacket) -> Mask {
        mask_none()
    }
    #[inline(always)]
    fn trace(geometry: &Geometry, p: &BenchPacket, occluded: &mut Mask) {
        let (rays, tmax) = (std::slice::from_ref(&p.rays), std::slice::from_ref(&p.tmax));
        geometry.occluded_batch(rays, tmax, std::slice::from_mut(occluded));
    }
    #[inline(always)]
    fn trace_many(geometry: &Geometry, items: &[BenchPacket], occluded: &mut [Mask]) {
        for (g, (p, o)) in items
            .chunks(MAX_STREAM)
            .zip(occluded.chunks_mut(MAX_STREAM))
            .enumerate()
        {
            prefetch_group(items, g + 1);
            let (rays, tmax) = gather(p);
            geometry.occluded_batch(&rays[..p.len()], &tmax[..p.len()], o);
        }
    }
    fn count(occluded: &Mask, tally: &mut Tally) {
        tally.hits += bitmask(*occluded).count_ones() as usize;
    }
}

/// Traces every entry of `items` into its result with kernel `K`, on the calling thread or
/// spread over `pool` in chunks of `CHUNK` entries.
#[inline(always)]
pub fn trace<K: Kernel>(
    geometry: &Geometry,
    items: &[K::Item],
    results: &mut [K::Result],
    pool: Option<&ThreadPool>,
) {
    match pool {
        None => K::trace_many(geometry, items, results),
        Some(pool) => pool.install(|| {
            items
                .par_chunks(CHUNK)
                .zip(results.par_chunks_mut(CHUNK))
                .for_each(|(items, results)| K::trace_many(geometry, items, results))
        }),
    }
}

/// The results of kernel `K` before tracing `items`.
pub fn fresh_results<K: Kernel>(items: &[K::Item]) -> Vec<K::Result> {
    items.iter().map(K::fresh).collect()
}

/// Resets `results` to [`fresh_results`] without allocating.
pub fn reset_results<K: Kernel>(items: &[K::Item], results: &mut [K::Result]) {
    for (result, item) in results.iter_mut().zip(items) {
        *result = K::fresh(item);
    }
}

/// The hits in results of kernel `K`, counted in queue order.
pub fn count_hits<K: Kernel>(results: &[K::Result]) -> Tally {
    let mut tally = Tally::default();
    for result in results {
        K::count(result, &mut tally);
    }
    tally
}

/// The closest hit of every ray, one at a time: `hits[i]` is `(t, geometry index)` or `None`.
pub fn intersect_closest(
    geometry: &Geometry,
    queue: &RayQueue,
    hits: &mut [Option<(f32, u32)>],
    pool: Option<&ThreadPool>,
) {
    trace::<Closest>(geometry, &queue.items, hits, pool);
}

/// The closest hits of every packet into `hits` (reset with [`PacketQueue::reset_hits`]).
pub fn intersect_closest_packet(
    geometry: &Geometry,
    queue: &PacketQueue,
    hits: &mut [HitPacket],
    pool: Option<&ThreadPool>,
) {
    trace::<ClosestPacket>(geometry, &queue.packets, hits, pool);
}

/// Whether anything lies on each ray, one at a time (shadow rays).
pub fn intersect_any(
    geometry: &Geometry,
    queue: &RayQueue,
    occluded: &mut [bool],
    pool: Option<&ThreadPool>,
) {
    trace::<Any>(geometry, &queue.items, occluded, pool);
}

/// The occluded lanes of every packet (shadow rays).
pub fn intersect_any_packet(
    geometry: &Geometry,
    queue: &PacketQueue,
    occluded: &mut [Mask],
    pool: Option<&ThreadPool>,
) {
    trace::<AnyPacket>(geometry, &queue.packets, occluded, pool);
}
