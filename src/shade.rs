//! Whitted shading, shared by both tracers: what a hit looks like under each light, which shadow
//! ray decides whether that light counts, and where the ray goes next (mirror and refracted
//! children with their colour weights). The reference tracer calls these recursively; the packet
//! tracer calls the same functions per queued ray and pushes the children onto next bounce's
//! queues. Routing ("where does this ray go next") lives only in [`scatter`].
//!
//! The model is the MIT 6.837 one: `ambient * diffuse + sum over lights of
//! light * (diffuse * max(n.l, 0) + specular * max(n.h, 0)^q)`, with the specular term scaled by
//! `max(n.l, 0)` (the lecture's fix; off with `specular_fix = false`, which only clamps it to
//! zero where `n.l <= 0`). Back faces are black unless `shade_back` flips their normal.
//!
//! Smooth meshes shade with their interpolated normal; the geometric normal still decides the
//! side a ray hit, whether a light is above the surface, and that mirror and refracted rays
//! leave on their own side of it.

use crate::intersect::Hit;
use crate::math::{Ray, Vec3, reflect, refract, saturate, schlick};
use crate::scene::{Light, Phong, Scene};

/// Self-intersection offset: shadow, mirror and refracted rays start at `t = EPSILON`.
pub const EPSILON: f32 = 1e-3;

/// The switches of the shading model (the course's command-line options).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadeOptions {
    /// Cast shadow rays (`-shadows`).
    pub shadows: bool,
    /// Shade back faces by flipping their normal (`-shade_back`); otherwise they are black.
    pub shade_back: bool,
    /// Maximum number of mirror/refraction bounces (`-bounces`).
    pub bounces: u32,
    /// Children whose weight falls below this are not traced (`-weight`).
    pub weight: f32,
    /// Scale the specular term by `max(n.l, 0)` (the lecture's fix).
    pub specular_fix: bool,
    /// Shadows are tinted by the transparent colour of the occluders instead of black.
    pub transparent_shadows: bool,
    /// Split transparent colour between reflection and refraction with Schlick's Fresnel term.
    pub fresnel: bool,
}

impl Default for ShadeOptions {
    fn default() -> ShadeOptions {
        ShadeOptions {
            shadows: false,
            shade_back: false,
            bounces: 5,
            weight: 0.01,
            specular_fix: true,
            transparent_shadows: false,
            fresnel: false,
        }
    }
}

/// A hit ready to shade.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface<'m> {
    pub point: Vec3,
    /// The shading normal (a smooth mesh's interpolated one, else the geometric normal), on the
    /// side the ray arrived from (flipped with the geometric normal when `shade_back`).
    pub normal: Vec3,
    /// The geometric normal on the side the ray arrived from: it decides whether a light is
    /// above the surface and keeps mirror and refracted rays on their side of it.
    pub geometric: Vec3,
    /// True when the ray arrived from the side the geometric normal points to.
    pub front: bool,
    /// The material's parameters at the point (textures interpolated: the ambient term,
    /// mirror and transparent colours and index of refraction come from here): a plain
    /// material's own, in the scene, or a texture's blend, in the caller's `blend`.
    pub material: &'m Phong,
    /// The material's index, for direct light, which blends the shading of a texture's
    /// materials rather than their parameters ([`Scene::for_each_layer`]).
    pub material_index: u32,
}

/// Prepares `hit` for shading; `None` means the pixel contribution is black (a back face
/// without `shade_back`). A texture's blended parameters are written to `blend`, which the
/// surface then borrows; a plain material is borrowed from the scene, not copied (the copies
/// waited on their own stores: PERF.md, sitting 38). Always inlined, so that the packet
/// tracer's shading loop (`wavefront::stages::shade_hits`) keeps it inside (sitting 54).
#[inline(always)]
pub fn surface<'m>(
    scene: &'m Scene,
    ray: &Ray,
    hit: &Hit,
    opts: &ShadeOptions,
    blend: &'m mut Phong,
) -> Option<Surface<'m>> {
    let front = hit.normal.dot(ray.dir) <= 0.0;
    if !front && !opts.shade_back {
        return None;
    }
    let point = ray.at(hit.t);
    let material = scene.material_at(hit.material, point, blend);
    let geometric = if front { hit.normal } else { -hit.normal };
    // Corner normals that disagree with the winding still shade the side the ray hit.
    let shading = if hit.shading.dot(geometric) < 0.0 {
        -hit.shading
    } else {
        hit.shading
    };
    let normal = if hit.shading == hit.normal {
        geometric
    } else {
        shading
    };
    Some(Surface {
        point,
        normal,
        geometric,
        front,
        material,
        material_index: hit.material,
    })
}

/// The ambient term of a surface.
#[inline]
pub fn ambient(scene: &Scene, s: &Surface) -> Vec3 {
    scene.ambient * s.material.diffuse
}

/// Blinn-Phong for one light: `light * (kd max(n.l,0) + ks max(n.h,0)^q [* max(n.l,0)])`; zero
/// when the surface faces away from the light. `view` is the viewing ray's direction made unit
/// (`dir.normalize()`), once for all the lights of a hit.
#[inline]
pub fn phong(m: &Phong, view: Vec3, n: Vec3, l: Vec3, light: Vec3, specular_fix: bool) -> Vec3 {
    let nl = n.dot(l);
    if nl <= 0.0 || nl.is_nan() {
        return Vec3::ZERO;
    }
    let h = (l - view).normalize_or_zero();
    let nh = n.dot(h).max(0.0);
    // A black specular colour (the course's default) adds nothing, so `powf` (8% of a bunny
    // frame's samples, its plane being black) is skipped, with the same bits: for exponents in
    // 0..=1e6 the power of `nh` (at most 1 plus rounding) is finite and not negative, so black
    // times it is black times 0, the same signed zero.
    let mut spec = if m.specular == Vec3::ZERO && (0.0..=1e6).contains(&m.exponent) {
        0.0
    } else {
        nh.powf(m.exponent)
    };
    if specular_fix {
        spec *= nl;
    }
    light * (m.diffuse * nl + m.specular * spec)
}

/// One light's contribution to a surface, before the shadow test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// What the light adds if nothing blocks it.
    pub color: Vec3,
    /// The shadow ray: from the surface point towards the light.
    pub shadow: Ray,
    /// The shadow ray is blocked by hits with `EPSILON < t < max_t`.
    pub max_t: f32,
}

/// The contribution of `light` to `s` seen along the unit direction `view` (the ray's
/// `dir.normalize()`, made once for every light), with the shadow ray that decides it; `None`
/// when the light adds nothing (surface facing away). On a solid texture it is the blend of
/// each of its materials' own Blinn-Phong result.
///
/// Always inlined into the shading loops, as [`scatter`] is (PERF.md, sitting 37).
#[inline(always)]
pub fn light_sample(
    scene: &Scene,
    s: &Surface,
    view: Vec3,
    light: &Light,
    opts: &ShadeOptions,
) -> Option<LightSample> {
    let ill = light.illuminate(s.point);
    // A light below the geometric surface is blocked by the surface itself, whatever the
    // shading normal says (with shadows, the shadow ray would hit the mesh).
    if s.geometric.dot(ill.dir) <= 0.0 {
        return None;
    }
    let mut color = Vec3::ZERO;
    scene.for_each_layer(s.material_index, s.point, &mut |m, w| {
        color += w * phong(m, view, s.normal, ill.dir, ill.color, opts.specular_fix);
    });
    let color = saturate(color);
    if color == Vec3::ZERO {
        return None;
    }
    Some(LightSample {
        color,
        shadow: Ray::new(s.point, ill.dir),
        max_t: ill.distance,
    })
}

/// A child ray: where it goes, the colour its result is multiplied by, its weight for the
/// cutoff test, and whether it travels inside an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spawn {
    pub ray: Ray,
    pub color: Vec3,
    pub weight: f32,
}

/// The children of a surface hit: mirror and refracted rays, each `None` when not traced
/// (black material colour, bounce limit reached, weight under the cutoff, or total internal
/// reflection for the refracted ray). `geometric` is the unflipped normal that decides whether
/// the ray enters or leaves (objects sit in vacuum, no nesting).
///
/// Always inlined: as a plain `#[inline]` LLVM stopped inlining it into the wavefront's
/// `shade_hits` when `intersect_closest` beside it changed, and the showcase frame took 5-6%
/// longer, every bounce (PERF.md, sitting 32).
#[inline(always)]
pub fn scatter(
    s: &Surface,
    dir: Vec3,
    geometric: Vec3,
    weight: f32,
    bounce: u32,
    opts: &ShadeOptions,
) -> [Option<Spawn>; 2] {
    if bounce >= opts.bounces {
        return [None, None];
    }
    let m = s.material;
    let mut reflective = m.reflective;
    let mut transparent = m.transparent;
    let mut refracted = None;
    if transparent != Vec3::ZERO {
        let entering = geometric.dot(dir) < 0.0;
        let (n, n_i, n_t) = if entering {
            (geometric, 1.0, m.ior)
        } else {
            (-geometric, m.ior, 1.0)
        };
        // Bent by the shading normal (on the arrival side), unless that would send the ray
        // back out of the geometric surface.
        let ns = if s.normal.dot(n) < 0.0 {
            -s.normal
        } else {
            s.normal
        };
        refracted = match refract(dir, ns, n_i / n_t) {
            Some(t) if t.dot(n) >= 0.0 => refract(dir, n, n_i / n_t),
            bent => bent,
        };
        if opts.fresnel {
            let f = schlick(-dir.normalize().dot(ns), n_i, n_t);
            reflective += transparent * f;
            transparent *= 1.0 - f;
        }
    }
    let child = |color: Vec3, d: Vec3| {
        let w = weight * color.length();
        (color != Vec3::ZERO && w >= opts.weight).then(|| Spawn {
            ray: Ray::new(s.point, d),
            color,
            weight: w,
        })
    };
    // Mirrored about the shading normal, unless that would send the ray into the surface.
    let mut mirrored = reflect(dir, s.normal);
    if mirrored.dot(s.geometric) < 0.0 {
        mirrored = reflect(dir, s.geometric);
    }
    let mirror = child(reflective, mirrored.normalize());
    let transmitted = refracted.and_then(|t| child(transparent, t));
    [mirror, transmitted]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    fn mat() -> Phong {
        Phong {
            diffuse: Vec3::new(0.5, 0.5, 0.5),
            specular: Vec3::ONE,
            exponent: 10.0,
            ..Phong::default()
        }
    }

    #[test]
    fn surfaces_facing_away_from_the_light_are_not_lit() {
        let c = phong(&mat(), -Vec3::Z, Vec3::Z, -Vec3::X, Vec3::ONE, true);
        assert_eq!(c, Vec3::ZERO);
        let c = phong(
            &mat(),
            -Vec3::Z,
            Vec3::Z,
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::ONE,
            false,
        );
        assert_eq!(c, Vec3::ZERO);
    }

    #[test]
    fn specular_fix_scales_by_n_dot_l() {
        let l = Vec3::new(1.0, 0.0, 0.2).normalize();
        let d = Vec3::new(1.0, 0.0, -0.2).normalize(); // mirror direction: n.h is 1
        let plain = phong(&mat(), d, Vec3::Z, l, Vec3::ONE, false);
        let fixed = phong(&mat(), d, Vec3::Z, l, Vec3::ONE, true);
        let nl = l.z;
        assert!((plain.x - (0.5 * nl + 1.0)).abs() < 1e-5);
        assert!((fixed.x - (0.5 * nl + nl)).abs() < 1e-5);
    }

    /// Blinn-Phong as written before the black-specular shortcut: `powf` always.
    fn phong_with_powf(m: &Phong, view: Vec3, n: Vec3, l: Vec3, light: Vec3, fix: bool) -> Vec3 {
        let nl = n.dot(l);
        if nl <= 0.0 || nl.is_nan() {
            return Vec3::ZERO;
        }
        let h = (l - view).normalize_or_zero();
        let mut spec = n.dot(h).max(0.0).powf(m.exponent);
        if fix {
            spec *= nl;
        }
        light * (m.diffuse * nl + m.specular * spec)
    }

    #[test]
    fn black_specular_gives_the_bits_powf_gives() {
        let mut rng = Rng(0x2545_f491);
        let mut cases = Vec::new();
        for _ in 0..4000 {
            let mut v = || rng.vec(-1.0, 1.0);
            let (n, l, view) = (v().normalize(), v().normalize(), v().normalize());
            cases.push((n, l, view, v()));
        }
        // n.h rounded to just above 1 (light along the normal, seen head on), and n.h = 0
        // on a lit surface (pow(0, negative) is infinite: black times it is NaN)
        for k in 0..200 {
            let n = Vec3::new(k as f32 * 0.013 - 1.3, 0.7, 0.3).normalize();
            cases.push((n, n, -n, Vec3::splat(0.5)));
        }
        cases.push((Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::Z, Vec3::ONE));
        let blacks = [Vec3::ZERO, Vec3::splat(-0.0), Vec3::new(0.0, -0.0, 0.0)];
        let exponents = [
            -0.0,
            0.0,
            1e-3,
            1.0,
            10.0,
            100.0,
            1e6,
            1e7,
            1e30,
            f32::INFINITY,
            -1.0,
            f32::NAN,
        ];
        let bits = |c: Vec3| c.to_array().map(f32::to_bits);
        for (n, l, view, diffuse) in cases {
            for specular in blacks {
                for exponent in exponents {
                    for diffuse in [diffuse, Vec3::splat(-0.0)] {
                        let m = Phong {
                            diffuse,
                            specular,
                            exponent,
                            ..Phong::default()
                        };
                        for fix in [false, true] {
                            let (fast, full) = (
                                phong(&m, view, n, l, Vec3::ONE, fix),
                                phong_with_powf(&m, view, n, l, Vec3::ONE, fix),
                            );
                            assert_eq!(bits(fast), bits(full), "{m:?} n {n} l {l} view {view}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn head_on_light_gives_diffuse_plus_specular() {
        let c = phong(&mat(), -Vec3::Z, Vec3::Z, Vec3::Z, Vec3::ONE, true);
        assert!((c - Vec3::splat(1.5)).length() < 1e-6);
    }
}
