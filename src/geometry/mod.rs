//! The packet tracer's view of a scene: every primitive flattened to world space and stored
//! structure of arrays ([`soa`]), an 8-wide BVH over the bounded ones whose leaves are blocks of
//! primitives stored ready for intersection ([`blocks`]), and closest-hit and any-hit queries
//! for single rays, 8-ray packets and streams of packets (`query.rs`). Flattening bakes
//! transforms: triangles and planes to world space, spheres under similarity transforms to
//! world-space spheres, and other spheres kept as transformed spheres (inverse affine to the
//! unit sphere, normals by the inverse transpose).
//!
//! ```text
//! Scene.root (tree) --flatten--> Geometry { triangles, spheres, transformed spheres, planes }
//!                                    | build_bvh: Bvh8 + leaf Blocks (Triangle4, Sphere4)
//!                                    | closest_hit / occluded                 (single rays)
//!                                    | closest_hit_packet / occluded_packet   (8 rays)
//!                                    | closest_hit_stream / occluded_stream   (up to 8 packets)
//! ```
//!
//! A hit names its primitive by a geometry index: triangles first, then spheres, transformed
//! spheres and planes, each kind in the order flattening met it. The index is stable: building
//! the BVH copies primitives into leaf blocks and reorders nothing, so per-primitive data kept
//! beside the arrays (normals, materials, ids; or per-vertex normals of a caller) is looked up
//! by it after the hit. [`Geometry::surface`] turns it into a normal (a smooth mesh's corner
//! normals, kept in [`normals`], interpolated by [`crate::math::barycentrics`] of the one hit),
//! a material and the scene id. Planes have no bounds and are tested apart from the BVH.

pub mod blocks;
pub mod normals;
mod query;
pub mod soa;

use crate::bvh::build::BuildSettings;
use crate::bvh::{self, Aabb, Bvh8, Leaf};
use crate::intersect::Hit;
use crate::intersect::sphere::{affine_point, affine_vector};
use crate::math::{Mat3, Mat4, Ray, Vec3, barycentrics};
use crate::scene::normals::interpolate;
use crate::scene::{Object, Scene};
use blocks::{BLOCK, BlockSink, Blocks};
use normals::CornerNormals;
pub use query::{COHERENT_COS, LIST_PACKETS, ListBatch, Path, SMALL_TREE_NODES, coherent};
pub use soa::{PlaneSoa, SphereSoa, TransformedSphereSoa, TriangleSoa};

/// The most primitives a leaf holds in a tree with spheres (the builder's default, 12, is for
/// triangles). Sphere leaves are mostly tested a packet of rays at a time, where leaves of 12
/// cost more than the nodes they save: with leaves of 12, spheres64 primary rays fell from 143
/// to 112 Mrays/s, spheres4096 from 120 to 111 (PERF.md, sitting 21).
pub const SPHERE_MAX_LEAF: usize = 8;

/// The kinds of primitive, in geometry-index order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimKind {
    Triangle,
    Sphere,
    TransformedSphere,
    Plane,
}

impl PrimKind {
    /// The kind a BVH leaf tag names (tags are `kind as u8`).
    #[inline(always)]
    pub fn from_tag(tag: u8) -> PrimKind {
        match tag {
            0 => PrimKind::Triangle,
            1 => PrimKind::Sphere,
            2 => PrimKind::TransformedSphere,
            _ => PrimKind::Plane,
        }
    }
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
    bvh: Bvh8,
    /// The BVH's leaves.
    blocks: Blocks,
}

impl Geometry {
    /// Flattens the scene's object tree and builds the BVH.
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

    /// The geometry index of the first primitive of `kind`.
    #[inline(always)]
    pub fn base(&self, kind: PrimKind) -> usize {
        let t = self.triangles.len();
        match kind {
            PrimKind::Triangle => 0,
            PrimKind::Sphere => t,
            PrimKind::TransformedSphere => t + self.spheres.len(),
            PrimKind::Plane => t + self.spheres.len() + self.transformed.len(),
        }
    }

    /// The kind of the primitive with geometry index `prim` and its index in its array.
    pub fn locate(&self, prim: u32) -> (PrimKind, usize) {
        let p = prim as usize;
        let kind = if p < self.base(PrimKind::Sphere) {
            PrimKind::Triangle
        } else if p < self.base(PrimKind::TransformedSphere) {
            PrimKind::Sphere
        } else if p < self.base(PrimKind::Plane) {
            PrimKind::TransformedSphere
        } else {
            PrimKind::Plane
        };
        (kind, p - self.base(kind))
    }

    /// The surface hit by `ray` at `t` on primitive `prim`: unit world normal, material, scene id.
    ///
    /// Always inlined into the shading loops: called, it returned its `Hit` through memory and
    /// the caller's first loads of it waited on the stores (a store-forwarding stall per hit;
    /// the showcase's render 12–13% slower at 1 thread, PERF.md sitting 37).
    #[inline(always)]
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

    /// Builds the BVH over the bounded primitives (all but planes) with the default settings,
    /// but leaves of at most [`SPHERE_MAX_LEAF`] primitives in a tree that holds spheres.
    /// Queries use it from then on.
    pub fn build_bvh(&mut self) {
        let mut settings = BuildSettings::default();
        if !(self.spheres.is_empty() && self.transformed.is_empty()) {
            settings.max_leaf = settings.max_leaf.min(SPHERE_MAX_LEAF);
        }
        self.build_bvh_with(&settings);
    }

    /// Builds the BVH with the given builder settings (see [`BuildSettings`]). Leaves are
    /// blocks of [`BLOCK`] primitives, so the SAH prices leaves in blocks of that width.
    pub fn build_bvh_with(&mut self, settings: &BuildSettings) {
        let bounded = self.base(PrimKind::Plane);
        let settings = BuildSettings {
            block: BLOCK,
            ..*settings
        };
        let g = &*self;
        let sink = BlockSink::new(g);
        let bvh = bvh::build::build(
            bounded,
            |i| (g.bounds(i as u32), g.locate(i as u32).0 as u8),
            &settings,
            &sink,
        );
        let blocks = sink.finish();
        self.bvh = bvh;
        self.blocks = blocks;
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

    /// The geometry indices a leaf holds.
    pub fn leaf_prims(&self, leaf: Leaf) -> Vec<u32> {
        let (first, count) = (leaf.first as usize, leaf.count as usize);
        let kind = PrimKind::from_tag(leaf.tag);
        let lanes = |prims: &mut dyn Iterator<Item = u32>| -> Vec<u32> {
            prims.filter(|&p| p != u32::MAX).collect()
        };
        match kind {
            PrimKind::Triangle => lanes(
                &mut self.blocks.triangles
                    [first..(first + count.div_ceil(BLOCK)).min(self.blocks.triangles.len())]
                    .iter()
                    .flat_map(|b| b.prim),
            ),
            PrimKind::Sphere => lanes(
                &mut self.blocks.spheres
                    [first..(first + count.div_ceil(BLOCK)).min(self.blocks.spheres.len())]
                    .iter()
                    .flat_map(|b| b.prim),
            ),
            PrimKind::TransformedSphere => {
                let base = self.base(kind) as u32;
                self.blocks.transformed[first..(first + count).min(self.blocks.transformed.len())]
                    .iter()
                    .map(|&i| base + i)
                    .collect()
            }
            PrimKind::Plane => Vec::new(),
        }
    }

    /// Checks the BVH against the primitives it was built over (see [`Bvh8::validate`]) and
    /// the leaf blocks against the primitives they copy: each lane holds its primitive's data,
    /// unused lanes only at a leaf's end.
    pub fn validate_bvh(&self) -> Result<(), String> {
        let bounded = 0..self.base(PrimKind::Plane) as u32;
        let (bounds, tags): (Vec<Aabb>, Vec<u8>) = bounded
            .map(|g| (self.bounds(g), self.locate(g).0 as u8))
            .unzip();
        self.bvh
            .validate(&bounds, &tags, |leaf| self.leaf_prims(leaf))?;
        for (k, b) in self.blocks.triangles.iter().enumerate() {
            for lane in 0..BLOCK {
                let p = b.prim[lane];
                if p == u32::MAX {
                    if b.prim[lane..].iter().any(|&q| q != u32::MAX) {
                        return Err(format!("triangle block {k}: a gap before lane {lane}"));
                    }
                    continue;
                }
                let (kind, i) = self.locate(p);
                let (v0, e1, e2) = self.triangles.get(i);
                if kind != PrimKind::Triangle
                    || b.lane(lane) != (v0, e1, e2)
                    || b.normal(lane) != e1.cross(e2)
                {
                    return Err(format!(
                        "triangle block {k} lane {lane} is not primitive {p}"
                    ));
                }
            }
        }
        for (k, b) in self.blocks.spheres.iter().enumerate() {
            for lane in 0..BLOCK {
                let p = b.prim[lane];
                if p == u32::MAX {
                    continue;
                }
                let (kind, i) = self.locate(p);
                let want = (self.spheres.center(i), self.spheres.radius2[i]);
                if kind != PrimKind::Sphere || b.lane(lane) != want {
                    return Err(format!("sphere block {k} lane {lane} is not primitive {p}"));
                }
            }
        }
        Ok(())
    }

    /// The BVH (empty before [`Geometry::build_bvh`]).
    pub fn bvh(&self) -> &Bvh8 {
        &self.bvh
    }

    /// The BVH's leaf blocks.
    pub fn blocks(&self) -> &Blocks {
        &self.blocks
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
            let (world, normal) = world_triangle(v, m, n, identity);
            g.triangles.push(world, normal, *material, *id);
        }
        Object::Mesh {
            triangles,
            normals,
            material,
            first_id,
        } => {
            // big meshes transform in parallel (no serial pass over a million triangles)
            g.triangles.extend_with(triangles.len(), |k| {
                let (world, normal) = world_triangle(&triangles[k], m, n, identity);
                (world, normal, *material, first_id + k as u32)
            });
            for (k, corners) in normals.iter().enumerate() {
                let world = if identity {
                    *corners
                } else {
                    corners.map(|c| *n * c)
                };
                g.corner_normals.push(first_id + k as u32, world);
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

/// A triangle in world space and its unit normal (by the normal matrix `n`).
#[inline]
fn world_triangle(v: &[Vec3; 3], m: &Mat4, n: &Mat3, identity: bool) -> ([Vec3; 3], Vec3) {
    let n_obj = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    if identity {
        (*v, n_obj)
    } else {
        (v.map(|p| m.transform_point3(p)), (*n * n_obj).normalize())
    }
}
