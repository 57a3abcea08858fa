//! The course's reconstruction filters (assignment 7): how much a sample counts towards a pixel,
//! by its offset `(dx, dy)` from the pixel's centre, and the integer support radius `r` that
//! bounds which pixels' samples can count at all. The film ([`crate::film`]) makes pixel
//! `(i, j)` the weighted average of the samples of pixels `i-r..=i+r` x `j-r..=j+r`; the
//! `-render_filter` picture draws the weights. A leaf: it knows nothing but numbers.
//!
//! ```text
//! box R        1 where |dx| <= R and |dy| <= R, else 0          r = ceil(R - 1/2)
//! tent R       max(0, 1 - d / R),  d = sqrt(dx^2 + dy^2)        r = ceil(R - 1/2)
//! gaussian S   exp(-d^2 / (2 S^2))                              r = ceil(2 S - 1/2)
//! ```
//!
//! `r` is the smallest integer for which a sample in a pixel `r + 1` away can lie no nearer
//! than `R` (the box, tent) or `2 S` (the Gaussian) in both axes. The Gaussian is not set to
//! zero beyond `2 S`: inside the square support it keeps its value, as the instructor's
//! `filter7_01f` image shows (Gaussian 1.7: the corner pixels of the 7 x 7 support, 4.9 pixels
//! from the centre, are still grey 4-5; a clamp at 3.4 would leave them black and match only
//! 86% of that image's pixels). The parameters are read as `f32`, as the course's C code did,
//! and the weights are computed in `f64` from the `f32` offsets and rounded once to `f32`: with
//! that, both instructor filter images are reproduced exactly. The Gaussian is evaluated as the
//! product of its two axes' factors (it is separable), which lets the film compute one `exp`
//! per sample and axis rather than one per sample and pixel reached.

/// The three filter shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Box,
    Tent,
    Gaussian,
}

impl Shape {
    /// Parses `box`, `tent` or `gaussian`.
    pub fn from_name(name: &str) -> Option<Shape> {
        match name {
            "box" => Some(Shape::Box),
            "tent" => Some(Shape::Tent),
            "gaussian" => Some(Shape::Gaussian),
            _ => None,
        }
    }

    /// The name `--filter` takes.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Box => "box",
            Shape::Tent => "tent",
            Shape::Gaussian => "gaussian",
        }
    }

    /// What the parameter is called in messages.
    pub fn parameter(self) -> &'static str {
        match self {
            Shape::Box | Shape::Tent => "radius",
            Shape::Gaussian => "sigma",
        }
    }
}

/// A filter: a shape and its radius (box, tent) or standard deviation (Gaussian), in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Filter {
    pub shape: Shape,
    /// The radius (box, tent) or sigma (Gaussian); positive and finite.
    pub size: f32,
}

impl Default for Filter {
    /// A box of radius 0.5: a pixel is the plain average of its own samples (one centred
    /// sample gives it unchanged).
    fn default() -> Filter {
        Filter {
            shape: Shape::Box,
            size: 0.5,
        }
    }
}

impl Filter {
    /// The integer support radius `r` in pixels (see the module notes). Saturates for sizes
    /// too large to count in pixels; [`crate::options::check_options`] refuses those first.
    pub fn support_radius(&self) -> u32 {
        let reach = match self.shape {
            Shape::Box | Shape::Tent => self.size,
            Shape::Gaussian => 2.0 * self.size,
        };
        (reach - 0.5).ceil().max(0.0) as u32
    }

    /// The weight of a sample at `(dx, dy)` pixels from the centre of the pixel being made:
    /// `combine(axis(dx), axis(dy))`. It depends only on `|dx|` and `|dy|`, and is symmetric
    /// in them.
    #[inline]
    pub fn weight(&self, dx: f32, dy: f32) -> f32 {
        self.combine(self.axis(dx), self.axis(dy))
    }

    /// The part of a weight that depends on one axis' offset `t`, in `f64`: `t^2` for the
    /// tent, `exp(-t^2 / (2 S^2))` for the Gaussian, 1 or 0 for the box (inside or outside).
    /// The film computes these once per sample and axis, and combines them for each pixel the
    /// sample reaches.
    #[inline]
    pub fn axis(&self, t: f32) -> f64 {
        let (t, size) = (t as f64, self.size as f64);
        match self.shape {
            Shape::Box => {
                if t.abs() <= size {
                    1.0
                } else {
                    0.0
                }
            }
            Shape::Tent => t * t,
            Shape::Gaussian => (-(t * t) / (2.0 * size * size)).exp(),
        }
    }

    /// The weight from its two axis parts, rounded once to `f32`: their product (box,
    /// Gaussian: `exp(-d^2 / 2S^2)` is `exp(-dx^2 / 2S^2) exp(-dy^2 / 2S^2)`), or
    /// `max(0, 1 - sqrt(x + y) / R)` (tent).
    #[inline]
    pub fn combine(&self, x: f64, y: f64) -> f32 {
        match self.shape {
            Shape::Box | Shape::Gaussian => (x * y) as f32,
            Shape::Tent => (1.0 - (x + y).sqrt() / self.size as f64).max(0.0) as f32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(shape: Shape, size: f32) -> Filter {
        Filter { shape, size }
    }

    #[test]
    fn the_support_radii_of_the_course_lines() {
        let radii = [
            (f(Shape::Box, 0.5), 0),
            (f(Shape::Box, 1.7), 2),
            (f(Shape::Box, 2.3), 2),
            (f(Shape::Tent, 0.5), 0),
            (f(Shape::Tent, 1.5), 1),
            (f(Shape::Tent, 1.7), 2),
            (f(Shape::Tent, 2.3), 2),
            (f(Shape::Gaussian, 0.4), 1),
            (f(Shape::Gaussian, 0.5), 1),
            (f(Shape::Gaussian, 0.6), 1),
            (f(Shape::Gaussian, 1.0), 2),
            (f(Shape::Gaussian, 1.7), 3),
            (f(Shape::Gaussian, 2.3), 5),
            (f(Shape::Box, 0.01), 0),
        ];
        for (filter, r) in radii {
            assert_eq!(filter.support_radius(), r, "{filter:?}");
        }
    }

    #[test]
    fn weights_peak_at_the_centre_and_fall_off() {
        for filter in [
            f(Shape::Box, 1.0),
            f(Shape::Tent, 1.5),
            f(Shape::Gaussian, 0.6),
        ] {
            assert_eq!(filter.weight(0.0, 0.0), 1.0, "{filter:?}");
            assert!(filter.weight(0.3, 0.2) <= 1.0);
            assert!(
                filter.weight(2.0, 0.0) < filter.weight(0.2, 0.0) || filter.shape == Shape::Box
            );
        }
        assert_eq!(
            f(Shape::Box, 0.5).weight(0.5, -0.5),
            1.0,
            "the box is inclusive"
        );
        assert_eq!(f(Shape::Box, 0.5).weight(0.51, 0.0), 0.0);
        assert_eq!(f(Shape::Tent, 1.0).weight(0.6, 0.8), 0.0);
        assert_eq!(f(Shape::Tent, 2.0).weight(1.0, 0.0), 0.5);
        let g = f(Shape::Gaussian, 1.0).weight(1.0, 0.0);
        assert_eq!(g, (-0.5f64).exp() as f32);
        let g = f(Shape::Gaussian, 0.7).weight(0.3, -1.1);
        let direct = (-(0.3f64.powi(2) + 1.1f64.powi(2)) / 0.98).exp();
        assert!((g as f64 - direct).abs() < 1e-7, "{g} {direct}");
        // Not clamped at 2 sigma (the instructor image filter7_01f).
        assert!(f(Shape::Gaussian, 1.7).weight(3.45, 3.45) > 0.01);
    }
}
