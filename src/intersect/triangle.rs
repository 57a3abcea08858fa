//! Ray-triangle intersection, Moller-Trumbore, on triangles stored ready for it: a vertex `v0`
//! and the edges `e1 = v1 - v0`, `e2 = v2 - v0`. The scalar kernel sits directly above its
//! packet twin.

use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{F32x8, Mask, Vec3x8, eq, ge, gt, le, lt, select};

/// The `t` where the ray crosses the triangle `(v0, v0 + e1, v0 + e2)`, if inside
/// `(tmin, tmax)`. Both sides count; rays in the triangle's plane miss.
///
/// Moller-Trumbore rearranged as Embree does: with `s = o - v0`, `R = s x d` and the
/// unnormalised normal `Ng = e1 x e2`, the determinant is `det = -(d . Ng)` and
/// `u = (R . e2) / det`, `v = -(R . e1) / det`, `t = (s . Ng) / det`. The tests run on the
/// numerators scaled by the sign of `det`; `t` is divided out only for rays inside.
#[inline]
pub fn intersect_triangle(
    v0: Vec3,
    e1: Vec3,
    e2: Vec3,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let ng = e1.cross(e2);
    let s = ray.origin - v0;
    let r = s.cross(ray.dir);
    let det = -ray.dir.dot(ng);
    let sign = if det < 0.0 { -1.0 } else { 1.0 };
    let abs_det = det.abs();
    let u = r.dot(e2) * sign;
    let v = -r.dot(e1) * sign;
    let t = s.dot(ng) * sign;
    let inside = det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= abs_det;
    if !inside {
        return None;
    }
    let t = t / abs_det;
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
    let zero = F32x8::splat(0.0);
    let ng = Vec3x8::splat(e1.cross(e2));
    let s = rays.origin - Vec3x8::splat(v0);
    let r = s.cross(rays.dir);
    let det = -rays.dir.dot(ng);
    let sign = select(lt(det, zero), F32x8::splat(-1.0), F32x8::splat(1.0));
    let abs_det = det.abs();
    let u = r.dot(Vec3x8::splat(e2)) * sign;
    let v = -r.dot(Vec3x8::splat(e1)) * sign;
    let t = s.dot(ng) * sign;
    let inside = !eq(det, zero) & ge(u, zero) & ge(v, zero) & le(u + v, abs_det);
    let t = t / abs_det;
    (inside & gt(t, rays.tmin) & lt(t, tmax) & rays.active, t)
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
