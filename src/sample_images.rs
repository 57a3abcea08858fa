//! The two pictures of assignment 7 that show how anti-aliasing works, as the course's provided
//! `Film::renderSamples` and `Film::renderFilter` draw them: [`render_samples`] (one dot per
//! sample, in its own colour, where it lies in its pixel) and [`render_filter`] (the filter's
//! weights around the centre pixel, with the pixel grid). Above the film and `output.rs`: it
//! reads a frame's kept samples and writes [`Rgb8`] images.
//!
//! ```text
//! -render_samples FILE Z   (W*Z) x (H*Z): a checkerboard of pixels (grey 0.2 where i + j is even,
//!                          j counted from the bottom; else black), then per sample one dot at
//!                          floor((i + ox) * Z), floor((j + oy) * Z)
//! -render_filter FILE Z    (W*Z + 1) x (H*Z + 1): dark blue; the weight (not normalised) as grey
//!                          on the support of the centre pixel (W/2, H/2), taken at each zoomed
//!                          pixel's lower-left corner; then the grid lines in blue every Z pixels
//! ```

use crate::filter::Filter;
use crate::frame::Frame;
use crate::math::Vec3;
use crate::output::{Rgb8, to_byte};
use crate::sampler::Sampler;

/// The grey of the even pixels of the `-render_samples` checkerboard.
const CHECKER: f32 = 0.2;
/// The background of `-render_filter`.
const FILTER_BACKGROUND: Vec3 = Vec3::new(0.0, 0.0, 0.5);
/// The grid lines of `-render_filter`.
const GRID: Vec3 = Vec3::new(0.0, 0.0, 1.0);

/// A canvas addressed as the course addresses images: `(x, y)` with `y` from the bottom.
struct Canvas {
    width: usize,
    height: usize,
    data: Vec<u8>,
}

impl Canvas {
    fn new(width: usize, height: usize, fill: Vec3) -> Canvas {
        let px = [to_byte(fill.x), to_byte(fill.y), to_byte(fill.z)];
        Canvas {
            width,
            height,
            data: px.repeat(width * height),
        }
    }

    fn set(&mut self, x: usize, y_up: usize, c: Vec3) {
        let i = ((self.height - 1 - y_up) * self.width + x) * 3;
        self.data[i..i + 3].copy_from_slice(&[to_byte(c.x), to_byte(c.y), to_byte(c.z)]);
    }

    fn into_image(self) -> Rgb8 {
        Rgb8 {
            width: self.width as u32,
            height: self.height as u32,
            data: self.data,
        }
    }
}

/// The `-render_samples` picture of `frame`, zoomed `zoom` times: every sample a dot of its own
/// colour at its place in its pixel (later samples of a pixel over earlier ones). `frame` must
/// have kept its samples ([`crate::RenderOptions::keep_samples`]) made with `sampler`. A crop's
/// frame gives the picture of its window (the checkerboard's parity is the full image's).
pub fn render_samples(frame: &Frame, sampler: &Sampler, zoom: u32) -> Rgb8 {
    let (w, h, z) = (frame.width as usize, frame.height as usize, zoom as usize);
    let spp = sampler.count as usize;
    assert_eq!(
        frame.samples.len(),
        w * h * spp,
        "render_samples needs a frame that kept its samples"
    );
    let mut canvas = Canvas::new(w * z, h * z, Vec3::ZERO);
    // Pixel (i, y) of the frame is pixel (x0 + i, y0 + y) of the image, row j_image from the
    // bottom of the image.
    let (x0, y0) = (frame.window.x0 as usize, frame.window.y0 as usize);
    let image_row_up = |y: usize| frame.image_height as usize - 1 - (y0 + y);
    for y in 0..h {
        let j = h - 1 - y;
        for i in 0..w {
            if (x0 + i + image_row_up(y)) % 2 == 0 {
                for y2 in 0..z {
                    for x2 in 0..z {
                        canvas.set(i * z + x2, j * z + y2, Vec3::splat(CHECKER));
                    }
                }
            }
        }
    }
    for y in 0..h {
        let j = h - 1 - y;
        for i in 0..w {
            let p = y * w + i;
            for s in 0..spp {
                let o = sampler.offset((x0 + i) as u32, (y0 + y) as u32, s as u32);
                let dot_x = (((i as f64 + o.x as f64) * z as f64) as usize).min(w * z - 1);
                let dot_y = (((j as f64 + o.y as f64) * z as f64) as usize).min(h * z - 1);
                canvas.set(dot_x, dot_y, frame.samples[p * spp + s]);
            }
        }
    }
    canvas.into_image()
}

/// The `-render_filter` picture of `filter` for a `width` x `height` image, zoomed `zoom` times:
/// the weight of a sample at each zoomed pixel's lower-left corner towards the centre pixel
/// `(width / 2, height / 2)` (counted from the bottom left), in grey, over that pixel's support;
/// dark blue outside it; blue grid lines between the pixels. It depends on nothing but its
/// arguments. (The course centres both axes on `width / 2`; for square images, the only kind
/// its command lines use, that is the same.)
pub fn render_filter(width: u32, height: u32, zoom: u32, filter: &Filter) -> Rgb8 {
    let (w, h, z) = (width as i64, height as i64, zoom as i64);
    let mut canvas = Canvas::new(
        (w * z + 1) as usize,
        (h * z + 1) as usize,
        FILTER_BACKGROUND,
    );
    let r = filter.support_radius() as i64;
    let (ci, cj) = (w / 2, h / 2);
    for i in (ci - r).max(0)..=(ci + r).min(w - 1) {
        for j in (cj - r).max(0)..=(cj + r).min(h - 1) {
            for i2 in 0..z {
                for j2 in 0..z {
                    let x = (i as f64 + i2 as f64 / z as f64 - (ci as f64 + 0.5)) as f32;
                    let y = (j as f64 + j2 as f64 / z as f64 - (cj as f64 + 0.5)) as f32;
                    let g = filter.weight(x, y);
                    canvas.set((i * z + i2) as usize, (j * z + j2) as usize, Vec3::splat(g));
                }
            }
        }
    }
    for y in 0..canvas.height {
        for x in 0..canvas.width {
            if x % z as usize == 0 || y % z as usize == 0 {
                canvas.set(x, y, GRID);
            }
        }
    }
    canvas.into_image()
}
