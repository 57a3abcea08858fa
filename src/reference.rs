//! The scalar reference tracer: the specification every faster path is held to. It is the
//! lecture's algorithm and nothing clever: one ray at a time, brute force over the object tree
//! as parsed (transforms move the ray into object space, `t` stays in world units because the
//! direction is not renormalised, normals come back through the inverse transpose), recursion for
//! mirror and refracted rays, one any-hit shadow ray per light.
//!
//! ```text
//! trace(ray) = background                                 if nothing is hit
//!            = 0                                          on a back face without shade_back
//!            = ambient + sum_lights visible * phong
//!              + reflective * trace(mirror) + transparent * trace(refracted)
//! ```

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::film::{FilmSpec, SampleBlock, render_film};
use crate::frame::Frame;
use crate::grid::Grid;
use crate::grid::picture::{self, GridView};
use crate::intersect::{Hit, intersect_plane, intersect_sphere, intersect_triangle};
use crate::math::{Ray, Vec3, barycentrics, saturate, transform_normal};
use crate::options::{FinishedRows, Progress, RenderOptions, stack_size};
use crate::raytree::{RayTree, SegmentId, SegmentKind};
use crate::scene::normals::interpolate;
use crate::scene::{Camera, Object, Phong, Scene};
use crate::shade::{self, EPSILON, ShadeOptions};
use crate::stats::RayCounts;

/// The closest hit of `ray` with `obj` in `(tmin, tmax)`.
pub fn closest_hit(obj: &Object, ray: &Ray, tmin: f32, tmax: f32) -> Option<Hit> {
    let mut best = None;
    intersect(obj, ray, tmin, tmax, &mut best);
    best
}

/// Updates `best` if `obj` has a hit nearer than it (and than `tmax`); true if it did.
fn intersect(obj: &Object, ray: &Ray, tmin: f32, tmax: f32, best: &mut Option<Hit>) -> bool {
    let limit = best.map_or(tmax, |h| h.t);
    match obj {
        Object::Sphere {
            center,
            radius,
            material,
            id,
        } => match intersect_sphere(*center, radius * radius, ray, tmin, limit) {
            Some(t) => {
                // A ray through the very centre of a tiny sphere has no direction to normalise:
                // face it back along the ray rather than produce NaN.
                let normal = (ray.at(t) - *center).normalize_or(-ray.dir.normalize());
                *best = Some(Hit {
                    t,
                    normal,
                    shading: normal,
                    material: *material,
                    prim: *id,
                });
                true
            }
            None => false,
        },
        Object::Plane {
            normal,
            offset,
            material,
            id,
        } => match intersect_plane(*normal, *offset, ray, tmin, limit) {
            Some(t) => {
                *best = Some(Hit {
                    t,
                    normal: *normal,
                    shading: *normal,
                    material: *material,
                    prim: *id,
                });
                true
            }
            None => false,
        },
        Object::Triangle { v, material, id } => {
            intersect_one_triangle(v, None, *material, *id, ray, tmin, limit, best)
        }
        Object::Mesh {
            triangles,
            normals,
            material,
            first_id,
        } => {
            let mut found = false;
            for (k, v) in triangles.iter().enumerate() {
                let limit = best.map_or(tmax, |h| h.t);
                let id = first_id + k as u32;
                let corners = normals.get(k);
                found |= intersect_one_triangle(v, corners, *material, id, ray, tmin, limit, best);
            }
            found
        }
        Object::Group(children) => {
            let mut found = false;
            for child in children {
                found |= intersect(child, ray, tmin, tmax, best);
            }
            found
        }
        Object::Transform(tr) => {
            let local = Ray::new(
                tr.inverse.transform_point3(ray.origin),
                tr.inverse.transform_vector3(ray.dir),
            );
            let mut local_best = *best;
            if intersect(&tr.child, &local, tmin, tmax, &mut local_best) {
                let mut hit = local_best.expect("a hit was found");
                let flat = hit.shading == hit.normal;
                hit.normal = transform_normal(&tr.normal_matrix, hit.normal);
                hit.shading = if flat {
                    hit.normal
                } else {
                    transform_normal(&tr.normal_matrix, hit.shading)
                };
                *best = Some(hit);
                true
            } else {
                false
            }
        }
    }
}

/// One triangle, with its corner normals if it is shaded smoothly (the barycentrics that
/// interpolate them are computed only for the hit).
#[allow(clippy::too_many_arguments)] // reason: the triangle, its material and id, the query
fn intersect_one_triangle(
    v: &[Vec3; 3],
    corners: Option<&[Vec3; 3]>,
    material: u32,
    prim: u32,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
    best: &mut Option<Hit>,
) -> bool {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    match intersect_triangle(v[0], e1, e2, ray, tmin, tmax) {
        Some(t) => {
            let normal = e1.cross(e2).normalize();
            let shading = match corners {
                Some(n) => {
                    let (u, w) = barycentrics(v[0], e1, e2, ray);
                    interpolate(n, u, w, normal)
                }
                None => normal,
            };
            *best = Some(Hit {
                t,
                normal,
                shading,
                material,
                prim,
            });
            true
        }
        None => false,
    }
}

/// True if anything of `obj` lies on the ray in `(tmin, tmax)`; stops at the first such hit.
pub fn any_hit(obj: &Object, ray: &Ray, tmin: f32, tmax: f32) -> bool {
    match obj {
        Object::Sphere { center, radius, .. } => {
            intersect_sphere(*center, radius * radius, ray, tmin, tmax).is_some()
        }
        Object::Plane { normal, offset, .. } => {
            intersect_plane(*normal, *offset, ray, tmin, tmax).is_some()
        }
        Object::Triangle { v, .. } => {
            intersect_triangle(v[0], v[1] - v[0], v[2] - v[0], ray, tmin, tmax).is_some()
        }
        Object::Mesh { triangles, .. } => triangles
            .iter()
            .any(|v| intersect_triangle(v[0], v[1] - v[0], v[2] - v[0], ray, tmin, tmax).is_some()),
        Object::Group(children) => children.iter().any(|c| any_hit(c, ray, tmin, tmax)),
        Object::Transform(tr) => {
            let local = Ray::new(
                tr.inverse.transform_point3(ray.origin),
                tr.inverse.transform_vector3(ray.dir),
            );
            any_hit(&tr.child, &local, tmin, tmax)
        }
    }
}

/// How much light passes along a shadow ray: 1 if nothing is in the way; with transparent
/// shadows, the product of the transparent colours of every surface crossed; else 0.
fn visibility(scene: &Scene, ray: &Ray, max_t: f32, opts: &ShadeOptions) -> Vec3 {
    if !opts.transparent_shadows {
        return if any_hit(&scene.root, ray, EPSILON, max_t) {
            Vec3::ZERO
        } else {
            Vec3::ONE
        };
    }
    let mut light = Vec3::ONE;
    let mut tmin = EPSILON;
    while let Some(hit) = closest_hit(&scene.root, ray, tmin, max_t) {
        light = saturate(light * scene.phong_at(hit.material, ray.at(hit.t)).transparent);
        if light == Vec3::ZERO {
            break;
        }
        tmin = hit.t;
    }
    light
}

/// Renders with the reference tracer: the film streams bands of rows in parallel, and each
/// band traces its samples one by one, counting its rays locally (the counts are summed at
/// the end).
pub fn render_reference(scene: &Scene, opts: &RenderOptions, progress: Progress) -> Result<Frame> {
    let tracer = ReferenceTracer::new(scene, opts.shade);
    let spec = FilmSpec::for_options(opts);
    let (film, counts) = render_film(
        &spec,
        progress,
        || (),
        |_, block| Ok(tracer.trace_block(block)),
    )?;
    let rays = counts
        .into_iter()
        .fold(RayCounts::default(), RayCounts::merged);
    Ok(film.into_frame(rays))
}

/// Draws the grid picture of `grid` (see [`crate::grid::picture`]): one camera ray per pixel,
/// rows in parallel, each marched through the grid by the march the packet tracer shares.
pub fn render_grid_reference(
    scene: &Scene,
    grid: &Grid,
    view: GridView,
    opts: &RenderOptions,
    progress: Progress,
) -> Frame {
    let (w, h) = (opts.width, opts.height);
    let mut frame = Frame::new(w, h);
    frame
        .color
        .par_chunks_mut(w as usize)
        .zip(frame.depth.par_chunks_mut(w as usize))
        .zip(frame.normal.par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(y, ((color, depth), normal))| {
            for x in 0..w {
                let ray = scene
                    .camera
                    .generate_ray(Camera::pixel_point(x, y as u32, w, h));
                let i = x as usize;
                let (c, hit) = picture::pixel(scene, grid, view, &ray, scene.camera.tmin());
                color[i] = c;
                if let Some((t, n)) = hit {
                    depth[i] = t;
                    normal[i] = n;
                }
            }
            progress(&FinishedRows::counted(1));
        });
    frame
        .rays
        .count_many(SegmentKind::Eye, 0, w as u64 * h as u64);
    frame
}

/// Traces pixel `(x, y)` of the frame `opts` describes once more, recording its ray tree;
/// returns the pixel's colour and the tree. With several samples per pixel, the tree is that of
/// the sample nearest the pixel centre, and the colour that sample's. The tracer recurses once
/// per bounce, so it runs on a thread with the render's stack.
pub fn trace_pixel_tree(
    scene: &Scene,
    opts: &RenderOptions,
    x: u32,
    y: u32,
) -> Result<(Vec3, RayTree)> {
    let offset = opts.sampler.nearest_offset(x, y);
    let ray =
        scene
            .camera
            .generate_ray(Camera::sample_screen(x, y, offset, opts.width, opts.height));
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(stack_size(opts.shade.bounces))
            .spawn_scoped(s, || {
                let mut tree = RayTree::new();
                let tracer = ReferenceTracer::new(scene, opts.shade);
                let sample = tracer.trace_primary(&ray, Some(&mut tree));
                (sample.color, tree)
            })
            .map_err(|e| Error::Other(format!("cannot start a thread: {e}")))?
            .join()
            .map_err(|_| Error::Other("the ray-tree thread failed".to_string()))
    })
}

/// The reference tracer over one scene with fixed options.
pub struct ReferenceTracer<'s> {
    pub scene: &'s Scene,
    pub opts: ShadeOptions,
}

/// What a primary ray found: the pixel colour and, for the depth and normal images, the hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimarySample {
    pub color: Vec3,
    pub hit: Option<Hit>,
}

impl<'s> ReferenceTracer<'s> {
    /// A tracer for `scene`.
    pub fn new(scene: &'s Scene, opts: ShadeOptions) -> ReferenceTracer<'s> {
        ReferenceTracer { scene, opts }
    }

    /// Traces every sample of `block`, one camera ray each, in slot order; returns the rays cast.
    pub fn trace_block(&self, block: &mut SampleBlock) -> RayCounts {
        let mut rays = RayCounts::default();
        for slot in 0..block.len() {
            let ray = self.scene.camera.generate_ray(block.screen_point(slot));
            let sample = self.trace_primary_counted(&ray, None, &mut rays);
            block.color[slot] = sample.color;
            if let Some(hit) = sample.hit {
                block.record_hit(slot, hit.t, hit.shading);
            }
        }
        rays
    }

    /// Traces a primary ray, recording its tree into `tree` when given.
    pub fn trace_primary(&self, ray: &Ray, tree: Option<&mut RayTree>) -> PrimarySample {
        self.trace_primary_counted(ray, tree, &mut RayCounts::default())
    }

    /// Traces a primary ray, adding every ray cast to `counts` and recording the ray tree
    /// into `tree` when given (the tree also names each shadow ray's nearest occluder, which
    /// costs a closest-hit query per shadow ray, so only the ray-tree pixel pays it).
    pub fn trace_primary_counted(
        &self,
        ray: &Ray,
        tree: Option<&mut RayTree>,
        counts: &mut RayCounts,
    ) -> PrimarySample {
        let mut log = Log { tree, counts };
        log.counts.count(SegmentKind::Eye, 0);
        let hit = closest_hit(
            &self.scene.root,
            ray,
            self.scene.camera.tmin(),
            f32::INFINITY,
        );
        let color = self.shade(ray, hit, 0, 1.0, SegmentKind::Eye, None, &mut log);
        PrimarySample { color, hit }
    }

    /// The colour seen along `ray` (a secondary ray, starting at `EPSILON`).
    fn trace(
        &self,
        ray: &Ray,
        bounce: u32,
        weight: f32,
        kind: SegmentKind,
        parent: Option<SegmentId>,
        log: &mut Log,
    ) -> Vec3 {
        log.counts.count(kind, bounce);
        let hit = closest_hit(&self.scene.root, ray, EPSILON, f32::INFINITY);
        self.shade(ray, hit, bounce, weight, kind, parent, log)
    }

    #[allow(clippy::too_many_arguments)] // reason: the recursion state of one ray, kept flat for reading
    fn shade(
        &self,
        ray: &Ray,
        hit: Option<Hit>,
        bounce: u32,
        weight: f32,
        kind: SegmentKind,
        parent: Option<SegmentId>,
        log: &mut Log,
    ) -> Vec3 {
        let scene = self.scene;
        let me = log
            .tree
            .as_deref_mut()
            .map(|t| t.add_ray(kind, parent, ray, hit, bounce, weight));
        let Some(hit) = hit else {
            return scene.background;
        };
        let mut blend = Phong::default();
        let Some(s) = shade::surface(scene, ray, &hit, &self.opts, &mut blend) else {
            return Vec3::ZERO;
        };
        let mut color = shade::ambient(scene, &s);
        let view = ray.dir.normalize();
        for (index, light) in scene.lights.iter().enumerate() {
            let Some(sample) = shade::light_sample(scene, &s, view, light, &self.opts) else {
                continue;
            };
            let visible = if self.opts.shadows {
                log.counts.count(SegmentKind::Shadow, bounce);
                if let (Some(t), Some(me)) = (log.tree.as_deref_mut(), me) {
                    let occluder = closest_hit(&scene.root, &sample.shadow, EPSILON, sample.max_t);
                    t.add_shadow(me, index as u32, &sample.shadow, sample.max_t, occluder);
                }
                visibility(scene, &sample.shadow, sample.max_t, &self.opts)
            } else {
                Vec3::ONE
            };
            color += sample.color * visible;
        }
        let [mirror, refracted] =
            shade::scatter(&s, ray.dir, hit.normal, weight, bounce, &self.opts);
        if let Some(m) = mirror {
            color += m.color
                * self.trace(
                    &m.ray,
                    bounce + 1,
                    m.weight,
                    SegmentKind::Reflected,
                    me,
                    log,
                );
        }
        if let Some(r) = refracted {
            color += r.color
                * self.trace(
                    &r.ray,
                    bounce + 1,
                    r.weight,
                    SegmentKind::Transmitted,
                    me,
                    log,
                );
        }
        saturate(color)
    }
}

/// What tracing one pixel reports besides its colour: ray counts always, the tree when asked.
struct Log<'a> {
    tree: Option<&'a mut RayTree>,
    counts: &'a mut RayCounts,
}
