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
//! normal, a material and the scene id. [`Geometry::build_bvh`] builds one BVH over all bounded
//! primitives (planes are tested apart), reorders the arrays so each leaf is a contiguous range
//! of one kind, and hands the BVH the leaf test as a closure over a range of geometry indices.

pub mod normals;
pub mod soa;

use crate::bvh::{self, Aabb, Bvh, TraversalProbe};
use crate::intersect::sphere::{affine_point, affine_vector};
use crate::intersect::{
    Hit, intersect_plane, intersect_plane_packet, intersect_sphere, intersect_sphere_packet,
    intersect_transformed_sphere, intersect_transformed_sphere_packet, intersect_triangle,
    intersect_triangle_packet,
};
use crate::math::{Mat3, Mat4, Ray, Vec3, barycentrics};
use crate::packet::{HitPacket, RayPacket};
use crate::scene::normals::interpolate;
use crate::scene::{Object, Scene};
use crate::simd::{F32x8, I32x8, LANES, Mask, all, any, bitmask, mask_none, select, select_i32};
use normals::CornerNormals;
pub use soa::{PlaneSoa, SphereSoa, TransformedSphereSoa, TriangleSoa};
use std::ops::Range;

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
    /// Corner normals of smooth mesh triangles, by scene id (outside the kernels' data).
    pub corner_normals: CornerNormals,
    /// Over the bounded primitives; empty until [`Geometry::build_bvh`].
    bvh: Bvh,
}

impl Geometry {
    /// Flattens the scene's object tree.
    pub fn from_scene(scene: &Scene) -> Geometry {
        let mut g = Geometry::default();
        flatten(&scene.root, &Mat4::IDENTITY, &Mat3::IDENTITY, true, &mut g);
        g.build_bvh();
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
        let mut shading = None;
        let (normal, material, id) = match kind {
            PrimKind::Triangle => {
                let (normal, id) = (self.triangles.normal(i), self.triangles.id[i]);
                if let Some(corners) = self.corner_normals.get(id) {
                    let (v0, e1, e2) = self.triangles.get(i);
                    let (u, v) = barycentrics(v0, e1, e2, ray);
                    shading = Some(interpolate(corners, u, v, normal));
                }
                (normal, self.triangles.material[i], id)
            }
            PrimKind::Sphere => (
                // A ray through the very centre of a tiny sphere: face the ray (as the
                // reference tracer does).
                (ray.at(t) - self.spheres.center(i)).normalize_or(-ray.dir.normalize()),
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
                    n.normalize_or(-ray.dir.normalize()),
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
            shading: shading.unwrap_or(normal),
            material,
            prim: id,
        }
    }

    /// Builds the BVH over the bounded primitives (all but planes), reordering the SoA arrays
    /// so that every leaf is one contiguous range of one of them. Queries use it from then on.
    pub fn build_bvh(&mut self) {
        let bounded = self.plane_base();
        let mut bounds = Vec::with_capacity(bounded);
        let mut tags = Vec::with_capacity(bounded);
        for g in 0..bounded as u32 {
            let (kind, _) = self.locate(g);
            bounds.push(self.bounds(g));
            tags.push(kind as u8);
        }
        let (mut bvh, order) = bvh::build::build(&bounds, &tags);
        // New geometry index of each position of `order`, and each kind's new order.
        let bases = [0, self.sphere_base(), self.transformed_base()];
        let mut next = bases;
        let mut orders: [Vec<u32>; 3] = Default::default();
        let mut new_index = Vec::with_capacity(order.len());
        for &g in &order {
            let (kind, i) = self.locate(g);
            let k = kind as usize;
            new_index.push(next[k] as u32);
            next[k] += 1;
            orders[k].push(i as u32);
        }
        for node in bvh.nodes.iter_mut().filter(|n| n.is_leaf()) {
            node.first = new_index[node.first as usize];
        }
        self.triangles.permute(&orders[0]);
        self.spheres.permute(&orders[1]);
        self.transformed.permute(&orders[2]);
        self.bvh = bvh;
    }

    /// The bounds of primitive `g` (planes have none: infinite box).
    pub fn bounds(&self, g: u32) -> Aabb {
        let (kind, i) = self.locate(g);
        match kind {
            PrimKind::Triangle => {
                let (v0, e1, e2) = self.triangles.get(i);
                let mut b = Aabb::EMPTY;
                for p in [v0, v0 + e1, v0 + e2] {
                    b.grow(p);
                }
                b
            }
            PrimKind::Sphere => {
                let (c, r) = (self.spheres.center(i), self.spheres.radius[i]);
                Aabb {
                    min: c - Vec3::splat(r),
                    max: c + Vec3::splat(r),
                }
            }
            PrimKind::TransformedSphere => {
                // The unit sphere under `world`: centre = translation, half extent along each
                // axis = length of that row of the linear part.
                let w = &self.transformed.world[i];
                let c = Vec3::new(w[3], w[7], w[11]);
                let h = Vec3::new(
                    Vec3::new(w[0], w[1], w[2]).length(),
                    Vec3::new(w[4], w[5], w[6]).length(),
                    Vec3::new(w[8], w[9], w[10]).length(),
                );
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            }
            PrimKind::Plane => Aabb {
                min: Vec3::NEG_INFINITY,
                max: Vec3::INFINITY,
            },
        }
    }

    /// Checks the BVH against the primitives it was built over (see [`Bvh::validate`]).
    pub fn validate_bvh(&self) -> Result<(), String> {
        let (bounds, tags): (Vec<Aabb>, Vec<u8>) = self
            .bounded_range()
            .map(|g| (self.bounds(g), self.locate(g).0 as u8))
            .unzip();
        self.bvh.validate(&bounds, &tags)
    }

    /// The BVH (empty before [`Geometry::build_bvh`]).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    fn planes_range(&self) -> Range<u32> {
        self.plane_base() as u32..self.len() as u32
    }

    fn bounded_range(&self) -> Range<u32> {
        0..self.plane_base() as u32
    }

    /// The closest hit of one ray in `(tmin, tmax)`: `(t, geometry index)`.
    pub fn closest_hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, u32)> {
        let mut best = None;
        let mut limit = tmax;
        let mut leaf = |range: Range<u32>, limit: &mut f32| {
            if let Some(hit) = self.closest_in(range, ray, tmin, *limit) {
                *limit = hit.0;
                best = Some(hit);
            }
        };
        if self.bvh.is_empty() {
            leaf(self.bounded_range(), &mut limit);
        } else {
            self.bvh.closest(ray, tmin, &mut limit, &mut leaf);
        }
        leaf(self.planes_range(), &mut limit);
        best
    }

    /// Updates `hit` with the closest hits of the packet's active lanes; inactive lanes of `hit`
    /// are left untouched.
    pub fn closest_hit_packet(&self, rays: &RayPacket, hit: &mut HitPacket) {
        let HitPacket { t, prim } = hit;
        if self.bvh.is_empty() {
            self.closest_in_packet(self.bounded_range(), rays, t, prim);
        } else {
            self.bvh.closest_packet(rays, t, |range, rays, t| {
                self.closest_in_packet(range, rays, t, prim)
            });
        }
        self.closest_in_packet(self.planes_range(), rays, t, prim);
    }

    /// [`Geometry::closest_hit_packet`] that also adds to `cost` each lane's traversal work:
    /// BVH nodes it entered plus primitives tested for it (planes included). The heatmap's
    /// counter; the same traversal, in the same order, as the render's.
    pub fn closest_hit_packet_counted(
        &self,
        rays: &RayPacket,
        hit: &mut HitPacket,
        cost: &mut [u32; LANES],
    ) {
        let (mut nodes, mut prims) = (LaneCounter::default(), LaneCounter::default());
        let HitPacket { t, prim } = hit;
        if self.bvh.is_empty() {
            prims.add(rays.active, self.plane_base() as u32);
            self.closest_in_packet(self.bounded_range(), rays, t, prim);
        } else {
            let leaf = |range: Range<u32>, rays: &RayPacket, t: &mut F32x8| {
                prims.add(rays.active, range.len() as u32);
                self.closest_in_packet(range, rays, t, prim);
            };
            self.bvh.closest_packet_probed(rays, t, leaf, &mut nodes);
        }
        prims.add(rays.active, self.planes.len() as u32);
        self.closest_in_packet(self.planes_range(), rays, t, prim);
        for (lane, c) in cost.iter_mut().enumerate() {
            *c += nodes.0[lane] + prims.0[lane];
        }
    }

    /// True if anything lies on the ray in `(tmin, tmax)`.
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        let leaf = |range: Range<u32>| self.occluded_in(range, ray, tmin, tmax);
        let bounded = if self.bvh.is_empty() {
            leaf(self.bounded_range())
        } else {
            self.bvh.occluded(ray, tmin, tmax, leaf)
        };
        bounded || leaf(self.planes_range())
    }

    /// The active lanes with something in `(tmin, tmax)`; stops as soon as every active lane is
    /// occluded.
    pub fn occluded_packet(&self, rays: &RayPacket, tmax: F32x8) -> Mask {
        let leaf = |range: Range<u32>, rays: &RayPacket| self.occluded_in_packet(range, rays, tmax);
        let mut occluded = if self.bvh.is_empty() {
            leaf(self.bounded_range(), rays)
        } else {
            self.bvh.occluded_packet(rays, tmax, leaf)
        };
        let rest = !occluded & rays.active;
        if any(rest) && !self.planes.is_empty() {
            occluded |= leaf(
                self.planes_range(),
                &RayPacket {
                    active: rest,
                    ..*rays
                },
            );
        }
        occluded
    }

    /// Calls `f(kind, index range in that kind's array, geometry index of the first)` for each
    /// kind present in the geometry-index `range`.
    #[inline(always)]
    fn for_kinds(&self, range: Range<u32>, mut f: impl FnMut(PrimKind, Range<usize>, usize)) {
        let bases = [
            (PrimKind::Triangle, 0, self.sphere_base()),
            (
                PrimKind::Sphere,
                self.sphere_base(),
                self.transformed_base(),
            ),
            (
                PrimKind::TransformedSphere,
                self.transformed_base(),
                self.plane_base(),
            ),
            (PrimKind::Plane, self.plane_base(), self.len()),
        ];
        let (lo, hi) = (range.start as usize, range.end as usize);
        for (kind, start, end) in bases {
            let (a, b) = (lo.max(start), hi.min(end));
            if a < b {
                f(kind, a - start..b - start, start);
            }
        }
    }

    /// Brute-force closest hit over a range of geometry indices.
    fn closest_in(&self, range: Range<u32>, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, u32)> {
        let mut best = None;
        let mut limit = tmax;
        self.for_kinds(range, |kind, idx, base| {
            for i in idx {
                let t = match kind {
                    PrimKind::Triangle => {
                        let (v0, e1, e2) = self.triangles.get(i);
                        intersect_triangle(v0, e1, e2, ray, tmin, limit)
                    }
                    PrimKind::Sphere => {
                        let (c, r2) = (self.spheres.center(i), self.spheres.radius2[i]);
                        intersect_sphere(c, r2, ray, tmin, limit)
                    }
                    PrimKind::TransformedSphere => {
                        intersect_transformed_sphere(&self.transformed.inverse(i), ray, tmin, limit)
                    }
                    PrimKind::Plane => {
                        let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
                        intersect_plane(n, d, ray, tmin, limit)
                    }
                };
                if let Some(t) = t {
                    limit = t;
                    best = Some((t, (base + i) as u32));
                }
            }
        });
        best
    }

    /// Brute-force closest hits of a packet over a range of geometry indices.
    #[inline(always)]
    fn closest_in_packet(
        &self,
        range: Range<u32>,
        rays: &RayPacket,
        t: &mut F32x8,
        prim: &mut I32x8,
    ) {
        self.for_kinds(range, |kind, idx, base| {
            for i in idx {
                let (m, ti) = match kind {
                    PrimKind::Triangle => {
                        let (v0, e1, e2) = self.triangles.get(i);
                        intersect_triangle_packet(v0, e1, e2, rays, *t)
                    }
                    PrimKind::Sphere => {
                        let (c, r2) = (self.spheres.center(i), self.spheres.radius2[i]);
                        intersect_sphere_packet(c, r2, rays, *t)
                    }
                    PrimKind::TransformedSphere => {
                        intersect_transformed_sphere_packet(&self.transformed.inverse(i), rays, *t)
                    }
                    PrimKind::Plane => {
                        let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
                        intersect_plane_packet(n, d, rays, *t)
                    }
                };
                *t = select(m, ti, *t);
                *prim = select_i32(m, I32x8::splat((base + i) as i32), *prim);
            }
        });
    }

    /// Brute-force any hit over a range of geometry indices.
    fn occluded_in(&self, range: Range<u32>, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        let mut hit = false;
        self.for_kinds(range, |kind, mut idx, _| {
            hit = hit
                || match kind {
                    PrimKind::Triangle => idx.any(|i| {
                        let (v0, e1, e2) = self.triangles.get(i);
                        intersect_triangle(v0, e1, e2, ray, tmin, tmax).is_some()
                    }),
                    PrimKind::Sphere => idx.any(|i| {
                        let (c, r2) = (self.spheres.center(i), self.spheres.radius2[i]);
                        intersect_sphere(c, r2, ray, tmin, tmax).is_some()
                    }),
                    PrimKind::TransformedSphere => idx.any(|i| {
                        intersect_transformed_sphere(&self.transformed.inverse(i), ray, tmin, tmax)
                            .is_some()
                    }),
                    PrimKind::Plane => idx.any(|i| {
                        let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
                        intersect_plane(n, d, ray, tmin, tmax).is_some()
                    }),
                };
        });
        hit
    }

    /// Brute-force any hit of a packet over a range of geometry indices; stops once every
    /// active lane is blocked.
    #[inline(always)]
    fn occluded_in_packet(&self, range: Range<u32>, rays: &RayPacket, tmax: F32x8) -> Mask {
        let mut occluded = mask_none();
        self.for_kinds(range, |kind, idx, _| {
            for i in idx {
                if all(occluded | !rays.active) {
                    return;
                }
                occluded |= match kind {
                    PrimKind::Triangle => {
                        let (v0, e1, e2) = self.triangles.get(i);
                        intersect_triangle_packet(v0, e1, e2, rays, tmax).0
                    }
                    PrimKind::Sphere => {
                        let (c, r2) = (self.spheres.center(i), self.spheres.radius2[i]);
                        intersect_sphere_packet(c, r2, rays, tmax).0
                    }
                    PrimKind::TransformedSphere => {
                        intersect_transformed_sphere_packet(
                            &self.transformed.inverse(i),
                            rays,
                            tmax,
                        )
                        .0
                    }
                    PrimKind::Plane => {
                        let (n, d) = (self.planes.normal(i), self.planes.offset[i]);
                        intersect_plane_packet(n, d, rays, tmax).0
                    }
                };
            }
        });
        occluded
    }
}

/// Counts per lane, for the heatmap: the BVH's probe (one per node a lane enters) and the
/// primitive tests of the leaves a lane reaches.
#[derive(Default)]
struct LaneCounter([u32; LANES]);

impl LaneCounter {
    fn add(&mut self, lanes: Mask, n: u32) {
        let bits = bitmask(lanes);
        for (lane, c) in self.0.iter_mut().enumerate() {
            if bits >> lane & 1 == 1 {
                *c += n;
            }
        }
    }
}

impl TraversalProbe for LaneCounter {
    fn node(&mut self, lanes: Mask) {
        self.add(lanes, 1);
    }
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
            normals,
            material,
            first_id,
        } => {
            for (k, v) in triangles.iter().enumerate() {
                let id = first_id + k as u32;
                push_triangle(g, v, m, identity, &normal, *material, id);
                if let Some(corners) = normals.get(k) {
                    let world = if identity {
                        *corners
                    } else {
                        corners.map(|c| *n * c)
                    };
                    g.corner_normals.push(id, world);
                }
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
