//! The rays of the contract (`../shared/bench/SCENES.md`): the pinhole camera's primary rays in
//! 4x2 pixel tiles (one tile = one packet), and the shadow, mirror and diffuse rays built from
//! the primary hits. Everything is computed in `f32` with the same formulas, in the same order,
//! as the C harness, so both programs trace bit-identical rays. Feeds the queues of
//! `queues.rs` to the kernels of `kernels.rs`.

use std::f32::consts::PI;

use super::queues::RayQueue;
use crate::error::{Error, Result};
use crate::geometry::Geometry;
use crate::math::{Ray, Vec3};
use crate::packet::HitPacket;
use crate::simd::LANES;

/// The largest image `whitted bench` accepts (4096 x 4096): its rays alone take ~2 GB.
pub const MAX_BENCH_PIXELS: u64 = 1 << 24;

/// The point light of the shadow rays.
pub const LIGHT: Vec3 = Vec3::new(2.0, 4.0, 1.0);

/// How far secondary rays start off the surface, along the normal facing the incoming ray.
pub const SURFACE_EPSILON: f32 = 1e-4;

/// Checks an image size for [`generate_camera_rays`]: a width that is a multiple of 4, a
/// height that is a multiple of 2, at most [`MAX_BENCH_PIXELS`] pixels.
pub fn check_size(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 || width % 4 != 0 || height % 2 != 0 {
        return Err(Error::Usage(format!(
            "image size {width}x{height}: the width must be a positive multiple of 4 and the \
             height a positive multiple of 2 (rays come in 4x2 tiles)"
        )));
    }
    let pixels = width as u64 * height as u64;
    if pixels > MAX_BENCH_PIXELS {
        return Err(Error::Limit(format!(
            "image size {width}x{height} is {pixels} pixels, over the benchmark's limit of \
             {MAX_BENCH_PIXELS}"
        )));
    }
    Ok(())
}

/// The camera rays of a `width` x `height` image, in 4x2 tiles: tiles row-major, lanes
/// row-major inside a tile (lane = ty * 4 + tx). Eye (0, 2, 3), look-at (0, 0.25, 0), up +Y,
/// vertical field of view 40 degrees; every ray accepts hits in `(0, inf)`.
pub fn generate_camera_rays(width: u32, height: u32) -> Result<RayQueue> {
    check_size(width, height)?;
    let eye = Vec3::new(0.0, 2.0, 3.0);
    let look_at = Vec3::new(0.0, 0.25, 0.0);
    let f = (look_at - eye).normalize();
    let right = f.cross(Vec3::Y).normalize();
    let up = right.cross(f);
    let th = (0.5 * 40.0 * PI / 180.0f32).tan();
    let aspect = width as f32 / height as f32;
    let (w, h) = (width as f32, height as f32);
    let mut queue = RayQueue::with_capacity(width as usize * height as usize);
    for ty in (0..height).step_by(2) {
        for tx in (0..width).step_by(4) {
            for ly in 0..2 {
                for lx in 0..4 {
                    let (px, py) = ((tx + lx) as f32, (ty + ly) as f32);
                    let sx = (2.0 * (px + 0.5) / w - 1.0) * th * aspect;
                    let sy = (1.0 - 2.0 * (py + 0.5) / h) * th;
                    let dir = (f + (right * sx + up * sy)).normalize();
                    queue.push(Ray::new(eye, dir), f32::INFINITY);
                }
            }
        }
    }
    Ok(queue)
}

/// The three secondary queues: one ray of each kind per primary hit, in primary order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SecondaryQueues {
    /// Towards [`LIGHT`], stopping just short of it; any-hit.
    pub shadow: RayQueue,
    /// The mirror reflection; closest hit.
    pub mirror: RayQueue,
    /// Cosine-weighted around the normal (incoherent); closest hit.
    pub diffuse: RayQueue,
}

/// The kinds of secondary ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Secondary {
    Shadow,
    Mirror,
    Diffuse,
}

/// The secondary rays of the primary hits `hits` (one per packet of `primary.packets()`):
/// origin `P = o + t d + 1e-4 N` with `N` the unit geometric normal facing the incoming ray.
pub fn generate_secondary_rays(
    geometry: &Geometry,
    primary: &RayQueue,
    hits: &[HitPacket],
) -> SecondaryQueues {
    let queue = |kind| secondary_rays(geometry, primary, hits, kind);
    SecondaryQueues {
        shadow: queue(Secondary::Shadow),
        mirror: queue(Secondary::Mirror),
        diffuse: queue(Secondary::Diffuse),
    }
}

/// One queue of [`generate_secondary_rays`] alone (the benchmark builds one at a time, so
/// only one is in memory).
pub fn secondary_rays(
    geometry: &Geometry,
    primary: &RayQueue,
    hits: &[HitPacket],
    kind: Secondary,
) -> RayQueue {
    let count = (0..primary.len())
        .filter(|&k| hits[k / LANES].lane(k % LANES).is_some())
        .count();
    let mut q = RayQueue::with_capacity(count);
    for (k, item) in primary.items.iter().enumerate() {
        let Some((t, prim)) = hits[k / LANES].lane(k % LANES) else {
            continue;
        };
        let (o, d) = (item.ray.origin, item.ray.dir);
        let mut n = geometry.surface(prim as u32, &item.ray, t).normal;
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let p = o + d * t + n * SURFACE_EPSILON;
        match kind {
            Secondary::Shadow => {
                // to the light, stopping 1e-4 of the distance short of it
                let to_light = LIGHT - p;
                let dist = to_light.dot(to_light).sqrt();
                let shadow_dir = to_light * (1.0 / dist);
                q.push(Ray::new(p, shadow_dir), dist * (1.0 - 1e-4));
            }
            Secondary::Mirror => {
                let mirror_dir = d - n * (2.0 * d.dot(n));
                q.push(Ray::new(p, mirror_dir), f32::INFINITY);
            }
            Secondary::Diffuse => {
                // cosine-weighted, seeded by the queue index
                let diffuse_dir = cosine_direction(n, q.len() as u32);
                q.push(Ray::new(p, diffuse_dir), f32::INFINITY);
            }
        }
    }
    q
}

/// The contract's random numbers: an LCG, each value its top 24 bits over 2^24.
fn lcg_next(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(1664525).wrapping_add(1013904223);
    (*state >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The cosine-weighted direction around unit `n` of queue entry `index`, in the branchless
/// orthonormal basis of Duff et al. 2017.
fn cosine_direction(n: Vec3, index: u32) -> Vec3 {
    let mut state = index.wrapping_mul(2654435769).wrapping_add(1);
    let u1 = lcg_next(&mut state);
    let u2 = lcg_next(&mut state);
    let phi = 2.0 * PI * u1;
    let rr = u2.sqrt();
    let (lx, ly, lz) = (rr * phi.cos(), rr * phi.sin(), (1.0 - u2).max(0.0).sqrt());
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let b1 = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let b2 = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (b1 * lx + b2 * ly + n * lz).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lcg_matches_the_contract() {
        let mut state = 1u32;
        let u = lcg_next(&mut state);
        assert_eq!(state, 1664525 + 1013904223);
        assert_eq!(u, (state >> 8) as f32 / 16_777_216.0);
    }

    #[test]
    fn cosine_directions_are_unit_and_above_the_surface() {
        for (k, n) in [Vec3::Y, -Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::Z]
            .into_iter()
            .enumerate()
        {
            for i in 0..100 {
                let d = cosine_direction(n, (k * 100 + i) as u32);
                assert!((d.length() - 1.0).abs() < 1e-5);
                assert!(d.dot(n) >= 0.0, "{d} below {n}");
            }
        }
    }

    #[test]
    fn bad_sizes_are_usage_errors() {
        for (w, h) in [(63, 64), (64, 63), (0, 2), (4, 0)] {
            assert!(matches!(check_size(w, h), Err(Error::Usage(_))), "{w}x{h}");
        }
        assert!(matches!(check_size(8192, 8192), Err(Error::Limit(_))));
        assert!(check_size(4, 2).is_ok());
    }
}
