//! The course's two cameras. A camera maps a point of the screen square, measured from its
//! centre (`(0, 0)` the centre, `(-0.5, -0.5)` bottom left, `(0.5, 0.5)` top right), to a
//! world-space ray; [`Camera::sample_screen`] maps a sample position inside a pixel of an image
//! to that square and [`Camera::pixel_point`] a pixel's centre (non-square images crop the
//! square, keeping its centre).
//!
//! The screen point is computed from the centre with one rounding, so that it is exactly
//! antisymmetric: pixel `x` and pixel `width - 1 - x` get opposite coordinates. (Computing
//! `(x + 0.5) / side` first and subtracting 0.5 afterwards rounds twice; the two roundings
//! differ on either side of the centre, and pixel centres lying exactly on an edge through
//! the centre, like the diagonal of the course's `scene7_01`, fell on either side of it.)
//!
//! ```text
//! OrthographicCamera { center 0 0 10  direction 0 0 -1  up 0 1 0  size 5 }
//! PerspectiveCamera  { center 0 0 10  direction 0 0 -1  up 0 1 0  angle 30 }   # full field of view, degrees
//! ```
//!
//! An orthographic camera sees everything along its rays, also behind its centre: its rays start
//! at `t = -f32::MAX`, as in the course.

use crate::math::{Ray, Vec2, Vec3};
use crate::simd::{F32x8, LANES, Vec3x8, from_lanes};

/// A camera with an orthonormal frame (`direction`, `up`, `horizontal = direction x up`).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub kind: Projection,
    pub center: Vec3,
    pub direction: Vec3,
    pub up: Vec3,
    pub horizontal: Vec3,
    /// Width of the screen square in world units: `size` (orthographic) or
    /// `2 tan(angle / 2)` at distance 1 (perspective).
    pub screen: f32,
}

/// Orthographic (`size` = world width of the screen) or perspective (`angle` = full field of
/// view in radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    Orthographic { size: f32 },
    Perspective { angle: f32 },
}

impl Camera {
    /// A camera from the scene file's vectors. `direction` and `up` must be non-zero and not
    /// parallel (the parser checks); `up` is made orthogonal to `direction`.
    pub fn new(kind: Projection, center: Vec3, direction: Vec3, up: Vec3) -> Camera {
        let direction = direction.normalize();
        let horizontal = direction.cross(up.normalize()).normalize();
        let up = horizontal.cross(direction).normalize();
        let screen = match kind {
            Projection::Orthographic { size } => size,
            Projection::Perspective { angle } => 2.0 * (angle * 0.5).tan(),
        };
        Camera {
            kind,
            center,
            direction,
            up,
            horizontal,
            screen,
        }
    }

    /// The smallest `t` a primary ray accepts: `-f32::MAX` for orthographic cameras (they see
    /// behind their centre), 0 for perspective ones.
    pub fn tmin(&self) -> f32 {
        match self.kind {
            Projection::Orthographic { .. } => -f32::MAX,
            Projection::Perspective { .. } => 0.0,
        }
    }

    /// The ray through `screen`, a point of the screen square measured from its centre
    /// (x to the right, y up, the square's edges at -0.5 and 0.5).
    pub fn generate_ray(&self, screen: Vec2) -> Ray {
        let (h, v) = (
            self.horizontal * (screen.x * self.screen),
            self.up * (screen.y * self.screen),
        );
        match self.kind {
            Projection::Orthographic { .. } => Ray::new(self.center + h + v, self.direction),
            Projection::Perspective { .. } => {
                Ray::new(self.center, (self.direction + h + v).normalize())
            }
        }
    }

    /// [`Camera::generate_ray`] of eight screen points, lane `i` at `(x[i], y[i])`: the rays'
    /// origins and directions, bit for bit those of the scalar function (the same operations
    /// in the same order, lane by lane).
    pub fn generate_ray_packet(&self, x: F32x8, y: F32x8) -> (Vec3x8, Vec3x8) {
        let screen = F32x8::splat(self.screen);
        let (h, v) = (
            Vec3x8::splat(self.horizontal) * (x * screen),
            Vec3x8::splat(self.up) * (y * screen),
        );
        match self.kind {
            Projection::Orthographic { .. } => (
                Vec3x8::splat(self.center) + h + v,
                Vec3x8::splat(self.direction),
            ),
            Projection::Perspective { .. } => (
                Vec3x8::splat(self.center),
                (Vec3x8::splat(self.direction) + h + v).normalize(),
            ),
        }
    }

    /// The screen point of pixel `(x, y)`'s centre in a `width` x `height` image, `y = 0` being
    /// the top row. The square screen covers the larger dimension; the smaller one is cropped.
    pub fn pixel_point(x: u32, y: u32, width: u32, height: u32) -> Vec2 {
        Camera::sample_screen(x, y, Vec2::splat(0.5), width, height)
    }

    /// The screen point of a sample of pixel `(x, y)` (`y = 0` the top row) of a `width` x
    /// `height` image, `offset` being its place in the pixel as the course measures it: from the
    /// pixel's lower-left corner, y up, in `[0, 1)`. The numerators are the distance from the
    /// image centre in pixels (`x - width/2` and `j - height/2` are exact, `j = height - 1 - y`
    /// counting rows from the bottom), so adding the offset and dividing by the side round once
    /// each and a pixel centre is rounded once.
    pub fn sample_screen(x: u32, y: u32, offset: Vec2, width: u32, height: u32) -> Vec2 {
        let side = width.max(height) as f32;
        let j = height - 1 - y;
        let dx = (x as f32 - width as f32 * 0.5) + offset.x;
        let dy = (j as f32 - height as f32 * 0.5) + offset.y;
        Vec2::new(dx / side, dy / side)
    }

    /// [`Camera::sample_screen`] of eight samples, lane `i` that of pixel `(x[i], y[i])` at
    /// `offset[i]`: the screen points' coordinates, bit for bit those of the scalar function.
    pub fn sample_screen_packet(
        x: [u32; LANES],
        y: [u32; LANES],
        offset: [Vec2; LANES],
        width: u32,
        height: u32,
    ) -> (F32x8, F32x8) {
        let side = F32x8::splat(width.max(height) as f32);
        let j = y.map(|y| (height - 1 - y) as f32);
        let dx = (from_lanes(x.map(|x| x as f32)) - F32x8::splat(width as f32 * 0.5))
            + from_lanes(offset.map(|o| o.x));
        let dy =
            (from_lanes(j) - F32x8::splat(height as f32 * 0.5)) + from_lanes(offset.map(|o| o.y));
        (dx / side, dy / side)
    }

    /// The screen point of a position inside the image in pixel units from its top-left corner
    /// (x to the right, y down, continuous): the inverse of what the witness camera projects.
    pub fn sample_point(px: f32, py: f32, width: u32, height: u32) -> Vec2 {
        let side = width.max(height) as f32;
        Vec2::new(
            (px - width as f32 * 0.5) / side,
            (height as f32 * 0.5 - py) / side,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::lanes;
    use crate::test_rng::Rng;

    #[test]
    fn up_is_orthogonalised() {
        let c = Camera::new(
            Projection::Perspective { angle: 1.0 },
            Vec3::ZERO,
            Vec3::new(0.0, -0.2, -1.0),
            Vec3::Y,
        );
        assert!(c.direction.dot(c.up).abs() < 1e-6);
        assert!((c.up.length() - 1.0).abs() < 1e-6);
        assert!(c.horizontal.x > 0.99, "right-handed: horizontal points +x");
    }

    #[test]
    fn centre_pixel_looks_along_the_direction() {
        let c = Camera::new(
            Projection::Perspective { angle: 0.5 },
            Vec3::new(0.0, 0.0, 10.0),
            -Vec3::Z,
            Vec3::Y,
        );
        let r = c.generate_ray(Vec2::ZERO);
        assert!((r.dir - -Vec3::Z).length() < 1e-6);
        // Top of the screen is up.
        assert!(c.generate_ray(Vec2::new(0.0, 0.5)).dir.y > 0.0);
        // Pixel row 0 is the top row.
        assert!(Camera::pixel_point(0, 0, 10, 10).y > 0.4);
    }

    #[test]
    fn non_square_images_crop_the_screen() {
        let p = Camera::pixel_point(0, 0, 400, 200);
        assert_eq!(p.x, -199.5 / 400.0);
        assert_eq!(p.y, 99.5 / 400.0);
    }

    #[test]
    fn pixel_centres_are_antisymmetric() {
        for (w, h) in [(12, 12), (9, 9), (400, 200), (3, 1000), (1, 1)] {
            for x in 0..w {
                let (a, b) = (
                    Camera::pixel_point(x, 0, w, h),
                    Camera::pixel_point(w - 1 - x, h - 1, w, h),
                );
                assert_eq!((a.x, a.y), (-b.x, -b.y), "{w}x{h} pixel {x}");
            }
        }
        assert_eq!(Camera::pixel_point(4, 4, 9, 9), Vec2::ZERO);
    }

    #[test]
    fn sample_point_agrees_with_pixel_centres() {
        for (x, y) in [(0, 0), (5, 7), (399, 199)] {
            let p = Camera::sample_point(x as f32 + 0.5, y as f32 + 0.5, 400, 200);
            assert_eq!(p, Camera::pixel_point(x, y, 400, 200));
        }
    }

    #[test]
    fn packet_rays_are_the_scalar_rays_bit_for_bit() {
        let mut rng = Rng(0x9e37_79b9);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for c in 0..200 {
            let kind = if c % 2 == 0 {
                Projection::Perspective {
                    angle: 0.1 + 2.5 * rng.range(0.0, 1.0),
                }
            } else {
                Projection::Orthographic {
                    size: 0.5 + 20.0 * rng.range(0.0, 1.0),
                }
            };
            let (center, direction) = (rng.vec(-5.0, 5.0), rng.vec(-5.0, 5.0));
            let up = direction.cross(rng.vec(-5.0, 5.0));
            let camera = Camera::new(kind, center, direction, up);
            let (width, height) = (1 + rng.next() % 2000, 1 + rng.next() % 2000);
            let x: [u32; LANES] = std::array::from_fn(|_| rng.next() % width);
            let y: [u32; LANES] = std::array::from_fn(|_| rng.next() % height);
            let offset: [Vec2; LANES] =
                std::array::from_fn(|_| Vec2::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0)));
            let (sx, sy) = Camera::sample_screen_packet(x, y, offset, width, height);
            let (origin, dir) = camera.generate_ray_packet(sx, sy);
            for i in 0..LANES {
                let point = Camera::sample_screen(x[i], y[i], offset[i], width, height);
                assert_eq!(
                    (point.x.to_bits(), point.y.to_bits()),
                    (lanes(sx)[i].to_bits(), lanes(sy)[i].to_bits()),
                    "camera {c} lane {i}: screen point"
                );
                let ray = camera.generate_ray(point);
                assert_eq!(
                    bits(ray.origin),
                    bits(origin.lane(i)),
                    "camera {c} lane {i}"
                );
                assert_eq!(bits(ray.dir), bits(dir.lane(i)), "camera {c} lane {i}");
            }
        }
    }
}
