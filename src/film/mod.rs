//! The film of assignment 7: the samples a tracer traced, and the filter that turns them into
//! pixels. A tracer's frame loop hands [`render_film`] a closure that traces one
//! [`SampleBlock`] (a band of rows of the image, every sample of every pixel, their offsets set
//! by the [`Sampler`]); the film streams the image band by band and makes each output pixel the
//! normalised, filtered average of the samples around it ([`filter_rows`]), with a halo of `r`
//! rows taken from the neighbouring bands. Nothing grows with width x height x samples: only the
//! bands in flight hold samples. Between the tracers (which call it) and the sampler, filter
//! and camera (which it calls).
//!
//! ```text
//! window (output pixels) --grow by r, crop at the image--> sample region --cut--> bands of BAND_ROWS
//! band k --trace(closure)--> samples k --once bands k-h..k+h are in--> filter --> output rows of band k
//! ```
//!
//! Depth and normal images are not filtered: each pixel shows the hit of its sample nearest the
//! pixel centre (the first one on ties; with one sample, the centre), so a depth stays the
//! distance to a surface that is there, and a normal a unit normal of it. When every weight of a
//! pixel's support is zero (a box or tent narrower than the spacing of the samples, a tiny
//! Gaussian), the pixel is black, as the course's `Filter::getColor` makes it.

mod stream;

pub use stream::{BAND_ROWS, FilmOutput, TAIL_PIECES, render_film};

use std::ops::Range;

use crate::filter::Filter;
use crate::frame::Frame;
use crate::math::{Vec2, Vec3};
use crate::options::{RenderOptions, Window};
use crate::sampler::Sampler;
use crate::scene::Camera;
use crate::stats::RayCounts;

/// `window` grown by `r` pixels on every side, cropped to a `width` x `height` image.
pub fn grown(window: Window, r: u32, width: u32, height: u32) -> Window {
    Window {
        x0: window.x0.saturating_sub(r),
        y0: window.y0.saturating_sub(r),
        x1: window.x1.saturating_add(r).min(width),
        y1: window.y1.saturating_add(r).min(height),
    }
}

/// What a frame loop asks the film for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmSpec {
    pub image_width: u32,
    pub image_height: u32,
    /// The pixels to make (the whole image, or a crop of it).
    pub window: Window,
    pub sampler: Sampler,
    pub filter: Filter,
    /// Keep the depth and normal of each pixel.
    pub depth_normal: bool,
    /// Keep every sample's colour (for `-render_samples`).
    pub keep_samples: bool,
    /// Keep every output pixel (colour, and depth and normal when kept) in the [`FilmOutput`].
    /// Without, a band's pixels live only while the progress hook sees them.
    pub keep_pixels: bool,
}

impl FilmSpec {
    /// The film a render with `opts` makes: its window (the crop, or the whole image).
    pub fn for_options(opts: &RenderOptions) -> FilmSpec {
        FilmSpec {
            image_width: opts.width,
            image_height: opts.height,
            window: opts.window(),
            sampler: opts.sampler,
            filter: opts.filter,
            depth_normal: opts.depth_normal,
            keep_samples: opts.keep_samples,
            keep_pixels: opts.keep_pixels,
        }
    }

    /// The pixels whose samples the film traces: the window grown by the filter's support
    /// radius, cropped at the image border, and its rows rounded out to whole bands of
    /// [`BAND_ROWS`] rows of the image. A band is then traced exactly as the whole image's render
    /// traces it (the packet tracer's packets depend on the band's pixels), so a window of whole
    /// rows, such as a `--tile` strip, gets the whole render's bytes, its halo included. (On
    /// several threads the last bands come in column pieces, [`TAIL_PIECES`]: other packets,
    /// the same samples, as `tests/threads.rs` checks.)
    pub fn region(&self) -> Window {
        let grown = grown(
            self.window,
            self.filter.support_radius(),
            self.image_width,
            self.image_height,
        );
        Window {
            y0: grown.y0 / BAND_ROWS * BAND_ROWS,
            y1: grown
                .y1
                .div_ceil(BAND_ROWS)
                .saturating_mul(BAND_ROWS)
                .min(self.image_height),
            ..grown
        }
    }
}

/// The samples of a rectangle of pixels: where each lies (set by the film) and what colour it
/// saw (set by the tracer). Sample `s` of pixel `(x, y)` is slot
/// `((y - y0) * width + (x - x0)) * spp + s`.
#[derive(Clone, Debug, PartialEq)]
pub struct SampleBlock {
    /// The first column and row, in the full image's coordinates.
    pub x0: u32,
    pub y0: u32,
    pub width: u32,
    pub rows: u32,
    pub image_width: u32,
    pub image_height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Each slot's offset in its pixel (from the lower-left corner, y up, in `[0, 1)`).
    pub offsets: Vec<Vec2>,
    /// Per pixel, the sample whose hit the depth and normal show (nearest the centre).
    pub nearest: Vec<u32>,
    /// Each slot's colour, black until traced.
    pub color: Vec<Vec3>,
    /// Per pixel, the distance to the nearest sample's hit (`+inf` for none); empty unless the
    /// film keeps depth and normals.
    pub depth: Vec<f32>,
    /// Per pixel, the unit normal at that hit (zero for none); empty like `depth`.
    pub normal: Vec<Vec3>,
}

impl SampleBlock {
    /// The block of pixels `x0..x0 + width` x `y0..y0 + rows` of a `image_width` x
    /// `image_height` image, with the offsets of `sampler`; depth and normals kept if asked.
    #[allow(clippy::too_many_arguments)] // reason: a rectangle, the image it lies in, and two choices
    pub fn new(
        x0: u32,
        y0: u32,
        width: u32,
        rows: u32,
        image_width: u32,
        image_height: u32,
        sampler: &Sampler,
        depth_normal: bool,
    ) -> SampleBlock {
        let spp = sampler.count;
        let pixels = width as usize * rows as usize;
        let slots = pixels * spp as usize;
        let (offsets, nearest) = if sampler.varies_by_pixel() {
            let mut offsets = vec![Vec2::ZERO; slots];
            let mut nearest = vec![0; pixels];
            // Pixel by pixel, rows top to bottom as the slots lie.
            let coords = (y0..y0 + rows).flat_map(|y| (x0..x0 + width).map(move |x| (x, y)));
            let each_pixel = offsets.chunks_exact_mut(spp as usize).zip(&mut nearest);
            for ((x, y), (chunk, near)) in coords.zip(each_pixel) {
                *near = sampler.pixel_offsets(x, y, chunk);
            }
            (offsets, nearest)
        } else {
            // Every pixel's offsets are the first pixel's.
            let mut first = vec![Vec2::ZERO; spp as usize];
            let near = sampler.pixel_offsets(x0, y0, &mut first);
            (first.repeat(pixels), vec![near; pixels])
        };
        let aux = if depth_normal { pixels } else { 0 };
        SampleBlock {
            x0,
            y0,
            width,
            rows,
            image_width,
            image_height,
            spp,
            offsets,
            nearest,
            color: vec![Vec3::ZERO; slots],
            depth: vec![f32::INFINITY; aux],
            normal: vec![Vec3::ZERO; aux],
        }
    }

    /// The block that column pieces of one band make side by side: `pieces` (in any order) are
    /// blocks of the same rows, image and samples per pixel whose columns follow one another
    /// without gap or overlap. The result is the block [`SampleBlock::new`] makes for all their
    /// columns, with every sample as its piece holds it.
    pub fn join_columns(mut pieces: Vec<SampleBlock>) -> SampleBlock {
        pieces.sort_by_key(|p| p.x0);
        let first = &pieces[0];
        let (y0, rows, spp) = (first.y0, first.rows, first.spp as usize);
        let mut x1 = first.x0;
        for p in &pieces {
            assert!(
                p.x0 == x1 && p.y0 == y0 && p.rows == rows && p.spp == first.spp,
                "column pieces of one band"
            );
            x1 += p.width;
        }
        let width = x1 - first.x0;
        let pixels = width as usize * rows as usize;
        let aux = if first.depth.is_empty() { 0 } else { pixels };
        let mut joined = SampleBlock {
            x0: first.x0,
            y0,
            width,
            rows,
            image_width: first.image_width,
            image_height: first.image_height,
            spp: first.spp,
            offsets: Vec::with_capacity(pixels * spp),
            nearest: Vec::with_capacity(pixels),
            color: Vec::with_capacity(pixels * spp),
            depth: Vec::with_capacity(aux),
            normal: Vec::with_capacity(aux),
        };
        for r in 0..rows as usize {
            for p in &pieces {
                let w = p.width as usize;
                let (px, slots) = (r * w..(r + 1) * w, r * w * spp..(r + 1) * w * spp);
                joined.offsets.extend_from_slice(&p.offsets[slots.clone()]);
                joined.color.extend_from_slice(&p.color[slots]);
                joined.nearest.extend_from_slice(&p.nearest[px.clone()]);
                if aux > 0 {
                    joined.depth.extend_from_slice(&p.depth[px.clone()]);
                    joined.normal.extend_from_slice(&p.normal[px]);
                }
            }
        }
        joined
    }

    /// The number of samples.
    pub fn len(&self) -> usize {
        self.offsets.len()
    }

    /// True when the block holds no sample.
    pub fn is_empty(&self) -> bool {
        self.offsets.is_empty()
    }

    /// The pixel (full-image coordinates) of `slot`.
    #[inline]
    pub fn pixel_of(&self, slot: usize) -> (u32, u32) {
        let p = slot / self.spp as usize;
        (
            self.x0 + (p % self.width as usize) as u32,
            self.y0 + (p / self.width as usize) as u32,
        )
    }

    /// The screen point of `slot`'s sample, for [`Camera::generate_ray`].
    #[inline]
    pub fn screen_point(&self, slot: usize) -> Vec2 {
        let (x, y) = self.pixel_of(slot);
        Camera::sample_screen(
            x,
            y,
            self.offsets[slot],
            self.image_width,
            self.image_height,
        )
    }

    /// True if `slot` is its pixel's nearest-to-centre sample: the one whose hit goes into the
    /// depth and normal images (always false when they are not kept).
    #[inline]
    pub fn keeps_hit(&self, slot: usize) -> bool {
        !self.depth.is_empty() && is_nearest(&self.nearest, self.spp, slot)
    }

    /// Records the hit of `slot`'s ray if it is the one the depth and normal images show.
    #[inline]
    pub fn record_hit(&mut self, slot: usize, t: f32, normal: Vec3) {
        if self.keeps_hit(slot) {
            let p = slot / self.spp as usize;
            self.depth[p] = t;
            self.normal[p] = normal;
        }
    }
}

impl FilmOutput {
    /// The frame of these pixels, made with `rays`.
    pub fn into_frame(self, rays: RayCounts) -> Frame {
        Frame {
            width: self.window.width(),
            height: self.window.height(),
            window: self.window,
            image_width: self.image_width,
            image_height: self.image_height,
            color: self.color,
            depth: self.depth,
            normal: self.normal,
            samples: self.samples,
            rays,
            accel: None,
            bounce_time: Vec::new(),
            grid: None,
        }
    }
}

/// True if sample slot `slot` (`spp` slots a pixel) is its pixel's sample nearest the centre,
/// `nearest` holding that sample's index for each pixel.
#[inline]
pub fn is_nearest(nearest: &[u32], spp: u32, slot: usize) -> bool {
    let spp = spp as usize;
    nearest[slot / spp] as usize == slot % spp
}

/// The samples the filter reads: per row of the sample region (row `y0` first), the colours
/// and offsets of its pixels (columns `x0..`, `spp` slots each).
pub struct SampleRows<'a> {
    /// Row `y0` first.
    pub y0: u32,
    pub x0: u32,
    pub spp: u32,
    pub rows: Vec<(&'a [Vec3], &'a [Vec2])>,
}

/// Filters the pixels `cols` x `rows` (full-image coordinates, rows from the top) of a
/// `width` x `height` image from `samples` (which hold every sample row and column within the
/// support radius `r` of them) into `out`, row by row. Pixel `(i, j)` is the weighted average
/// of the samples of pixels `i-r..=i+r` x `j-r..=j+r` that lie in the image, the weights
/// normalised over that cropped support; black if they sum to zero.
///
/// Each sample is visited once: its axis terms ([`Filter::axis`]) are computed for the
/// columns and the rows it reaches and combined for each pixel, and its weighted colour added to
/// that pixel's sums. A pixel's sums so run over its support's samples by row, then column, then
/// sample index, in `f64` (so a flat colour averaged by a box comes back exactly), in the same
/// order wherever the pixel is made.
pub fn filter_rows(
    filter: &Filter,
    samples: &SampleRows<'_>,
    cols: Range<u32>,
    rows: Range<u32>,
    width: u32,
    height: u32,
    out: &mut [Vec3],
) {
    let r = filter.support_radius();
    let (nw, spp) = (cols.len(), samples.spp as usize);
    debug_assert_eq!(out.len(), nw * rows.len());
    if r == 0 && spp == 1 {
        // Each pixel is its one sample: the same bits as the sums below, without them.
        for (y, row) in rows.clone().zip(out.chunks_exact_mut(nw)) {
            let (colors, offsets) = samples.rows[(y - samples.y0) as usize];
            let pixels = (cols.start - samples.x0) as usize..(cols.end - samples.x0) as usize;
            for ((o, c), s) in row
                .iter_mut()
                .zip(&colors[pixels.clone()])
                .zip(&offsets[pixels])
            {
                *o = one_sample(filter, c, s);
            }
        }
        return;
    }
    if r == 0 {
        // Each pixel is made of its own samples alone: the same sums, without the scatter.
        for (y, row) in rows.clone().zip(out.chunks_exact_mut(nw)) {
            let (colors, offsets) = samples.rows[(y - samples.y0) as usize];
            for (x, o) in cols.clone().zip(row.iter_mut()) {
                let first = (x - samples.x0) as usize * spp;
                let mut a = [0f64; 4];
                for (c, o) in colors[first..first + spp]
                    .iter()
                    .zip(&offsets[first..first + spp])
                {
                    let w = filter.weight(o.x - 0.5, o.y - 0.5) as f64;
                    accumulate(&mut a, w, c);
                }
                *o = normalised(&a);
            }
        }
        return;
    }
    let mut acc = vec![[0f64; 4]; out.len()];
    let mut ax = vec![0f64; 2 * r as usize + 1];
    let mut ay = vec![0f64; 2 * r as usize + 1];
    let sample_cols = cols.start.saturating_sub(r)..cols.end.saturating_add(r).min(width);
    let sample_rows = rows.start.saturating_sub(r)..rows.end.saturating_add(r).min(height);
    for y in sample_rows {
        let (colors, offsets) = samples.rows[(y - samples.y0) as usize];
        let (ja, jb) = (
            y.saturating_sub(r).max(rows.start),
            (y + r).min(rows.end - 1),
        );
        if ja > jb {
            continue;
        }
        for x in sample_cols.clone() {
            let (ia, ib) = (
                x.saturating_sub(r).max(cols.start),
                (x + r).min(cols.end - 1),
            );
            if ia > ib {
                continue;
            }
            let first = (x - samples.x0) as usize * spp;
            for (c, o) in colors[first..first + spp]
                .iter()
                .zip(&offsets[first..first + spp])
            {
                for (k, i) in (ia..=ib).enumerate() {
                    ax[k] = filter.axis((x as i64 - i as i64) as f32 - 0.5 + o.x);
                }
                for (k, j) in (ja..=jb).enumerate() {
                    ay[k] = filter.axis((j as i64 - y as i64) as f32 - 0.5 + o.y);
                }
                for (kj, j) in (ja..=jb).enumerate() {
                    let row = (j - rows.start) as usize * nw;
                    for (ki, i) in (ia..=ib).enumerate() {
                        let w = filter.combine(ax[ki], ay[kj]) as f64;
                        accumulate(&mut acc[row + (i - cols.start) as usize], w, c);
                    }
                }
            }
        }
    }
    for (o, a) in out.iter_mut().zip(&acc) {
        *o = normalised(a);
    }
}

/// A pixel made of one sample at offset `o` alone: the sample's colour `c`, or black where the
/// filter gives it no weight. The same bits as [`normalised`] of its one weighted sum: `w * c`
/// is exact in `f64` (two 24-bit significands), so dividing it by `w` gives `c` back exactly.
#[inline]
fn one_sample(filter: &Filter, c: &Vec3, o: &Vec2) -> Vec3 {
    let w = filter.weight(o.x - 0.5, o.y - 0.5);
    if w > 0.0 { *c } else { Vec3::ZERO }
}

/// Adds a sample of colour `c` and weight `w` to the sums `a` (colour, then weight).
#[inline]
fn accumulate(a: &mut [f64; 4], w: f64, c: &Vec3) {
    a[0] += w * c.x as f64;
    a[1] += w * c.y as f64;
    a[2] += w * c.z as f64;
    a[3] += w;
}

/// The weighted average of the sums `a`; black when the weights sum to zero.
#[inline]
fn normalised(a: &[f64; 4]) -> Vec3 {
    if a[3] > 0.0 {
        Vec3::new(
            (a[0] / a[3]) as f32,
            (a[1] / a[3]) as f32,
            (a[2] / a[3]) as f32,
        )
    } else {
        Vec3::ZERO
    }
}
