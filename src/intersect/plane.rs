//! Ray-plane intersection for the plane `n . p = offset`.

use crate::math::{Ray, Vec3};

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_misses_and_parallel() {
        let r = Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y);
        assert_eq!(
            intersect_plane(Vec3::Y, -1.0, &r, 0.0, f32::INFINITY),
            Some(6.0)
        );
        assert_eq!(intersect_plane(Vec3::Y, 6.0, &r, 0.0, f32::INFINITY), None);
        assert_eq!(
            intersect_plane(
                Vec3::Y,
                -1.0,
                &Ray::new(Vec3::ZERO, Vec3::X),
                0.0,
                f32::INFINITY
            ),
            None
        );
    }
}
