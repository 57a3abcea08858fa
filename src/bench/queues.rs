//! The benchmark's ray queues: a [`RayQueue`] of single rays in contract order (made by
//! `rays.rs`) and the same rays loaded as 8-wide packets, [`PacketQueue`], which the packet
//! kernels of `kernels.rs` trace. Each ray carries its own `tmax` (shadow rays stop short of
//! the light).

use crate::math::Ray;
use crate::packet::{HitPacket, RayPacket};
use crate::simd::{F32x8, LANES, from_lanes};

/// One queued ray; it accepts hits with `0 < t < tmax`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BenchRay {
    pub ray: Ray,
    pub tmax: f32,
}

/// Rays of one kind in queue order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayQueue {
    pub items: Vec<BenchRay>,
}

impl RayQueue {
    /// An empty queue with room for `n` rays.
    pub fn with_capacity(n: usize) -> RayQueue {
        RayQueue {
            items: Vec::with_capacity(n),
        }
    }

    /// The number of rays.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// True when the queue holds no ray.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Appends a ray accepting hits in `(0, tmax)`.
    pub fn push(&mut self, ray: Ray, tmax: f32) {
        self.items.push(BenchRay { ray, tmax });
    }

    /// The queue as packets of 8 consecutive rays; the last packet's missing lanes are inactive.
    pub fn packets(&self) -> PacketQueue {
        let packets = self
            .items
            .chunks(LANES)
            .map(|chunk| {
                let rays: Vec<Ray> = chunk.iter().map(|r| r.ray).collect();
                BenchPacket {
                    rays: RayPacket::from_rays(&rays, 0.0),
                    tmax: from_lanes(std::array::from_fn(|i| {
                        chunk.get(i).map_or(0.0, |r| r.tmax)
                    })),
                }
            })
            .collect();
        PacketQueue {
            packets,
            len: self.len(),
        }
    }
}

/// Eight queued rays and their per-lane `tmax`.
#[derive(Clone, Copy, Debug)]
pub struct BenchPacket {
    pub rays: RayPacket,
    pub tmax: F32x8,
}

/// A [`RayQueue`] loaded as packets.
#[derive(Clone, Debug)]
pub struct PacketQueue {
    pub packets: Vec<BenchPacket>,
    /// The number of rays (active lanes).
    pub len: usize,
}

impl PacketQueue {
    /// Hit records accepting hits up to each ray's `tmax`, one per packet.
    pub fn fresh_hits(&self) -> Vec<HitPacket> {
        self.packets
            .iter()
            .map(|p| HitPacket::with_tmax(p.tmax))
            .collect()
    }

    /// Resets `hits` to [`PacketQueue::fresh_hits`] without allocating.
    pub fn reset_hits(&self, hits: &mut [HitPacket]) {
        for (h, p) in hits.iter_mut().zip(&self.packets) {
            *h = HitPacket::with_tmax(p.tmax);
        }
    }
}
