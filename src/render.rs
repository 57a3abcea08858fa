//! Whole-frame rendering: options, the choice of tracer, and the [`Frame`] they fill (colour,
//! plus the primary hit's distance and normal for the depth and normal images). Rows are
//! rendered in parallel with rayon; every pixel is computed independently, so the result does
//! not depend on the thread count.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::Geometry;
use crate::math::Vec3;
use crate::reference::ReferenceTracer;
use crate::scene::{Camera, Scene};
use crate::shade::ShadeOptions;
use crate::wavefront::render_packet;

/// The largest image the renderer accepts without `--max-pixels` (64 megapixels).
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 26;
/// The largest bounce count accepted.
pub const MAX_BOUNCES: u32 = 1000;

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
}

impl Frame {
    /// A black frame with no hits.
    pub fn new(width: u32, height: u32) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            color: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            normal: vec![Vec3::ZERO; n],
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
    if opts.shade.bounces > MAX_BOUNCES {
        return Err(Error::Limit(format!(
            "bounce count {} is over the limit of {MAX_BOUNCES}",
            opts.shade.bounces
        )));
    }
    if !(opts.shade.weight >= 0.0 && opts.shade.weight.is_finite()) {
        return Err(Error::Usage(format!(
            "weight {}: expected a non-negative number",
            opts.shade.weight
        )));
    }
    Ok(())
}

/// Renders `scene` with `opts`.
pub fn render(scene: &Scene, opts: &RenderOptions) -> Result<Frame> {
    check_options(opts)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.threads)
        .build()
        .map_err(|e| Error::Other(format!("cannot start worker threads: {e}")))?;
    match opts.tracer {
        Tracer::Reference => Ok(pool.install(|| render_reference(scene, opts))),
        Tracer::Packet => {
            let geometry = Geometry::from_scene(scene);
            Ok(pool.install(|| render_packet(scene, &geometry, opts)))
        }
    }
}

/// Renders with the reference tracer, rows in parallel.
pub fn render_reference(scene: &Scene, opts: &RenderOptions) -> Frame {
    let (w, h) = (opts.width, opts.height);
    let mut frame = Frame::new(w, h);
    let tracer = ReferenceTracer::new(scene, opts.shade);
    frame
        .color
        .par_chunks_mut(w as usize)
        .zip(frame.depth.par_chunks_mut(w as usize))
        .zip(frame.normal.par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(y, ((color, depth), normal))| {
            for x in 0..w {
                let ray = scene
                    .camera
                    .generate_ray(Camera::pixel_point(x, y as u32, w, h));
                let sample = tracer.trace_primary(&ray, None);
                let i = x as usize;
                color[i] = sample.color;
                if let Some(hit) = sample.hit {
                    depth[i] = hit.t;
                    normal[i] = hit.normal;
                }
            }
        });
    frame
}
