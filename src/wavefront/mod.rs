//! The packet tracer: the reference tracer's algorithm reorganised as a wavefront. The film
//! ([`crate::film`]) cuts the image into bands of rows rendered in parallel; a band's samples
//! are traced in runs of whole 4x2-pixel tiles, and within a run, all rays of one bounce are
//! gathered into typed queues, intersected 8 at a time as SIMD packets against the SoA
//! [`Geometry`], then shaded one by one with the same functions as the reference tracer
//! ([`crate::shade`]), which push the next bounce's mirror and refracted rays and this bounce's
//! shadow rays onto queues. No recursion: colour reaches a pixel as `throughput * local term`.
//!
//! ```text
//! generate_sample_rays -> for each bounce { intersect_closest -> shade_hits -> trace_shadow_rays }
//! ```
//!
//! A run's camera rays are its tiles' pixels row by row, each pixel's samples in order: with one
//! sample a packet of 8 rays is a 4x2 tile, with 8 or more a pixel's samples fill the lanes
//! (sample rays of a pixel are as coherent as rays get).
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

use crate::error::{Error, Result};
pub use crate::film::BAND_ROWS;
use crate::film::{FilmSpec, SampleBlock, is_nearest, render_film};
use crate::frame::Frame;
use crate::geometry::Geometry;
use crate::math::{Vec2, Vec3, saturate};
use crate::options::{Progress, RenderOptions, TILE_ROW_STEP};
use crate::raytree::{RayTree, SegmentKind};
use crate::scene::Scene;
use crate::shade::ShadeOptions;
use crate::stats::RayCounts;
pub use grid::render_grid_packet;
pub use heatmap::eye_ray_costs;
use queue::RayQueue;
use stages::{BounceQueues, intersect_closest, shade_hits, trace_shadow_rays};

// A `--tile` strip is whole bands, so it traces the packets the one-go render traces.
const _: () = assert!(TILE_ROW_STEP % BAND_ROWS == 0);

/// What every stage reads: the scene, its flattened geometry, the shading options.
pub struct Context<'s> {
    pub scene: &'s Scene,
    pub geometry: &'s Geometry,
    pub opts: &'s ShadeOptions,
}

/// The most samples one run of the wavefront traces: a band of a wide image, or of many
/// samples per pixel, is traced in several runs so its queues stay small (with one sample per
/// pixel, a band of 8 rows of up to 8192 pixels is one run).
pub const RUN_SAMPLES: u32 = 1 << 16;

/// What a run writes: the colour of its samples, the depth and normal of its pixels, the rays
/// it cast, and (for a single traced pixel) its ray tree. Ray `pixel` fields index `color`
/// (with one sample per pixel, a slot is a pixel).
pub struct BandOutput<'f> {
    /// Per sample slot of the block.
    pub color: &'f mut [Vec3],
    /// Per pixel (empty when not kept).
    pub depth: &'f mut [f32],
    pub normal: &'f mut [Vec3],
    /// Per pixel, the sample whose hit the depth and normal show.
    pub nearest: &'f [u32],
    pub spp: u32,
    pub rays: RayCounts,
    /// Time spent on each bounce.
    pub bounce_time: Vec<Duration>,
    pub tree: Option<&'f mut RayTree>,
}

impl BandOutput<'_> {
    /// Records the first hit of the camera ray of `slot` if its pixel's depth and normal show it.
    #[inline]
    pub fn record_hit(&mut self, slot: usize, t: f32, normal: Vec3) {
        if !self.depth.is_empty() && is_nearest(self.nearest, self.spp, slot) {
            let p = slot / self.spp as usize;
            self.depth[p] = t;
            self.normal[p] = normal;
        }
    }
}

/// A rectangle of pixels with one sample at each centre: columns `x0..x0 + width` of rows
/// `y0..y0 + rows` of an `image_width` x `image_height` image (a band of the grid picture or of
/// the heatmap's eye rays).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Band {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub rows: u32,
    pub image_width: u32,
    pub image_height: u32,
}

impl Band {
    /// Band `index` of a `width` x `height` image cut into whole-width bands of [`BAND_ROWS`]
    /// rows (the last one shorter).
    pub fn of_image(index: u32, width: u32, height: u32) -> Band {
        let y0 = index * BAND_ROWS;
        Band {
            x0: 0,
            y0,
            width,
            rows: BAND_ROWS.min(height - y0),
            image_width: width,
            image_height: height,
        }
    }

    /// Its camera samples: one per pixel, at the centre.
    pub fn samples(&self) -> CameraSamples<'static> {
        CameraSamples {
            x0: self.x0,
            y0: self.y0,
            width: self.width,
            rows: self.rows,
            image_width: self.image_width,
            image_height: self.image_height,
            spp: 1,
            offsets: &[],
        }
    }
}

/// The camera samples of a block: its pixels (full-image coordinates) and each sample's offset
/// in its pixel, slot `((y - y0) * width + (x - x0)) * spp + s` (no offsets: one sample at
/// each pixel centre).
#[derive(Clone, Copy, Debug)]
pub struct CameraSamples<'b> {
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub rows: u32,
    pub image_width: u32,
    pub image_height: u32,
    pub spp: u32,
    pub offsets: &'b [Vec2],
}

impl CameraSamples<'_> {
    /// The number of 4x2-pixel tiles, row-major: `width.div_ceil(4)` per row of tiles.
    pub fn tiles(&self) -> u32 {
        self.width.div_ceil(4) * self.rows.div_ceil(2)
    }
}

/// The tiles `first_tile..end_tile` of a block that one run of the wavefront traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Run {
    pub first_tile: u32,
    pub end_tile: u32,
}

/// The three arenas one worker thread reuses band after band.
#[derive(Default)]
pub struct Arenas {
    even: Bump,
    odd: Bump,
    scratch: Bump,
}

/// Renders `scene` with the packet tracer: the film streams bands of rows in parallel, and
/// each band is traced run by run, reporting finished rows to `progress`. The bytes do not
/// depend on the thread count: each sample is traced by exactly one band, in runs fixed by the
/// band alone.
pub fn render_packet(
    scene: &Scene,
    geometry: &Geometry,
    opts: &RenderOptions,
    progress: Progress,
) -> Result<Frame> {
    let ctx = Context {
        scene,
        geometry,
        opts: &opts.shade,
    };
    let spec = FilmSpec::for_options(opts);
    let (film, bands) = render_film(&spec, progress, Arenas::default, |arenas, block| {
        trace_block(&ctx, block, arenas)
    })?;
    let mut rays = RayCounts::default();
    let mut bounce_time: Vec<Duration> = Vec::new();
    for (r, times) in bands {
        rays = rays.merged(r);
        if bounce_time.len() < times.len() {
            bounce_time.resize(times.len(), Duration::ZERO);
        }
        for (a, b) in bounce_time.iter_mut().zip(times) {
            *a += b;
        }
    }
    let mut frame = film.into_frame(rays);
    frame.bounce_time = bounce_time;
    Ok(frame)
}

/// Traces every sample of `block` in runs of whole tiles, at most [`RUN_SAMPLES`] samples each
/// (at least one tile); returns the rays cast and the time per bounce.
pub fn trace_block(
    ctx: &Context<'_>,
    block: &mut SampleBlock,
    arenas: &mut Arenas,
) -> Result<(RayCounts, Vec<Duration>)> {
    let samples = CameraSamples {
        x0: block.x0,
        y0: block.y0,
        width: block.width,
        rows: block.rows,
        image_width: block.image_width,
        image_height: block.image_height,
        spp: block.spp,
        offsets: &block.offsets,
    };
    let mut out = BandOutput {
        color: &mut block.color,
        depth: &mut block.depth,
        normal: &mut block.normal,
        nearest: &block.nearest,
        spp: block.spp,
        rays: RayCounts::default(),
        bounce_time: Vec::new(),
        tree: None,
    };
    let per_run = (RUN_SAMPLES / (8 * samples.spp)).max(1);
    let mut first_tile = 0;
    while first_tile < samples.tiles() {
        let run = Run {
            first_tile,
            end_tile: (first_tile + per_run).min(samples.tiles()),
        };
        render_run(ctx, &samples, run, &mut out, arenas)?;
        first_tile = run.end_tile;
    }
    // Sums of overflowing colours stay at the largest finite value, as in the reference tracer.
    for c in out.color.iter_mut() {
        *c = saturate(*c);
    }
    Ok((out.rays, out.bounce_time))
}

/// Traces pixel `(x, y)` alone through the wavefront, recording its ray tree; returns the
/// pixel's colour and the tree. With several samples per pixel, the tree and colour are those
/// of the sample nearest the pixel centre, as in the reference tracer.
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
    let offsets = [opts.sampler.nearest_offset(x, y)];
    let samples = CameraSamples {
        x0: x,
        y0: y,
        width: 1,
        rows: 1,
        image_width: opts.width,
        image_height: opts.height,
        spp: 1,
        offsets: &offsets,
    };
    let (mut color, mut depth, mut normal) = ([Vec3::ZERO], [f32::INFINITY], [Vec3::ZERO]);
    let mut tree = RayTree::default();
    let mut out = BandOutput {
        color: &mut color,
        depth: &mut depth,
        normal: &mut normal,
        nearest: &[0],
        spp: 1,
        rays: RayCounts::default(),
        bounce_time: Vec::new(),
        tree: Some(&mut tree),
    };
    let run = Run {
        first_tile: 0,
        end_tile: 1,
    };
    render_run(&ctx, &samples, run, &mut out, &mut Arenas::default())?;
    Ok((color[0], tree))
}

/// The per-run driver: camera rays, then bounce after bounce until no ray is left.
fn render_run(
    ctx: &Context<'_>,
    samples: &CameraSamples<'_>,
    run: Run,
    out: &mut BandOutput<'_>,
    arenas: &mut Arenas,
) -> Result<()> {
    let Arenas { even, odd, scratch } = arenas;
    even.reset();
    odd.reset();
    let tiles = (run.end_tile - run.first_tile) as usize;
    let mut rays = RayQueue::with_capacity_in(tiles * 8 * samples.spp as usize, even);
    stages::generate_sample_rays(&ctx.scene.camera, samples, run, &mut rays);
    let band = (samples.y0, samples.rows);
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
fn check_queue<'a>(next: RayQueue<'a>, band: (u32, u32), bounce: u32) -> Result<RayQueue<'a>> {
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
        band.0,
        band.0 + band.1
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
