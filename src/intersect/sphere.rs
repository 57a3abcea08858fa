//! Ray-sphere intersection: the quadratic `|o + t d - c|^2 = r^2`, with `d` of any length (rays
//! in the object space of a scaling transform are not unit length).

use crate::math::{Ray, Vec3};

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
    let a = ray.dir.dot(ray.dir);
    let half_b = oc.dot(ray.dir);
    let c = oc.dot(oc) - radius2;
    let disc = half_b * half_b - a * c;
    if disc < 0.0 || disc.is_nan() {
        return None;
    }
    let sq = disc.sqrt();
    let t0 = (-half_b - sq) / a;
    let t1 = (-half_b + sq) / a;
    if t0 > tmin && t0 < tmax {
        Some(t0)
    } else if t1 > tmin && t1 < tmax {
        Some(t1)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_back_inside_and_miss() {
        let r = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        assert_eq!(
            intersect_sphere(Vec3::ZERO, 1.0, &r, 0.0, f32::INFINITY),
            Some(4.0)
        );
        // From inside: the far root.
        let inside = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert_eq!(
            intersect_sphere(Vec3::ZERO, 1.0, &inside, 1e-4, f32::INFINITY),
            Some(1.0)
        );
        // Behind the ray.
        assert_eq!(
            intersect_sphere(
                Vec3::ZERO,
                1.0,
                &Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z),
                0.0,
                f32::INFINITY
            ),
            None
        );
        // A closer hit already known.
        assert_eq!(intersect_sphere(Vec3::ZERO, 1.0, &r, 0.0, 3.0), None);
        // Miss.
        assert_eq!(
            intersect_sphere(Vec3::new(3.0, 0.0, 0.0), 1.0, &r, 0.0, f32::INFINITY),
            None
        );
        // Non-unit direction: t is in units of the direction.
        let r2 = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(
            intersect_sphere(Vec3::ZERO, 1.0, &r2, 0.0, f32::INFINITY),
            Some(2.0)
        );
        // Orthographic rays accept negative t.
        assert_eq!(
            intersect_sphere(
                Vec3::ZERO,
                1.0,
                &Ray::new(Vec3::ZERO, -Vec3::Z),
                -f32::MAX,
                f32::INFINITY
            ),
            Some(-1.0)
        );
    }
}
