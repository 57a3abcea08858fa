//! Where the samples of a pixel lie: the course's three sampling patterns (assignment 7). A
//! [`Sampler`] gives each sample of each pixel an offset inside its pixel, measured as the
//! course measures it (from the pixel's lower-left corner, y up, in `[0, 1)`); the frame loops
//! of both tracers turn offsets into camera rays ([`crate::scene::Camera::sample_screen`]) and
//! the film ([`crate::film`]) weighs the traced colours by them. A leaf: it knows no tracer.
//!
//! ```text
//! uniform  n = k*k   the centres of a k x k grid of cells       ((a + 1/2)/k, (b + 1/2)/k)
//! jittered n = k*k   one random point in each cell               ((a + u)/k,   (b + v)/k)
//! random   n         n random points in the pixel                (u, v)
//! ```
//!
//! Sample `s = b*k + a` lies in cell column `a` and row `b` (from the bottom). The random numbers
//! `u, v` are not drawn from a stream: they are a hash of (pixel x, pixel y, sample index,
//! seed), so a sample's place depends on nothing else (not on threads, bands, tiles or the
//! tracer), and `--seed` changes every one of them.

use crate::math::Vec2;

/// The largest `f32` below 1: offsets stay inside their pixel.
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

/// The seed used unless `--seed` says otherwise.
pub const DEFAULT_SEED: u64 = 0;

/// The three patterns of the course.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// The centres of a `k x k` grid of cells (`n = k * k`); one sample is the pixel centre.
    Uniform,
    /// Uniformly random points in the pixel.
    Random,
    /// One random point in each cell of a `k x k` grid (`n = k * k`).
    Jittered,
}

impl Pattern {
    /// Parses `uniform`, `random` or `jittered`.
    pub fn from_name(name: &str) -> Option<Pattern> {
        match name {
            "uniform" => Some(Pattern::Uniform),
            "random" => Some(Pattern::Random),
            "jittered" => Some(Pattern::Jittered),
            _ => None,
        }
    }

    /// The name `--sampler` takes.
    pub fn name(self) -> &'static str {
        match self {
            Pattern::Uniform => "uniform",
            Pattern::Random => "random",
            Pattern::Jittered => "jittered",
        }
    }

    /// True if the pattern needs a perfect square count (a grid of cells).
    pub fn needs_square(self) -> bool {
        self != Pattern::Random
    }
}

/// A sampling pattern with its count per pixel and seed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sampler {
    pub pattern: Pattern,
    /// Samples per pixel, at least 1 (a perfect square for uniform and jittered).
    pub count: u32,
    /// Changes every random offset (not the uniform ones).
    pub seed: u64,
}

impl Default for Sampler {
    /// One sample at the centre of each pixel, as before assignment 7.
    fn default() -> Sampler {
        Sampler {
            pattern: Pattern::Uniform,
            count: 1,
            seed: DEFAULT_SEED,
        }
    }
}

impl Sampler {
    /// `k` for a `k x k` grid (uniform and jittered); for random, the smallest `k` with
    /// `k * k >= count` (unused).
    pub fn grid(&self) -> u32 {
        let mut k = (self.count as f64).sqrt() as u32;
        while k * k < self.count {
            k += 1;
        }
        while k > 1 && (k - 1) * (k - 1) >= self.count {
            k -= 1;
        }
        k.max(1)
    }

    /// The offset of sample `s` of pixel `(x, y)` (`y = 0` the top row), from the pixel's
    /// lower-left corner, y up, each coordinate in `[0, 1)`.
    pub fn offset(&self, x: u32, y: u32, s: u32) -> Vec2 {
        self.offset_in_grid(self.grid(), x, y, s)
    }

    /// [`Sampler::offset`] with the grid's `k` ([`Sampler::grid`]) given, so that a loop over
    /// many samples finds it once.
    fn offset_in_grid(&self, k: u32, x: u32, y: u32, s: u32) -> Vec2 {
        let cell = |i: u32, t: f32| ((i as f32 + t) / k as f32).min(BELOW_ONE);
        match self.pattern {
            Pattern::Uniform => Vec2::new(cell(s % k, 0.5), cell(s / k, 0.5)),
            Pattern::Jittered => {
                let (u, v) = unit_pair(x, y, s, self.seed);
                Vec2::new(cell(s % k, u), cell(s / k, v))
            }
            Pattern::Random => {
                let (u, v) = unit_pair(x, y, s, self.seed);
                Vec2::new(u, v)
            }
        }
    }

    /// Fills `out` (one entry per sample) with the offsets of pixel `(x, y)` and returns the
    /// index of the sample nearest the pixel centre (the first one on ties): the sample whose
    /// hit the depth and normal images show.
    pub fn pixel_offsets(&self, x: u32, y: u32, out: &mut [Vec2]) -> u32 {
        debug_assert_eq!(out.len(), self.count as usize);
        let k = self.grid();
        for (s, o) in out.iter_mut().enumerate() {
            *o = self.offset_in_grid(k, x, y, s as u32);
        }
        nearest_to_centre(out)
    }

    /// True if the offsets differ from pixel to pixel (random and jittered); the uniform
    /// pattern gives every pixel the same ones.
    pub fn varies_by_pixel(&self) -> bool {
        self.pattern != Pattern::Uniform
    }

    /// The offset of pixel `(x, y)`'s sample nearest its centre (see [`Sampler::pixel_offsets`]):
    /// the sample a ray tree of the pixel follows.
    pub fn nearest_offset(&self, x: u32, y: u32) -> Vec2 {
        let mut all = vec![Vec2::ZERO; self.count as usize];
        let s = self.pixel_offsets(x, y, &mut all);
        all[s as usize]
    }
}

/// The index of the offset nearest `(0.5, 0.5)`, the first one on ties (0 for none).
pub fn nearest_to_centre(offsets: &[Vec2]) -> u32 {
    let mut best = (0, f32::INFINITY);
    for (s, o) in offsets.iter().enumerate() {
        let d = (*o - Vec2::splat(0.5)).length_squared();
        if d < best.1 {
            best = (s as u32, d);
        }
    }
    best.0
}

/// Two numbers in `[0, 1)` for sample `s` of pixel `(x, y)`: the top and the next 24 bits of
/// a 64-bit hash of the four counters (SplitMix64's finaliser, applied three times).
fn unit_pair(x: u32, y: u32, s: u32, seed: u64) -> (f32, f32) {
    let h = hash4(x, y, s, seed);
    let scale = 1.0 / (1u32 << 24) as f32;
    (
        (h >> 40) as f32 * scale,
        ((h >> 16) & 0xFF_FFFF) as f32 * scale,
    )
}

/// A counter-based hash of (x, y, s, seed): every input bit changes about half the output bits.
pub fn hash4(x: u32, y: u32, s: u32, seed: u64) -> u64 {
    let a = mix64(seed ^ 0x9E37_79B9_7F4A_7C15);
    let b = mix64(a ^ ((x as u64) << 32 | y as u64));
    mix64(b ^ s as u64)
}

/// SplitMix64's output function (Steele, Lea and Flood 2014): a bijection of `u64`.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler(pattern: Pattern, count: u32) -> Sampler {
        Sampler {
            pattern,
            count,
            ..Sampler::default()
        }
    }

    #[test]
    fn one_uniform_sample_is_the_centre() {
        assert_eq!(Sampler::default().offset(3, 4, 0), Vec2::splat(0.5));
    }

    #[test]
    fn uniform_samples_are_the_cell_centres() {
        let s = sampler(Pattern::Uniform, 9);
        assert_eq!(s.grid(), 3);
        let third = 1.0f32 / 3.0;
        assert_eq!(s.offset(0, 0, 0), Vec2::new(0.5 / 3.0, 0.5 / 3.0));
        assert_eq!(s.offset(0, 0, 4), Vec2::new(1.5 / 3.0, 1.5 / 3.0));
        assert_eq!(s.offset(7, 1, 5), Vec2::new(2.5 / 3.0, 1.5 / 3.0));
        assert!(s.offset(0, 0, 8).x > 2.0 * third);
        let mut out = [Vec2::ZERO; 9];
        assert_eq!(s.pixel_offsets(0, 0, &mut out), 4, "the centre sample");
        let four = sampler(Pattern::Uniform, 4);
        let mut out = [Vec2::ZERO; 4];
        assert_eq!(four.pixel_offsets(0, 0, &mut out), 0, "ties: the first");
    }

    #[test]
    fn jittered_samples_stay_in_their_cells() {
        let s = sampler(Pattern::Jittered, 16);
        for (x, y) in [(0, 0), (1, 0), (1000, 77), (u32::MAX, u32::MAX)] {
            for i in 0..16 {
                let o = s.offset(x, y, i);
                let (a, b) = ((i % 4) as f32, (i / 4) as f32);
                assert!(o.x >= a / 4.0 && o.x < (a + 1.0) / 4.0, "{o:?}");
                assert!(o.y >= b / 4.0 && o.y < (b + 1.0) / 4.0, "{o:?}");
            }
        }
    }

    #[test]
    fn random_offsets_depend_on_every_counter_and_the_seed() {
        let s = sampler(Pattern::Random, 4);
        let o = s.offset(5, 6, 2);
        assert!(o.x >= 0.0 && o.x < 1.0 && o.y >= 0.0 && o.y < 1.0);
        assert_eq!(o, s.offset(5, 6, 2), "a pure function");
        assert_ne!(o, s.offset(6, 6, 2));
        assert_ne!(o, s.offset(5, 7, 2));
        assert_ne!(o, s.offset(5, 6, 3));
        assert_ne!(o, s.offset(6, 5, 2), "x and y are not interchangeable");
        let seeded = Sampler { seed: 1, ..s };
        assert_ne!(o, seeded.offset(5, 6, 2));
    }

    #[test]
    fn random_offsets_cover_the_pixel_evenly() {
        // 64k samples in 16 x 16 bins: Pearson's chi-squared over the 255 degrees of freedom is
        // 255 +- 23 for a uniform source; 400 is over 6 standard deviations out.
        let s = sampler(Pattern::Random, 16);
        let mut bins = [0u32; 256];
        for p in 0..4096 {
            for i in 0..16 {
                let o = s.offset(p % 64, p / 64, i);
                bins[(o.y * 16.0) as usize * 16 + (o.x * 16.0) as usize] += 1;
            }
        }
        let chi2: f64 = bins
            .iter()
            .map(|&n| (n as f64 - 256.0).powi(2) / 256.0)
            .sum();
        assert!(chi2 < 400.0, "chi-squared {chi2}: {bins:?}");
    }

    #[test]
    fn offsets_never_reach_one() {
        const { assert!(BELOW_ONE < 1.0 && BELOW_ONE + f32::EPSILON / 2.0 == 1.0) };
        let s = sampler(Pattern::Jittered, 1024);
        for i in 0..1024 {
            let o = s.offset(9, 9, i);
            assert!(o.x < 1.0 && o.y < 1.0);
        }
    }
}
