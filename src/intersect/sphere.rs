//! Ray-sphere intersection: the quadratic `|o + t d - c|^2 = r^2`, with `d` of any length (rays
//! in the object space of a scaling transform are not unit length). Also spheres under a general
//! affine transform, stored as the inverse transform that maps them to the unit sphere.
//! Each scalar kernel sits directly above its packet twin.

use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::simd::{F32x8, Mask, Simd, Vec3v, Vec3x8, gt, lt, select};

/// The nearer root of the ray-sphere quadratic inside `(tmin, tmax)`, else the farther one.
#[inline]
pub fn intersect_sphere(
    center: Vec3,
    radius2: f32,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let oc = ray.origin - center;
    // `1 / (d . d)` once, then products: a packet divides once per ray rather than twice per
    // sphere (its kernel waited on the divider; PERF.md, sitting 25)
    let inv_a = 1.0 / ray.dir.dot(ray.dir);
    // t of the closest approach to the centre, and the squared distance there: the
    // discriminant r^2 - d^2 does not cancel catastrophically as b^2 - ac does for small,
    // distant spheres.
    let mid = -oc.dot(ray.dir) * inv_a;
    let perp = oc + ray.dir * mid;
    let disc = radius2 - perp.dot(perp);
    if disc < 0.0 || disc.is_nan() {
        return None;
    }
    let half = (disc * inv_a).sqrt();
    let t0 = mid - half;
    let t1 = mid + half;
    if t0 > tmin && t0 < tmax {
        Some(t0)
    } else if t1 > tmin && t1 < tmax {
        Some(t1)
    } else {
        None
    }
}

/// The arithmetic of [`intersect_sphere`] for any lane width (8 rays against one sphere, or one
/// ray against a leaf block of 4 spheres): the lanes with real roots and the two roots
/// `t0 <= t1`, the same bits as the scalar kernel computes.
#[inline(always)]
pub fn sphere_lanes<T: Simd>(
    center: Vec3v<T>,
    radius2: T,
    origin: Vec3v<T>,
    dir: Vec3v<T>,
) -> (T, T, T) {
    let oc = origin - center;
    let inv_a = T::splat(1.0) / dir.dot(dir);
    let mid = -oc.dot(dir) * inv_a;
    let perp = oc + dir * mid;
    let disc = radius2 - perp.dot(perp);
    let real = disc.ge(T::splat(0.0));
    let half = (disc * inv_a).sqrt_lanes();
    (real, mid - half, mid + half)
}

/// [`intersect_sphere`] for the active lanes of a packet: the lanes that hit inside
/// `(rays.tmin, tmax)` and their `t`. Inactive lanes are never reported.
#[inline(always)]
pub fn intersect_sphere_packet(
    center: Vec3,
    radius2: f32,
    rays: &RayPacket,
    tmax: F32x8,
) -> (Mask, F32x8) {
    let (real, t0, t1) = sphere_lanes(
        Vec3x8::splat(center),
        F32x8::splat(radius2),
        rays.origin,
        rays.dir,
    );
    let hit0 = gt(t0, rays.tmin) & lt(t0, tmax);
    let hit1 = gt(t1, rays.tmin) & lt(t1, tmax);
    (real & rays.active & (hit0 | hit1), select(hit0, t0, t1))
}

/// Applies the 3x4 row-major affine `m` to a point.
#[inline]
pub fn affine_point(m: &[f32; 12], p: Vec3) -> Vec3 {
    Vec3::new(
        m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3],
        m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
        m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11],
    )
}

/// Applies the linear part of the 3x4 row-major affine `m` to a direction.
#[inline]
pub fn affine_vector(m: &[f32; 12], d: Vec3) -> Vec3 {
    Vec3::new(
        m[0] * d.x + m[1] * d.y + m[2] * d.z,
        m[4] * d.x + m[5] * d.y + m[6] * d.z,
        m[8] * d.x + m[9] * d.y + m[10] * d.z,
    )
}

/// [`affine_point`] and [`affine_vector`] for every lane of a packet: the packet moved by `m`
/// (origins as points, directions as vectors), its limits and active lanes unchanged.
#[inline(always)]
pub fn affine_packet(m: &[f32; 12], rays: &RayPacket) -> RayPacket {
    let m = |i: usize| F32x8::splat(m[i]);
    let (o, d) = (rays.origin, rays.dir);
    RayPacket {
        origin: Vec3x8 {
            x: m(0) * o.x + m(1) * o.y + m(2) * o.z + m(3),
            y: m(4) * o.x + m(5) * o.y + m(6) * o.z + m(7),
            z: m(8) * o.x + m(9) * o.y + m(10) * o.z + m(11),
        },
        dir: Vec3x8 {
            x: m(0) * d.x + m(1) * d.y + m(2) * d.z,
            y: m(4) * d.x + m(5) * d.y + m(6) * d.z,
            z: m(8) * d.x + m(9) * d.y + m(10) * d.z,
        },
        ..*rays
    }
}

/// A sphere under an arbitrary affine transform, given as `inv`: the 3x4 row-major affine
/// taking world space to the space where the sphere is the unit sphere at the origin. `t` is
/// the same in both spaces because the direction is not renormalised.
#[inline]
pub fn intersect_transformed_sphere(
    inv: &[f32; 12],
    ray: &Ray,
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let local = Ray::new(affine_point(inv, ray.origin), affine_vector(inv, ray.dir));
    intersect_sphere(Vec3::ZERO, 1.0, &local, tmin, tmax)
}

/// [`intersect_transformed_sphere`] for the active lanes of a packet.
#[inline(always)]
pub fn intersect_transformed_sphere_packet(
    inv: &[f32; 12],
    rays: &RayPacket,
    tmax: F32x8,
) -> (Mask, F32x8) {
    let local = affine_packet(inv, rays);
    intersect_sphere_packet(Vec3::ZERO, 1.0, &local, tmax)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_back_inside_and_miss() {
        let inf = f32::INFINITY;
        let r = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        assert_eq!(intersect_sphere(Vec3::ZERO, 1.0, &r, 0.0, inf), Some(4.0));
        // From inside: the far root.
        let inside = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert_eq!(
            intersect_sphere(Vec3::ZERO, 1.0, &inside, 1e-4, inf),
            Some(1.0)
        );
        // Behind the ray.
        let away = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
        assert_eq!(intersect_sphere(Vec3::ZERO, 1.0, &away, 0.0, inf), None);
        // A closer hit already known.
        assert_eq!(intersect_sphere(Vec3::ZERO, 1.0, &r, 0.0, 3.0), None);
        // Miss.
        assert_eq!(
            intersect_sphere(Vec3::new(3.0, 0.0, 0.0), 1.0, &r, 0.0, inf),
            None
        );
        // Non-unit direction: t is in units of the direction.
        let r2 = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(intersect_sphere(Vec3::ZERO, 1.0, &r2, 0.0, inf), Some(2.0));
        // Orthographic rays accept negative t.
        let ortho = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert_eq!(
            intersect_sphere(Vec3::ZERO, 1.0, &ortho, -f32::MAX, inf),
            Some(-1.0)
        );
    }

    #[test]
    fn small_distant_spheres_are_hit_on_their_surface() {
        // A sphere of the bench's spheres4096 grid seen from its camera, 4 units away: the hit
        // point must lie on the sphere to well under the 1e-4 offset of secondary rays (the
        // b^2 - ac discriminant missed it by up to ~1e-4 here).
        let (center, r) = (Vec3::new(0.40625, 0.0125, -0.40625), 0.0125f32);
        let eye = Vec3::new(0.0, 2.0, 3.0);
        let mut hits = 0;
        for i in 0..200 {
            let offset = Vec3::new(1.0, 0.3, 0.7) * (r * (i as f32 / 100.0 - 1.0));
            let ray = Ray::new(eye, (center + offset - eye).normalize());
            if let Some(t) = intersect_sphere(center, r * r, &ray, 0.0, f32::INFINITY) {
                hits += 1;
                let miss = ((ray.at(t) - center).length() - r).abs();
                assert!(miss < 2e-6, "ray {i}: hit point {miss} off the surface");
            }
        }
        assert!(hits > 50, "{hits}");
    }

    #[test]
    fn transformed_sphere_is_the_unit_sphere_in_its_own_space() {
        // World: a sphere of radius 2 at (0, 0, -3); inverse maps it to the unit sphere.
        let inv = [0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.5, 1.5];
        let r = Ray::new(Vec3::ZERO, -Vec3::Z);
        let t = intersect_transformed_sphere(&inv, &r, 0.0, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6, "{t}");
    }
}
