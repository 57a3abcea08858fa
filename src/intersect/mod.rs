//! Ray-primitive intersection kernels. Each file holds one primitive's scalar kernel and, directly
//! below it, its 8-wide packet twin of the same name with a `_packet` suffix, so the two can be
//! compared by eye. Every kernel reports the nearest `t` in the open interval `(tmin, tmax)`:
//! scalar kernels as `Option<f32>`, packet kernels as a lane mask (always within the packet's
//! active lanes) and the lanes' `t`. Callers pass their current closest hit as `tmax`. [`Hit`] is
//! what a closest-hit query reports to the tracers, the ray tree and shading.

pub mod plane;
pub mod sphere;
pub mod triangle;

pub use plane::{intersect_plane, intersect_plane_packet};
pub use sphere::{
    intersect_sphere, intersect_sphere_packet, intersect_transformed_sphere,
    intersect_transformed_sphere_packet,
};
pub use triangle::{intersect_triangle, intersect_triangle_packet};

use crate::math::Vec3;

/// A closest hit as the intersection code reports it, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Unit geometric normal, as the primitive defines it (not flipped towards the ray): it
    /// decides the side a ray hits.
    pub normal: Vec3,
    /// Unit shading normal, on the same side as `normal`'s definition: the mesh's corner
    /// normals interpolated at the hit for a smooth mesh, else `normal` itself.
    pub shading: Vec3,
    pub material: u32,
    /// The primitive's id (see [`crate::scene::Object`]).
    pub prim: u32,
}
