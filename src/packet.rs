//! Eight rays at once, structure of arrays: [`RayPacket`] (origins, directions, per-lane `tmin`
//! and an active mask) and [`HitPacket`] (per-lane closest `t` so far and the id of the
//! primitive hit). Queues load packets of 8 rays, kernels read packets and update hit packets
//! in their active lanes only, and the shading stage reads hits back lane by lane.

use crate::math::Ray;
use crate::simd::{F32x8, I32x8, LANES, Mask, Vec3x8, lanes, lanes_i32};

/// The primitive id of a lane that hit nothing.
pub const NO_HIT: i32 = -1;

/// Eight rays. Lanes whose `active` bit is clear are ignored by every kernel.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket {
    pub origin: Vec3x8,
    pub dir: Vec3x8,
    /// Hits must lie beyond this distance.
    pub tmin: F32x8,
    pub active: Mask,
}

impl RayPacket {
    /// A packet from up to 8 rays sharing `tmin`; missing lanes are inactive.
    pub fn from_rays(rays: &[Ray], tmin: f32) -> RayPacket {
        let mut p = RayPacket {
            origin: Vec3x8::zero(),
            dir: Vec3x8::zero(),
            tmin: F32x8::splat(tmin),
            active: crate::simd::mask_first(rays.len()),
        };
        for (i, r) in rays.iter().take(LANES).enumerate() {
            p.origin.set_lane(i, r.origin);
            p.dir.set_lane(i, r.dir);
        }
        p
    }

    /// The ray in lane `i`.
    pub fn ray(&self, i: usize) -> Ray {
        Ray::new(self.origin.lane(i), self.dir.lane(i))
    }
}

/// The closest hits of a packet so far: `t` starts at each ray's `tmax`, `prim` at [`NO_HIT`].
#[derive(Clone, Copy, Debug)]
pub struct HitPacket {
    pub t: F32x8,
    pub prim: I32x8,
}

impl HitPacket {
    /// No hit yet, accepting hits nearer than `tmax` in every lane.
    pub fn new(tmax: f32) -> HitPacket {
        HitPacket {
            t: F32x8::splat(tmax),
            prim: I32x8::splat(NO_HIT),
        }
    }

    /// No hit yet, accepting hits nearer than the per-lane `tmax`.
    pub fn with_tmax(tmax: F32x8) -> HitPacket {
        HitPacket {
            t: tmax,
            prim: I32x8::splat(NO_HIT),
        }
    }

    /// Lane `i`: `(t, prim)` if it hit something.
    pub fn lane(&self, i: usize) -> Option<(f32, i32)> {
        let prim = lanes_i32(self.prim)[i];
        (prim != NO_HIT).then(|| (lanes(self.t)[i], prim))
    }
}
