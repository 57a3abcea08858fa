//! The corner normals of smooth mesh triangles, kept beside the geometry rather than in it: the
//! intersection kernels never read them. After a traversal, [`Geometry::surface`] looks up the
//! hit triangle's normals by its scene id and interpolates them with the barycentrics of that
//! one hit.
//!
//! [`Geometry::surface`]: super::Geometry::surface

use crate::math::Vec3;

/// Corner normals in world space (not normalised: transformed by the inverse transpose, they
/// interpolate to the same direction as the object-space normals would), by scene id.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CornerNormals {
    /// Index into `normals` for each scene id, `NONE` for flat primitives; empty when no
    /// triangle is smooth.
    slot: Vec<u32>,
    normals: Vec<[Vec3; 3]>,
}

const NONE: u32 = u32::MAX;

impl CornerNormals {
    /// Records the corner normals of the triangle with scene id `id`.
    pub fn push(&mut self, id: u32, normals: [Vec3; 3]) {
        let id = id as usize;
        if self.slot.len() <= id {
            self.slot.resize(id + 1, NONE);
        }
        self.slot[id] = self.normals.len() as u32;
        self.normals.push(normals);
    }

    /// The corner normals of the triangle with scene id `id`, if it is smooth.
    #[inline]
    pub fn get(&self, id: u32) -> Option<&[Vec3; 3]> {
        match self.slot.get(id as usize) {
            Some(&k) if k != NONE => Some(&self.normals[k as usize]),
            _ => None,
        }
    }
}
