//! The traversal cost of the eye rays, for `--heatmap`: the packet tracer's camera rays, queued
//! in the same 4x2 tiles and traced as the same packets through the same BVH walk as in a
//! render, but through the counting twin of the closest-hit query
//! ([`Geometry::closest_hit_packet_counted`]). A ray's cost is the BVH nodes it entered plus
//! the primitives tested for it (in the leaves it reached, and the planes, which every ray
//! tests). The render itself never counts, so it pays nothing for this.

use bumpalo::Bump;
use rayon::prelude::*;

use super::queue::RayQueue;
use super::{BAND_ROWS, Band, stages};
use crate::frame::CostMap;
use crate::geometry::Geometry;
use crate::options::{FinishedRows, Progress, RenderOptions};
use crate::packet::HitPacket;
use crate::scene::Scene;
use crate::simd::LANES;

/// Traces the eye rays of the frame `opts` describes, counting each one's traversal work.
pub fn eye_ray_costs(
    scene: &Scene,
    geometry: &Geometry,
    opts: &RenderOptions,
    progress: Progress,
) -> CostMap {
    let (w, h) = (opts.width, opts.height);
    let mut cost = vec![0u32; w as usize * h as usize];
    let tmin = scene.camera.tmin();
    cost.par_chunks_mut((w * BAND_ROWS) as usize)
        .enumerate()
        .for_each_init(Bump::new, |arena, (i, out)| {
            arena.reset();
            let band = Band::of_image(i as u32, w, h);
            let mut rays = RayQueue::with_capacity_in((band.width * band.rows) as usize, arena);
            stages::generate_camera_rays(&scene.camera, band, &mut rays);
            for first in (0..rays.len()).step_by(LANES) {
                let packet = rays.packet(first, tmin);
                let mut hit = HitPacket::new(f32::INFINITY);
                let mut lanes = [0u32; LANES];
                geometry.closest_hit_packet_counted(&packet, &mut hit, &mut lanes);
                let n = (rays.len() - first).min(LANES);
                for (lane, &c) in lanes.iter().enumerate().take(n) {
                    out[rays.pixel[first + lane] as usize] = c;
                }
            }
            progress(&FinishedRows::counted(band.rows));
        });
    CostMap {
        width: w,
        height: h,
        cost,
    }
}
