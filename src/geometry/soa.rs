//! Primitives stored structure of arrays, ready for intersection: spheres as centre and radius
//! squared, triangles as a vertex and two edges plus their unit normal, planes as normal and
//! offset, and spheres under non-similarity transforms as the inverse affine that maps them to
//! the unit sphere (with its transpose for normals). Every kind also keeps, per primitive, its
//! material index and its scene id (see [`crate::scene::Object`]).

use crate::math::Vec3;

/// Spheres: centre and radius squared.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphereSoa {
    pub cx: Vec<f32>,
    pub cy: Vec<f32>,
    pub cz: Vec<f32>,
    pub radius: Vec<f32>,
    pub radius2: Vec<f32>,
    pub material: Vec<u32>,
    pub id: Vec<u32>,
}

impl SphereSoa {
    /// Appends a sphere.
    pub fn push(&mut self, center: Vec3, radius: f32, material: u32, id: u32) {
        self.cx.push(center.x);
        self.cy.push(center.y);
        self.cz.push(center.z);
        self.radius.push(radius);
        self.radius2.push(radius * radius);
        self.material.push(material);
        self.id.push(id);
    }

    /// The number of spheres.
    pub fn len(&self) -> usize {
        self.cx.len()
    }

    /// True when there is no sphere.
    pub fn is_empty(&self) -> bool {
        self.cx.is_empty()
    }

    /// The centre of sphere `i`.
    #[inline(always)]
    pub fn center(&self, i: usize) -> Vec3 {
        Vec3::new(self.cx[i], self.cy[i], self.cz[i])
    }

    /// Reorders the spheres: new position `k` holds old sphere `order[k]`.
    pub fn permute(&mut self, order: &[u32]) {
        for col in [
            &mut self.cx,
            &mut self.cy,
            &mut self.cz,
            &mut self.radius,
            &mut self.radius2,
        ] {
            permute(col, order);
        }
        permute(&mut self.material, order);
        permute(&mut self.id, order);
    }
}

/// Triangles: `v0`, edges `e1 = v1 - v0`, `e2 = v2 - v0`, and the unit geometric normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleSoa {
    pub v0x: Vec<f32>,
    pub v0y: Vec<f32>,
    pub v0z: Vec<f32>,
    pub e1x: Vec<f32>,
    pub e1y: Vec<f32>,
    pub e1z: Vec<f32>,
    pub e2x: Vec<f32>,
    pub e2y: Vec<f32>,
    pub e2z: Vec<f32>,
    pub nx: Vec<f32>,
    pub ny: Vec<f32>,
    pub nz: Vec<f32>,
    pub material: Vec<u32>,
    pub id: Vec<u32>,
}

impl TriangleSoa {
    /// Appends a triangle with vertices `v` and unit normal `n`.
    pub fn push(&mut self, v: [Vec3; 3], n: Vec3, material: u32, id: u32) {
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        self.v0x.push(v[0].x);
        self.v0y.push(v[0].y);
        self.v0z.push(v[0].z);
        self.e1x.push(e1.x);
        self.e1y.push(e1.y);
        self.e1z.push(e1.z);
        self.e2x.push(e2.x);
        self.e2y.push(e2.y);
        self.e2z.push(e2.z);
        self.nx.push(n.x);
        self.ny.push(n.y);
        self.nz.push(n.z);
        self.material.push(material);
        self.id.push(id);
    }

    /// The number of triangles.
    pub fn len(&self) -> usize {
        self.v0x.len()
    }

    /// True when there is no triangle.
    pub fn is_empty(&self) -> bool {
        self.v0x.is_empty()
    }

    /// `(v0, e1, e2)` of triangle `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> (Vec3, Vec3, Vec3) {
        (
            Vec3::new(self.v0x[i], self.v0y[i], self.v0z[i]),
            Vec3::new(self.e1x[i], self.e1y[i], self.e1z[i]),
            Vec3::new(self.e2x[i], self.e2y[i], self.e2z[i]),
        )
    }

    /// The unit normal of triangle `i`.
    #[inline(always)]
    pub fn normal(&self, i: usize) -> Vec3 {
        Vec3::new(self.nx[i], self.ny[i], self.nz[i])
    }

    /// Reorders the triangles: new position `k` holds old triangle `order[k]`.
    pub fn permute(&mut self, order: &[u32]) {
        for col in [
            &mut self.v0x,
            &mut self.v0y,
            &mut self.v0z,
            &mut self.e1x,
            &mut self.e1y,
            &mut self.e1z,
            &mut self.e2x,
            &mut self.e2y,
            &mut self.e2z,
            &mut self.nx,
            &mut self.ny,
            &mut self.nz,
        ] {
            permute(col, order);
        }
        permute(&mut self.material, order);
        permute(&mut self.id, order);
    }
}

/// Infinite planes `n . p = offset` (unit `n`). They have no bounds, so they stay out of the BVH.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlaneSoa {
    pub nx: Vec<f32>,
    pub ny: Vec<f32>,
    pub nz: Vec<f32>,
    pub offset: Vec<f32>,
    pub material: Vec<u32>,
    pub id: Vec<u32>,
}

impl PlaneSoa {
    /// Appends a plane.
    pub fn push(&mut self, normal: Vec3, offset: f32, material: u32, id: u32) {
        self.nx.push(normal.x);
        self.ny.push(normal.y);
        self.nz.push(normal.z);
        self.offset.push(offset);
        self.material.push(material);
        self.id.push(id);
    }

    /// The number of planes.
    pub fn len(&self) -> usize {
        self.nx.len()
    }

    /// True when there is no plane.
    pub fn is_empty(&self) -> bool {
        self.nx.is_empty()
    }

    /// The unit normal of plane `i`.
    #[inline(always)]
    pub fn normal(&self, i: usize) -> Vec3 {
        Vec3::new(self.nx[i], self.ny[i], self.nz[i])
    }
}

/// Spheres under an affine transform that is not a similarity (non-uniform scale, shear): each
/// is the unit sphere at the origin of its own space; `inv` maps world to that space (3x4, row
/// major) and `world` is its inverse, for bounds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TransformedSphereSoa {
    /// `inv[k][i]`: element `k` of the 3x4 inverse affine of sphere `i`.
    pub inv: [Vec<f32>; 12],
    pub world: Vec<[f32; 12]>,
    pub material: Vec<u32>,
    pub id: Vec<u32>,
}

impl TransformedSphereSoa {
    /// Appends a sphere given its world-to-unit-sphere affine and its inverse.
    pub fn push(&mut self, inv: [f32; 12], world: [f32; 12], material: u32, id: u32) {
        for (col, v) in self.inv.iter_mut().zip(inv) {
            col.push(v);
        }
        self.world.push(world);
        self.material.push(material);
        self.id.push(id);
    }

    /// The number of spheres.
    pub fn len(&self) -> usize {
        self.material.len()
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.material.is_empty()
    }

    /// The inverse affine of sphere `i`.
    #[inline(always)]
    pub fn inverse(&self, i: usize) -> [f32; 12] {
        std::array::from_fn(|k| self.inv[k][i])
    }

    /// Reorders the spheres: new position `k` holds old sphere `order[k]`.
    pub fn permute(&mut self, order: &[u32]) {
        for col in self.inv.iter_mut() {
            permute(col, order);
        }
        permute(&mut self.world, order);
        permute(&mut self.material, order);
        permute(&mut self.id, order);
    }
}

fn permute<T: Copy>(col: &mut Vec<T>, order: &[u32]) {
    let old = std::mem::take(col);
    *col = order.iter().map(|&i| old[i as usize]).collect();
}
