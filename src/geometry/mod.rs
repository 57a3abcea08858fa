//! The packet tracer's view of a scene: every primitive flattened to world space and stored
//! structure of arrays ([`soa`]), with closest-hit and any-hit queries for single rays and for
//! 8-ray packets. Flattening bakes transforms: triangles and planes to world space, spheres under
//! similarity transforms to world-space spheres, and other spheres kept as transformed spheres
//! (inverse affine to the unit sphere, normals by the inverse transpose).
//!
//! ```text
//! Scene.root (tree) --flatten--> Geometry { triangles, spheres, transformed spheres, planes }
//!                                    | closest_hit_packet / occluded_packet (wavefront)
//!                                    | closest_hit / occluded (single rays)
//! ```
//!
//! A hit names its primitive by a geometry index: triangles first, then spheres, transformed
//! spheres and planes, each kind in its array order. [`Geometry::surface`] turns it back into a
//! normal, a material and the scene id.

pub mod soa;

use crate::intersect::sphere::{affine_point, affine_vector};
use crate::intersect::{
    intersect_plane, intersect_plane_packet, intersect_sphere, intersect_sphere_packet,
    intersect_transformed_sphere, intersect_transformed_sphere_packet, intersect_triangle,
    intersect_triangle_packet,
};
use crate::math::{Mat3, Mat4, Ray, Vec3};
use crate::packet::{HitPacket, RayPacket};
use crate::scene::{Object, Scene};
use crate::shade::Hit;
use crate::simd::{F32x8, I32x8, Mask, all, mask_none, select, select_i32};
pub use soa::{PlaneSoa, SphereSoa, TransformedSphereSoa, TriangleSoa};

/// The kinds of primitive, in geometry-index order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimKind {
    Triangle,
    Sphere,
    TransformedSphere,
    Plane,
}

/// All primitives of a scene in world space, ready for intersection.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    pub triangles: TriangleSoa,
    pub spheres: SphereSoa,
    pub transformed: TransformedSphereSoa,
    pub planes: PlaneSoa,
}

impl Geometry {
    /// Flattens the scene's object tree.
    pub fn from_scene(scene: &Scene) -> Geometry {
        let mut g = Geometry::default();
        flatten(&scene.root, &Mat4::IDENTITY, &Mat3::IDENTITY, true, &mut g);
        g
    }

    /// The number of primitives.
    pub fn len(&self) -> usize {
        self.triangles.len() + self.spheres.len() + self.transformed.len() + self.planes.len()
    }

    /// True when there is no primitive.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn sphere_base(&self) -> usize {
        self.triangles.len()
    }

    fn transformed_base(&self) -> usize {
        self.sphere_base() + self.spheres.len()
    }

    fn plane_base(&self) -> usize {
        self.transformed_base() + self.transformed.len()
    }

    /// The kind of the primitive with geometry index `prim` and its index in its array.
    pub fn locate(&self, prim: u32) -> (PrimKind, usize) {
        let p = prim as usize;
        if p < self.sphere_base() {
            (PrimKind::Triangle, p)
        } else if p < self.transformed_base() {
            (PrimKind::Sphere, p - self.sphere_base())
        } else if p < self.plane_base() {
            (PrimKind::TransformedSphere, p - self.transformed_base())
        } else {
            (PrimKind::Plane, p - self.plane_base())
        }
    }

    /// The surface hit by `ray` at `t` on primitive `prim`: unit world normal, material, scene id.
    pub fn surface(&self, prim: u32, ray: &Ray, t: f32) -> Hit {
        let (kind, i) = self.locate(prim);
        let (normal, material, id) = match kind {
            PrimKind::Triangle => (
                self.triangles.normal(i),
                self.triangles.material[i],
                self.triangles.id[i],
            ),
            PrimKind::Sphere => (
                (ray.at(t) - self.spheres.center(i)).normalize(),
                self.spheres.material[i],
                self.spheres.id[i],
            ),
            PrimKind::TransformedSphere => {
                let inv = self.transformed.inverse(i);
                let local = affine_point(&inv, ray.origin) + affine_vector(&inv, ray.dir) * t;
                // Normals by the inverse transpose: the transpose of inv's linear part.
                let n = Vec3::new(
                    inv[0] * local.x + inv[4] * local.y + inv[8] * local.z,
                    inv[1] * local.x + inv[5] * local.y + inv[9] * local.z,
                    inv[2] * local.x + inv[6] * local.y + inv[10] * local.z,
                );
                (
                    n.normalize(),
                    self.transformed.material[i],
                    self.transformed.id[i],
                )
            }
            PrimKind::Plane => (
                self.planes.normal(i),
                self.planes.material[i],
                self.planes.id[i],
            ),
        };
        Hit {
            t,
            normal,
            material,
            prim: id,
        }
    }

    /// The closest hit of one ray in `(tmin, tmax)`: `(t, geometry index)`.
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let mut limit = tmax;
        let mut take = |t: Option<f32>, prim: usize, limit: &mut f32| {
            if let Some(t) = t {
                *limit = t;
                best = Some((t, prim as u32));
            }
        };
        let tri = &self.triangles;
        for i in 0..tri.len() {
            let (v0, e1, e2) = tri.get(i);
            take(
                intersect_triangle(v0, e1, e2, ray, tmin, limit),
                i,
                &mut limit,
            );
        }
        let base = self.sphere_base();
        for i in 0..self.spheres.len() {
            let t = intersect_sphere(
                self.spheres.center(i),
                self.spheres.radius2[i],
                ray,
                tmin,
                limit,
            );
            take(t, base + i, &mut limit);
        }
        let base = self.transformed_base();
        for i in 0..self.transformed.len() {
            let t = intersect_transformed_sphere(&self.transformed.inverse(i), ray, tmin, limit);
            take(t, base + i, &mut limit);
        }
        let base = self.plane_base();
        for i in 0..self.planes.len() {
            let t = intersect_plane(
                self.planes.normal(i),
                self.planes.offset[i],
                ray,
                tmin,
                limit,
            );
            take(t, base + i, &mut limit);
        }
        best
    }

    /// True if anything lies on the ray in `(tmin, tmax)`.
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        let tri = &self.triangles;
        (0..tri.len()).any(|i| {
            let (v0, e1, e2) = tri.get(i);
            intersect_triangle(v0, e1, e2, ray, tmin, tmax).is_some()
        }) || (0..self.spheres.len()).any(|i| {
            intersect_sphere(
                self.spheres.center(i),
                self.spheres.radius2[i],
                ray,
                tmin,
                tmax,
            )
            .is_some()
        }) || (0..self.transformed.len()).any(|i| {
            intersect_transformed_sphere(&self.transformed.inverse(i), ray, tmin, tmax).is_some()
        }) || (0..self.planes.len()).any(|i| {
            intersect_plane(
                self.planes.normal(i),
                self.planes.offset[i],
                ray,
                tmin,
                tmax,
            )
            .is_some()
        })
    }

    /// Updates `hit` with the closest hits of the packet's active lanes; inactive lanes of `hit`
    /// are left untouched.
    pub fn closest_hit_packet(&self, rays: &RayPacket, hit: &mut HitPacket) {
        let tri = &self.triangles;
        for i in 0..tri.len() {
            let (v0, e1, e2) = tri.get(i);
            let (m, t) = intersect_triangle_packet(v0, e1, e2, rays, hit.t);
            update(hit, m, t, i);
        }
        let base = self.sphere_base();
        for i in 0..self.spheres.len() {
            let (m, t) = intersect_sphere_packet(
                self.spheres.center(i),
                self.spheres.radius2[i],
                rays,
                hit.t,
            );
            update(hit, m, t, base + i);
        }
        let base = self.transformed_base();
        for i in 0..self.transformed.len() {
            let (m, t) =
                intersect_transformed_sphere_packet(&self.transformed.inverse(i), rays, hit.t);
            update(hit, m, t, base + i);
        }
        let base = self.plane_base();
        for i in 0..self.planes.len() {
            let (m, t) =
                intersect_plane_packet(self.planes.normal(i), self.planes.offset[i], rays, hit.t);
            update(hit, m, t, base + i);
        }
    }

    /// The active lanes with something in `(tmin, tmax)`; stops as soon as every active lane is
    /// occluded.
    pub fn occluded_packet(&self, rays: &RayPacket, tmax: F32x8) -> Mask {
        let mut occluded = mask_none();
        let done = |occluded: Mask| all(occluded | !rays.active);
        let tri = &self.triangles;
        for i in 0..tri.len() {
            let (v0, e1, e2) = tri.get(i);
            occluded |= intersect_triangle_packet(v0, e1, e2, rays, tmax).0;
            if done(occluded) {
                return occluded;
            }
        }
        for i in 0..self.spheres.len() {
            let c = self.spheres.center(i);
            occluded |= intersect_sphere_packet(c, self.spheres.radius2[i], rays, tmax).0;
            if done(occluded) {
                return occluded;
            }
        }
        for i in 0..self.transformed.len() {
            let inv = self.transformed.inverse(i);
            occluded |= intersect_transformed_sphere_packet(&inv, rays, tmax).0;
            if done(occluded) {
                return occluded;
            }
        }
        for i in 0..self.planes.len() {
            let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
            occluded |= intersect_plane_packet(n, d, rays, tmax).0;
            if done(occluded) {
                return occluded;
            }
        }
        occluded
    }
}

/// Records the hits `(m, t)` of primitive `prim` in the lanes of `m`.
#[inline(always)]
fn update(hit: &mut HitPacket, m: Mask, t: F32x8, prim: usize) {
    hit.t = select(m, t, hit.t);
    hit.prim = select_i32(m, I32x8::splat(prim as i32), hit.prim);
}

/// True if the linear part of `m` is a rotation times a uniform scale (maybe mirrored): spheres
/// stay spheres under it.
fn is_similarity(m: &Mat4) -> Option<f32> {
    let c = [
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    ];
    let l = c[0].length();
    let tol = 1e-6 * l;
    let same_length = c.iter().all(|v| (v.length() - l).abs() <= tol);
    let orthogonal = c[0].dot(c[1]).abs() <= tol * l
        && c[0].dot(c[2]).abs() <= tol * l
        && c[1].dot(c[2]).abs() <= tol * l;
    (same_length && orthogonal && l > 0.0).then_some(l)
}

fn affine_rows(m: &Mat4) -> [f32; 12] {
    let r = m.transpose().to_cols_array();
    // transpose's columns are m's rows: take the first three rows (x, y, z).
    std::array::from_fn(|k| r[k])
}

fn flatten(obj: &Object, m: &Mat4, n: &Mat3, identity: bool, g: &mut Geometry) {
    let normal = |v: Vec3| if identity { v } else { (*n * v).normalize() };
    match obj {
        Object::Sphere {
            center,
            radius,
            material,
            id,
        } => {
            if identity {
                g.spheres.push(*center, *radius, *material, *id);
            } else if let Some(scale) = is_similarity(m) {
                g.spheres
                    .push(m.transform_point3(*center), radius * scale, *material, *id);
            } else {
                let world =
                    *m * Mat4::from_translation(*center) * Mat4::from_scale(Vec3::splat(*radius));
                let inv = world.inverse();
                g.transformed
                    .push(affine_rows(&inv), affine_rows(&world), *material, *id);
            }
        }
        Object::Plane {
            normal: pn,
            offset,
            material,
            id,
        } => {
            if identity {
                g.planes.push(*pn, *offset, *material, *id);
            } else {
                let nw = normal(*pn);
                let p0 = m.transform_point3(*pn * *offset);
                g.planes.push(nw, nw.dot(p0), *material, *id);
            }
        }
        Object::Triangle { v, material, id } => {
            push_triangle(g, v, m, identity, &normal, *material, *id)
        }
        Object::Mesh {
            triangles,
            material,
            first_id,
        } => {
            for (k, v) in triangles.iter().enumerate() {
                push_triangle(g, v, m, identity, &normal, *material, first_id + k as u32);
            }
        }
        Object::Group(children) => {
            for c in children {
                flatten(c, m, n, identity, g);
            }
        }
        Object::Transform(t) => {
            flatten(
                &t.child,
                &(*m * t.matrix),
                &(*n * t.normal_matrix),
                false,
                g,
            );
        }
    }
}

fn push_triangle(
    g: &mut Geometry,
    v: &[Vec3; 3],
    m: &Mat4,
    identity: bool,
    normal: &dyn Fn(Vec3) -> Vec3,
    material: u32,
    id: u32,
) {
    let n_obj = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    let world = if identity {
        *v
    } else {
        v.map(|p| m.transform_point3(p))
    };
    g.triangles.push(world, normal(n_obj), material, id);
}
