//! The wavefront's queues: one typed queue per kind of work, structure of arrays, allocated in a
//! bumpalo arena that is reset once the bounce that reads it is over. [`RayQueue`] holds rays
//! to intersect (camera rays at bounce 0, mirror and refracted rays after), [`ShadowQueue`]
//! the shadow rays of one bounce, [`HitColumns`] the closest hits of a ray queue. Each queue has
//! a `push_*` per kind of ray that sets every field, and loads its rays as 8-lane packets
//! through the [`RayColumns`] they share.

use bumpalo::Bump;
use bumpalo::collections::Vec as BVec;

use crate::math::{Ray, Vec3};
use crate::packet::RayPacket;
use crate::raytree::SegmentKind;
use crate::simd::{F32x8, LANES, Vec3x8, lanes, load_partial, mask_first, prefetch_all};

/// Marks a ray that is not recorded in a ray tree.
pub const NO_NODE: u32 = u32::MAX;

/// Origins and directions of queued rays, one column per coordinate.
pub struct RayColumns<'b> {
    ox: BVec<'b, f32>,
    oy: BVec<'b, f32>,
    oz: BVec<'b, f32>,
    dx: BVec<'b, f32>,
    dy: BVec<'b, f32>,
    dz: BVec<'b, f32>,
}

impl<'b> RayColumns<'b> {
    /// Empty columns with room for `n` rays in `arena`.
    pub fn with_capacity_in(n: usize, arena: &'b Bump) -> RayColumns<'b> {
        RayColumns {
            ox: BVec::with_capacity_in(n, arena),
            oy: BVec::with_capacity_in(n, arena),
            oz: BVec::with_capacity_in(n, arena),
            dx: BVec::with_capacity_in(n, arena),
            dy: BVec::with_capacity_in(n, arena),
            dz: BVec::with_capacity_in(n, arena),
        }
    }

    #[inline(always)]
    fn push(&mut self, ray: &Ray) {
        self.ox.push(ray.origin.x);
        self.oy.push(ray.origin.y);
        self.oz.push(ray.origin.z);
        self.dx.push(ray.dir.x);
        self.dy.push(ray.dir.y);
        self.dz.push(ray.dir.z);
    }

    /// [`RayColumns::push`] of the first `n` lanes of `origin` and `dir`, in lane order.
    #[inline(always)]
    fn push_lanes(&mut self, origin: &Vec3x8, dir: &Vec3x8, n: usize) {
        for (column, v) in [
            (&mut self.ox, origin.x),
            (&mut self.oy, origin.y),
            (&mut self.oz, origin.z),
            (&mut self.dx, dir.x),
            (&mut self.dy, dir.y),
            (&mut self.dz, dir.z),
        ] {
            column.extend_from_slice_copy(&lanes(v)[..n]);
        }
    }

    /// The number of rays.
    pub fn len(&self) -> usize {
        self.ox.len()
    }

    /// True when there is no ray.
    pub fn is_empty(&self) -> bool {
        self.ox.is_empty()
    }

    /// Ray `i`.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        Ray::new(
            Vec3::new(self.ox[i], self.oy[i], self.oz[i]),
            Vec3::new(self.dx[i], self.dy[i], self.dz[i]),
        )
    }

    /// Starts fetching rays `first..first + count` (those that exist) into the cache: a hint
    /// for the group traced after the current one.
    #[inline]
    fn prefetch(&self, first: usize, count: usize) {
        let (start, end) = (first.min(self.len()), (first + count).min(self.len()));
        for c in [&self.ox, &self.oy, &self.oz, &self.dx, &self.dy, &self.dz] {
            prefetch_all(&c[start..end]);
        }
    }

    /// Rays `first..first + 8` (fewer at the end, the missing lanes inactive) as a packet
    /// starting at `tmin`.
    #[inline]
    pub fn packet(&self, first: usize, tmin: f32) -> RayPacket {
        let end = (first + LANES).min(self.len());
        let col = |c: &BVec<'b, f32>| load_partial(&c[first..end], 0.0);
        RayPacket {
            origin: Vec3x8 {
                x: col(&self.ox),
                y: col(&self.oy),
                z: col(&self.oz),
            },
            dir: Vec3x8 {
                x: col(&self.dx),
                y: col(&self.dy),
                z: col(&self.dz),
            },
            tmin: F32x8::splat(tmin),
            active: mask_first(end - first),
        }
    }
}

/// Rays to intersect in one bounce, and what each one carries.
pub struct RayQueue<'b> {
    rays: RayColumns<'b>,
    /// Pixel index inside the band being rendered.
    pub pixel: BVec<'b, u32>,
    /// RGB factor the colour seen along the ray is multiplied by before reaching the pixel.
    pub throughput: BVec<'b, Vec3>,
    /// Scalar weight for the cutoff (product of the colour magnitudes along the path).
    pub weight: BVec<'b, f32>,
    /// Eye, reflected or transmitted.
    pub kind: BVec<'b, SegmentKind>,
    /// The ray-tree segment of the ray that spawned this one, or [`NO_NODE`].
    pub parent: BVec<'b, u32>,
}

impl<'b> RayQueue<'b> {
    /// An empty queue with room for `n` rays in `arena` (filling past `n` still works, it
    /// just reallocates).
    pub fn with_capacity_in(n: usize, arena: &'b Bump) -> RayQueue<'b> {
        RayQueue {
            rays: RayColumns::with_capacity_in(n, arena),
            pixel: BVec::with_capacity_in(n, arena),
            throughput: BVec::with_capacity_in(n, arena),
            weight: BVec::with_capacity_in(n, arena),
            kind: BVec::with_capacity_in(n, arena),
            parent: BVec::with_capacity_in(n, arena),
        }
    }

    #[inline]
    fn push(
        &mut self,
        ray: &Ray,
        pixel: u32,
        throughput: Vec3,
        weight: f32,
        kind: SegmentKind,
        parent: u32,
    ) {
        self.rays.push(ray);
        self.pixel.push(pixel);
        self.throughput.push(throughput);
        self.weight.push(weight);
        self.kind.push(kind);
        self.parent.push(parent);
    }

    /// Queues the camera ray of `pixel`: full weight, no parent.
    pub fn push_camera(&mut self, ray: &Ray, pixel: u32) {
        self.push(ray, pixel, Vec3::ONE, 1.0, SegmentKind::Eye, NO_NODE);
    }

    /// Queues the camera rays of the first `pixels.len()` lanes (at most 8) of `origin` and
    /// `dir`, lane `i`'s pixel being `pixels[i]`: as [`RayQueue::push_camera`] lane by lane.
    pub fn push_camera_packet(&mut self, origin: &Vec3x8, dir: &Vec3x8, pixels: &[u32]) {
        let n = pixels.len();
        self.rays.push_lanes(origin, dir, n);
        self.pixel.extend_from_slice_copy(pixels);
        self.throughput
            .extend_from_slice_copy(&[Vec3::ONE; LANES][..n]);
        self.weight.extend_from_slice_copy(&[1.0; LANES][..n]);
        self.kind
            .extend_from_slice_copy(&[SegmentKind::Eye; LANES][..n]);
        self.parent.extend_from_slice_copy(&[NO_NODE; LANES][..n]);
    }

    /// Queues a mirror ray.
    pub fn push_reflected(
        &mut self,
        ray: &Ray,
        pixel: u32,
        throughput: Vec3,
        weight: f32,
        parent: u32,
    ) {
        self.push(
            ray,
            pixel,
            throughput,
            weight,
            SegmentKind::Reflected,
            parent,
        );
    }

    /// Queues a refracted ray.
    pub fn push_transmitted(
        &mut self,
        ray: &Ray,
        pixel: u32,
        throughput: Vec3,
        weight: f32,
        parent: u32,
    ) {
        self.push(
            ray,
            pixel,
            throughput,
            weight,
            SegmentKind::Transmitted,
            parent,
        );
    }

    /// The number of queued rays.
    pub fn len(&self) -> usize {
        self.rays.len()
    }

    /// True when no ray is queued.
    pub fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    /// Ray `i`.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        self.rays.ray(i)
    }

    /// Rays `first..first + 8` (fewer at the end, the missing lanes inactive) as a packet.
    #[inline]
    pub fn packet(&self, first: usize, tmin: f32) -> RayPacket {
        self.rays.packet(first, tmin)
    }

    /// Starts fetching rays `first..first + count` into the cache (a hint).
    #[inline]
    pub fn prefetch(&self, first: usize, count: usize) {
        self.rays.prefetch(first, count);
    }
}

/// Shadow rays of one bounce: each carries the colour it adds to its pixel if unblocked.
pub struct ShadowQueue<'b> {
    rays: RayColumns<'b>,
    /// Blocked by hits in `(EPSILON, max_t)`.
    pub max_t: BVec<'b, f32>,
    pub pixel: BVec<'b, u32>,
    /// What reaching the light adds to the pixel (throughput times the light's Phong term).
    pub contribution: BVec<'b, Vec3>,
    /// Which light of the scene the ray goes to.
    pub light: BVec<'b, u32>,
    /// The ray-tree segment of the ray being shaded, or [`NO_NODE`].
    pub parent: BVec<'b, u32>,
}

impl<'b> ShadowQueue<'b> {
    /// An empty queue with room for `n` shadow rays in `arena`.
    pub fn with_capacity_in(n: usize, arena: &'b Bump) -> ShadowQueue<'b> {
        ShadowQueue {
            rays: RayColumns::with_capacity_in(n, arena),
            max_t: BVec::with_capacity_in(n, arena),
            pixel: BVec::with_capacity_in(n, arena),
            contribution: BVec::with_capacity_in(n, arena),
            light: BVec::with_capacity_in(n, arena),
            parent: BVec::with_capacity_in(n, arena),
        }
    }

    /// Queues a shadow ray towards light number `light`.
    ///
    /// Always inlined, as `RayColumns::push` is: called, it took the ray by reference, so
    /// the shading loop copied each ray it built into memory for it, and the copy waited on
    /// the stores (PERF.md, sitting 37).
    #[inline(always)]
    pub fn push_shadow(
        &mut self,
        ray: &Ray,
        max_t: f32,
        pixel: u32,
        contribution: Vec3,
        light: u32,
        parent: u32,
    ) {
        self.rays.push(ray);
        self.max_t.push(max_t);
        self.pixel.push(pixel);
        self.contribution.push(contribution);
        self.light.push(light);
        self.parent.push(parent);
    }

    /// The number of queued shadow rays.
    pub fn len(&self) -> usize {
        self.rays.len()
    }

    /// True when no shadow ray is queued.
    pub fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    /// Shadow ray `i`.
    #[inline]
    pub fn ray(&self, i: usize) -> Ray {
        self.rays.ray(i)
    }

    /// Shadow rays `first..first + 8` as a packet starting at `tmin`, with their `max_t`.
    #[inline]
    pub fn packet(&self, first: usize, tmin: f32) -> (RayPacket, F32x8) {
        let end = (first + LANES).min(self.len());
        let max_t = load_partial(&self.max_t[first..end], 0.0);
        (self.rays.packet(first, tmin), max_t)
    }

    /// Starts fetching shadow rays `first..first + count` into the cache (a hint).
    #[inline]
    pub fn prefetch(&self, first: usize, count: usize) {
        self.rays.prefetch(first, count);
        let (start, end) = (first.min(self.len()), (first + count).min(self.len()));
        prefetch_all(&self.max_t[start..end]);
    }
}

/// The closest hit of every ray of a [`RayQueue`]: `t` and geometry index (negative: none).
pub struct HitColumns<'b> {
    pub t: BVec<'b, f32>,
    pub prim: BVec<'b, i32>,
}

impl<'b> HitColumns<'b> {
    /// Room for `n` hits in `arena`.
    pub fn with_capacity_in(n: usize, arena: &'b Bump) -> HitColumns<'b> {
        HitColumns {
            t: BVec::with_capacity_in(n, arena),
            prim: BVec::with_capacity_in(n, arena),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd::bitmask;

    #[test]
    fn packets_cover_every_ray_once_with_the_tail_masked() {
        let arena = Bump::new();
        for n in [0usize, 1, 7, 8, 9, 16, 23] {
            let mut q = RayQueue::with_capacity_in(n, &arena);
            for i in 0..n {
                q.push_camera(&Ray::new(Vec3::splat(i as f32), Vec3::X), i as u32);
            }
            let mut seen = Vec::new();
            for first in (0..q.len()).step_by(LANES) {
                let p = q.packet(first, 0.0);
                let live = bitmask(p.active).count_ones() as usize;
                assert_eq!(live, (n - first).min(LANES));
                for lane in 0..live {
                    seen.push(p.origin.lane(lane).x as usize);
                }
            }
            assert_eq!(seen, (0..n).collect::<Vec<_>>());
        }
    }

    #[test]
    fn a_packet_of_camera_rays_queues_as_its_lanes_one_by_one() {
        let arena = Bump::new();
        let lane = |i: usize| {
            let f = i as f32;
            Ray::new(Vec3::new(f, -f, 0.5 * f), Vec3::new(1.0, f, -2.0 * f))
        };
        let (origin, dir) = (
            Vec3x8::from_lanes(std::array::from_fn(|i| lane(i).origin)),
            Vec3x8::from_lanes(std::array::from_fn(|i| lane(i).dir)),
        );
        for n in 0..=LANES {
            // after a ray already queued, so the lanes land behind it
            let (mut packed, mut single) = (
                RayQueue::with_capacity_in(1, &arena),
                RayQueue::with_capacity_in(1, &arena),
            );
            let first = Ray::new(Vec3::splat(9.0), Vec3::Z);
            packed.push_reflected(&first, 99, Vec3::splat(0.5), 0.5, 3);
            single.push_reflected(&first, 99, Vec3::splat(0.5), 0.5, 3);
            let pixels: Vec<u32> = (0..n as u32).map(|i| 10 + i).collect();
            packed.push_camera_packet(&origin, &dir, &pixels);
            for (i, &p) in pixels.iter().enumerate() {
                single.push_camera(&lane(i), p);
            }
            assert_eq!(packed.len(), 1 + n);
            for i in 0..packed.len() {
                assert_eq!(packed.ray(i), single.ray(i), "{n} lanes, ray {i}");
            }
            assert_eq!(packed.pixel.as_slice(), single.pixel.as_slice());
            assert_eq!(packed.throughput.as_slice(), single.throughput.as_slice());
            assert_eq!(packed.weight.as_slice(), single.weight.as_slice());
            assert_eq!(packed.kind.as_slice(), single.kind.as_slice());
            assert_eq!(packed.parent.as_slice(), single.parent.as_slice());
        }
    }
}
