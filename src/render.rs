//! Whole-frame rendering: options, the choice of tracer, and the [`Frame`] they fill (colour,
//! plus the primary hit's distance and normal for the depth and normal images, and the rays
//! cast). Rows are rendered in parallel with rayon; every pixel is computed independently, so
//! the result does not depend on the thread count. A render reports finished rows to an
//! optional [`Progress`] hook (the CLI's progress bar); [`trace_ray_tree`] traces one pixel
//! again and records its ray tree.

use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::Geometry;
use crate::math::Vec3;
use crate::raytree::RayTree;
use crate::reference::ReferenceTracer;
use crate::scene::{Camera, Scene};
use crate::shade::ShadeOptions;
use crate::stats::RayCounts;
use crate::wavefront::render_packet;

/// The largest image the renderer accepts without `--max-pixels` (64 megapixels).
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 26;
/// The largest bounce count accepted without `--max-bounces`.
pub const DEFAULT_MAX_BOUNCES: u32 = 1000;
/// The most worker threads a render starts.
pub const MAX_THREADS: usize = 1024;
/// Worker-thread stack for the recursion of one bounce (measured: between 256 B and 1 KiB).
const STACK_PER_BOUNCE: usize = 8 << 10;
/// Bytes a frame holds per pixel (colour, depth, normal) plus the 8-bit image made from it.
const BYTES_PER_PIXEL: u64 = 28 + 3;

/// Which tracer renders the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tracer {
    /// The scalar recursive reference tracer (the specification).
    Reference,
    /// The 8-wide SIMD packet/wavefront tracer.
    Packet,
}

impl Tracer {
    /// Parses `reference` or `packet`.
    pub fn from_name(name: &str) -> Option<Tracer> {
        match name {
            "reference" => Some(Tracer::Reference),
            "packet" => Some(Tracer::Packet),
            _ => None,
        }
    }

    /// The name `--tracer` takes.
    pub fn name(self) -> &'static str {
        match self {
            Tracer::Reference => "reference",
            Tracer::Packet => "packet",
        }
    }
}

/// Everything that decides the pixels of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub shade: ShadeOptions,
    pub tracer: Tracer,
    /// Worker threads; 0 means all cores.
    pub threads: usize,
    /// Refuse frames with more pixels than this.
    pub max_pixels: u64,
    /// Refuse bounce counts above this.
    pub max_bounces: u32,
}

impl Default for RenderOptions {
    fn default() -> RenderOptions {
        RenderOptions {
            width: 512,
            height: 512,
            shade: ShadeOptions::default(),
            tracer: Tracer::Packet,
            threads: 0,
            max_pixels: DEFAULT_MAX_PIXELS,
            max_bounces: DEFAULT_MAX_BOUNCES,
        }
    }
}

/// A rendered frame, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Linear RGB per pixel.
    pub color: Vec<Vec3>,
    /// Distance along the primary ray to the first hit; `+inf` where nothing was hit.
    pub depth: Vec<f32>,
    /// Unit world normal of the first hit; zero where nothing was hit.
    pub normal: Vec<Vec3>,
    /// The rays cast to make the frame, by kind and bounce.
    pub rays: RayCounts,
    /// Packet tracer: the acceleration structure it built.
    pub accel: Option<AccelStats>,
    /// Packet tracer: time spent on each bounce, summed over worker threads.
    pub bounce_time: Vec<Duration>,
}

/// What building the packet tracer's geometry cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelStats {
    /// Flattening the scene to SoA arrays and building the BVH.
    pub build: Duration,
    /// BVH nodes.
    pub nodes: usize,
    /// Primitives in the BVH (planes stay outside).
    pub bounded: usize,
}

/// Told how many image rows a render has just finished; called from worker threads, so it
/// must be cheap and thread-safe (the CLI's progress bar; `&|_| {}` for none).
pub type Progress<'a> = &'a (dyn Fn(u32) + Sync);

impl Frame {
    /// The first pixel `(x, y)` holding a NaN or infinite value: in its colour anywhere, in its
    /// depth and normal where the primary ray hit (depth is `+inf` and the normal zero
    /// elsewhere). `None` when every value is finite, as it must be.
    pub fn non_finite_pixel(&self) -> Option<(u32, u32)> {
        let bad = |i: usize| {
            let hit = self.depth[i] != f32::INFINITY;
            !self.color[i].is_finite()
                || self.depth[i].is_nan()
                || (hit && !self.normal[i].is_finite())
                || (!hit && self.normal[i] != Vec3::ZERO)
        };
        let w = self.width.max(1) as usize;
        (0..self.color.len())
            .find(|&i| bad(i))
            .map(|i| ((i % w) as u32, (i / w) as u32))
    }

    /// A black frame with no hits.
    pub fn new(width: u32, height: u32) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            color: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            normal: vec![Vec3::ZERO; n],
            rays: RayCounts::default(),
            accel: None,
            bounce_time: Vec::new(),
        }
    }
}

/// Checks the options against the limits before anything is allocated.
pub fn check_options(opts: &RenderOptions) -> Result<()> {
    if opts.width == 0 || opts.height == 0 {
        return Err(Error::Usage(format!(
            "image size {}x{}: expected a width and height of at least 1",
            opts.width, opts.height
        )));
    }
    let pixels = opts.width as u64 * opts.height as u64;
    if pixels > opts.max_pixels {
        return Err(Error::Limit(format!(
            "image size {}x{} is {pixels} pixels, over the limit of {} (raise it with --max-pixels N)",
            opts.width, opts.height, opts.max_pixels
        )));
    }
    if opts.shade.bounces > opts.max_bounces {
        return Err(Error::Limit(format!(
            "bounce count {} is over the limit of {} (raise it with --max-bounces N)",
            opts.shade.bounces, opts.max_bounces
        )));
    }
    if !(opts.shade.weight >= 0.0 && opts.shade.weight.is_finite()) {
        return Err(Error::Usage(format!(
            "weight {}: expected a non-negative number",
            opts.shade.weight
        )));
    }
    if opts.threads > MAX_THREADS {
        return Err(Error::Limit(format!(
            "thread count {} is over the limit of {MAX_THREADS}",
            opts.threads
        )));
    }
    // Probe for the frame's memory so a size that cannot be allocated is an error, not an abort.
    let bytes = pixels.saturating_mul(BYTES_PER_PIXEL);
    let fits = usize::try_from(bytes).is_ok_and(|b| Vec::<u8>::new().try_reserve_exact(b).is_ok());
    if !fits {
        return Err(Error::Limit(format!(
            "image size {}x{} needs {} MiB, more memory than can be allocated",
            opts.width,
            opts.height,
            (pixels as u128 * BYTES_PER_PIXEL as u128) >> 20
        )));
    }
    Ok(())
}

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
    check_options(opts)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .stack_size(stack_size(opts.shade.bounces))
        .build()
        .map_err(|e| {
            Error::Other(format!(
                "cannot start worker threads ({} MiB of stack each for {} bounces): {e}",
                stack_size(opts.shade.bounces) >> 20,
                opts.shade.bounces
            ))
        })?;
    match opts.tracer {
        Tracer::Reference => Ok(pool.install(|| render_reference(scene, opts, progress))),
        Tracer::Packet => {
            let t0 = Instant::now();
            let geometry = Geometry::from_scene(scene);
            let accel = AccelStats {
                build: t0.elapsed(),
                nodes: geometry.bvh().nodes.len(),
                bounded: geometry.len() - geometry.planes.len(),
            };
            let mut frame = pool.install(|| render_packet(scene, &geometry, opts, progress))?;
            frame.accel = Some(accel);
            Ok(frame)
        }
    }
}

/// The worker-thread stack a render with `bounces` needs: the reference tracer recurses once
/// per bounce (and the object tree, at most `MAX_NESTING` deep, once per level).
fn stack_size(bounces: u32) -> usize {
    (8 << 20) + bounces as usize * STACK_PER_BOUNCE
}

/// Renders with the reference tracer, rows in parallel; each row counts its rays locally and
/// the counts are summed at the end.
pub fn render_reference(scene: &Scene, opts: &RenderOptions, progress: Progress) -> Frame {
    let (w, h) = (opts.width, opts.height);
    let mut frame = Frame::new(w, h);
    let tracer = ReferenceTracer::new(scene, opts.shade);
    frame.rays = frame
        .color
        .par_chunks_mut(w as usize)
        .zip(frame.depth.par_chunks_mut(w as usize))
        .zip(frame.normal.par_chunks_mut(w as usize))
        .enumerate()
        .map(|(y, ((color, depth), normal))| {
            let mut rays = RayCounts::default();
            for x in 0..w {
                let ray = scene
                    .camera
                    .generate_ray(Camera::pixel_point(x, y as u32, w, h));
                let sample = tracer.trace_primary_counted(&ray, None, &mut rays);
                let i = x as usize;
                color[i] = sample.color;
                if let Some(hit) = sample.hit {
                    depth[i] = hit.t;
                    normal[i] = hit.normal;
                }
            }
            progress(1);
            rays
        })
        .reduce(RayCounts::default, RayCounts::merged);
    frame
}

/// Checks that pixel `(x, y)` (x from the left, y from the top) lies in the image of `opts`.
pub fn check_pixel(x: u32, y: u32, opts: &RenderOptions) -> Result<()> {
    if x >= opts.width || y >= opts.height {
        return Err(Error::Usage(format!(
            "pixel ({x}, {y}) is outside the {}x{} image: expected x in 0..={} and y in 0..={}",
            opts.width,
            opts.height,
            opts.width.saturating_sub(1),
            opts.height.saturating_sub(1)
        )));
    }
    Ok(())
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
    let ray = scene
        .camera
        .generate_ray(Camera::pixel_point(x, y, opts.width, opts.height));
    match opts.tracer {
        Tracer::Reference => {
            // The reference tracer recurses once per bounce: give it the render's stack.
            std::thread::scope(|s| {
                std::thread::Builder::new()
                    .stack_size(stack_size(opts.shade.bounces))
                    .spawn_scoped(s, || {
                        let mut tree = RayTree::new();
                        let tracer = ReferenceTracer::new(scene, opts.shade);
                        let sample = tracer.trace_primary(&ray, Some(&mut tree));
                        (tree, sample.color)
                    })
                    .map_err(|e| Error::Other(format!("cannot start a thread: {e}")))?
                    .join()
                    .map_err(|_| Error::Other("the ray-tree thread failed".to_string()))
            })
        }
        Tracer::Packet => {
            let geometry = Geometry::from_scene(scene);
            let (color, tree) = crate::wavefront::trace_pixel_tree(scene, &geometry, opts, x, y)?;
            Ok((tree, color))
        }
    }
}
