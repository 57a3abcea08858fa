//! Ray-primitive intersection kernels. Each file holds one primitive's scalar kernel and, directly
//! below it, its 8-wide packet twin of the same name with a `_packet` suffix, so the two can be
//! compared by eye. Every kernel reports the nearest `t` in the open interval `(tmin, tmax)`:
//! scalar kernels as `Option<f32>`, packet kernels as a lane mask (always within the packet's
//! active lanes) and the lanes' `t`. Callers pass their current closest hit as `tmax`.

pub mod plane;
pub mod sphere;
pub mod triangle;

pub use plane::{intersect_plane, intersect_plane_packet};
pub use sphere::{
    intersect_sphere, intersect_sphere_packet, intersect_transformed_sphere,
    intersect_transformed_sphere_packet,
};
pub use triangle::{intersect_triangle, intersect_triangle_packet};
