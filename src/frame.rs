//! The [`Frame`] a render fills: linear colour per pixel, plus (when asked) the primary hit's
//! distance and normal for the depth and normal images and every sample's colour, and what the
//! render cost (rays cast, the packet tracer's BVH and time per bounce). A leaf of the data flow: both tracers write frames,
//! `output.rs` turns them into image files, `witness/` draws over them. Beside it, the
//! [`CostMap`] the packet tracer's counting pass fills for `--heatmap`.

use std::time::Duration;

use crate::math::Vec3;
use crate::options::Window;
use crate::stats::{AccelStats, GridStats, RayCounts};

/// A rendered frame, rows top to bottom: the whole image, or the window of it a crop asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// The frame's own size (the window's).
    pub width: u32,
    pub height: u32,
    /// Where the frame lies in the full image (all of it unless cropped).
    pub window: Window,
    /// The full image's size.
    pub image_width: u32,
    pub image_height: u32,
    /// Linear RGB per pixel (filtered from its samples). Empty when the render was asked to
    /// keep no pixels ([`RenderOptions::keep_pixels`](crate::RenderOptions::keep_pixels)): its
    /// progress hook saw them.
    pub color: Vec<Vec3>,
    /// Distance along the primary ray to the first hit; `+inf` where nothing was hit. With
    /// several samples per pixel, the ray of the sample nearest the pixel centre. Empty when
    /// the render was asked not to keep depth and normals
    /// ([`RenderOptions::depth_normal`](crate::RenderOptions::depth_normal)) or no pixels.
    pub depth: Vec<f32>,
    /// Unit world normal of the first hit; zero where nothing was hit. The same sample as the
    /// depth; empty like it.
    pub normal: Vec<Vec3>,
    /// Every sample's colour, pixel by pixel (rows top to bottom), each pixel's samples in
    /// order; empty unless [`RenderOptions::keep_samples`](crate::RenderOptions::keep_samples).
    pub samples: Vec<Vec3>,
    /// The rays cast to make the frame, by kind and bounce.
    pub rays: RayCounts,
    /// Packet tracer: the acceleration structure it built.
    pub accel: Option<AccelStats>,
    /// Packet tracer: time spent on each bounce, summed over worker threads.
    pub bounce_time: Vec<Duration>,
    /// The course's grid, when the options asked for one.
    pub grid: Option<GridStats>,
}

impl Frame {
    /// The first pixel `(x, y)` holding a NaN or infinite value: in its colour anywhere, in its
    /// depth and normal where the primary ray hit (depth is `+inf` and the normal zero
    /// elsewhere). `None` when every value is finite, as it must be.
    pub fn non_finite_pixel(&self) -> Option<(u32, u32)> {
        let aux = !self.depth.is_empty();
        let bad = |i: usize| {
            if !self.color[i].is_finite() {
                return true;
            }
            if !aux {
                return false;
            }
            let hit = self.depth[i] != f32::INFINITY;
            self.depth[i].is_nan()
                || (hit && !self.normal[i].is_finite())
                || (!hit && self.normal[i] != Vec3::ZERO)
        };
        let w = self.width.max(1) as usize;
        (0..self.color.len())
            .find(|&i| bad(i))
            .map(|i| ((i % w) as u32, (i / w) as u32))
    }

    /// A black frame with no hits, the whole of a `width` x `height` image.
    pub fn new(width: u32, height: u32) -> Frame {
        Frame::window(Window::full(width, height), width, height)
    }

    /// A black frame with no hits for `window` of a `image_width` x `image_height` image.
    pub fn window(window: Window, image_width: u32, image_height: u32) -> Frame {
        let (width, height) = (window.width(), window.height());
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            window,
            image_width,
            image_height,
            color: vec![Vec3::ZERO; n],
            depth: vec![f32::INFINITY; n],
            normal: vec![Vec3::ZERO; n],
            samples: Vec::new(),
            rays: RayCounts::default(),
            accel: None,
            bounce_time: Vec::new(),
            grid: None,
        }
    }
}

/// The eye-ray cost of every pixel, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CostMap {
    pub width: u32,
    pub height: u32,
    /// Nodes visited plus primitives tested, per pixel.
    pub cost: Vec<u32>,
}

impl CostMap {
    /// The most expensive pixel `(x, y)` and its cost (the first, in reading order, on ties).
    pub fn max(&self) -> ((u32, u32), u32) {
        let (i, c) =
            self.cost.iter().enumerate().fold(
                (0, 0),
                |best, (i, &c)| if c > best.1 { (i, c) } else { best },
            );
        let w = self.width.max(1) as usize;
        (((i % w) as u32, (i / w) as u32), c)
    }
}
