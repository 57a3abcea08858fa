//! The wavefront's stages, in the order the driver calls them. Each reads one queue and writes
//! others or the band's pixels; the routing of a shaded ray's children is [`crate::shade`]'s
//! (`scatter`), shared with the reference tracer.

use bumpalo::Bump;

use super::queue::{HitColumns, NO_NODE, RayQueue, ShadowQueue};
use super::{Band, BandOutput, CameraSamples, Context, Run};
use crate::geometry::Geometry;
use crate::math::{Ray, Vec2, Vec3, saturate};
use crate::packet::{HitPacket, NO_HIT};
use crate::scene::Camera;
use crate::shade::{self, EPSILON};
use crate::simd::{LANES, bitmask, from_lanes, lanes, lanes_i32, mask_from_bits};

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
                    let point = Camera::sample_screen(
                        samples.x0 + x,
                        samples.y0 + y,
                        offset.unwrap_or(Vec2::splat(0.5)),
                        samples.image_width,
                        samples.image_height,
                    );
                    queue.push_camera(&camera.generate_ray(point), slot as u32);
                }
            }
        }
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

/// Finds the closest hit of every queued ray, 8 rays at a time.
pub fn intersect_closest<'s>(
    geometry: &Geometry,
    rays: &RayQueue<'_>,
    tmin: f32,
    scratch: &'s Bump,
) -> HitColumns<'s> {
    let mut hits = HitColumns::with_capacity_in(rays.len(), scratch);
    for first in (0..rays.len()).step_by(LANES) {
        let packet = rays.packet(first, tmin);
        let mut hit = HitPacket::new(f32::INFINITY);
        geometry.closest_hit_packet(&packet, &mut hit);
        let n = (rays.len() - first).min(LANES);
        hits.t.extend_from_slice(&lanes(hit.t)[..n]);
        hits.prim.extend_from_slice(&lanes_i32(hit.prim)[..n]);
    }
    hits
}

/// Shades every queued ray's hit: background for misses, ambient and direct light (through
/// queued shadow rays when shadows are on) for hits, and children queued for the next bounce.
pub fn shade_hits(
    ctx: &Context<'_>,
    bounce: u32,
    q: &mut BounceQueues<'_, '_, '_>,
    out: &mut BandOutput<'_>,
) {
    let scene = ctx.scene;
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
        let Some(s) = shade::surface(scene, &ray, &hit, ctx.opts) else {
            continue;
        };
        out.color[px] += throughput * shade::ambient(scene, &s);
        for (index, light) in scene.lights.iter().enumerate() {
            let Some(sample) = shade::light_sample(scene, &s, ray.dir, light, ctx.opts) else {
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
        let [mirror, refracted] = shade::scatter(&s, ray.dir, hit.normal, weight, bounce, ctx.opts);
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

/// Traces the queued shadow rays, 8 at a time, and adds the light of the unblocked ones. With
/// transparent shadows, each lane walks its hits in order, tinting by their transparent colour.
pub fn trace_shadow_rays(ctx: &Context<'_>, shadows: &ShadowQueue<'_>, out: &mut BandOutput<'_>) {
    for first in (0..shadows.len()).step_by(LANES) {
        let (mut rays, max_t) = shadows.packet(first, EPSILON);
        let n = (shadows.len() - first).min(LANES);
        let mut light = [Vec3::ONE; LANES];
        if ctx.opts.transparent_shadows {
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
        } else {
            let occluded = bitmask(ctx.geometry.occluded_packet(&rays, max_t));
            for (lane, l) in light.iter_mut().enumerate().take(n) {
                if occluded >> lane & 1 == 1 {
                    *l = Vec3::ZERO;
                }
            }
        }
        for (lane, l) in light.iter().enumerate().take(n) {
            let k = first + lane;
            out.color[shadows.pixel[k] as usize] += shadows.contribution[k] * *l;
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
    }
}
