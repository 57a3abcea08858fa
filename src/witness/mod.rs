//! The picture of a ray tree: the scene seen by a second, "witness" camera placed beside the
//! main one, with the tree's segments drawn over it in the course's colours (eye gray, shadow
//! green, reflected red, transmitted blue; blocked shadow rays dashed dark green), the main
//! camera drawn as a small white frustum, lights as yellow dots and a legend.
//!
//! ```text
//! RayTree + main Camera --witness_camera--> Camera --render--> Frame --draw_ray_tree--> Rgb8
//! ```
//!
//! The witness camera ([`witness_camera`], default [`WitnessPlace::Orbit`]): it sees the eye
//! ray's first hit (or, if the eye ray escapes, the point [`ESCAPE_LOOK_AT`] along it) from the
//! main camera's side of the scene turned [`DEFAULT_YAW_DEG`] degrees about the scene's vertical
//! axis (the world axis nearest the main camera's up vector; positive turns to the main
//! camera's right) and raised [`DEFAULT_PITCH_DEG`] degrees, with a [`DEFAULT_ANGLE_DEG`] degree
//! field of view. It frames the main camera, the eye ray, and the tree's hits, occluders and
//! point lights within twice the main camera's distance of that hit (farther ones may leave
//! the picture): centred on their extent across the view, as near as keeps them in the middle
//! 85% of the picture. [`WitnessPlace::At`] places it explicitly instead. The witness sees the
//! scene through [`cutaway`]: planes and lone triangles it would see from behind are left out,
//! so it can look into a room of walls (the facing mirrors) from outside.
//!
//! Drawing: segments are clipped against the witness camera's near plane in 3D and against the
//! image in 2D, drawn 2-3 pixels wide (scaled with the image) with anti-aliased edges over a dark
//! halo, so they read on any background; parts hidden behind a surface (by the witness frame's
//! depth) are drawn fainter.

mod font;
mod placement;
mod projection;

pub use self::placement::{
    DEFAULT_ANGLE_DEG, DEFAULT_PITCH_DEG, DEFAULT_YAW_DEG, ESCAPE_LOOK_AT, WitnessPlace,
    WitnessSpec, cutaway, look_at_point, vertical_axis, witness_camera,
};

use self::font::{descends, glyph};
use self::projection::View;
use crate::frame::Frame;
use crate::math::Vec3;
use crate::output::{Rgb8, color_image};
use crate::raytree::{EndKind, RayTree, SegmentKind};
use crate::scene::{Camera, Projection};

/// Display-space RGB canvas with the witness frame's depths for the hidden-part test.
struct Canvas<'f> {
    width: usize,
    height: usize,
    rgb: Vec<[f32; 3]>,
    frame: &'f Frame,
}

/// How one line is drawn.
#[derive(Clone, Copy)]
struct Pen {
    color: [f32; 3],
    width: f32,
    alpha: f32,
    /// Dash and gap lengths in pixels.
    dash: Option<(f32, f32)>,
}

const HIDDEN_ALPHA: f32 = 0.35;

impl Canvas<'_> {
    fn blend(&mut self, x: usize, y: usize, c: [f32; 3], a: f32) {
        let p = &mut self.rgb[y * self.width + x];
        for k in 0..3 {
            p[k] += (c[k] - p[k]) * a;
        }
    }

    /// Draws the 2D segment `a`-`b`; with `depths` `(view, za, zb)`, the parts behind the
    /// witness frame's surfaces (as `view` projects them) fainter, with `None` no hidden test.
    fn line(&mut self, a: [f32; 2], b: [f32; 2], depths: Option<(&View, f32, f32)>, pen: Pen) {
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
    fn segment3(&mut self, view: &View, a: Vec3, b: Vec3, pen: Pen) {
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
    fn dot(&mut self, c: [f32; 2], radius: f32, color: [f32; 3]) {
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
    fn rect(&mut self, x: usize, y: usize, w: usize, h: usize, color: [f32; 3], alpha: f32) {
        for yy in y..(y + h).min(self.height) {
            for xx in x..(x + w).min(self.width) {
                self.blend(xx, yy, color, alpha);
            }
        }
    }

    /// Text in the built-in 5x7 font, `scale` pixels per font pixel, top-left at `(x, y)`.
    fn text(&mut self, x: usize, y: usize, scale: usize, s: &str, color: [f32; 3]) {
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

/// The colour the course gives a kind of segment (display space).
pub fn kind_color(kind: SegmentKind, blocked: bool) -> [f32; 3] {
    match (kind, blocked) {
        (SegmentKind::Eye, _) => [0.78, 0.78, 0.78],
        (SegmentKind::Shadow, false) => [0.3, 1.0, 0.35],
        (SegmentKind::Shadow, true) => [0.1, 0.7, 0.2],
        (SegmentKind::Reflected, _) => [1.0, 0.2, 0.15],
        (SegmentKind::Transmitted, _) => [0.25, 0.5, 1.0],
    }
}

const CAMERA_COLOR: [f32; 3] = [1.0, 1.0, 1.0];
const LIGHT_COLOR: [f32; 3] = [1.0, 0.85, 0.1];

/// Draws `tree` over `frame`, the scene rendered by `witness`; `main` is the camera the tree's
/// pixel belongs to, rendering a `main_size` image; `title` is written at the top left.
pub fn draw_ray_tree(
    frame: &Frame,
    witness: &Camera,
    main: &Camera,
    main_size: (u32, u32),
    tree: &RayTree,
    title: &str,
) -> Rgb8 {
    let img = color_image(frame);
    let (w, h) = (frame.width as usize, frame.height as usize);
    let look_at = look_at_point(main, tree);
    let scale_len = (main.center - look_at).length().max(1e-3);
    let near = 1e-4 * (witness.center - look_at).length().max(1e-3);
    let view = View::new(witness, frame.width, frame.height, near);
    let mut canvas = Canvas {
        width: w,
        height: h,
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
    };
    let unit = (w.min(h) as f32 / 400.0).clamp(0.75, 3.0);

    draw_main_camera(&mut canvas, &view, main, main_size, 0.18 * scale_len, unit);

    // Shadow rays first, then the rays that carry colour, deepest first, so the eye ray and
    // the first bounces stay on top.
    let mut order: Vec<usize> = (0..tree.segments.len()).collect();
    order.sort_by_key(|&i| {
        let s = &tree.segments[i];
        (s.kind != SegmentKind::Shadow, std::cmp::Reverse(s.depth))
    });
    for &i in &order {
        let s = &tree.segments[i];
        let pen = Pen {
            color: kind_color(s.kind, s.blocked),
            width: if s.kind == SegmentKind::Shadow {
                2.0
            } else {
                2.6
            } * unit,
            alpha: 1.0,
            dash: s.blocked.then_some((7.0 * unit, 5.0 * unit)),
        };
        canvas.segment3(&view, s.origin, s.end, pen);
    }
    for s in &tree.segments {
        let c = view.to_camera(s.end);
        if c.z <= view.near {
            continue;
        }
        let p = view.to_pixel(c);
        match s.end_kind {
            EndKind::Hit => canvas.dot(p, 2.5 * unit, kind_color(s.kind, false)),
            EndKind::Light => canvas.dot(p, 4.5 * unit, LIGHT_COLOR),
            EndKind::Occluder => {
                let r = 4.0 * unit;
                let pen = Pen {
                    color: kind_color(SegmentKind::Shadow, true),
                    width: 2.0 * unit,
                    alpha: 1.0,
                    dash: None,
                };
                for (a, b) in [
                    ([p[0] - r, p[1] - r], [p[0] + r, p[1] + r]),
                    ([p[0] - r, p[1] + r], [p[0] + r, p[1] - r]),
                ] {
                    canvas.line(
                        a,
                        b,
                        None,
                        Pen {
                            color: [0.0; 3],
                            width: pen.width + 2.0,
                            ..pen
                        },
                    );
                    canvas.line(a, b, None, pen);
                }
            }
            EndKind::Escape | EndKind::DistantLight => {}
        }
    }
    // Sample points of everything drawn, so the legend goes where it hides least.
    let mut drawn = Vec::new();
    for s in &tree.segments {
        if let Some((pa, _, pb, _)) = view.project_segment(s.origin, s.end) {
            drawn.extend((0..=16).map(|k| {
                let t = k as f32 / 16.0;
                [pa[0] + (pb[0] - pa[0]) * t, pa[1] + (pb[1] - pa[1]) * t]
            }));
        }
    }
    let c = view.to_camera(main.center);
    if c.z > view.near {
        drawn.extend([view.to_pixel(c); 8]);
    }
    draw_legend(&mut canvas, title, unit, &drawn);

    let mut out = img;
    for (px, c) in out.data.chunks_exact_mut(3).zip(&canvas.rgb) {
        for k in 0..3 {
            px[k] = (c[k] * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
        }
    }
    out
}

/// The main camera as a small white frustum (apex at its centre, base `size` ahead, shaped
/// like its image) with a dot at the centre; an orthographic camera as its image rectangle
/// and a line along its direction.
fn draw_main_camera(
    canvas: &mut Canvas,
    view: &View,
    main: &Camera,
    size: (u32, u32),
    len: f32,
    unit: f32,
) {
    let pen = Pen {
        color: CAMERA_COLOR,
        width: 1.6 * unit,
        alpha: 1.0,
        dash: None,
    };
    let side = size.0.max(size.1).max(1) as f32;
    let (fx, fy) = (size.0 as f32 / side * 0.5, size.1 as f32 / side * 0.5);
    let (apex, corners) = match main.kind {
        Projection::Perspective { angle } => {
            let half = (angle * 0.5).tan() * 2.0;
            let base = main.center + main.direction * len;
            let corner = |sx: f32, sy: f32| {
                base + main.horizontal * (sx * fx * half * len) + main.up * (sy * fy * half * len)
            };
            (
                Some(main.center),
                [
                    corner(-1.0, -1.0),
                    corner(1.0, -1.0),
                    corner(1.0, 1.0),
                    corner(-1.0, 1.0),
                ],
            )
        }
        Projection::Orthographic { size } => {
            let corner = |sx: f32, sy: f32| {
                main.center + main.horizontal * (sx * fx * size) + main.up * (sy * fy * size)
            };
            let tip = main.center + main.direction * len;
            canvas.segment3(view, main.center, tip, pen);
            (
                None,
                [
                    corner(-1.0, -1.0),
                    corner(1.0, -1.0),
                    corner(1.0, 1.0),
                    corner(-1.0, 1.0),
                ],
            )
        }
    };
    for k in 0..4 {
        canvas.segment3(view, corners[k], corners[(k + 1) % 4], pen);
        if let Some(apex) = apex {
            canvas.segment3(view, apex, corners[k], pen);
        }
    }
    // The image's top edge is marked by a small tick so the frustum's orientation reads.
    let top = (corners[2] + corners[3]) * 0.5;
    let tick = top + main.up * (0.25 * (corners[2] - corners[1]).length());
    canvas.segment3(view, corners[2], tick, pen);
    canvas.segment3(view, corners[3], tick, pen);
    let c = view.to_camera(main.center);
    if c.z > view.near {
        canvas.dot(view.to_pixel(c), 3.0 * unit, CAMERA_COLOR);
    }
}

/// The title at the top left and the colour key in the other corner (bottom left, bottom right
/// or top right) that covers the fewest of the `drawn` points, on dark panels.
fn draw_legend(canvas: &mut Canvas, title: &str, unit: f32, drawn: &[[f32; 2]]) {
    let s = if unit >= 1.2 { 2 } else { 1 };
    let line_h = 10 * s;
    let pad = 4 * s;
    let title_w = title.chars().count() * 6 * s;
    canvas.rect(0, 0, title_w + 2 * pad, 7 * s + 2 * pad, [0.0; 3], 0.6);
    canvas.text(pad, pad, s, title, [1.0; 3]);

    let entries: [(&str, [f32; 3], bool); 7] = [
        ("eye", kind_color(SegmentKind::Eye, false), false),
        ("shadow", kind_color(SegmentKind::Shadow, false), false),
        (
            "shadow, blocked",
            kind_color(SegmentKind::Shadow, true),
            true,
        ),
        (
            "reflected",
            kind_color(SegmentKind::Reflected, false),
            false,
        ),
        (
            "transmitted",
            kind_color(SegmentKind::Transmitted, false),
            false,
        ),
        ("camera", CAMERA_COLOR, false),
        ("light", LIGHT_COLOR, false),
    ];
    let swatch = 18 * s;
    let box_w = pad * 3 + swatch + 15 * 6 * s;
    let box_h = entries.len() * line_h + 2 * pad;
    if box_h + 7 * s + 4 * pad > canvas.height || box_w > canvas.width {
        return;
    }
    let (right, bottom) = (canvas.width - box_w, canvas.height - box_h);
    let corners = [(0, bottom), (right, bottom), (right, 0)];
    let hidden = |&(x0, y0): &(usize, usize)| {
        drawn
            .iter()
            .filter(|p| {
                (x0 as f32..(x0 + box_w) as f32).contains(&p[0])
                    && (y0 as f32..(y0 + box_h) as f32).contains(&p[1])
            })
            .count()
    };
    let (x0, y0) = corners
        .iter()
        .copied()
        .min_by_key(|c| hidden(c))
        .unwrap_or((0, bottom));
    canvas.rect(x0, y0, box_w, box_h, [0.0; 3], 0.6);
    for (k, (label, color, dashed)) in entries.iter().enumerate() {
        let y = y0 + pad + k * line_h;
        let mid = y + 7 * s / 2;
        if *label == "light" {
            canvas.dot(
                [(x0 + pad + swatch / 2) as f32, mid as f32 + 0.5],
                3.0 * s as f32,
                *color,
            );
        } else {
            let pen = Pen {
                color: *color,
                width: 2.0 * s as f32,
                alpha: 1.0,
                dash: dashed.then_some((5.0 * s as f32, 3.0 * s as f32)),
            };
            let a = [(x0 + pad) as f32, mid as f32 + 0.5];
            let b = [(x0 + pad + swatch) as f32, mid as f32 + 0.5];
            canvas.line(a, b, None, pen);
        }
        canvas.text(x0 + 2 * pad + swatch, y, s, label, [1.0; 3]);
    }
}

/// The main camera the unit tests of `witness/` look through.
#[cfg(test)]
fn main_camera() -> Camera {
    Camera::new(
        Projection::Perspective { angle: 0.6 },
        Vec3::new(0.0, 1.0, 6.0),
        Vec3::new(0.0, -0.2, -1.0),
        Vec3::Y,
    )
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
