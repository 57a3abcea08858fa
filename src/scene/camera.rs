//! The course's two cameras. A camera maps a point of the unit screen square (`(0, 0)` bottom
//! left, `(1, 1)` top right) to a world-space ray; [`Camera::pixel_point`] maps pixel centres of
//! an image to that square (non-square images crop the square, keeping its centre).
//!
//! ```text
//! OrthographicCamera { center 0 0 10  direction 0 0 -1  up 0 1 0  size 5 }
//! PerspectiveCamera  { center 0 0 10  direction 0 0 -1  up 0 1 0  angle 30 }   # full field of view, degrees
//! ```
//!
//! An orthographic camera sees everything along its rays, also behind its centre: its rays start
//! at `t = -f32::MAX`, as in the course.

use crate::math::{Ray, Vec2, Vec3};

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

    /// The ray through `point` of the unit screen square.
    pub fn generate_ray(&self, point: Vec2) -> Ray {
        let sx = point.x - 0.5;
        let sy = point.y - 0.5;
        let (h, v) = (
            self.horizontal * (sx * self.screen),
            self.up * (sy * self.screen),
        );
        match self.kind {
            Projection::Orthographic { .. } => Ray::new(self.center + h + v, self.direction),
            Projection::Perspective { .. } => {
                Ray::new(self.center, (self.direction + h + v).normalize())
            }
        }
    }

    /// The screen point of pixel `(x, y)` of a `width` x `height` image, `y = 0` being the top
    /// row. The square screen covers the larger dimension; the smaller one is cropped.
    pub fn pixel_point(x: u32, y: u32, width: u32, height: u32) -> Vec2 {
        Camera::sample_point(x as f32 + 0.5, y as f32 + 0.5, width, height)
    }

    /// Like [`Camera::pixel_point`] for an arbitrary position inside the image, in pixel units
    /// from the top-left corner (used for supersampling).
    pub fn sample_point(px: f32, py: f32, width: u32, height: u32) -> Vec2 {
        let side = width.max(height) as f32;
        let x0 = (side - width as f32) * 0.5;
        let y0 = (side - height as f32) * 0.5;
        Vec2::new((x0 + px) / side, (y0 + height as f32 - py) / side)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let r = c.generate_ray(Vec2::splat(0.5));
        assert!((r.dir - -Vec3::Z).length() < 1e-6);
        // Top of the screen is up.
        assert!(c.generate_ray(Vec2::new(0.5, 1.0)).dir.y > 0.0);
        // Pixel row 0 is the top row.
        assert!(Camera::pixel_point(0, 0, 10, 10).y > 0.9);
    }

    #[test]
    fn non_square_images_crop_the_screen() {
        let p = Camera::pixel_point(0, 0, 400, 200);
        assert!((p.x - 0.5 / 400.0).abs() < 1e-6);
        assert!((p.y - (100.0 + 199.5) / 400.0).abs() < 1e-6);
    }
}
