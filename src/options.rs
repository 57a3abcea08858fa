//! What a render is asked to do and the checks made before anything is allocated: the
//! [`RenderOptions`] (size, crop window, shading switches, sampling and filter, tracer,
//! threads, limits), the
//! [`Tracer`] choice, the [`Window`] of the full image a render covers (`--crop`, `--tile`), the
//! [`Progress`] hook, and the limits with the flags that lift them. A leaf shared by the command
//! line, `render.rs`, both tracers' frame loops and the tile merge.

use std::ops::Range;

use crate::error::{Error, Result};
use crate::filter::Filter;
use crate::math::Vec3;
use crate::sampler::Sampler;
use crate::shade::ShadeOptions;

/// The largest image the renderer accepts without `--max-pixels` (64 megapixels).
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 26;
/// The largest bounce count accepted without `--max-bounces`.
pub const DEFAULT_MAX_BOUNCES: u32 = 1000;
/// The most worker threads a render starts.
pub const MAX_THREADS: usize = 1024;
/// The most cells a grid may have without `--max-grid-cells` (16 Mi cells, 64 MiB of counts).
pub const DEFAULT_MAX_GRID_CELLS: u64 = 1 << 24;
/// The most samples per pixel accepted without `--max-samples`.
pub const DEFAULT_MAX_SAMPLES: u32 = 1024;
/// The largest filter support radius (in pixels) accepted without `--max-filter-radius`.
pub const DEFAULT_MAX_FILTER_RADIUS: u32 = 32;
/// Worker-thread stack for the recursion of one bounce (measured: between 256 B and 1 KiB).
const STACK_PER_BOUNCE: usize = 8 << 10;
/// Bytes a frame holds per pixel for colour, plus the 8-bit image made from it.
const BYTES_PER_PIXEL: u64 = 12 + 3;
/// Bytes a frame holds per pixel for depth and normal, when kept.
const BYTES_PER_PIXEL_AUX: u64 = 16;
/// Bytes the film holds per sample in flight (colour and offset).
const BYTES_PER_SAMPLE: u64 = 20;
/// `--tile` strips start and end on multiples of this many rows (the last ends at the image's
/// bottom): a whole number of the packet tracer's bands, so a tile traces exactly the packets
/// the one-go render traces for its rows.
pub const TILE_ROW_STEP: u32 = 8;

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

/// A window of the full image: columns `x0..x1` and rows `y0..y1` (half-open, x from the left,
/// y from the top, in the full image's pixel coordinates).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Window {
    pub x0: u32,
    pub x1: u32,
    pub y0: u32,
    pub y1: u32,
}

impl Window {
    /// The whole `width` x `height` image.
    pub fn full(width: u32, height: u32) -> Window {
        Window {
            x0: 0,
            x1: width,
            y0: 0,
            y1: height,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels in the window.
    pub fn pixels(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }

    /// Tile `index` of `count` (`--tile I/N`) of a `width` x `height` image: a horizontal strip
    /// of whole rows. The image's rows are grouped in `B = ceil(height / 8)` runs of
    /// [`TILE_ROW_STEP`] rows (the last may be shorter), and tile `I` takes runs
    /// `floor(I * B / N)` to `floor((I + 1) * B / N)`: N strips as equal as runs allow, top to
    /// bottom, each at least one run.
    pub fn tile(index: u32, count: u32, width: u32, height: u32) -> Result<Window> {
        let runs = height.div_ceil(TILE_ROW_STEP);
        if count == 0 || index >= count {
            return Err(Error::Usage(format!(
                "option --tile {index}/{count}: expected a tile I/N with 0 <= I < N"
            )));
        }
        if count > runs {
            return Err(Error::Usage(format!(
                "option --tile {index}/{count}: a {width}x{height} image has {runs} strips of \
                 {TILE_ROW_STEP} rows to share, fewer than {count} tiles"
            )));
        }
        let row =
            |i: u32| ((i as u64 * runs as u64 / count as u64) as u32 * TILE_ROW_STEP).min(height);
        Ok(Window {
            x0: 0,
            x1: width,
            y0: row(index),
            y1: row(index + 1),
        })
    }
}

impl std::fmt::Display for Window {
    /// `X0 X1 Y0 Y1`, as `--crop` takes it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {} {} {}", self.x0, self.x1, self.y0, self.y1)
    }
}

/// Everything that decides the pixels of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// The full image's size (a crop renders a window of it).
    pub width: u32,
    pub height: u32,
    /// Render only this window of the full image (`--crop`, `--tile`); `None`: all of it.
    pub crop: Option<Window>,
    pub shade: ShadeOptions,
    /// Where the samples of a pixel lie, and how many there are ([`Sampler::default`]: one, at
    /// the centre).
    pub sampler: Sampler,
    /// How samples become pixels ([`Filter::default`]: the average of a pixel's own samples).
    pub filter: Filter,
    /// Keep each pixel's depth and normal in the frame (16 bytes a pixel); the depth and normal
    /// images need them, a colour image does not.
    pub depth_normal: bool,
    /// Keep every sample's colour in the frame (for the `-render_samples` picture).
    pub keep_samples: bool,
    /// Keep every pixel in the frame (the default). Without, the frame holds no colour, depth
    /// or normals, and the render no memory for them: for a caller whose images are all made
    /// from the rows its progress hook sees (the command line's images written while
    /// rendering).
    pub keep_pixels: bool,
    pub tracer: Tracer,
    /// Worker threads; 0 means all cores.
    pub threads: usize,
    /// Refuse renders of more pixels than this (a crop counts its window's pixels).
    pub max_pixels: u64,
    /// Refuse bounce counts above this.
    pub max_bounces: u32,
    /// Refuse more samples per pixel than this.
    pub max_samples: u32,
    /// Refuse filters whose support radius is over this many pixels.
    pub max_filter_radius: u32,
    /// The course's grid, if asked for.
    pub grid: Option<GridOptions>,
}

impl Default for RenderOptions {
    fn default() -> RenderOptions {
        RenderOptions {
            width: 512,
            height: 512,
            crop: None,
            shade: ShadeOptions::default(),
            sampler: Sampler::default(),
            filter: Filter::default(),
            depth_normal: true,
            keep_samples: false,
            keep_pixels: true,
            tracer: Tracer::Packet,
            threads: 0,
            max_pixels: DEFAULT_MAX_PIXELS,
            max_bounces: DEFAULT_MAX_BOUNCES,
            max_samples: DEFAULT_MAX_SAMPLES,
            max_filter_radius: DEFAULT_MAX_FILTER_RADIUS,
            grid: None,
        }
    }
}

impl RenderOptions {
    /// The window this render covers: the crop, or the whole image.
    pub fn window(&self) -> Window {
        self.crop
            .unwrap_or_else(|| Window::full(self.width, self.height))
    }
}

/// Told which image rows a render has just finished; called from worker threads, so it must
/// be thread-safe and should be cheap (the CLI's progress bar, and its images written while the
/// render runs; `&|_| {}` for none).
pub type Progress<'a> = &'a (dyn Fn(&FinishedRows<'_>) + Sync);

/// Rows a render has just finished, as its [`Progress`] hook is told.
pub struct FinishedRows<'a> {
    /// How many rows.
    pub count: u32,
    /// Their final pixels, where the frame loop has them (the film both tracers stream through
    /// does; the grid picture and the heatmap count rows only).
    pub pixels: Option<RowPixels<'a>>,
}

impl FinishedRows<'_> {
    /// `count` rows, without their pixels.
    pub fn counted(count: u32) -> FinishedRows<'static> {
        FinishedRows {
            count,
            pixels: None,
        }
    }
}

/// The final pixels of whole rows of a frame, as the frame will hold them: rows `rows` of its
/// window (0 is the window's top row), each as wide as the window, rows top to bottom.
pub struct RowPixels<'a> {
    pub rows: Range<u32>,
    /// Linear RGB per pixel.
    pub color: &'a [Vec3],
    /// Empty unless the render keeps depth and normals ([`RenderOptions::depth_normal`]).
    pub depth: &'a [f32],
    /// Empty like `depth`.
    pub normal: &'a [Vec3],
}

/// Checks the options against the limits before anything is allocated.
pub fn check_options(opts: &RenderOptions) -> Result<()> {
    if opts.width == 0 || opts.height == 0 {
        return Err(Error::Usage(format!(
            "image size {}x{}: expected a width and height of at least 1",
            opts.width, opts.height
        )));
    }
    if let Some(c) = opts.crop {
        if !(c.x0 < c.x1 && c.x1 <= opts.width && c.y0 < c.y1 && c.y1 <= opts.height) {
            return Err(Error::Usage(format!(
                "option --crop {c}: expected a non-empty window of the {}x{} image, \
                 0 <= X0 < X1 <= {} and 0 <= Y0 < Y1 <= {}",
                opts.width, opts.height, opts.width, opts.height
            )));
        }
    }
    let window = opts.window();
    let pixels = window.pixels();
    if pixels > opts.max_pixels {
        let what = match opts.crop {
            None => format!("image size {}x{}", opts.width, opts.height),
            Some(c) => format!("crop {}x{}", c.width(), c.height()),
        };
        return Err(Error::Limit(format!(
            "{what} is {pixels} pixels, over the limit of {} (raise it with --max-pixels N)",
            opts.max_pixels
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
    check_sampling(opts)?;
    // Probe for the frame's memory so a size that cannot be allocated is an error, not an abort.
    // A side effect to keep in mind: under the binary's allocator (`hugepages.rs`) a probe of 4
    // MiB or more is advised for huge pages, and once freed its memory is where malloc puts the
    // next blocks (the scene's loading, the BVH build's), which so get huge pages too. Probed
    // without the advice, the course bunny's 800x800 parse took 1.38 ms more at 1 thread and
    // 0.63 ms more at 2 (PERF.md, sitting 59).
    let bytes = memory_bytes(opts);
    let fits = usize::try_from(bytes).is_ok_and(|b| Vec::<u8>::new().try_reserve_exact(b).is_ok());
    if !fits {
        let samples = match opts.sampler.count {
            1 => String::new(),
            n => format!(" at {n} samples per pixel"),
        };
        return Err(Error::Limit(format!(
            "image size {}x{}{samples} needs {} MiB, more memory than can be allocated",
            window.width(),
            window.height(),
            bytes >> 20
        )));
    }
    Ok(())
}

/// Checks the sampler and the filter.
fn check_sampling(opts: &RenderOptions) -> Result<()> {
    let s = &opts.sampler;
    if s.count == 0 {
        return Err(Error::Usage(
            "sample count 0: expected at least 1 sample per pixel".to_string(),
        ));
    }
    if s.count > opts.max_samples {
        return Err(Error::Limit(format!(
            "sample count {} is over the limit of {} per pixel (raise it with --max-samples N)",
            s.count, opts.max_samples
        )));
    }
    if s.pattern.needs_square() && s.grid() * s.grid() != s.count {
        return Err(Error::Usage(format!(
            "{} sampling with {} samples: expected a perfect square (1, 4, 9, 16, ...), the \
             samples of a k x k grid",
            s.pattern.name(),
            s.count
        )));
    }
    let f = &opts.filter;
    if !(f.size > 0.0 && f.size.is_finite()) {
        return Err(Error::Usage(format!(
            "{} filter {} {}: expected a positive number",
            f.shape.name(),
            f.shape.parameter(),
            f.size
        )));
    }
    let r = f.support_radius();
    if r > opts.max_filter_radius {
        return Err(Error::Limit(format!(
            "{} filter {} {} reaches {r} pixels, over the limit of {} (raise it with \
             --max-filter-radius N)",
            f.shape.name(),
            f.shape.parameter(),
            f.size,
            opts.max_filter_radius
        )));
    }
    Ok(())
}

/// What a render holds at its peak: the frame of its window (colour, depth and normal if
/// kept, every sample if kept) and the 8-bit image made from it, and the film's bands in flight
/// (a few per thread, each 8 rows of samples as wide as the window and its filter halo).
pub fn memory_bytes(opts: &RenderOptions) -> u128 {
    let window = opts.window();
    let pixels = window.pixels() as u128;
    let spp = opts.sampler.count as u128;
    let aux = if opts.depth_normal {
        BYTES_PER_PIXEL_AUX
    } else {
        0
    } as u128;
    let kept = if opts.keep_samples { 12 * spp } else { 0 };
    let threads = match opts.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    } as u128;
    let r = opts.filter.support_radius() as u128;
    let bands = threads + 2 * (r / 8 + 1) + 1;
    let width = window.width() as u128 + 2 * r;
    let film = bands * 8 * width * spp * BYTES_PER_SAMPLE as u128;
    pixels * (BYTES_PER_PIXEL as u128 + aux + kept) + film
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
