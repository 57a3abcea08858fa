//! Ray-primitive intersection kernels. Each file holds one primitive's scalar kernel and, directly
//! below it, its 8-wide packet twin of the same name with a `_packet` suffix, so the two can be
//! compared by eye. Every kernel reports the nearest `t` in the open interval `(tmin, tmax)`;
//! callers pass their current closest hit as `tmax`.

pub mod plane;
pub mod sphere;
pub mod triangle;

pub use plane::intersect_plane;
pub use sphere::intersect_sphere;
pub use triangle::intersect_triangle;
