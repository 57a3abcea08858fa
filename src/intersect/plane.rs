//! Ray-plane intersection for the plane `n . p = offset`. The scalar kernel sits directly above
//! its packet twin.

use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{F32x8, Mask, Vec3x8, eq, gt, lt};

/// The `t` where the ray meets the plane, if inside `(tmin, tmax)`; rays parallel to the plane
/// miss.
#[inline]
pub fn intersect_plane(normal: Vec3, offset: f32, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
    let denom = normal.dot(ray.dir);
    if denom == 0.0 {
        return None;
    }
    let t = (offset - normal.dot(ray.origin)) / denom;
    (t > tmin && t < tmax).then_some(t)
}

/// [`intersect_plane`] for the active lanes of a packet.
#[inline(always)]
pub fn intersect_plane_packet(
    normal: Vec3,
    offset: f32,
    rays: &RayPacket,
    tmax: F32x8,
) -> (Mask, F32x8) {
    let n = Vec3x8::splat(normal);
    let denom = n.dot(rays.dir);
    let parallel = eq(denom, F32x8::splat(0.0));
    let t = (F32x8::splat(offset) - n.dot(rays.origin)) / denom;
    let hit = gt(t, rays.tmin) & lt(t, tmax) & rays.active;
    (hit & !parallel, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_misses_and_parallel() {
        let inf = f32::INFINITY;
        let r = Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y);
        assert_eq!(intersect_plane(Vec3::Y, -1.0, &r, 0.0, inf), Some(6.0));
        assert_eq!(intersect_plane(Vec3::Y, 6.0, &r, 0.0, inf), None);
        let along = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(intersect_plane(Vec3::Y, -1.0, &along, 0.0, inf), None);
    }
}
