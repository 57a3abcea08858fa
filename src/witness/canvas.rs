//! The witness picture's raster: [`Canvas`] holds the witness frame's colour image in display
//! space and draws on it with a [`Pen`]: anti-aliased lines clipped to the image (fainter where
//! the witness frame's depths say a surface hides them), world segments through the projection
//! with a dark halo, dots, panels and text in the bitmap font. Below `overlay.rs`, which decides
//! what to draw; above `projection.rs` and `font.rs`, whose pixels and glyphs it fills.
//!
//! ```text
//! Frame --Canvas::new--> display RGB --line/segment3/dot/rect/text--> --into_image--> Rgb8
//! ```

use super::font::{descends, glyph};
use super::projection::View;
use crate::frame::Frame;
use crate::math::Vec3;
use crate::output::{Rgb8, color_image};

/// Display-space RGB canvas with the witness frame's depths for the hidden-part test.
pub(crate) struct Canvas<'f> {
    pub(crate) width: usize,
    pub(crate) height: usize,
    rgb: Vec<[f32; 3]>,
    frame: &'f Frame,
}

/// How one line is drawn.
#[derive(Clone, Copy)]
pub(super) struct Pen {
    pub(super) color: [f32; 3],
    pub(super) width: f32,
    pub(super) alpha: f32,
    /// Dash and gap lengths in pixels.
    pub(super) dash: Option<(f32, f32)>,
}

const HIDDEN_ALPHA: f32 = 0.35;

impl Canvas<'_> {
    /// A canvas holding `frame`'s colour image, as the PNG would store it.
    pub(crate) fn new(frame: &Frame) -> Canvas<'_> {
        let img = color_image(frame);
        Canvas {
            width: frame.width as usize,
            height: frame.height as usize,
            rgb: img
                .data
                .chunks_exact(3)
                .map(|p| {
                    [
                        p[0] as f32 / 255.0,
                        p[1] as f32 / 255.0,
                        p[2] as f32 / 255.0,
                    ]
                })
                .collect(),
            frame,
        }
    }

    /// The finished picture, rounded to bytes.
    pub(crate) fn into_image(self) -> Rgb8 {
        let data = (self.rgb.iter().flatten())
            .map(|&c| (c * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
            .collect();
        Rgb8 {
            width: self.frame.width,
            height: self.frame.height,
            data,
        }
    }

    fn blend(&mut self, x: usize, y: usize, c: [f32; 3], a: f32) {
        let p = &mut self.rgb[y * self.width + x];
        for k in 0..3 {
            p[k] += (c[k] - p[k]) * a;
        }
    }

    /// Draws the 2D segment `a`-`b`; with `depths` `(view, za, zb)`, the parts behind the
    /// witness frame's surfaces (as `view` projects them) fainter, with `None` no hidden test.
    pub(super) fn line(
        &mut self,
        a: [f32; 2],
        b: [f32; 2],
        depths: Option<(&View, f32, f32)>,
        pen: Pen,
    ) {
        let hw = pen.width * 0.5;
        let pad = hw + 2.0;
        let Some((t0, t1)) = clip_to_rect(
            a,
            b,
            -pad,
            -pad,
            self.width as f32 + pad,
            self.height as f32 + pad,
        ) else {
            return;
        };
        let lerp = |t: f32| [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
        let (p, q) = (lerp(t0), lerp(t1));
        let d = [b[0] - a[0], b[1] - a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        let len = len2.sqrt();
        let x_major = d[0].abs() >= d[1].abs();
        // Walk the major axis; each column (or row) covers the pixels within the pen's reach,
        // so every pixel is visited once per line.
        let (major, minor) = if x_major { (0, 1) } else { (1, 0) };
        let (lim_major, lim_minor) = if x_major {
            (self.width, self.height)
        } else {
            (self.height, self.width)
        };
        let lo = p[major].min(q[major]) - hw - 1.0;
        let hi = p[major].max(q[major]) + hw + 1.0;
        let slope = if d[major] != 0.0 {
            d[minor] / d[major]
        } else {
            0.0
        };
        let reach = (hw + 1.5) * (1.0 + slope * slope).sqrt() + 1.0;
        let i0 = lo.floor().max(0.0) as usize;
        let i1 = (hi.ceil().max(0.0) as usize).min(lim_major);
        for i in i0..i1 {
            let m = (i as f32 + 0.5).clamp(p[major].min(q[major]), p[major].max(q[major]));
            let c = p[minor] + (m - p[major]) * slope;
            let j0 = (c - reach).floor().max(0.0) as usize;
            let j1 = ((c + reach).ceil().max(0.0) as usize).min(lim_minor);
            for j in j0..j1 {
                let (x, y) = if x_major { (i, j) } else { (j, i) };
                let px = [x as f32 + 0.5, y as f32 + 0.5];
                let t = if len2 > 0.0 {
                    (((px[0] - a[0]) * d[0] + (px[1] - a[1]) * d[1]) / len2).clamp(t0, t1)
                } else {
                    0.0
                };
                let near = lerp(t);
                let dist = ((px[0] - near[0]).powi(2) + (px[1] - near[1]).powi(2)).sqrt();
                let cover = (hw + 0.5 - dist).clamp(0.0, 1.0);
                if cover <= 0.0 {
                    continue;
                }
                if pen
                    .dash
                    .is_some_and(|(on, off)| (t * len) % (on + off) >= on)
                {
                    continue;
                }
                let mut alpha = pen.alpha * cover;
                if let Some((view, za, zb)) = depths {
                    let z = 1.0 / ((1.0 - t) / za + t / zb);
                    let surface =
                        self.frame.depth[y * self.width + x] / view.ray_length(px[0], px[1]);
                    if z > surface * 1.02 + view.near {
                        alpha *= HIDDEN_ALPHA;
                    }
                }
                self.blend(x, y, pen.color, alpha);
            }
        }
    }

    /// Draws the world segment `a`-`b`, clipped to the near plane, with its halo.
    pub(super) fn segment3(&mut self, view: &View, a: Vec3, b: Vec3, pen: Pen) {
        if let Some((pa, za, pb, zb)) = view.project_segment(a, b) {
            let halo = Pen {
                color: [0.0; 3],
                width: pen.width + 2.5,
                alpha: 0.55 * pen.alpha,
                ..pen
            };
            self.line(pa, pb, Some((view, za, zb)), halo);
            self.line(pa, pb, Some((view, za, zb)), pen);
        }
    }

    /// A filled disc with a dark rim.
    pub(super) fn dot(&mut self, c: [f32; 2], radius: f32, color: [f32; 3]) {
        let r = radius + 1.5;
        let x0 = (c[0] - r - 1.0).floor().max(0.0) as usize;
        let y0 = (c[1] - r - 1.0).floor().max(0.0) as usize;
        let x1 = ((c[0] + r + 1.0).ceil().max(0.0) as usize).min(self.width);
        let y1 = ((c[1] + r + 1.0).ceil().max(0.0) as usize).min(self.height);
        for y in y0..y1 {
            for x in x0..x1 {
                let d = ((x as f32 + 0.5 - c[0]).powi(2) + (y as f32 + 0.5 - c[1]).powi(2)).sqrt();
                let rim = (r + 0.5 - d).clamp(0.0, 1.0);
                if rim > 0.0 {
                    self.blend(x, y, [0.0; 3], 0.8 * rim);
                }
                let fill = (radius + 0.5 - d).clamp(0.0, 1.0);
                if fill > 0.0 {
                    self.blend(x, y, color, fill);
                }
            }
        }
    }

    /// A filled rectangle.
    pub(crate) fn rect(
        &mut self,
        x: usize,
        y: usize,
        w: usize,
        h: usize,
        color: [f32; 3],
        alpha: f32,
    ) {
        for yy in y..(y + h).min(self.height) {
            for xx in x..(x + w).min(self.width) {
                self.blend(xx, yy, color, alpha);
            }
        }
    }

    /// Text in the built-in 5x7 font, `scale` pixels per font pixel, top-left at `(x, y)`.
    pub(crate) fn text(&mut self, x: usize, y: usize, scale: usize, s: &str, color: [f32; 3]) {
        for (k, ch) in s.chars().enumerate() {
            let Some(rows) = glyph(ch) else {
                continue;
            };
            let drop = usize::from(descends(ch));
            for (r, row) in rows.iter().enumerate() {
                let r = r + drop;
                for (c, bit) in row.bytes().enumerate() {
                    if bit == b'#' {
                        let gx = x + (k * 6 + c) * scale;
                        self.rect(gx, y + r * scale, scale, scale, color, 1.0);
                    }
                }
            }
        }
    }
}

/// The parameter range `[t0, t1]` of segment `a`-`b` inside the rectangle (Liang-Barsky).
fn clip_to_rect(
    a: [f32; 2],
    b: [f32; 2],
    x0: f32,
    y0: f32,
    x1: f32,
    y1: f32,
) -> Option<(f32, f32)> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-d[0], a[0] - x0),
        (d[0], x1 - a[0]),
        (-d[1], a[1] - y0),
        (d[1], y1 - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_the_inside_part_of_a_line() {
        let (t0, t1) = clip_to_rect([-10.0, 5.0], [20.0, 5.0], 0.0, 0.0, 10.0, 10.0).unwrap();
        assert!((t0 - 1.0 / 3.0).abs() < 1e-6 && (t1 - 2.0 / 3.0).abs() < 1e-6);
        assert!(clip_to_rect([-10.0, 50.0], [20.0, 50.0], 0.0, 0.0, 10.0, 10.0).is_none());
    }
}
