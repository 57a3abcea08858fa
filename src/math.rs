//! Scalar maths shared by every stage: glam's `Vec3`/`Mat4` re-exported, the single [`Ray`], and
//! the optics of the Whitted model (mirror reflection, Snell refraction, Schlick's Fresnel term).
//! Both tracers call these functions, so a disagreement between them never comes from the optics.

pub use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

/// One ray: `origin + t * dir`. Directions are not required to be unit length (object-space rays
/// under a scaling transform are not), but every world-space ray the tracers create is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Ray {
        Ray { origin, dir }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// `a . b` with fused operations: `a.x b.x + (a.y b.y + a.z b.z)`, each sum one fused
/// multiply-add (Embree's `dot`; two roundings fewer than `Vec3::dot`, and shorter to compute).
/// The triangle test's twins take it ([`crate::simd::Vec3v::dot_fused`] computes the same bits
/// per lane).
#[inline(always)]
pub fn dot_fused(a: Vec3, b: Vec3) -> f32 {
    a.x.mul_add(b.x, a.y.mul_add(b.y, a.z * b.z))
}

/// `a x b` with fused operations: each component `p q - r s` as one fused multiply-add of `p q`
/// and `-(r s)` (Embree's `cross`; [`crate::simd::Vec3v::cross_fused`] per lane, the same bits).
#[inline(always)]
pub fn cross_fused(a: Vec3, b: Vec3) -> Vec3 {
    Vec3::new(
        a.y.mul_add(b.z, -(b.y * a.z)),
        a.z.mul_add(b.x, -(b.z * a.x)),
        a.x.mul_add(b.y, -(b.x * a.y)),
    )
}

/// Clamps channels that overflowed to infinity down to `f32::MAX`. Colours are never negative
/// (the parser checks), so sums and products of finite colours are never NaN, only possibly
/// infinite; saturating every colour that is later multiplied (by a zero shadow factor, say)
/// keeps `inf * 0 = NaN` out of the pixels.
#[inline]
pub fn saturate(c: Vec3) -> Vec3 {
    c.min(Vec3::splat(f32::MAX))
}

/// True when a triangle's vertices are (numerically) collinear or coincide.
pub fn is_degenerate(v: &[Vec3; 3]) -> bool {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let cross = e1.cross(e2);
    let area2 = cross.length();
    !(area2 > 1e-7 * e1.length() * e2.length() && cross.try_normalize().is_some())
}

/// The barycentric coordinates `(u, v)` (weights of `v0 + e1` and `v0 + e2`) of the point
/// where `ray` crosses the plane of the triangle `(v0, v0 + e1, v0 + e2)`, by the same
/// Moller-Trumbore numerators as the intersection kernels; `(0, 0)` for a ray in the plane.
/// Tracers compute them for the one triangle a ray hit, after the traversal.
#[inline]
pub fn barycentrics(v0: Vec3, e1: Vec3, e2: Vec3, ray: &Ray) -> (f32, f32) {
    let s = ray.origin - v0;
    let r = s.cross(ray.dir);
    let det = -ray.dir.dot(e1.cross(e2));
    if det == 0.0 || !det.is_finite() {
        return (0.0, 0.0);
    }
    (r.dot(e2) / det, -r.dot(e1) / det)
}

/// Mirror direction of `dir` about the normal `n` (unit): `R = V - 2 (V.N) N`. The sign of `n`
/// does not matter.
#[inline]
pub fn reflect(dir: Vec3, n: Vec3) -> Vec3 {
    dir - n * (2.0 * dir.dot(n))
}

/// Snell's law. `n` is the unit normal on the side the ray arrives from (`dir . n < 0`), `eta` is
/// `index_incident / index_transmitted`. Returns the normalised transmitted direction, or `None`
/// past the critical angle (total internal reflection).
#[inline]
pub fn refract(dir: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let i = -dir.normalize();
    let cos_i = n.dot(i);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    // NaN comes from an overflowing eta at normal incidence: no transmitted ray either.
    if k < 0.0 || k.is_nan() {
        return None;
    }
    Some((n * (eta * cos_i - k.sqrt()) - i * eta).normalize())
}

/// Schlick's approximation of the Fresnel reflectance for light going from index `n_i` into
/// index `n_t`, where `cos_i` is the cosine of the angle of incidence. When leaving a denser
/// medium the cosine of the transmitted angle is used, as the approximation requires; past the
/// critical angle the reflectance is 1.
#[inline]
pub fn schlick(cos_i: f32, n_i: f32, n_t: f32) -> f32 {
    let r0 = ((n_i - n_t) / (n_i + n_t)).powi(2);
    let cos = if n_i > n_t {
        let eta = n_i / n_t;
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    r0 + (1.0 - r0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// Transforms a normal by the inverse transpose `normal_matrix` and normalises it.
#[inline]
pub fn transform_normal(normal_matrix: &Mat3, n: Vec3) -> Vec3 {
    (*normal_matrix * n).normalize_or(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn barycentrics_locate_the_crossing_point() {
        let (v0, e1, e2) = (Vec3::new(1.0, 0.0, 0.0), Vec3::X, Vec3::Y * 2.0);
        for (u, v) in [(0.25, 0.5), (0.0, 0.0), (1.0, 0.0), (0.1, 0.9)] {
            let p = v0 + e1 * u + e2 * v;
            for dir in [-Vec3::Z, Vec3::new(0.3, -0.2, 1.0)] {
                let ray = Ray::new(p - dir * 3.0, dir);
                let (bu, bv) = barycentrics(v0, e1, e2, &ray);
                assert!(
                    (bu - u).abs() < 1e-5 && (bv - v).abs() < 1e-5,
                    "{u} {v}: {bu} {bv}"
                );
            }
        }
        let along = Ray::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::X);
        assert_eq!(barycentrics(v0, e1, e2, &along), (0.0, 0.0));
    }

    #[test]
    fn reflection_mirrors_about_the_normal_either_sign() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let r = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!(close(reflect(d, Vec3::Y), r));
        assert!(close(reflect(d, -Vec3::Y), r));
        assert!(close(reflect(-Vec3::Y, Vec3::Y), Vec3::Y));
    }

    #[test]
    fn refraction_obeys_snell_and_is_normalised() {
        let theta_i = 30f32.to_radians();
        let d = Vec3::new(theta_i.sin(), -theta_i.cos(), 0.0);
        let t = refract(d, Vec3::Y, 1.0 / 1.5).unwrap();
        assert!((t.length() - 1.0).abs() < 1e-6);
        let sin_t = t.x;
        assert!((theta_i.sin() - 1.5 * sin_t).abs() < 1e-6);
        assert!(t.y < 0.0);
        // Index 1: the ray goes straight on.
        assert!(close(refract(d, Vec3::Y, 1.0).unwrap(), d));
        // Head-on: straight through whatever the index.
        assert!(close(
            refract(-Vec3::Y, Vec3::Y, 1.0 / 2.0).unwrap(),
            -Vec3::Y
        ));
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        let eta = 1.5f32; // glass to vacuum
        let critical = (1.0 / eta).asin();
        let just_below = critical - 0.01;
        let just_above = critical + 0.01;
        let dir = |a: f32| Vec3::new(a.sin(), -a.cos(), 0.0);
        let t = refract(dir(just_below), Vec3::Y, eta).expect("below critical angle");
        assert!(t.x > 0.95, "near grazing exit: {t}");
        assert!(refract(dir(just_above), Vec3::Y, eta).is_none());
        assert!(refract(dir(80f32.to_radians()), Vec3::Y, eta).is_none());
    }

    #[test]
    fn schlick_limits() {
        // Normal incidence gives R0, grazing incidence gives 1.
        let r0 = (0.5f32 / 2.5).powi(2);
        assert!((schlick(1.0, 1.0, 1.5) - r0).abs() < 1e-6);
        assert!((schlick(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6);
        // Equal indices: no reflection at normal incidence.
        assert!(schlick(1.0, 1.3, 1.3).abs() < 1e-6);
        // Leaving glass past the critical angle: total reflection.
        assert_eq!(schlick(0.2, 1.5, 1.0), 1.0);
        // Monotone in the angle.
        assert!(schlick(0.5, 1.0, 1.5) > schlick(0.9, 1.0, 1.5));
    }

    #[test]
    fn normals_use_the_inverse_transpose_under_non_uniform_scale() {
        // A sphere squashed to half height: the normal at 45 degrees tilts towards Y.
        let m = Mat4::from_scale(Vec3::new(1.0, 0.5, 1.0));
        let normal_matrix = Mat3::from_mat4(m.inverse().transpose());
        let n_obj = Vec3::new(1.0, 1.0, 0.0).normalize();
        let n = transform_normal(&normal_matrix, n_obj);
        assert!(close(n, Vec3::new(1.0, 2.0, 0.0).normalize()));
        // The transformed normal is perpendicular to the transformed tangent.
        let tangent_obj = Vec3::new(-1.0, 1.0, 0.0);
        let tangent = m.transform_vector3(tangent_obj);
        assert!(n.dot(tangent).abs() < 1e-6);
        // Transforming the normal like a direction would be wrong here.
        let naive = m.transform_vector3(n_obj).normalize();
        assert!(naive.dot(tangent).abs() > 0.1);
    }
}
