//! Whole-frame rendering, the front door both the command line and the library use: it starts
//! the worker threads and hands the frame to the chosen tracer's own frame loop
//! ([`crate::reference::render_reference`] or [`crate::wavefront::render_packet`]), and traces
//! one pixel again to record its ray tree ([`trace_ray_tree`]). It knows no tracer's insides.
//! With a grid in the options it builds the course's grid first (for `--stats`), and for a grid
//! picture hands the frame to the tracer's grid loop instead.

use std::time::Instant;

use crate::error::{Error, Result};
use crate::frame::{CostMap, Frame};
use crate::geometry::Geometry;
use crate::grid::Grid;
use crate::math::Vec3;
use crate::options::{Progress, RenderOptions, Tracer, check_options, check_pixel, stack_size};
use crate::raytree::RayTree;
use crate::reference::{render_grid_reference, render_reference, trace_pixel_tree};
use crate::scene::Scene;
use crate::stats::{AccelStats, GridStats};
use crate::wavefront::{render_grid_packet, render_packet};

/// Renders `scene` with `opts`.
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Frame> {
    render_with_progress(scene, opts, &|_| {})
}

/// Renders `scene` with `opts`, reporting finished rows to `progress`.
pub fn render_with_progress(
    scene: &Scene,
    opts: &RenderOptions,
    progress: Progress,
) -> Result<Frame> {
    render_on(&worker_pool(opts)?, scene, opts, progress)
}

/// The worker threads a render with `opts` runs on: `opts.threads` of them, each with the
/// stack its bounces need, pinned one to a CPU when they take every CPU the process may use.
/// The command line makes one pool for the whole run and loads the scene and encodes the
/// images on it too: the threads that render are then already running, spread over the CPUs
/// and with their memory in use.
pub fn worker_pool(opts: &RenderOptions) -> Result<rayon::ThreadPool> {
    check_options(opts)?;
    crate::workers::pool(opts.threads, Some(stack_size(opts.shade.bounces))).map_err(|e| {
        Error::Other(format!(
            "cannot start worker threads ({} MiB of stack each for {} bounces): {e}",
            stack_size(opts.shade.bounces) >> 20,
            opts.shade.bounces
        ))
    })
}

/// Renders `scene` with `opts` on `pool` (made by [`worker_pool`] for these options),
/// reporting finished rows to `progress`.
pub fn render_on(
    pool: &rayon::ThreadPool,
    scene: &Scene,
    opts: &RenderOptions,
    progress: Progress,
) -> Result<Frame> {
    check_options(opts)?;
    if let Some(grid_opts) = &opts.grid {
        let t0 = Instant::now();
        let grid = Grid::build(scene, grid_opts.cells);
        let stats = GridStats {
            build: t0.elapsed(),
            ..grid.stats()
        };
        let mut frame = match (grid_opts.view, opts.tracer) {
            (Some(view), Tracer::Reference) => {
                pool.install(|| render_grid_reference(scene, &grid, view, opts, progress))
            }
            (Some(view), Tracer::Packet) => {
                pool.install(|| render_grid_packet(scene, &grid, view, opts, progress))
            }
            (None, _) => render_scene(scene, opts, pool, progress)?,
        };
        frame.grid = Some(stats);
        return Ok(frame);
    }
    render_scene(scene, opts, pool, progress)
}

/// Renders the scene itself (not the grid picture) with the chosen tracer.
fn render_scene(
    scene: &Scene,
    opts: &RenderOptions,
    pool: &rayon::ThreadPool,
    progress: Progress,
) -> Result<Frame> {
    match opts.tracer {
        Tracer::Reference => pool.install(|| render_reference(scene, opts, progress)),
        Tracer::Packet => {
            let t0 = Instant::now();
            // on the render's threads: the BVH build is parallel
            let geometry = pool.install(|| Geometry::from_scene(scene));
            let accel = AccelStats {
                build: t0.elapsed(),
                nodes: geometry.bvh().nodes().len(),
                bounded: geometry.len() - geometry.planes.len(),
            };
            let mut frame = pool.install(|| render_packet(scene, &geometry, opts, progress))?;
            frame.accel = Some(accel);
            Ok(frame)
        }
    }
}

/// The traversal cost of every pixel's eye ray in the packet tracer (BVH nodes entered plus
/// primitives tested), for `--heatmap`; whatever `opts.tracer` says, the packet tracer's BVH
/// is what it measures.
pub fn eye_ray_costs(scene: &Scene, opts: &RenderOptions, progress: Progress) -> Result<CostMap> {
    let pool = worker_pool(opts)?;
    let geometry = pool.install(|| Geometry::from_scene(scene));
    Ok(pool.install(|| crate::wavefront::eye_ray_costs(scene, &geometry, opts, progress)))
}

/// Traces pixel `(x, y)` of the frame `opts` describes once more, recording its ray tree (the
/// render itself never records, so it stays fast). The colour is the pixel's colour.
pub fn trace_ray_tree(
    scene: &Scene,
    opts: &RenderOptions,
    x: u32,
    y: u32,
) -> Result<(RayTree, Vec3)> {
    check_options(opts)?;
    check_pixel(x, y, opts)?;
    let (color, tree) = match opts.tracer {
        Tracer::Reference => trace_pixel_tree(scene, opts, x, y)?,
        Tracer::Packet => {
            let geometry = Geometry::from_scene(scene);
            crate::wavefront::trace_pixel_tree(scene, &geometry, opts, x, y)?
        }
    };
    Ok((tree, color))
}
