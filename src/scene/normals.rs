//! Smooth shading normals of meshes: the corner normals a mesh's triangles carry (from the OBJ
//! file's `vn`, or computed here for `--smooth-normals`), and their interpolation at a hit.
//!
//! ```text
//! OBJ vn + f a//n  --obj.rs-->  Mesh { triangles, normals }
//! Mesh without vn  --Scene::smooth_normals-->  area-weighted vertex normals
//! hit (u, v) on triangle k  --interpolate-->  shading normal (both tracers)
//! ```
//!
//! The shading normal only shades: the geometric normal still decides which side a ray hits
//! and whether a light is above the surface (see [`crate::shade`]), so smoothing adds no
//! self-shadowing and no light leaks.
//!
//! Computed normals are area weighted: each corner gets the sum of the unnormalised normals
//! (twice the area times the unit normal) of the triangles meeting at its vertex, normalised.
//! Vertices are the same when their coordinates are equal (the OBJ index is not kept), so
//! seams where a file repeats a vertex are smoothed over too.

use std::collections::HashMap;

use super::{Object, Scene};
use crate::math::Vec3;

/// The unit geometric normal of a triangle (counter-clockwise vertices face the viewer).
pub fn face_normal(t: &[Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
}

/// Area-weighted vertex normals for `triangles`, as corner normals parallel to them.
pub fn vertex_normals(triangles: &[[Vec3; 3]]) -> Vec<[Vec3; 3]> {
    // Bit patterns as keys, with -0.0 and 0.0 the same vertex.
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut sums: HashMap<[u32; 3], Vec3> = HashMap::with_capacity(triangles.len());
    for t in triangles {
        let weighted = (t[1] - t[0]).cross(t[2] - t[0]);
        for p in t {
            *sums.entry(key(*p)).or_insert(Vec3::ZERO) += weighted;
        }
    }
    triangles
        .iter()
        .map(|t| {
            let face = face_normal(t);
            t.map(|p| sums[&key(p)].normalize_or(face))
        })
        .collect()
}

/// The normal at barycentric coordinates `(u, v)` (weights `1 - u - v`, `u`, `v` of corners 0,
/// 1, 2) of a triangle with corner normals `n`, normalised; `fallback` when they cancel out.
#[inline]
pub fn interpolate(n: &[Vec3; 3], u: f32, v: f32, fallback: Vec3) -> Vec3 {
    (n[0] * (1.0 - u - v) + n[1] * u + n[2] * v).normalize_or(fallback)
}

impl Scene {
    /// Gives every mesh without normals area-weighted vertex normals (`--smooth-normals`);
    /// meshes whose file has normals keep them.
    pub fn smooth_normals(&mut self) {
        smooth(&mut self.root);
    }
}

fn smooth(obj: &mut Object) {
    match obj {
        Object::Mesh {
            triangles, normals, ..
        } => {
            if normals.is_empty() {
                *normals = vertex_normals(triangles);
            }
        }
        Object::Group(children) => children.iter_mut().for_each(smooth),
        Object::Transform(t) => smooth(&mut t.child),
        Object::Sphere { .. } | Object::Plane { .. } | Object::Triangle { .. } => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_vertices_average_their_faces_by_area() {
        // Two triangles meeting at the edge (0,0,0)-(1,0,0): one in z = 0 (area 1/2), one
        // tilted up to face +y (area 1): their shared corners get the area-weighted mean.
        let a = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let b = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, -2.0)];
        let n = vertex_normals(&[a, b]);
        let shared = (Vec3::Z * 1.0 + Vec3::Y * 2.0).normalize();
        assert!((n[0][0] - shared).length() < 1e-6);
        assert!((n[0][1] - shared).length() < 1e-6);
        assert_eq!(n[0][2], Vec3::Z);
        assert!((n[1][0] - shared).length() < 1e-6);
        assert_eq!(n[1][2], Vec3::Y);
    }

    #[test]
    fn interpolation_weights_the_corners_by_barycentrics() {
        let n = [Vec3::X, Vec3::Y, Vec3::Z];
        assert_eq!(interpolate(&n, 0.0, 0.0, Vec3::Z), Vec3::X);
        assert_eq!(interpolate(&n, 1.0, 0.0, Vec3::Z), Vec3::Y);
        let mid = interpolate(&n, 0.5, 0.5, Vec3::Z);
        assert!((mid - Vec3::new(0.0, 1.0, 1.0).normalize()).length() < 1e-6);
        // Opposite corner normals cancel: the fallback.
        let n = [Vec3::X, -Vec3::X, Vec3::X];
        assert_eq!(interpolate(&n, 0.5, 0.0, Vec3::Y), Vec3::Y);
    }
}
