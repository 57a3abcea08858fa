//! The packet tracer's frame loop for the grid picture (`-visualize_grid`): bands of rows in
//! parallel as for a render, camera rays queued by the same stage in the same 4x2 tiles, then
//! each queued ray marched through the grid one by one. The 3D-DDA is a scalar loop whose length
//! differs from ray to ray, so there is no packet kernel for it: both tracers call the same
//! [`crate::grid::picture::pixel`], which makes their pictures identical.

use bumpalo::Bump;
use rayon::prelude::*;

use super::queue::RayQueue;
use super::{BAND_ROWS, Band, stages};
use crate::frame::Frame;
use crate::grid::Grid;
use crate::grid::picture::{self, GridView};
use crate::options::{FinishedRows, Progress, RenderOptions};
use crate::raytree::SegmentKind;
use crate::scene::Scene;
use crate::stats::RayCounts;

/// Draws the grid picture of `grid` with the packet tracer's bands and camera queues.
pub fn render_grid_packet(
    scene: &Scene,
    grid: &Grid,
    view: GridView,
    opts: &RenderOptions,
    progress: Progress,
) -> Frame {
    let (w, h) = (opts.width, opts.height);
    let mut frame = Frame::new(w, h);
    let tmin = scene.camera.tmin();
    let band_len = (w * BAND_ROWS) as usize;
    frame.rays = frame
        .color
        .par_chunks_mut(band_len)
        .zip(frame.depth.par_chunks_mut(band_len))
        .zip(frame.normal.par_chunks_mut(band_len))
        .enumerate()
        .map_init(Bump::new, |arena, (i, ((color, depth), normal))| {
            arena.reset();
            let band = Band::of_image(i as u32, w, h);
            let mut rays = RayQueue::with_capacity_in((band.width * band.rows) as usize, arena);
            stages::generate_camera_rays(&scene.camera, band, &mut rays);
            for k in 0..rays.len() {
                let px = rays.pixel[k] as usize;
                let (c, hit) = picture::pixel(scene, grid, view, &rays.ray(k), tmin);
                color[px] = c;
                if let Some((t, n)) = hit {
                    depth[px] = t;
                    normal[px] = n;
                }
            }
            let mut counts = RayCounts::default();
            counts.count_many(SegmentKind::Eye, 0, rays.len() as u64);
            progress(&FinishedRows::counted(band.rows));
            counts
        })
        .reduce(RayCounts::default, RayCounts::merged);
    frame
}
