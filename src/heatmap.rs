//! The cost heatmap (`--heatmap FILE`): where a scene is slow to trace, the modern counterpart
//! of the course's grid picture. Each pixel shows its eye ray's traversal cost in the packet
//! tracer ([`CostMap`]: BVH nodes entered plus primitives tested) on a linear scale from 0
//! (black) through purple, red and orange to the most expensive pixel (pale yellow), the
//! "inferno" colour map. A strip below the map, which keeps the render's size and pixels,
//! holds the scale: a bar of the colour map with its numbers (0, half the maximum, the maximum)
//! and what is counted, drawn with the witness picture's canvas and font.
//!
//! ```text
//! render::eye_ray_costs -> CostMap --draw_heatmap--> Rgb8 (map + legend strip) --> output
//! ```

use crate::frame::{CostMap, Frame};
use crate::math::Vec3;
use crate::output::Rgb8;
use crate::witness::canvas::Canvas;

/// The inferno colour map at 0, 1/4, 1/2, 3/4 and 1 (linear RGB, interpolated between).
const INFERNO: [[f32; 3]; 5] = [
    [0.0015, 0.0005, 0.0139],
    [0.2582, 0.0386, 0.4065],
    [0.5783, 0.1480, 0.4044],
    [0.8650, 0.3168, 0.2261],
    [0.9884, 0.9984, 0.6449],
];

/// The colour of `x` in `[0, 1]` (clamped).
pub fn colormap(x: f32) -> Vec3 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let f = x * (INFERNO.len() - 1) as f32;
    let k = (f as usize).min(INFERNO.len() - 2);
    let a = Vec3::from_array(INFERNO[k]);
    a.lerp(Vec3::from_array(INFERNO[k + 1]), f - k as f32)
}

/// Pixels of the font per font pixel for an image `width` wide.
fn text_scale(width: u32) -> usize {
    (width as usize / 320).clamp(1, 4)
}

/// The height of the legend strip below the map.
pub fn legend_height(width: u32) -> u32 {
    // margin, bar, margin, numbers (8 rows), margin, caption (8 rows), margin
    (4 + 6 + 3 + 8 + 3 + 8 + 4) * text_scale(width) as u32
}

/// The heatmap of `costs` with its legend strip below (the image is `legend_height` taller).
pub fn draw_heatmap(costs: &CostMap) -> Rgb8 {
    let (w, h) = (costs.width, costs.height);
    let ((_, _), max) = costs.max();
    let scale = max.max(1) as f32;
    let mut frame = Frame::new(w, h + legend_height(w));
    for (pixel, &c) in frame.color.iter_mut().zip(&costs.cost) {
        *pixel = colormap(c as f32 / scale);
    }
    let s = text_scale(w);
    let pad = 4 * s;
    let (strip, width) = (h as usize, w as usize);
    // The bar: the colour map from 0 to the maximum across the strip.
    let bar_y = strip + pad;
    let bar_w = width.saturating_sub(2 * pad).max(1);
    for x in (0..bar_w).filter(|x| pad + x < width) {
        let c = colormap(x as f32 / (bar_w - 1).max(1) as f32);
        for y in bar_y..bar_y + 6 * s {
            frame.color[y * width + pad + x] = c;
        }
    }
    let mut canvas = Canvas::new(&frame);
    let white = [1.0, 1.0, 1.0];
    // The numbers under the bar's start, middle and end.
    let numbers_y = bar_y + 6 * s + 3 * s;
    let text_w = |t: &str| t.chars().count() * 6 * s;
    let labels = [
        (0.0, "0".to_string()),
        (0.5, (max / 2).to_string()),
        (1.0, max.to_string()),
    ];
    for (at, label) in &labels {
        let centre = pad + (*at * (bar_w - 1) as f32) as usize;
        let x = centre
            .saturating_sub(text_w(label) / 2)
            .min(width.saturating_sub(pad + text_w(label)))
            .max(pad.min(width));
        canvas.text(x, numbers_y, s, label, white);
    }
    let caption_y = numbers_y + 8 * s + 3 * s;
    let caption = [
        "eye ray cost = bvh nodes + primitives",
        "nodes + primitives",
        "cost",
    ]
    .into_iter()
    .find(|c| text_w(c) + 2 * pad <= width)
    .unwrap_or("");
    canvas.text(pad, caption_y, s, caption, white);
    canvas.into_image()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_colour_map_runs_from_black_to_pale_yellow_and_brightens() {
        assert!(colormap(0.0).max_element() < 0.02);
        assert!(colormap(1.0).min_element() > 0.6);
        let luma = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        for k in 0..100 {
            let (a, b) = (k as f32 / 100.0, (k + 1) as f32 / 100.0);
            assert!(luma(colormap(b)) > luma(colormap(a)), "{a}");
        }
        assert_eq!(colormap(f32::NAN), colormap(0.0));
    }

    #[test]
    fn the_picture_keeps_the_map_and_adds_the_legend_strip_below() {
        let costs = CostMap {
            width: 200,
            height: 50,
            cost: (0..200 * 50).map(|i| (i % 200) as u32).collect(),
        };
        let img = draw_heatmap(&costs);
        assert_eq!((img.width, img.height), (200, 50 + legend_height(200)));
        let px = |x: usize, y: usize| &img.data[3 * (y * 200 + x)..3 * (y * 200 + x) + 3];
        // Left column black, right column the maximum's pale yellow.
        assert!(px(0, 10).iter().all(|&b| b < 5));
        assert!(px(199, 10).iter().all(|&b| b > 150));
        // Some of the strip is white text.
        let strip = &img.data[3 * 200 * 50..];
        assert!(strip.chunks_exact(3).any(|p| p == [255, 255, 255]));
    }
}
