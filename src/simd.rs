//! The SIMD layer: the only file that names `wide` items. It fixes the packet width
//! ([`LANES`]), gives the 8-wide types the rest of the crate uses (`F32x8`, `I32x8`, [`Mask`]),
//! the few lane operations kernels need (compare, select, any/all, bitmask), and [`Vec3x8`], an
//! SoA 3-vector of 8 lanes with glam-like by-value methods. Packets, SoA primitives and kernels
//! are built on these. `wide` emits AVX2 only when it is enabled at compile time, which
//! `.cargo/config.toml` does (`target-cpu=x86-64-v3`).

use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Sub};

use crate::math::Vec3;

/// Rays per packet.
pub const LANES: usize = 8;

/// Eight `f32` lanes.
pub type F32x8 = wide::f32x8;
/// Eight `i32` lanes.
pub type I32x8 = wide::i32x8;
/// A lane mask: all bits set in a lane means true, all clear means false.
pub type Mask = wide::f32x8;
/// Four `f32` lanes: the width of the BVH's leaf blocks (a single ray against 4 primitives).
pub type F32x4 = wide::f32x4;
/// Four `i32` lanes.
pub type I32x4 = wide::i32x4;

/// What the kernels written once for every lane width need of a SIMD float type: arithmetic,
/// comparisons returning masks of the same type (as `wide` does), blending and a bitmask.
/// Implemented for [`F32x8`] (packets: 8 rays against one primitive) and [`F32x4`] (leaf
/// blocks: one ray against 4 primitives); the same expression on either gives the same bits in
/// every lane, which is what keeps the packet and single-ray paths identical.
pub trait Simd:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + Not<Output = Self>
{
    /// Every lane `v`.
    fn splat(v: f32) -> Self;
    /// Lane-wise `<`.
    fn lt(self, o: Self) -> Self;
    /// Lane-wise `<=`.
    fn le(self, o: Self) -> Self;
    /// Lane-wise `>`.
    fn gt(self, o: Self) -> Self;
    /// Lane-wise `>=`.
    fn ge(self, o: Self) -> Self;
    /// Lane-wise `==`.
    fn eq(self, o: Self) -> Self;
    /// Lanes of `a` where `mask` is set, else of `b`.
    fn pick(mask: Self, a: Self, b: Self) -> Self;
    /// Lane-wise absolute value.
    fn abs_lanes(self) -> Self;
    /// Lane-wise square root.
    fn sqrt_lanes(self) -> Self;
    /// Bit `i` set when lane `i` of the mask is.
    fn bits(self) -> u32;
    /// Lane-wise `self * b + c` with one rounding (as `f32::mul_add` in every lane): one
    /// instruction where the build enables FMA, lane by lane through `f32::mul_add` otherwise.
    fn mul_add_lanes(self, b: Self, c: Self) -> Self;
}

macro_rules! impl_simd {
    ($t:ty) => {
        impl Simd for $t {
            #[inline(always)]
            fn splat(v: f32) -> Self {
                <$t>::splat(v)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> Self {
                self.simd_lt(o)
            }
            #[inline(always)]
            fn le(self, o: Self) -> Self {
                self.simd_le(o)
            }
            #[inline(always)]
            fn gt(self, o: Self) -> Self {
                self.simd_gt(o)
            }
            #[inline(always)]
            fn ge(self, o: Self) -> Self {
                self.simd_ge(o)
            }
            #[inline(always)]
            fn eq(self, o: Self) -> Self {
                self.simd_eq(o)
            }
            #[inline(always)]
            fn pick(mask: Self, a: Self, b: Self) -> Self {
                mask.select(a, b)
            }
            #[inline(always)]
            fn abs_lanes(self) -> Self {
                self.abs()
            }
            #[inline(always)]
            fn sqrt_lanes(self) -> Self {
                self.sqrt()
            }
            #[inline(always)]
            fn bits(self) -> u32 {
                self.to_bitmask()
            }
            #[inline(always)]
            fn mul_add_lanes(self, b: Self, c: Self) -> Self {
                #[cfg(all(target_feature = "avx", target_feature = "fma"))]
                {
                    self.mul_add(b, c)
                }
                #[cfg(not(all(target_feature = "avx", target_feature = "fma")))]
                {
                    let (a, b, c) = (self.to_array(), b.to_array(), c.to_array());
                    <$t>::new(std::array::from_fn(|i| a[i].mul_add(b[i], c[i])))
                }
            }
        }
    };
}
impl_simd!(F32x8);
impl_simd!(F32x4);

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

/// The mask whose lane `i` is bit `i` of `bits` (the low 8 bits), without branches: for masks
/// kept as bits in hot loops.
#[inline(always)]
pub fn mask_from_byte(bits: u32) -> Mask {
    let lane_bit = I32x8::new([1, 2, 4, 8, 16, 32, 64, 128]);
    let set = (I32x8::splat(bits as i32) & lane_bit).simd_eq(lane_bit);
    bytemuck::cast(set)
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

/// The larger of `a` and `b` compared as integers (`vpmaxsd`, one cycle): the float maximum
/// wherever either is at least `+0` (non-negative floats order as their bits do, and the bits
/// of every negative float, as integers, are below those of every non-negative one).
#[inline(always)]
pub fn max_bits(a: F32x8, b: F32x8) -> F32x8 {
    let (a, b): (I32x8, I32x8) = (bytemuck::cast(a), bytemuck::cast(b));
    bytemuck::cast(a.max(b))
}

/// The smaller of `a` and `b` compared as integers (`vpminsd`): the float minimum where both
/// are at least `+0`; a negative value (or a NaN with its sign bit set) where either is one.
#[inline(always)]
pub fn min_bits(a: F32x8, b: F32x8) -> F32x8 {
    let (a, b): (I32x8, I32x8) = (bytemuck::cast(a), bytemuck::cast(b));
    bytemuck::cast(a.min(b))
}

/// `a <= b` compared as integers (`vpcmpgtd`, one cycle, negated; a float comparison takes four
/// on Intel's cores): the float comparison wherever `a` is at least `+0` and `b` is not `-0`
/// (non-negative floats order as their bits do, every other float's bits, as integers, are
/// below theirs, and `-0` is the lowest of all: `+0 <= -0` is true as floats, false here).
#[inline(always)]
pub fn le_bits(a: F32x8, b: F32x8) -> Mask {
    let (a, b): (I32x8, I32x8) = (bytemuck::cast(a), bytemuck::cast(b));
    let above: Mask = bytemuck::cast(a.simd_gt(b));
    !above
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

/// Asks the processor to fetch the cache line at `p` into all cache levels (a hint: no effect
/// on results).
#[inline(always)]
pub fn prefetch<T>(p: &T) {
    prefetch_address((p as *const T).cast());
}

/// [`prefetch`] for every cache line of `v` (a slice: all its elements).
#[inline(always)]
pub fn prefetch_all<T: ?Sized>(v: &T) {
    let start = (v as *const T).cast::<i8>();
    for offset in (0..std::mem::size_of_val(v)).step_by(64) {
        prefetch_address(start.wrapping_add(offset));
    }
}

#[inline(always)]
fn prefetch_address(p: *const i8) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: prefetching never faults, whatever the address.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// The lanes of `src` whose bit is set in `bits` (bit `k` = lane `k`, only the low 8 read),
/// moved to the front in lane order; the lanes after them are unspecified. A caller stores all
/// 8 and advances by `bits.count_ones()` (stream compaction: one permutation, where a lane at a
/// time took a branch per lane).
#[inline(always)]
pub fn compact_lanes(src: [u32; LANES], bits: u32) -> [u32; LANES] {
    let order = &COMPACT_ORDER[(bits & 0xff) as usize];
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        use std::arch::x86_64::{
            __m256i, _mm_loadl_epi64, _mm256_cvtepu8_epi32, _mm256_loadu_si256,
            _mm256_permutevar8x32_epi32, _mm256_storeu_si256,
        };
        let mut out = [0u32; LANES];
        // SAFETY: AVX2 is enabled at compile time (the cfg above); the loads read the 32 bytes
        // of `src` and the 8 of `order`, the store writes the 32 of `out`
        unsafe {
            let v = _mm256_loadu_si256(src.as_ptr().cast::<__m256i>());
            let idx = _mm256_cvtepu8_epi32(_mm_loadl_epi64(order.as_ptr().cast()));
            let packed = _mm256_permutevar8x32_epi32(v, idx);
            _mm256_storeu_si256(out.as_mut_ptr().cast::<__m256i>(), packed);
        }
        out
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        std::array::from_fn(|k| src[order[k] as usize])
    }
}

/// `COMPACT_ORDER[bits]`: the set bits of `bits`, lowest first, then zeros.
static COMPACT_ORDER: [[u8; LANES]; 256] = {
    let mut table = [[0u8; LANES]; 256];
    let mut bits = 0;
    while bits < 256 {
        let (mut lane, mut k) = (0, 0);
        while lane < LANES {
            if bits >> lane & 1 == 1 {
                table[bits][k] = lane as u8;
                k += 1;
            }
            lane += 1;
        }
        bits += 1;
    }
    table
};

/// The smallest lane (for lanes without NaN).
#[inline(always)]
pub fn reduce_min(a: F32x8) -> f32 {
    let v = a.to_array();
    let m = |x: f32, y: f32| if x < y { x } else { y };
    m(
        m(m(v[0], v[1]), m(v[2], v[3])),
        m(m(v[4], v[5]), m(v[6], v[7])),
    )
}

/// The largest lane (for lanes without NaN).
#[inline(always)]
pub fn reduce_max(a: F32x8) -> f32 {
    let v = a.to_array();
    let m = |x: f32, y: f32| if x > y { x } else { y };
    m(
        m(m(v[0], v[1]), m(v[2], v[3])),
        m(m(v[4], v[5]), m(v[6], v[7])),
    )
}

/// Lane-wise `a * b + c` with one rounding (a fused multiply-add): one instruction where the
/// build enables FMA (x86-64-v3), lane by lane through `f32::mul_add` otherwise (slow, but the
/// same single rounding, which the box tests' error bound relies on).
#[inline(always)]
pub fn fused_mul_add(a: F32x8, b: F32x8, c: F32x8) -> F32x8 {
    a.mul_add_lanes(b, c)
}

/// Lane-wise `a` with the sign of `sign`.
#[inline(always)]
pub fn copysign(a: F32x8, sign: F32x8) -> F32x8 {
    a.copysign(sign)
}

/// Lane-wise square root.
#[inline(always)]
pub fn sqrt(a: F32x8) -> F32x8 {
    a.sqrt()
}

/// Loads up to 8 values; missing lanes get `fill`.
#[inline]
pub fn load_partial(values: &[f32], fill: f32) -> F32x8 {
    if let Ok(full) = <[f32; LANES]>::try_from(values) {
        return F32x8::new(full);
    }
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

/// One 8-lane value from two 4-lane halves: `lo` in lanes 0–3, `hi` in lanes 4–7 (one
/// `vinsertf128`).
#[inline(always)]
pub fn join_halves(lo: crate::math::Vec4, hi: crate::math::Vec4) -> F32x8 {
    bytemuck::cast([lo.to_array(), hi.to_array()])
}

/// The two 4-lane halves of `v`, lanes 0–3 then 4–7: [`join_halves`] undone.
#[inline(always)]
pub fn split_halves(v: F32x8) -> (crate::math::Vec4, crate::math::Vec4) {
    let [lo, hi]: [[f32; 4]; 2] = bytemuck::cast(v);
    (
        crate::math::Vec4::from_array(lo),
        crate::math::Vec4::from_array(hi),
    )
}

/// Each lane times 255, clamped to `[0, 255]` and truncated to a byte, NaN giving 0: the
/// course's colour-to-byte rule (`(c * 255.0).clamp(0.0, 255.0) as u8`), 8 channels at once,
/// which a scalar loop of `as u8` is not (its saturating checks do not vectorise).
#[inline(always)]
pub fn unit_to_bytes(v: F32x8) -> [u8; LANES] {
    // `vmaxps` gives its second operand, 0, where the first is NaN
    let clamped = (v * F32x8::splat(255.0))
        .fast_max(F32x8::ZERO)
        .fast_min(F32x8::splat(255.0));
    clamped.fast_trunc_int().to_array().map(|b| b as u8)
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

/// Rows to columns: lane `j` of column `i` is lane `i` of row `j` (eight unpacks, eight
/// shuffles and eight permutations).
#[inline(always)]
pub fn transpose8x8(rows: [F32x8; 8]) -> [F32x8; 8] {
    F32x8::transpose(rows)
}

/// 3-vectors stored as one SIMD value per coordinate (structure of arrays): lane `i` of `x`,
/// `y`, `z` is vector `i`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vec3v<T> {
    pub x: T,
    pub y: T,
    pub z: T,
}

/// Eight 3-vectors (a packet's origins or directions).
pub type Vec3x8 = Vec3v<F32x8>;
/// Four 3-vectors (a leaf block's vertices).
pub type Vec3x4 = Vec3v<F32x4>;

impl<T: Simd> Vec3v<T> {
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Vec3v<T> {
        Vec3v {
            x: T::splat(v.x),
            y: T::splat(v.y),
            z: T::splat(v.z),
        }
    }

    /// All lanes zero.
    #[inline(always)]
    pub fn zero() -> Vec3v<T> {
        Vec3v::splat(Vec3::ZERO)
    }

    /// Lane-wise dot product.
    #[inline(always)]
    pub fn dot(self, o: Vec3v<T>) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Lane-wise cross product (glam's order of operations, so lanes match `Vec3::cross`).
    #[inline(always)]
    pub fn cross(self, o: Vec3v<T>) -> Vec3v<T> {
        Vec3v {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// Lane-wise dot product with fused operations: `x x' + (y y' + z z')`, each sum one fused
    /// multiply-add ([`crate::math::dot_fused`] for one vector, the same bits).
    #[inline(always)]
    pub fn dot_fused(self, o: Vec3v<T>) -> T {
        self.x
            .mul_add_lanes(o.x, self.y.mul_add_lanes(o.y, self.z * o.z))
    }

    /// Lane-wise cross product with fused operations: each component `a b - c d` as one fused
    /// multiply-add of `a b` and `-(c d)` ([`crate::math::cross_fused`], the same bits).
    #[inline(always)]
    pub fn cross_fused(self, o: Vec3v<T>) -> Vec3v<T> {
        Vec3v {
            x: self.y.mul_add_lanes(o.z, -(o.y * self.z)),
            y: self.z.mul_add_lanes(o.x, -(o.z * self.x)),
            z: self.x.mul_add_lanes(o.y, -(o.x * self.y)),
        }
    }

    /// Lane-wise squared length.
    #[inline(always)]
    pub fn length_squared(self) -> T {
        self.dot(self)
    }

    /// Lane-wise unit vector (as `glam::Vec3::normalize`: divides by the length).
    #[inline(always)]
    pub fn normalize(self) -> Vec3v<T> {
        let inv = T::splat(1.0) / self.dot(self).sqrt_lanes();
        self * inv
    }

    /// Lanes of `a` where `mask` is set, else of `b`.
    #[inline(always)]
    pub fn select(mask: T, a: Vec3v<T>, b: Vec3v<T>) -> Vec3v<T> {
        Vec3v {
            x: T::pick(mask, a.x, b.x),
            y: T::pick(mask, a.y, b.y),
            z: T::pick(mask, a.z, b.z),
        }
    }
}

impl Vec3x8 {
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
}

impl Vec3x4 {
    /// The vectors of four `[x; 4], [y; 4], [z; 4]` columns.
    #[inline(always)]
    pub fn from_columns(c: &[[f32; 4]; 3]) -> Vec3x4 {
        Vec3x4 {
            x: F32x4::new(c[0]),
            y: F32x4::new(c[1]),
            z: F32x4::new(c[2]),
        }
    }
}

impl<T: Simd> Add for Vec3v<T> {
    type Output = Vec3v<T>;
    #[inline(always)]
    fn add(self, o: Vec3v<T>) -> Vec3v<T> {
        Vec3v {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<T: Simd> Sub for Vec3v<T> {
    type Output = Vec3v<T>;
    #[inline(always)]
    fn sub(self, o: Vec3v<T>) -> Vec3v<T> {
        Vec3v {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<T: Simd> Mul<T> for Vec3v<T> {
    type Output = Vec3v<T>;
    #[inline(always)]
    fn mul(self, s: T) -> Vec3v<T> {
        Vec3v {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl<T: Simd> Neg for Vec3v<T> {
    type Output = Vec3v<T>;
    #[inline(always)]
    fn neg(self) -> Vec3v<T> {
        Vec3v {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lane `j` of column `i` is lane `i` of row `j`, for every `i` and `j`.
    #[test]
    fn transpose8x8_turns_rows_into_columns() {
        let rows: [F32x8; 8] =
            std::array::from_fn(|j| F32x8::new(std::array::from_fn(|i| (10 * j + i) as f32)));
        let columns = transpose8x8(rows);
        for (i, c) in columns.iter().enumerate() {
            for (j, v) in lanes(*c).iter().enumerate() {
                assert_eq!(*v, (10 * j + i) as f32, "column {i}, lane {j}");
            }
        }
    }

    #[test]
    fn unit_to_bytes_truncates_each_lane_as_a_saturating_cast_does() {
        let mut values = vec![
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            f32::MAX,
            f32::MIN,
            -1.0,
            7.0,
        ];
        for k in 0..=256 {
            let b = k as f32 / 255.0;
            values.extend([b.next_down(), b, b.next_up()]);
        }
        for lanes in values.chunks(LANES) {
            let got = unit_to_bytes(load_partial(lanes, 0.0));
            for (i, &c) in lanes.iter().enumerate() {
                assert_eq!(
                    got[i],
                    (c * 255.0).clamp(0.0, 255.0) as u8,
                    "{c:?} in lane {i}"
                );
            }
        }
    }

    #[test]
    fn compact_lanes_keeps_the_chosen_lanes_in_order() {
        let src: [u32; LANES] = std::array::from_fn(|k| 100 + k as u32);
        for bits in 0..256u32 {
            let want: Vec<u32> = (0..LANES)
                .filter(|&k| bits >> k & 1 == 1)
                .map(|k| src[k])
                .collect();
            let got = compact_lanes(src, bits);
            assert_eq!(&got[..want.len()], &want[..], "bits {bits:08b}");
        }
        // bits above the eighth are ignored
        assert_eq!(compact_lanes(src, 0x102)[0], 101);
    }

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
    fn halves_join_in_lane_order_and_split_back() {
        use crate::math::Vec4;
        let (lo, hi) = (
            Vec4::new(1.0, -0.0, f32::INFINITY, 4.0),
            Vec4::new(5.0, 6.0, -7.5, 8.0),
        );
        let v = join_halves(lo, hi);
        assert_eq!(
            lanes(v),
            [1.0, -0.0, f32::INFINITY, 4.0, 5.0, 6.0, -7.5, 8.0]
        );
        assert!(lanes(v)[1].is_sign_negative());
        let (l, h) = split_halves(v);
        assert_eq!((l.to_array(), h.to_array()), (lo.to_array(), hi.to_array()));
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
    fn fused_mul_add_rounds_once() {
        // 1 + 2^-12 squared is 1 + 2^-11 + 2^-24: the last bit is lost when the product is
        // rounded first, kept by the fused operation.
        let a = 1.0 + f32::EPSILON * 2048.0;
        let fused = lanes(fused_mul_add(
            F32x8::splat(a),
            F32x8::splat(a),
            F32x8::splat(-1.0),
        ));
        assert_eq!(fused[0], a.mul_add(a, -1.0));
        assert_eq!(fused[0], 2f32.powi(-11) + 2f32.powi(-24));
        assert_ne!(fused[0], a * a - 1.0);
        let x: [f32; LANES] = std::array::from_fn(|i| 0.1 + i as f32 * 1.37);
        let y: [f32; LANES] = std::array::from_fn(|i| -3.3 + i as f32 * 0.71);
        let got = lanes(fused_mul_add(F32x8::new(x), F32x8::new(y), F32x8::new(y)));
        for i in 0..LANES {
            assert_eq!(got[i].to_bits(), x[i].mul_add(y[i], y[i]).to_bits());
        }
    }

    /// The fused dot and cross products of 8 and of 4 lanes are the scalar ones
    /// (`math::dot_fused`, `math::cross_fused`) bit for bit, and they are fused: on some of these
    /// vectors they differ from the unfused products.
    #[test]
    fn fused_dot_and_cross_are_their_scalar_twins() {
        use crate::math::{cross_fused, dot_fused};
        let mut x = 0x2545_f491u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32 * 8.0 - 4.0
        };
        let (mut dot_rounded, mut cross_rounded) = (0, 0);
        for _ in 0..500 {
            let a: [Vec3; LANES] = std::array::from_fn(|_| Vec3::new(next(), next(), next()));
            let b: [Vec3; LANES] = std::array::from_fn(|_| Vec3::new(next(), next(), next()));
            let (pa, pb) = (Vec3x8::from_lanes(a), Vec3x8::from_lanes(b));
            let lo = |v: [Vec3; LANES]| {
                Vec3x4::from_columns(&std::array::from_fn(|axis| {
                    std::array::from_fn(|i| v[i][axis])
                }))
            };
            let (qa, qb) = (lo(a), lo(b));
            for i in 0..LANES {
                let (dot, cross) = (dot_fused(a[i], b[i]), cross_fused(a[i], b[i]));
                assert_eq!(lanes(pa.dot_fused(pb))[i].to_bits(), dot.to_bits());
                assert_eq!(
                    pa.cross_fused(pb).lane(i).to_array().map(f32::to_bits),
                    cross.to_array().map(f32::to_bits)
                );
                if i < 4 {
                    assert_eq!(qa.dot_fused(qb).to_array()[i].to_bits(), dot.to_bits());
                    let c = qa.cross_fused(qb);
                    assert_eq!(
                        [c.x, c.y, c.z].map(|v| v.to_array()[i].to_bits()),
                        cross.to_array().map(f32::to_bits)
                    );
                }
                dot_rounded += usize::from(dot != a[i].dot(b[i]));
                cross_rounded += usize::from(cross != a[i].cross(b[i]));
            }
        }
        assert!(
            dot_rounded > 100 && cross_rounded > 100,
            "{dot_rounded} / {cross_rounded} of 4000 differ from the unfused products"
        );
    }

    #[test]
    fn integer_comparisons_are_the_float_ones_from_plus_zero() {
        let a = [0.0, 0.0, 1.0, 1.0, 2.5e-39, f32::MAX, 3.0, 0.0];
        let b = [0.0, 1.0, 0.5, 1.0, 1.0e-39, f32::INFINITY, -1.0, -0.0];
        let (fa, fb) = (F32x8::new(a), F32x8::new(b));
        let le = lanes(le_bits(fa, fb));
        let (hi, lo) = (lanes(max_bits(fa, fb)), lanes(min_bits(fa, fb)));
        for l in 0..8 {
            // every pair but the last: `a >= +0`, `b` not `-0`
            let float_le = a[l] <= b[l] && l != 7;
            assert_eq!(le[l] != 0.0, float_le, "lane {l}");
            // `f32::max` leaves the sign of a zero result open; `+0` is above `-0`
            let float_max = if l == 7 { 0.0f32 } else { a[l].max(b[l]) };
            assert_eq!(hi[l].to_bits(), float_max.to_bits(), "lane {l}");
            if b[l] >= 0.0 && b[l].to_bits() != (-0.0f32).to_bits() {
                assert_eq!(lo[l].to_bits(), a[l].min(b[l]).to_bits(), "lane {l}");
            } else {
                assert!(lo[l].is_sign_negative(), "lane {l}");
            }
        }
    }

    #[test]
    fn masks() {
        assert_eq!(bitmask(mask_first(3)), 0b111);
        assert_eq!(bitmask(mask_first(8)), 0xff);
        assert_eq!(bitmask(mask_first(0)), 0);
        assert_eq!(bitmask(mask_from_bits(0b1010_0101)), 0b1010_0101);
        for bits in 0..256 {
            assert_eq!(bitmask(mask_from_byte(bits)), bits);
            assert_eq!(
                mask_from_byte(bits).to_array().map(f32::to_bits),
                mask_from_bits(bits).to_array().map(f32::to_bits)
            );
        }
        assert!(all(mask_first(8)) && !any(mask_none()));
        let m = mask_from_bits(0b0000_0110);
        let s = select_i32(m, I32x8::splat(7), I32x8::splat(-1));
        assert_eq!(lanes_i32(s), [-1, 7, 7, -1, -1, -1, -1, -1]);
        let f = select(m, F32x8::splat(1.0), F32x8::splat(2.0));
        assert_eq!(lanes(f), [2.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0]);
    }
}
