//! The unit tests' random numbers: a small deterministic generator (xorshift), so the packet
//! and single-ray tests draw their rays and boxes the same way, and the shading and camera
//! tests their random inputs. Test-only, a leaf.

use crate::math::Vec3;

pub(crate) struct Rng(pub u32);

impl Rng {
    /// 32 random bits.
    pub fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    /// A value in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * (self.next() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// A value in `[lo, hi)`, in `f64`.
    pub fn range64(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * f64::from(self.next() >> 8) / f64::from(1u32 << 24)
    }

    /// A vector with each coordinate in `[lo, hi)`.
    pub fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
}
