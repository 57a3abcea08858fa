//! The overlay: what the witness picture shows and in what order. [`draw_ray_tree`] draws, over
//! the witness camera's render of the scene, the main camera as a frustum, the tree's segments
//! in the course's colours ([`kind_color`]; shadow rays first, then deeper bounces under
//! shallower ones), a dot at each hit and light and an X at each occluder, then the title and
//! a legend in the corner that hides the least. The top of `witness/`: it takes the look-at
//! point from `placement.rs`, projects with `projection.rs` and draws with `canvas.rs`.
//!
//! ```text
//! witness Frame + RayTree + main Camera --draw_ray_tree--> Rgb8
//! ```

use super::canvas::{Canvas, Pen};
use super::placement::look_at_point;
use super::projection::View;
use crate::frame::Frame;
use crate::output::Rgb8;
use crate::raytree::{EndKind, RayTree, SegmentKind};
use crate::scene::{Camera, Projection};

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
    let (w, h) = (frame.width as usize, frame.height as usize);
    let look_at = look_at_point(main, tree);
    let scale_len = (main.center - look_at).length().max(1e-3);
    let near = 1e-4 * (witness.center - look_at).length().max(1e-3);
    let view = View::new(witness, frame.width, frame.height, near);
    let mut canvas = Canvas::new(frame);
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

    canvas.into_image()
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
