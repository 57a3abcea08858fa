//! Ray-triangle intersection, Moller-Trumbore, on triangles stored ready for it: a vertex `v0`
//! and the edges `e1 = v1 - v0`, `e2 = v2 - v0`. The scalar kernel sits directly above its
//! packet twin.

use crate::math::{Ray, Vec3, cross_fused, dot_fused};
use crate::packet::RayPacket;
use crate::simd::{F32x8, Mask, Simd, Vec3v, Vec3x8, gt, lt};

/// The `t` where the ray crosses the triangle `(v0, v0 + e1, v0 + e2)`, if inside
/// `(tmin, tmax)`. Both sides count; rays in the triangle's plane miss.
///
/// Moller-Trumbore rearranged as Embree does: with `s = o - v0`, `R = s x d` and the
/// unnormalised normal `Ng = e1 x e2`, the determinant is `det = -(d . Ng)` and
/// `u = (R . e2) / det`, `v = -(R . e1) / det`, `t = (s . Ng) / det`. The tests run on the
/// numerators scaled by the sign of `det`; `t` is divided out only for rays inside. The dot
/// and cross products are fused (`dot_fused`, `cross_fused`: each sum one fused multiply-add),
/// as Embree's are where the processor has FMA: fewer operations and a shorter chain, and the
/// hit counts of the benchmark's rays equal Embree's.
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
    let r = cross_fused(s, ray.dir);
    let det = -dot_fused(ray.dir, ng);
    let sign = if det < 0.0 { -1.0 } else { 1.0 };
    let abs_det = det.abs();
    let u = dot_fused(r, e2) * sign;
    let v = -dot_fused(r, e1) * sign;
    let t = dot_fused(s, ng) * sign;
    let inside = det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= abs_det;
    if !inside {
        return None;
    }
    let t = t / abs_det;
    (t > tmin && t < tmax).then_some(t)
}

/// The arithmetic of [`intersect_triangle`] for any lane width, written once so that every
/// caller computes the same bits: 8 rays against one triangle ([`intersect_triangle_packet`],
/// triangle splatted) or one ray against a leaf block of 4 triangles (ray splatted). `ng` is
/// `e1 x e2` (callers compute it where it is cheapest: once per triangle, or per lane). Returns
/// the lanes where the ray crosses the triangle's interior and their `t` (meaningless elsewhere).
#[inline(always)]
pub fn triangle_lanes<T: Simd>(
    v0: Vec3v<T>,
    e1: Vec3v<T>,
    e2: Vec3v<T>,
    ng: Vec3v<T>,
    origin: Vec3v<T>,
    dir: Vec3v<T>,
) -> (T, T) {
    let zero = T::splat(0.0);
    let s = origin - v0;
    let r = s.cross_fused(dir);
    let det = -dir.dot_fused(ng);
    // `x * sign(det)` as a flip of the sign bit (Embree's form): the same bits wherever `det`
    // is not zero, and a zero `det` is outside below
    let sign = det & T::splat(-0.0);
    let abs_det = det.abs_lanes();
    let u = r.dot_fused(e2) ^ sign;
    let v = -r.dot_fused(e1) ^ sign;
    let t = s.dot_fused(ng) ^ sign;
    let inside = !det.eq(zero) & u.ge(zero) & v.ge(zero) & (u + v).le(abs_det);
    (inside, t / abs_det)
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
    let (inside, t) = triangle_lanes(
        Vec3x8::splat(v0),
        Vec3x8::splat(e1),
        Vec3x8::splat(e2),
        Vec3x8::splat(e1.cross(e2)),
        rays.origin,
        rays.dir,
    );
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
