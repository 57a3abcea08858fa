//! Solid textures (assignment 6): materials whose parameters vary with the world-space point.
//! Each maps the world point `p` through its own matrix into texture space, `q = T p` (the
//! matrix as parsed, not inverted, as the handout says), and blends two other materials there
//! (which may be textures themselves) with a weight `w` of the *first* one, `a`:
//!
//! ```text
//! Checkerboard { Transform { <xform>* } materialIndex a materialIndex b }
//!     unit cubes alternate: w = 1 (a) where floor(x) + floor(y) + floor(z) is even, 0 (b) where odd
//! Noise  { ... materialIndex a materialIndex b octaves k }
//!     N(q) = sum over i < k of noise(2^i q) / 2^i          (k = 0: N = 0)
//!     w = clamp(N(q) + 1/2, 0, 1)                           (noise is centred on 0)
//! Marble { ... octaves k frequency f amplitude s }
//!     w = (1 + sin(f x + s N(q))) / 2
//! Wood   { ... octaves k frequency f amplitude s }          (whitted's design; see below)
//!     w = clamp(1/2 + 1.2 sin(f (r + y / 20) + s N(x, y / 4, z)), 0, 1),  r = sqrt(x^2 + z^2)
//! ```
//!
//! `noise` is Ken Perlin's improved noise (2002), the course's `perlin_noise.C`. A blend
//! interpolates the two materials' *shading results*, as the handout's 11/2 update asks:
//! direct light is `w shade(a) + (1 - w) shade(b)`, each material shaded with its own Phong
//! exponent ([`Scene::for_each_layer`]); the ambient term, mirror and transparent colours and
//! the index of refraction are the materials' parameters interpolated at the point
//! ([`Scene::phong_at`], the handout's "accessors that take the world coordinate").
//!
//! Wood is free design in the handout. Ours is fitted to its instructor image
//! (`output6_16_fix`): rings about the texture-space y axis with period `2 pi / f` in the
//! radius, growing slightly along the axis (`r + y / 20`, a tapering trunk), sharpened towards a
//! square wave (`1.2 sin`, clamped) so early and late wood read as two colours, and perturbed by
//! noise whose grain is stretched four times along the axis (`N(x, y / 4, z)`), as wood fibres
//! are. It agrees with the instructor's picture on 82% of pixels within 2/255 (the noise
//! perturbation of the instructor's own formula is not recoverable from one image).

use super::{Material, Phong, Scene};
use crate::math::{Mat4, Vec3};

/// Which solid texture, with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TextureKind {
    Checkerboard,
    Noise {
        octaves: u32,
    },
    Marble {
        octaves: u32,
        frequency: f32,
        amplitude: f32,
    },
    Wood {
        octaves: u32,
        frequency: f32,
        amplitude: f32,
    },
}

/// A solid texture between materials `a` (the first `materialIndex`) and `b`.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub kind: TextureKind,
    /// World space to texture space.
    pub matrix: Mat4,
    pub a: u32,
    pub b: u32,
}

impl Texture {
    /// The weight of material `a` at world point `p`, in `[0, 1]` (1 gives `a`, 0 gives `b`).
    pub fn weight(&self, p: Vec3) -> f32 {
        let q = self.matrix.transform_point3(p);
        match self.kind {
            TextureKind::Checkerboard => {
                let parity = q.x.floor() as i64 + q.y.floor() as i64 + q.z.floor() as i64;
                1.0 - parity.rem_euclid(2) as f32
            }
            TextureKind::Noise { octaves } => (turbulence(q, octaves) + 0.5).clamp(0.0, 1.0),
            TextureKind::Marble {
                octaves,
                frequency,
                amplitude,
            } => 0.5 * (1.0 + (frequency * q.x + amplitude * turbulence(q, octaves)).sin()),
            TextureKind::Wood {
                octaves,
                frequency,
                amplitude,
            } => {
                let r = (q.x * q.x + q.z * q.z).sqrt();
                let grain = Vec3::new(q.x, q.y * 0.25, q.z);
                let phase = frequency * (r + q.y * 0.05) + amplitude * turbulence(grain, octaves);
                (0.5 + 1.2 * phase.sin()).clamp(0.0, 1.0)
            }
        }
    }
}

impl Scene {
    /// The Phong parameters of material `index` at world point `p`, textures resolved by
    /// interpolating their materials' parameters (the parser guarantees textures never refer
    /// back to themselves). These give the ambient term, the mirror and transparent colours and
    /// the index of refraction; direct light blends shading results ([`Scene::for_each_layer`]).
    ///
    /// A copy of what [`Scene::material_at`] borrows, for callers that take one field (the
    /// transparent shadows: the transparent colour); always inlined, so for a plain material
    /// only that field is read. Shading borrows the parameters instead.
    #[inline(always)]
    pub fn phong_at(&self, index: u32, p: Vec3) -> Phong {
        let mut blend = Phong::default();
        *self.material_at(index, p, &mut blend)
    }

    /// The Phong parameters of material `index` at world point `p`, as [`Scene::phong_at`]
    /// gives them, borrowed: a plain material's from the scene, a texture's written to `blend`
    /// first. The shading's surface holds this reference; it held a copy, and in the
    /// wavefront's shading loop the copy was copied again through the stack, the second copy
    /// waiting on the first one's stores (PERF.md, sitting 38).
    #[inline(always)]
    pub fn material_at<'m>(&'m self, index: u32, p: Vec3, blend: &'m mut Phong) -> &'m Phong {
        match &self.materials[index as usize] {
            Material::Phong(m) => m,
            Material::Texture(_) => {
                *blend = self.texture_phong_at(index, p);
                blend
            }
        }
    }

    /// [`Scene::phong_at`] of a texture.
    #[inline(never)]
    fn texture_phong_at(&self, index: u32, p: Vec3) -> Phong {
        match &self.materials[index as usize] {
            Material::Phong(m) => *m,
            Material::Texture(t) => {
                let w = t.weight(p);
                if w >= 1.0 {
                    self.texture_phong_at(t.a, p)
                } else if w <= 0.0 {
                    self.texture_phong_at(t.b, p)
                } else {
                    lerp_phong(
                        &self.texture_phong_at(t.b, p),
                        &self.texture_phong_at(t.a, p),
                        w,
                    )
                }
            }
        }
    }

    /// Calls `f(material, weight)` for every plain material that material `index` shows at
    /// world point `p`, with its share of the blend (the shares sum to 1): once with weight 1
    /// for a plain material; for a texture, each side's layers scaled by its weight, sides of
    /// weight 0 skipped. Shading results summed with these weights are the handout's
    /// "interpolated `Material::Shade`".
    ///
    /// Always inlined, the texture case apart, as [`Scene::phong_at`] is: a plain material's
    /// shading then runs in its caller, not behind the recursion and a closure whose sum went
    /// through memory (PERF.md, sitting 38).
    #[inline(always)]
    pub fn for_each_layer(&self, index: u32, p: Vec3, f: &mut impl FnMut(&Phong, f32)) {
        match &self.materials[index as usize] {
            Material::Phong(m) => f(m, 1.0),
            Material::Texture(_) => self.layers(index, p, 1.0, f),
        }
    }

    fn layers(&self, index: u32, p: Vec3, share: f32, f: &mut impl FnMut(&Phong, f32)) {
        match &self.materials[index as usize] {
            Material::Phong(m) => f(m, share),
            Material::Texture(t) => {
                let w = t.weight(p);
                if w > 0.0 {
                    self.layers(t.a, p, share * w, f);
                }
                if w < 1.0 {
                    self.layers(t.b, p, share * (1.0 - w), f);
                }
            }
        }
    }
}

fn lerp_phong(a: &Phong, b: &Phong, w: f32) -> Phong {
    Phong {
        diffuse: a.diffuse.lerp(b.diffuse, w),
        specular: a.specular.lerp(b.specular, w),
        exponent: a.exponent + (b.exponent - a.exponent) * w,
        reflective: a.reflective.lerp(b.reflective, w),
        transparent: a.transparent.lerp(b.transparent, w),
        ior: a.ior + (b.ior - a.ior) * w,
    }
}

/// `N(p) = sum over i < octaves of noise(2^i p) / 2^i`.
pub fn turbulence(p: Vec3, octaves: u32) -> f32 {
    let mut sum = 0.0;
    let mut scale = 1.0;
    for _ in 0..octaves {
        sum += noise(p * scale) / scale;
        scale *= 2.0;
    }
    sum
}

/// Ken Perlin's improved noise: smooth, in about [-1, 1], zero at integer lattice points.
pub fn noise(p: Vec3) -> f32 {
    let cell = p.floor();
    let (x, y, z) = (
        cell.x as i64 as usize & 255,
        cell.y as i64 as usize & 255,
        cell.z as i64 as usize & 255,
    );
    let f = p - cell;
    let (u, v, w) = (fade(f.x), fade(f.y), fade(f.z));
    let perm = |i: usize| PERMUTATION[i & 255] as usize;
    let a = perm(x) + y;
    let (aa, ab) = (perm(a) + z, perm(a + 1) + z);
    let b = perm(x + 1) + y;
    let (ba, bb) = (perm(b) + z, perm(b + 1) + z);
    let (fx, fy, fz) = (f.x, f.y, f.z);
    lerp(
        w,
        lerp(
            v,
            lerp(
                u,
                grad(perm(aa), fx, fy, fz),
                grad(perm(ba), fx - 1.0, fy, fz),
            ),
            lerp(
                u,
                grad(perm(ab), fx, fy - 1.0, fz),
                grad(perm(bb), fx - 1.0, fy - 1.0, fz),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(perm(aa + 1), fx, fy, fz - 1.0),
                grad(perm(ba + 1), fx - 1.0, fy, fz - 1.0),
            ),
            lerp(
                u,
                grad(perm(ab + 1), fx, fy - 1.0, fz - 1.0),
                grad(perm(bb + 1), fx - 1.0, fy - 1.0, fz - 1.0),
            ),
        ),
    )
}

fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// The dot product of `(x, y, z)` with one of 12 gradient directions chosen by `hash`.
fn grad(hash: usize, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// Perlin's permutation of 0..=255.
const PERMUTATION: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permutation_is_a_permutation() {
        let mut seen = [false; 256];
        for &p in &PERMUTATION {
            assert!(!std::mem::replace(&mut seen[p as usize], true));
        }
    }

    #[test]
    fn noise_is_zero_on_the_lattice_and_bounded() {
        assert_eq!(noise(Vec3::new(3.0, -2.0, 7.0)), 0.0);
        for i in 0..1000 {
            let p = Vec3::new(i as f32 * 0.137, i as f32 * -0.071, i as f32 * 0.029);
            let n = noise(p);
            assert!(n.abs() <= 1.05, "{n}");
        }
        assert_ne!(noise(Vec3::new(0.5, 0.25, 0.75)), 0.0);
    }

    #[test]
    fn checkerboard_alternates_across_negative_coordinates() {
        let t = Texture {
            kind: TextureKind::Checkerboard,
            matrix: Mat4::IDENTITY,
            a: 0,
            b: 1,
        };
        // The weight is the first material's: 1 on even cubes.
        assert_eq!(t.weight(Vec3::new(0.5, 0.5, 0.5)), 1.0);
        assert_eq!(t.weight(Vec3::new(1.5, 0.5, 0.5)), 0.0);
        assert_eq!(t.weight(Vec3::new(-0.5, 0.5, 0.5)), 0.0);
        assert_eq!(t.weight(Vec3::new(-1.5, 0.5, 0.5)), 1.0);
        assert_eq!(t.weight(Vec3::new(-1.5, -0.5, 0.5)), 0.0);
    }
}
