//! The packet tracer: the reference tracer's algorithm reorganised as a wavefront. The image is
//! cut into bands of rows rendered in parallel; within a band, all rays of one bounce are
//! gathered into typed queues, intersected 8 at a time as SIMD packets against the SoA
//! [`Geometry`], then shaded one by one with the same functions as the reference tracer
//! ([`crate::shade`]), which push the next bounce's mirror and refracted rays and this bounce's
//! shadow rays onto queues. No recursion: colour reaches a pixel as `throughput * local term`.
//!
//! ```text
//! generate_camera_rays -> for each bounce { intersect_closest -> shade_hits -> trace_shadow_rays }
//! ```
//!
//! Memory: the ray queue of bounce `b` lives in arena `b & 1`; the other arena receives the rays
//! of bounce `b + 1` and the first is reset once bounce `b` is done. Hits and shadow rays live
//! in a scratch arena reset at every bounce.

mod grid;
mod heatmap;
pub mod queue;
mod stages;

use std::time::{Duration, Instant};

use bumpalo::Bump;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::geometry::Geometry;
use crate::math::{Vec3, saturate};
use crate::options::{Progress, RenderOptions, TILE_ROW_STEP, Window};
use crate::raytree::{RayTree, SegmentKind};
use crate::scene::Scene;
use crate::shade::ShadeOptions;
use crate::stats::RayCounts;
pub use grid::render_grid_packet;
pub use heatmap::eye_ray_costs;
use queue::RayQueue;
use stages::{BounceQueues, intersect_closest, shade_hits, trace_shadow_rays};

/// Rows per band: the unit of parallel work (a multiple of the 2-row camera tiles).
pub const BAND_ROWS: u32 = 8;
// A `--tile` strip is whole bands, so it traces the packets the one-go render traces.
const _: () = assert!(TILE_ROW_STEP % BAND_ROWS == 0);

/// What every stage reads: the scene, its flattened geometry, the shading options.
pub struct Context<'s> {
    pub scene: &'s Scene,
    pub geometry: &'s Geometry,
    pub opts: &'s ShadeOptions,
}

/// What a band writes: colour, depth and normal of its pixels, the rays it cast, and (for a
/// single traced pixel) its ray tree.
pub struct BandOutput<'f> {
    pub color: &'f mut [Vec3],
    pub depth: &'f mut [f32],
    pub normal: &'f mut [Vec3],
    pub rays: RayCounts,
    /// Time spent on each bounce.
    pub bounce_time: Vec<Duration>,
    pub tree: Option<&'f mut RayTree>,
}

/// A rectangle of pixels to render: columns `x0..x0 + width` of rows `y0..y0 + rows` of an
/// `image_width` x `image_height` image (a band of a frame's window, or a single pixel, for ray
/// trees).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Band {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub rows: u32,
    pub image_width: u32,
    pub image_height: u32,
}

/// The three arenas one worker thread reuses band after band.
#[derive(Default)]
pub struct Arenas {
    even: Bump,
    odd: Bump,
    scratch: Bump,
}

/// Renders `scene` with the packet tracer, bands of rows in parallel, reporting finished rows
/// to `progress`. The bytes do not depend on the thread count: each pixel is computed by exactly
/// one band, in a fixed order. Bands are [`BAND_ROWS`] rows of the full image (starting at row
/// 0) clipped to `opts.window()`, so a crop of whole bands traces the very packets the whole
/// render traces for those rows.
pub fn render_packet(
    scene: &Scene,
    geometry: &Geometry,
    opts: &RenderOptions,
    progress: Progress,
) -> Result<Frame> {
    let win = opts.window();
    let mut frame = Frame::window(win, opts.width, opts.height);
    let ctx = Context {
        scene,
        geometry,
        opts: &opts.shade,
    };
    let bands = window_bands(win, opts.width, opts.height);
    let mut work = Vec::with_capacity(bands.len());
    let (mut color, mut depth, mut normal) = (
        frame.color.as_mut_slice(),
        frame.depth.as_mut_slice(),
        frame.normal.as_mut_slice(),
    );
    for band in bands {
        let n = (band.width * band.rows) as usize;
        let (c, rest_c) = color.split_at_mut(n);
        let (d, rest_d) = depth.split_at_mut(n);
        let (m, rest_m) = normal.split_at_mut(n);
        (color, depth, normal) = (rest_c, rest_d, rest_m);
        work.push((band, c, d, m));
    }
    (frame.rays, frame.bounce_time) = work
        .into_par_iter()
        .map_init(Arenas::default, |arenas, (band, color, depth, normal)| {
            let mut out = BandOutput {
                color,
                depth,
                normal,
                rays: RayCounts::default(),
                bounce_time: Vec::new(),
                tree: None,
            };
            render_band(&ctx, band, &mut out, arenas)?;
            // Sums of overflowing colours stay at the largest finite value, as in the
            // reference tracer.
            for c in out.color.iter_mut() {
                *c = saturate(*c);
            }
            progress(band.rows);
            Ok((out.rays, out.bounce_time))
        })
        .try_reduce(
            Default::default,
            |(rays_a, mut time_a), (rays_b, time_b)| {
                if time_a.len() < time_b.len() {
                    time_a.resize(time_b.len(), Duration::ZERO);
                }
                for (a, b) in time_a.iter_mut().zip(time_b) {
                    *a += b;
                }
                Ok((rays_a.merged(rays_b), time_a))
            },
        )?;
    Ok(frame)
}

/// The bands of `win`, top to bottom: the full image's bands of [`BAND_ROWS`] rows (from row 0)
/// that meet the window, each clipped to it.
fn window_bands(win: Window, image_width: u32, image_height: u32) -> Vec<Band> {
    let mut bands = Vec::new();
    let mut y0 = win.y0;
    while y0 < win.y1 {
        let y1 = ((y0 / BAND_ROWS + 1) * BAND_ROWS).min(win.y1);
        bands.push(Band {
            x0: win.x0,
            y0,
            width: win.width(),
            rows: y1 - y0,
            image_width,
            image_height,
        });
        y0 = y1;
    }
    bands
}

/// Traces pixel `(x, y)` alone through the wavefront, recording its ray tree; returns the
/// pixel's colour and the tree.
pub fn trace_pixel_tree(
    scene: &Scene,
    geometry: &Geometry,
    opts: &RenderOptions,
    x: u32,
    y: u32,
) -> Result<(Vec3, RayTree)> {
    let ctx = Context {
        scene,
        geometry,
        opts: &opts.shade,
    };
    let band = Band {
        x0: x,
        y0: y,
        width: 1,
        rows: 1,
        image_width: opts.width,
        image_height: opts.height,
    };
    let (mut color, mut depth, mut normal) = ([Vec3::ZERO], [f32::INFINITY], [Vec3::ZERO]);
    let mut tree = RayTree::default();
    let mut out = BandOutput {
        color: &mut color,
        depth: &mut depth,
        normal: &mut normal,
        rays: RayCounts::default(),
        bounce_time: Vec::new(),
        tree: Some(&mut tree),
    };
    render_band(&ctx, band, &mut out, &mut Arenas::default())?;
    Ok((color[0], tree))
}

/// The per-band driver: camera rays, then bounce after bounce until no ray is left.
fn render_band(
    ctx: &Context<'_>,
    band: Band,
    out: &mut BandOutput<'_>,
    arenas: &mut Arenas,
) -> Result<()> {
    let Arenas { even, odd, scratch } = arenas;
    even.reset();
    odd.reset();
    let mut rays = RayQueue::with_capacity_in((band.width * band.rows) as usize, even);
    stages::generate_camera_rays(&ctx.scene.camera, band, &mut rays);
    let mut bounce = 0;
    // Two bounces per turn so each queue's arena is named: even bounces read `even`, odd `odd`.
    loop {
        let next = run_bounce(ctx, bounce, rays, odd, scratch, out);
        even.reset();
        let next = check_queue(next, band, bounce)?;
        if next.is_empty() {
            return Ok(());
        }
        bounce += 1;
        rays = run_bounce(ctx, bounce, next, even, scratch, out);
        odd.reset();
        rays = check_queue(rays, band, bounce)?;
        if rays.is_empty() {
            return Ok(());
        }
        bounce += 1;
    }
}

/// The most rays one band may queue for a bounce (about 200 MB of queue and hit columns).
pub const MAX_BAND_RAYS: usize = 1 << 22;

/// Refuses a queue past [`MAX_BAND_RAYS`]: where every hit spawns both a mirror and a refracted
/// ray whose colours are too bright for the weight cutoff to prune, the rays double each bounce.
fn check_queue<'a>(next: RayQueue<'a>, band: Band, bounce: u32) -> Result<RayQueue<'a>> {
    if next.len() <= MAX_BAND_RAYS {
        return Ok(next);
    }
    Err(Error::Limit(format!(
        "the packet tracer would queue {} rays at bounce {} for rows {}..{} (its limit is \
         {MAX_BAND_RAYS} per band of rows): there, every hit spawns both a mirror and a refracted \
         ray and the weight cutoff prunes neither; lower --bounces, raise --weight, or render \
         with --tracer reference",
        next.len(),
        bounce + 1,
        band.y0,
        band.y0 + band.rows
    )))
}

/// One bounce: intersect the queued rays, shade the hits, trace their shadow rays. Returns the
/// next bounce's rays, queued in `next_arena`.
fn run_bounce<'n>(
    ctx: &Context<'_>,
    bounce: u32,
    rays: RayQueue<'_>,
    next_arena: &'n Bump,
    scratch: &mut Bump,
    out: &mut BandOutput<'_>,
) -> RayQueue<'n> {
    let start = Instant::now();
    scratch.reset();
    let tmin = if bounce == 0 {
        ctx.scene.camera.tmin()
    } else {
        crate::shade::EPSILON
    };
    let hits = intersect_closest(ctx.geometry, &rays, tmin, scratch);
    // Upper bounds: one shadow ray per light and hit (with shadows on), two children per hit.
    let shadows = if ctx.opts.shadows {
        (ctx.scene.lights.len() * rays.len()).min(MAX_BAND_RAYS)
    } else {
        0
    };
    let children = if bounce < ctx.opts.bounces {
        (2 * rays.len()).min(MAX_BAND_RAYS)
    } else {
        0
    };
    let mut q = BounceQueues {
        shadows: queue::ShadowQueue::with_capacity_in(shadows, scratch),
        next: RayQueue::with_capacity_in(children, next_arena),
        rays,
        hits,
    };
    shade_hits(ctx, bounce, &mut q, out);
    trace_shadow_rays(ctx, &q.shadows, out);
    for kind in q.rays.kind.iter() {
        out.rays.count(*kind, bounce);
    }
    out.rays
        .count_many(SegmentKind::Shadow, bounce, q.shadows.len() as u64);
    let b = bounce as usize;
    if out.bounce_time.len() <= b {
        out.bounce_time.resize(b + 1, Duration::ZERO);
    }
    out.bounce_time[b] += start.elapsed();
    q.next
}
