//! The SIMD layer: the only file that names `wide` items. It fixes the packet width
//! ([`LANES`]), gives the 8-wide types the rest of the crate uses (`F32x8`, `I32x8`, [`Mask`]),
//! the few lane operations kernels need (compare, select, any/all, bitmask), and [`Vec3x8`], an
//! SoA 3-vector of 8 lanes with glam-like by-value methods. Packets, SoA primitives and kernels
//! are built on these. `wide` emits AVX2 only when it is enabled at compile time, which
//! `.cargo/config.toml` does (`target-cpu=x86-64-v3`).

use std::ops::{Add, Mul, Neg, Sub};

use crate::math::Vec3;

/// Rays per packet.
pub const LANES: usize = 8;

/// Eight `f32` lanes.
pub type F32x8 = wide::f32x8;
/// Eight `i32` lanes.
pub type I32x8 = wide::i32x8;
/// A lane mask: all bits set in a lane means true, all clear means false.
pub type Mask = wide::f32x8;

/// A mask with every lane false.
#[inline(always)]
pub fn mask_none() -> Mask {
    F32x8::splat(0.0)
}

/// The mask of the first `n` lanes.
#[inline]
pub fn mask_first(n: usize) -> Mask {
    mask_from_bits((1u32 << n.min(LANES)) - 1)
}

/// The mask whose lane `i` is bit `i` of `bits`.
#[inline]
pub fn mask_from_bits(bits: u32) -> Mask {
    let on = f32::from_bits(u32::MAX);
    F32x8::new(std::array::from_fn(|i| {
        if bits >> i & 1 == 1 { on } else { 0.0 }
    }))
}

/// Lane-wise `a < b`.
#[inline(always)]
pub fn lt(a: F32x8, b: F32x8) -> Mask {
    a.simd_lt(b)
}

/// Lane-wise `a <= b`.
#[inline(always)]
pub fn le(a: F32x8, b: F32x8) -> Mask {
    a.simd_le(b)
}

/// Lane-wise `a > b`.
#[inline(always)]
pub fn gt(a: F32x8, b: F32x8) -> Mask {
    a.simd_gt(b)
}

/// Lane-wise `a >= b`.
#[inline(always)]
pub fn ge(a: F32x8, b: F32x8) -> Mask {
    a.simd_ge(b)
}

/// Lane-wise `a == b`.
#[inline(always)]
pub fn eq(a: F32x8, b: F32x8) -> Mask {
    a.simd_eq(b)
}

/// Lanes of `if_true` where `mask` is set, else of `if_false`.
#[inline(always)]
pub fn select(mask: Mask, if_true: F32x8, if_false: F32x8) -> F32x8 {
    mask.select(if_true, if_false)
}

/// [`select`] for integer lanes.
#[inline(always)]
pub fn select_i32(mask: Mask, if_true: I32x8, if_false: I32x8) -> I32x8 {
    let m: I32x8 = bytemuck::cast(mask);
    m.select(if_true, if_false)
}

/// True if any lane of `mask` is set.
#[inline(always)]
pub fn any(mask: Mask) -> bool {
    mask.any()
}

/// True if every lane of `mask` is set.
#[inline(always)]
pub fn all(mask: Mask) -> bool {
    mask.all()
}

/// Bit `i` set when lane `i` of `mask` is.
#[inline(always)]
pub fn bitmask(mask: Mask) -> u32 {
    mask.to_bitmask()
}

/// Lane-wise minimum.
#[inline(always)]
pub fn min(a: F32x8, b: F32x8) -> F32x8 {
    // One `vminps`: lanes holding NaN give `b` (x86 semantics). Callers never pass NaN.
    a.fast_min(b)
}

/// Lane-wise maximum.
#[inline(always)]
pub fn max(a: F32x8, b: F32x8) -> F32x8 {
    // One `vmaxps`: lanes holding NaN give `b` (x86 semantics). Callers never pass NaN.
    a.fast_max(b)
}

/// Lane-wise square root.
#[inline(always)]
pub fn sqrt(a: F32x8) -> F32x8 {
    a.sqrt()
}

/// Loads up to 8 values; missing lanes get `fill`.
#[inline]
pub fn load_partial(values: &[f32], fill: f32) -> F32x8 {
    F32x8::new(std::array::from_fn(|i| {
        values.get(i).copied().unwrap_or(fill)
    }))
}

/// A vector from its lanes.
#[inline(always)]
pub fn from_lanes(values: [f32; LANES]) -> F32x8 {
    F32x8::new(values)
}

/// The integer parts of the first three lanes of `v` (non-negative, below 2^31): a plain
/// truncating conversion, without the saturation checks of `as usize`.
#[inline(always)]
pub fn trunc3(v: crate::math::Vec4) -> [usize; 3] {
    let t = wide::f32x4::new(v.to_array()).fast_trunc_int().to_array();
    [t[0] as usize, t[1] as usize, t[2] as usize]
}

/// The lanes as an array.
#[inline(always)]
pub fn lanes(a: F32x8) -> [f32; LANES] {
    a.to_array()
}

/// The integer lanes as an array.
#[inline(always)]
pub fn lanes_i32(a: I32x8) -> [i32; LANES] {
    a.to_array()
}

/// Eight 3-vectors stored as three `F32x8` (structure of arrays).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3x8 {
    pub x: F32x8,
    pub y: F32x8,
    pub z: F32x8,
}

impl Vec3x8 {
    /// All lanes zero.
    #[inline(always)]
    pub fn zero() -> Vec3x8 {
        Vec3x8::splat(Vec3::ZERO)
    }

    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Vec3x8 {
        Vec3x8 {
            x: F32x8::splat(v.x),
            y: F32x8::splat(v.y),
            z: F32x8::splat(v.z),
        }
    }

    /// Lane `i` is `v[i]`.
    #[inline]
    pub fn from_lanes(v: [Vec3; LANES]) -> Vec3x8 {
        Vec3x8 {
            x: F32x8::new(std::array::from_fn(|i| v[i].x)),
            y: F32x8::new(std::array::from_fn(|i| v[i].y)),
            z: F32x8::new(std::array::from_fn(|i| v[i].z)),
        }
    }

    /// The vector in lane `i`.
    #[inline]
    pub fn lane(&self, i: usize) -> Vec3 {
        Vec3::new(
            self.x.as_array()[i],
            self.y.as_array()[i],
            self.z.as_array()[i],
        )
    }

    /// Sets lane `i` to `v`.
    #[inline]
    pub fn set_lane(&mut self, i: usize, v: Vec3) {
        self.x.as_mut_array()[i] = v.x;
        self.y.as_mut_array()[i] = v.y;
        self.z.as_mut_array()[i] = v.z;
    }

    /// Lane-wise dot product.
    #[inline(always)]
    pub fn dot(self, o: Vec3x8) -> F32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Lane-wise cross product.
    #[inline(always)]
    pub fn cross(self, o: Vec3x8) -> Vec3x8 {
        Vec3x8 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// Lane-wise squared length.
    #[inline(always)]
    pub fn length_squared(self) -> F32x8 {
        self.dot(self)
    }

    /// Lane-wise unit vector (as `glam::Vec3::normalize`: divides by the length).
    #[inline(always)]
    pub fn normalize(self) -> Vec3x8 {
        let inv = F32x8::splat(1.0) / sqrt(self.dot(self));
        self * inv
    }

    /// Lanes of `a` where `mask` is set, else of `b`.
    #[inline(always)]
    pub fn select(mask: Mask, a: Vec3x8, b: Vec3x8) -> Vec3x8 {
        Vec3x8 {
            x: select(mask, a.x, b.x),
            y: select(mask, a.y, b.y),
            z: select(mask, a.z, b.z),
        }
    }
}

impl Add for Vec3x8 {
    type Output = Vec3x8;
    #[inline(always)]
    fn add(self, o: Vec3x8) -> Vec3x8 {
        Vec3x8 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for Vec3x8 {
    type Output = Vec3x8;
    #[inline(always)]
    fn sub(self, o: Vec3x8) -> Vec3x8 {
        Vec3x8 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Mul<F32x8> for Vec3x8 {
    type Output = Vec3x8;
    #[inline(always)]
    fn mul(self, s: F32x8) -> Vec3x8 {
        Vec3x8 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl Neg for Vec3x8 {
    type Output = Vec3x8;
    #[inline(always)]
    fn neg(self) -> Vec3x8 {
        Vec3x8 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_round_trip() {
        let vs: [Vec3; LANES] = std::array::from_fn(|i| Vec3::new(i as f32, -(i as f32), 0.5));
        let p = Vec3x8::from_lanes(vs);
        for (i, v) in vs.iter().enumerate() {
            assert_eq!(p.lane(i), *v);
        }
        let mut q = p;
        q.set_lane(3, Vec3::ONE);
        assert_eq!(q.lane(3), Vec3::ONE);
        assert_eq!(q.lane(2), vs[2]);
    }

    #[test]
    fn vector_ops_match_glam_bit_for_bit() {
        let a: [Vec3; LANES] =
            std::array::from_fn(|i| Vec3::new(1.5 + i as f32, 0.25, -3.0 * i as f32));
        let b: [Vec3; LANES] = std::array::from_fn(|i| Vec3::new(-0.5, 2.0 + i as f32, 0.75));
        let (pa, pb) = (Vec3x8::from_lanes(a), Vec3x8::from_lanes(b));
        for i in 0..LANES {
            assert_eq!(lanes(pa.dot(pb))[i], a[i].dot(b[i]));
            assert_eq!(pa.cross(pb).lane(i), a[i].cross(b[i]));
            assert_eq!((pa - pb).lane(i), a[i] - b[i]);
            assert_eq!(pa.normalize().lane(i), a[i] * (1.0 / a[i].length()));
        }
    }

    #[test]
    fn masks() {
        assert_eq!(bitmask(mask_first(3)), 0b111);
        assert_eq!(bitmask(mask_first(8)), 0xff);
        assert_eq!(bitmask(mask_first(0)), 0);
        assert_eq!(bitmask(mask_from_bits(0b1010_0101)), 0b1010_0101);
        assert!(all(mask_first(8)) && !any(mask_none()));
        let m = mask_from_bits(0b0000_0110);
        let s = select_i32(m, I32x8::splat(7), I32x8::splat(-1));
        assert_eq!(lanes_i32(s), [-1, 7, 7, -1, -1, -1, -1, -1]);
        let f = select(m, F32x8::splat(1.0), F32x8::splat(2.0));
        assert_eq!(lanes(f), [2.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0]);
    }
}
