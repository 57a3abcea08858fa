//! Ray-triangle intersection, Moller-Trumbore, on triangles stored ready for it: a vertex `v0`
//! and the edges `e1 = v1 - v0`, `e2 = v2 - v0`. The scalar kernel sits directly above its
//! packet twin.

use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{F32x8, Mask, Vec3x8, eq, ge, gt, le, lt};

/// The `t` where the ray crosses the triangle `(v0, v0 + e1, v0 + e2)`, if inside
/// `(tmin, tmax)`. Both sides count; rays in the triangle's plane miss.
#[inline]
pub fn intersect_triangle(
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > tmin && t < tmax).then_some(t)
}

/// [`intersect_triangle`] for the active lanes of a packet.
#[inline(always)]
pub fn intersect_triangle_packet(
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    rays: &RayPacket,
    tmax: F32x8,
) -> (Mask, F32x8) {
    let (zero, one) = (F32x8::splat(0.0), F32x8::splat(1.0));
    let (e1, e2) = (Vec3x8::splat(e1), Vec3x8::splat(e2));
    let p = rays.dir.cross(e2);
    let det = e1.dot(p);
    let inv = one / det;
    let s = rays.origin - Vec3x8::splat(v0);
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = rays.dir.dot(q) * inv;
    let t = e2.dot(q) * inv;
    let inside = ge(u, zero) & le(u, one) & ge(v, zero) & le(u + v, one);
    let hit = inside & gt(t, rays.tmin) & lt(t, tmax) & rays.active;
    (hit & !eq(det, zero), t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_outside_and_edges() {
        let inf = f32::INFINITY;
        let (v0, e1, e2) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let down = |x: f32, y: f32| Ray::new(Vec3::new(x, y, 1.0), -Vec3::Z);
        assert_eq!(
            intersect_triangle(v0, e1, e2, &down(0.25, 0.25), 0.0, inf),
            Some(1.0)
        );
        assert_eq!(
            intersect_triangle(v0, e1, e2, &down(0.75, 0.75), 0.0, inf),
            None
        );
        assert_eq!(
            intersect_triangle(v0, e1, e2, &down(-0.1, 0.2), 0.0, inf),
            None
        );
        // Back side counts too.
        let up = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z);
        assert_eq!(intersect_triangle(v0, e1, e2, &up, 0.0, inf), Some(1.0));
        // In the plane of the triangle: miss, no NaN.
        let along = Ray::new(Vec3::new(-1.0, 0.2, 0.0), Vec3::X);
        assert_eq!(intersect_triangle(v0, e1, e2, &along, 0.0, inf), None);
    }
}
