//! What a render is asked to do and the checks made before anything is allocated: the
//! [`RenderOptions`] (size, shading switches, tracer, threads, limits), the [`Tracer`] choice,
//! the [`Progress`] hook, and the limits with the flags that lift them. A leaf shared by the
//! command line, `render.rs` and both tracers' frame loops.

use crate::error::{Error, Result};
use crate::shade::ShadeOptions;

/// The largest image the renderer accepts without `--max-pixels` (64 megapixels).
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 26;
/// The largest bounce count accepted without `--max-bounces`.
pub const DEFAULT_MAX_BOUNCES: u32 = 1000;
/// The most worker threads a render starts.
pub const MAX_THREADS: usize = 1024;
/// The most cells a grid may have without `--max-grid-cells` (16 Mi cells, 64 MiB of counts).
pub const DEFAULT_MAX_GRID_CELLS: u64 = 1 << 24;
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

/// The grid pictures (see `grid::picture`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridView {
    /// The occupied cells shaded by the scene's lights (`-visualize_grid`).
    Lit,
    /// The occupied cells in their count's colour, unlit (`-visualize_grid_count`).
    Count,
}

/// The course's uniform grid (`-grid NX NY NZ`): whitted renders with its BVH whatever this
/// says; the grid is built for `--stats` and for its picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridOptions {
    /// Cells per axis.
    pub cells: [u32; 3],
    /// Draw the grid's occupancy instead of the scene.
    pub view: Option<GridView>,
    /// Refuse grids with more cells than this (`--max-grid-cells`).
    pub max_cells: u64,
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
    /// The course's grid, if asked for.
    pub grid: Option<GridOptions>,
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
            grid: None,
        }
    }
}

/// Told how many image rows a render has just finished; called from worker threads, so it
/// must be cheap and thread-safe (the CLI's progress bar; `&|_| {}` for none).
pub type Progress<'a> = &'a (dyn Fn(u32) + Sync);

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
    if let Some(grid) = &opts.grid {
        check_grid(grid)?;
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

/// Checks a grid resolution: at least one cell per axis, no more cells than its limit.
pub fn check_grid(grid: &GridOptions) -> Result<()> {
    let [nx, ny, nz] = grid.cells;
    if grid.cells.contains(&0) {
        return Err(Error::Usage(format!(
            "grid {nx}x{ny}x{nz}: expected at least 1 cell along each axis"
        )));
    }
    let total = grid.cells.iter().map(|&n| n as u64).product::<u64>();
    if total > grid.max_cells {
        return Err(Error::Limit(format!(
            "grid {nx}x{ny}x{nz} has {total} cells, over the limit of {} (raise it with \
             --max-grid-cells N)",
            grid.max_cells
        )));
    }
    Ok(())
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

/// The worker-thread stack a render with `bounces` needs: the reference tracer recurses once
/// per bounce (and the object tree, at most `MAX_NESTING` deep, once per level).
pub fn stack_size(bounces: u32) -> usize {
    (8 << 20) + bounces as usize * STACK_PER_BOUNCE
}
