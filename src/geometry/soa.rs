//! Primitives stored structure of arrays, ready for intersection: spheres as centre and radius
//! squared, triangles as a vertex and two edges plus their unit normal, planes as normal and
//! offset, and spheres under non-similarity transforms as the inverse affine that maps them to
//! the unit sphere (with its transpose for normals). Every kind also keeps, per primitive, its
//! material index and its scene id (see [`crate::scene::Object`]).

use rayon::prelude::*;

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

    /// Appends `n` triangles, triangle `k` being `f(k)`: `(vertices, unit normal, material,
    /// id)`, as [`TriangleSoa::push`] would one by one. Big batches (a mesh of a million
    /// triangles) are computed and written in parallel, straight into the columns.
    pub fn extend_with(
        &mut self,
        n: usize,
        f: impl Fn(usize) -> ([Vec3; 3], Vec3, u32, u32) + Sync,
    ) {
        const PARALLEL: usize = 1 << 14;
        if n < PARALLEL {
            for k in 0..n {
                let (v, normal, material, id) = f(k);
                self.push(v, normal, material, id);
            }
            return;
        }
        let floats = [
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
        ];
        let len = self.material.len();
        let mut float_chunks: Vec<_> = floats
            .into_iter()
            .map(|c| {
                c.reserve(n);
                c.spare_capacity_mut()[..n].chunks_mut(PARALLEL)
            })
            .collect();
        self.material.reserve(n);
        self.id.reserve(n);
        let mut material_chunks = self.material.spare_capacity_mut()[..n].chunks_mut(PARALLEL);
        let mut id_chunks = self.id.spare_capacity_mut()[..n].chunks_mut(PARALLEL);
        // one job per chunk of PARALLEL triangles: its slice of every column
        let jobs: Vec<_> = (0..n.div_ceil(PARALLEL))
            .map(|j| {
                let floats: Vec<_> = float_chunks.iter_mut().map(|c| c.next().unwrap()).collect();
                let (m, i) = (material_chunks.next().unwrap(), id_chunks.next().unwrap());
                (j * PARALLEL, floats, m, i)
            })
            .collect();
        jobs.into_par_iter()
            .for_each(|(first, mut floats, materials, ids)| {
                for k in 0..materials.len() {
                    let (v, normal, material, id) = f(first + k);
                    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
                    let values = [
                        v[0].x, v[0].y, v[0].z, e1.x, e1.y, e1.z, e2.x, e2.y, e2.z, normal.x,
                        normal.y, normal.z,
                    ];
                    for (col, value) in floats.iter_mut().zip(values) {
                        col[k].write(value);
                    }
                    materials[k].write(material);
                    ids[k].write(id);
                }
            });
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
            // SAFETY: the parallel pass above wrote the first `n` spare slots of every column
            // (its chunks cover 0..n exactly once).
            unsafe { col.set_len(len + n) };
        }
        // SAFETY: as above, for the two integer columns.
        unsafe {
            self.material.set_len(len + n);
            self.id.set_len(len + n);
        }
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extend_with_equals_pushes_in_order_for_small_and_big_batches() {
        for n in [0, 5, 1 << 14, (1 << 14) * 3 + 17] {
            let tri = |k: usize| {
                let a = Vec3::new(k as f32, (k % 7) as f32, 0.5);
                let v = [a, a + Vec3::X, a + Vec3::new(0.25, 1.0, (k % 3) as f32)];
                (v, Vec3::new(0.0, 0.6, 0.8), (k % 5) as u32, 1000 + k as u32)
            };
            let mut pushed = TriangleSoa::default();
            pushed.push([Vec3::ZERO, Vec3::X, Vec3::Y], Vec3::Z, 9, 9);
            let mut extended = pushed.clone();
            for k in 0..n {
                let (v, normal, m, id) = tri(k);
                pushed.push(v, normal, m, id);
            }
            extended.extend_with(n, tri);
            assert_eq!(extended, pushed, "{n} triangles");
        }
    }
}
