//! The witness camera's projection: [`View`] maps world points to pixel positions and depths
//! of its picture (the inverse of the camera's rays), clips segments at the near plane, and
//! turns the witness frame's hit distances into depths for the hidden-part test. Sits between
//! the placed camera (`placement.rs`) and the raster (`canvas.rs`, `overlay.rs`), which draw
//! at the pixels it gives.
//!
//! ```text
//! world point --to_camera--> (right, up, depth) --to_pixel--> (x, y) in the witness picture
//! ```

use super::placement::DEFAULT_ANGLE_DEG;
use crate::math::Vec3;
use crate::scene::{Camera, Projection};

/// Maps world points to the pixels of a perspective camera's picture.
pub(super) struct View {
    center: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// `tan(angle / 2)`: screen half-size at unit depth.
    tan_half: f32,
    width: f32,
    height: f32,
    side: f32,
    /// Depth of the near plane segments are clipped at.
    pub(super) near: f32,
}

impl View {
    /// The view through `cam` of a `width` x `height` picture, clipping at depth `near`. Only
    /// perspective cameras are placed as witnesses; an orthographic one is seen as a perspective
    /// camera with the default witness angle.
    pub(super) fn new(cam: &Camera, width: u32, height: u32, near: f32) -> View {
        let angle = match cam.kind {
            Projection::Perspective { angle } => angle,
            Projection::Orthographic { .. } => DEFAULT_ANGLE_DEG.to_radians(),
        };
        View {
            center: cam.center,
            forward: cam.direction,
            right: cam.horizontal,
            up: cam.up,
            tan_half: (angle * 0.5).tan(),
            width: width as f32,
            height: height as f32,
            side: width.max(height) as f32,
            near,
        }
    }

    /// Camera-space coordinates: (right, up, depth).
    pub(super) fn to_camera(&self, p: Vec3) -> Vec3 {
        let d = p - self.center;
        Vec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.forward))
    }

    /// Pixel position (x from the left, y from the top, continuous) of a camera-space point in
    /// front of the camera; the inverse of [`Camera::sample_point`] and `generate_ray`.
    pub(super) fn to_pixel(&self, c: Vec3) -> [f32; 2] {
        let sx = c.x / (c.z * 2.0 * self.tan_half);
        let sy = c.y / (c.z * 2.0 * self.tan_half);
        [
            sx * self.side + self.width * 0.5,
            self.height * 0.5 - sy * self.side,
        ]
    }

    /// Length of the un-normalised ray direction (unit depth) through pixel `(px, py)`, which
    /// turns the frame's distances into depths.
    pub(super) fn ray_length(&self, px: f32, py: f32) -> f32 {
        let sx = (px - self.width * 0.5) / self.side;
        let sy = (self.height * 0.5 - py) / self.side;
        let h = 2.0 * self.tan_half;
        (1.0 + (sx * h).powi(2) + (sy * h).powi(2)).sqrt()
    }

    /// The part of the world segment `a`-`b` in front of the near plane, as pixel positions
    /// with their depths; `None` if it lies wholly behind.
    pub(super) fn project_segment(
        &self,
        a: Vec3,
        b: Vec3,
    ) -> Option<([f32; 2], f32, [f32; 2], f32)> {
        let (mut ca, mut cb) = (self.to_camera(a), self.to_camera(b));
        if ca.z < self.near && cb.z < self.near {
            return None;
        }
        if ca.z < self.near {
            ca = ca + (cb - ca) * ((self.near - ca.z) / (cb.z - ca.z));
        } else if cb.z < self.near {
            cb = cb + (ca - cb) * ((self.near - cb.z) / (ca.z - cb.z));
        }
        Some((self.to_pixel(ca), ca.z, self.to_pixel(cb), cb.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::witness::main_camera;

    #[test]
    fn projection_inverts_the_camera_rays() {
        let cam = main_camera();
        let view = View::new(&cam, 300, 200, 1e-3);
        for (px, py) in [(0.5f32, 0.5f32), (150.0, 100.0), (299.5, 10.25)] {
            let ray = cam.generate_ray(Camera::sample_point(px, py, 300, 200));
            let p = view.to_pixel(view.to_camera(ray.at(7.0)));
            assert!(
                (p[0] - px).abs() < 1e-3 && (p[1] - py).abs() < 1e-3,
                "{p:?} vs {px},{py}"
            );
            let depth = view.to_camera(ray.at(7.0)).z;
            assert!((7.0 / view.ray_length(px, py) - depth).abs() < 1e-4);
        }
    }

    #[test]
    fn segments_behind_the_camera_are_clipped_at_the_near_plane() {
        let cam = main_camera();
        let view = View::new(&cam, 100, 100, 0.01);
        let behind = cam.center - cam.direction;
        assert!(
            view.project_segment(behind, behind - cam.direction)
                .is_none()
        );
        let ahead = cam.center + cam.direction * 3.0;
        let (_, za, _, zb) = view.project_segment(behind, ahead).unwrap();
        assert!((za - 0.01).abs() < 1e-5 && (zb - 3.0).abs() < 1e-4);
    }
}
