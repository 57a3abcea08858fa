//! The wavefront's stages, in the order the driver calls them. Each reads one queue and writes
//! others or the band's pixels; the routing of a shaded ray's children is [`crate::shade`]'s
//! (`scatter`), shared with the reference tracer.
//!
//! The two big stages, [`shade_hits`] and [`trace_shadow_rays`], are never inlined into the
//! driver, and the shading of a hit (`shade::surface`) always is into `shade_hits`: the shape
//! the compiler gave them before sitting 54. Left to it, that shape changed when a PNG encoder
//! was added elsewhere in the crate: both stages went into the driver, and the shading out of
//! them (`perf` profiles of the showcase, PERF.md, sitting 54).

use bumpalo::Bump;

use super::queue::{HitColumns, NO_NODE, RayQueue, ShadowQueue};
use super::{Band, BandOutput, CameraSamples, Context, Run};
use crate::bvh::MAX_STREAM;
use crate::geometry::{Geometry, ListBatch};
use crate::math::{Ray, Vec2, Vec3, saturate};
use crate::packet::{HitPacket, NO_HIT, RayPacket};
use crate::scene::{Camera, Phong};
use crate::shade::{self, EPSILON};
use crate::simd::{F32x8, LANES, bitmask, from_lanes, lanes, lanes_i32, mask_from_bits, mask_none};

/// The queues one bounce reads and writes.
pub struct BounceQueues<'c, 's, 'n> {
    /// The rays of this bounce.
    pub rays: RayQueue<'c>,
    /// Their closest hits.
    pub hits: HitColumns<'s>,
    /// The shadow rays of this bounce's hits.
    pub shadows: ShadowQueue<'s>,
    /// The mirror and refracted rays of the next bounce.
    pub next: RayQueue<'n>,
}

/// Queues the camera rays of the tiles of `run`: 4x2-pixel tiles, row-major, in each tile its
/// pixels row by row and each pixel's samples in order, each ray's `pixel` its sample's slot.
/// With one sample per pixel each packet of 8 consecutive rays is one tile; with 8 or more, a
/// pixel's samples fill the lanes.
pub fn generate_sample_rays(
    camera: &Camera,
    samples: &CameraSamples<'_>,
    run: Run,
    queue: &mut RayQueue<'_>,
) {
    let tiles_x = samples.width.div_ceil(4);
    let spp = samples.spp as usize;
    // Eight samples at a time become rays as one packet (the same bits as one by one).
    let mut lanes = CameraLanes::default();
    for tile in run.first_tile..run.end_tile {
        let (tx, ty) = ((tile % tiles_x) * 4, (tile / tiles_x) * 2);
        for ly in 0..2 {
            for lx in 0..4 {
                let (x, y) = (tx + lx, ty + ly);
                if x >= samples.width || y >= samples.rows {
                    continue;
                }
                let first = (y * samples.width + x) as usize * spp;
                for slot in first..first + spp {
                    let offset = samples.offsets.get(slot).copied();
                    let n = lanes.count;
                    lanes.x[n] = samples.x0 + x;
                    lanes.y[n] = samples.y0 + y;
                    lanes.offset[n] = offset.unwrap_or(Vec2::splat(0.5));
                    lanes.slot[n] = slot as u32;
                    lanes.count += 1;
                    if lanes.count == LANES {
                        lanes.queue(camera, samples, queue);
                    }
                }
            }
        }
    }
    lanes.queue(camera, samples, queue);
}

/// Camera samples gathered for one packet: lane `i`'s pixel `(x[i], y[i])` in the image, its
/// offset in the pixel and its slot; the first `count` lanes are filled.
#[derive(Default)]
struct CameraLanes {
    x: [u32; LANES],
    y: [u32; LANES],
    offset: [Vec2; LANES],
    slot: [u32; LANES],
    count: usize,
}

impl CameraLanes {
    /// Queues the filled lanes' camera rays and empties the lanes.
    #[inline]
    fn queue(&mut self, camera: &Camera, samples: &CameraSamples<'_>, queue: &mut RayQueue<'_>) {
        if self.count == 0 {
            return;
        }
        let (w, h) = (samples.image_width, samples.image_height);
        let (sx, sy) = Camera::sample_screen_packet(self.x, self.y, self.offset, w, h);
        let (origin, dir) = camera.generate_ray_packet(sx, sy);
        queue.push_camera_packet(&origin, &dir, &self.slot[..self.count]);
        self.count = 0;
    }
}

/// Queues one camera ray through each pixel centre of `band`, in 4x2-pixel tiles (4 wide, 2
/// tall, lanes row by row), so each packet of 8 consecutive rays is one tile; a ray's `pixel`
/// is its pixel's index in the band.
pub fn generate_camera_rays(camera: &Camera, band: Band, queue: &mut RayQueue<'_>) {
    let samples = band.samples();
    let run = Run {
        first_tile: 0,
        end_tile: samples.tiles(),
    };
    generate_sample_rays(camera, &samples, run, queue);
}

/// Finds the closest hit of every queued ray: packets of 8 consecutive rays, in groups of
/// [`MAX_STREAM`] packets that [`Geometry::closest_hit_group`] traces as a stream where they are
/// coherent (camera rays: a 32x2-pixel strip); the incoherent groups of a big tree wait and go
/// down the tree together as lists.
pub fn intersect_closest<'s>(
    geometry: &Geometry,
    rays: &RayQueue<'_>,
    tmin: f32,
    scratch: &'s Bump,
) -> HitColumns<'s> {
    let mut hits = HitColumns::with_capacity_in(rays.len(), scratch);
    hits.t.resize(rays.len(), f32::INFINITY);
    hits.prim.resize(rays.len(), NO_HIT);
    // packet `k`'s hits into the columns
    let mut store = |k: usize, h: HitPacket| {
        let (first, end) = (k * LANES, (k * LANES + LANES).min(rays.len()));
        hits.t[first..end].copy_from_slice(&lanes(h.t)[..end - first]);
        hits.prim[first..end].copy_from_slice(&lanes_i32(h.prim)[..end - first]);
    };
    let group = LANES * MAX_STREAM;
    ListBatch::with(|lists| {
        for first in (0..rays.len()).step_by(group) {
            // the next group's rays, fetched while this one is traced (PERF.md, "Prefetching
            // the queue")
            rays.prefetch(first + group, group);
            let packets = (rays.len() - first).div_ceil(LANES).min(MAX_STREAM);
            let batch: [RayPacket; MAX_STREAM] =
                std::array::from_fn(|k| rays.packet(first + (k % packets) * LANES, tmin));
            let mut hit = [HitPacket::new(f32::INFINITY); MAX_STREAM];
            let k0 = first / LANES;
            let (batch, hit) = (&batch[..packets], &mut hit[..packets]);
            if geometry.closest_hit_group(k0, batch, hit, lists) {
                for (k, h) in hit.iter().enumerate() {
                    store(k0 + k, *h);
                }
            } else if lists.is_full() {
                geometry.closest_hit_waiting(lists, &mut store);
            }
        }
        geometry.closest_hit_waiting(lists, &mut store);
    });
    hits
}

/// Shades every queued ray's hit: background for misses, ambient and direct light (through
/// queued shadow rays when shadows are on) for hits, and children queued for the next bounce.
#[inline(never)]
pub fn shade_hits(
    ctx: &Context<'_>,
    bounce: u32,
    q: &mut BounceQueues<'_, '_, '_>,
    out: &mut BandOutput<'_>,
) {
    let scene = ctx.scene;
    let mut blend = Phong::default();
    for i in 0..q.rays.len() {
        let ray = q.rays.ray(i);
        let pixel = q.rays.pixel[i];
        let px = pixel as usize;
        let throughput = q.rays.throughput[i];
        let weight = q.rays.weight[i];
        let prim = q.hits.prim[i];
        let hit = (prim != NO_HIT).then(|| ctx.geometry.surface(prim as u32, &ray, q.hits.t[i]));
        let node = match out.tree.as_deref_mut() {
            Some(t) => {
                let parent = q.rays.parent[i];
                let parent = (parent != NO_NODE).then_some(parent as usize);
                t.add_ray(q.rays.kind[i], parent, &ray, hit, bounce, weight) as u32
            }
            None => NO_NODE,
        };
        let Some(hit) = hit else {
            out.color[px] += throughput * scene.background;
            continue;
        };
        if bounce == 0 {
            out.record_hit(px, hit.t, hit.shading);
        }
        // The surface and each light's sample borrowed, not moved out of their `Option`s: a
        // move was a copy through the stack, which waited on the stores (PERF.md, sitting 37)
        let s = shade::surface(scene, &ray, &hit, ctx.opts, &mut blend);
        let Some(s) = s.as_ref() else {
            continue;
        };
        out.color[px] += throughput * shade::ambient(scene, s);
        let view = ray.dir.normalize();
        for (index, light) in scene.lights.iter().enumerate() {
            let sample = shade::light_sample(scene, s, view, light, ctx.opts);
            let Some(sample) = sample.as_ref() else {
                continue;
            };
            if ctx.opts.shadows {
                q.shadows.push_shadow(
                    &sample.shadow,
                    sample.max_t,
                    pixel,
                    saturate(throughput * sample.color),
                    index as u32,
                    node,
                );
            } else {
                out.color[px] += throughput * sample.color;
            }
        }
        let [mirror, refracted] = shade::scatter(s, ray.dir, hit.normal, weight, bounce, ctx.opts);
        if let Some(m) = mirror {
            let t = saturate(throughput * m.color);
            q.next.push_reflected(&m.ray, pixel, t, m.weight, node);
        }
        if let Some(r) = refracted {
            let t = saturate(throughput * r.color);
            q.next.push_transmitted(&r.ray, pixel, t, r.weight, node);
        }
    }
}

/// Traces the queued shadow rays and adds the light of the unblocked ones: packets of 8
/// consecutive rays in groups of [`MAX_STREAM`], through [`Geometry::occluded_batch`] (a stream
/// where the rays are coherent, as towards a point light from neighbouring hits). With
/// transparent shadows, each lane walks its hits in order, tinting by their transparent colour.
#[inline(never)]
pub fn trace_shadow_rays(ctx: &Context<'_>, shadows: &ShadowQueue<'_>, out: &mut BandOutput<'_>) {
    let group = LANES * MAX_STREAM;
    for first in (0..shadows.len()).step_by(group) {
        shadows.prefetch(first + group, group);
        let packets = (shadows.len() - first).div_ceil(LANES).min(MAX_STREAM);
        let loaded: [(RayPacket, F32x8); MAX_STREAM] =
            std::array::from_fn(|k| shadows.packet(first + (k % packets) * LANES, EPSILON));
        let mut light = [[Vec3::ONE; LANES]; MAX_STREAM];
        if ctx.opts.transparent_shadows {
            for (k, (rays, max_t)) in loaded[..packets].iter().enumerate() {
                let n = (shadows.len() - first - k * LANES).min(LANES);
                transparent_shadow(ctx, *rays, *max_t, n, &mut light[k]);
            }
        } else {
            let rays: [RayPacket; MAX_STREAM] = std::array::from_fn(|k| loaded[k].0);
            let max_t: [F32x8; MAX_STREAM] = std::array::from_fn(|k| loaded[k].1);
            let mut occluded = [mask_none(); MAX_STREAM];
            ctx.geometry.occluded_batch(
                &rays[..packets],
                &max_t[..packets],
                &mut occluded[..packets],
            );
            for (l, o) in light.iter_mut().zip(occluded) {
                let o = bitmask(o);
                for (lane, l) in l.iter_mut().enumerate() {
                    if o >> lane & 1 == 1 {
                        *l = Vec3::ZERO;
                    }
                }
            }
        }
        for (k, l) in light[..packets].iter().enumerate() {
            let n = (shadows.len() - first - k * LANES).min(LANES);
            for (lane, l) in l.iter().enumerate().take(n) {
                add_shadow_light(ctx, shadows, first + k * LANES + lane, *l, out);
            }
        }
    }
}

/// The light the `n` rays of a packet of shadow rays carry through transparent occluders.
fn transparent_shadow(
    ctx: &Context<'_>,
    mut rays: RayPacket,
    max_t: F32x8,
    n: usize,
    light: &mut [Vec3; LANES],
) {
    let mut tmin = lanes(rays.tmin);
    while bitmask(rays.active) != 0 {
        let mut hit = HitPacket::with_tmax(max_t);
        ctx.geometry.closest_hit_packet(&rays, &mut hit);
        let (ts, prims) = (lanes(hit.t), lanes_i32(hit.prim));
        let mut active = bitmask(rays.active);
        for lane in 0..n {
            if active >> lane & 1 == 0 {
                continue;
            }
            if prims[lane] == NO_HIT {
                active &= !(1 << lane);
                continue;
            }
            let ray = rays.ray(lane);
            let material = ctx
                .geometry
                .surface(prims[lane] as u32, &ray, ts[lane])
                .material;
            let transparent = ctx.scene.phong_at(material, ray.at(ts[lane])).transparent;
            light[lane] = saturate(light[lane] * transparent);
            tmin[lane] = ts[lane];
            if light[lane] == Vec3::ZERO {
                active &= !(1 << lane);
            }
        }
        rays.active = mask_from_bits(active);
        rays.tmin = from_lanes(tmin);
    }
}

/// Adds shadow ray `k`'s light (`light`: what reaches the surface) to its pixel, and records
/// the ray in the ray tree.
fn add_shadow_light(
    ctx: &Context<'_>,
    shadows: &ShadowQueue<'_>,
    k: usize,
    light: Vec3,
    out: &mut BandOutput<'_>,
) {
    out.color[shadows.pixel[k] as usize] += shadows.contribution[k] * light;
    if let Some(t) = out.tree.as_deref_mut() {
        let parent = shadows.parent[k];
        if parent != NO_NODE {
            // The tree names the nearest occluder, which an any-hit test does not find.
            let ray: Ray = shadows.ray(k);
            let max_t = shadows.max_t[k];
            let occluder = ctx
                .geometry
                .closest_hit(&ray, EPSILON, max_t)
                .map(|(t, prim)| ctx.geometry.surface(prim, &ray, t));
            t.add_shadow(parent as usize, shadows.light[k], &ray, max_t, occluder);
        }
    }
}
