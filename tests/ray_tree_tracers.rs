//! Claim: both tracers record the same ray tree for a pixel: the same segments (kind, parent,
//! depth, primitive, material, light, blocked), in the same order once made canonical, with
//! origins, end points and weights within 1e-4. Checked on a grid of pixels of every scene in
//! `scenes/` and of every A4 course scene; with several samples per pixel, both follow the
//! sample nearest the pixel centre, whose colour in the render the tree's colour is.

mod common;

use std::path::Path;

use common::{course_dir, our_scenes, scene_files};
use whitted::RenderOptions;
use whitted::Tracer;
use whitted::render::trace_ray_tree;
use whitted::scene::Scene;
use whitted::shade::ShadeOptions;

/// Compares the trees of a 7x7 grid of pixels; returns how many segments were compared.
fn compare_trees(path: &Path, shade: ShadeOptions) -> usize {
    let scene = Scene::load(path).unwrap();
    let mut opts = RenderOptions {
        width: 120,
        height: 90,
        shade,
        ..RenderOptions::default()
    };
    let mut segments = 0;
    for gy in 0..7 {
        for gx in 0..7 {
            let (x, y) = (8 + gx * 17, 6 + gy * 13);
            opts.tracer = Tracer::Reference;
            let (reference, _) = trace_ray_tree(&scene, &opts, x, y).unwrap();
            opts.tracer = Tracer::Packet;
            let (packet, _) = trace_ray_tree(&scene, &opts, x, y).unwrap();
            reference.validate().unwrap();
            packet.validate().unwrap();
            if let Some(diff) = reference.first_difference(&packet, 1e-4) {
                panic!("{} pixel ({x}, {y}): {diff}", path.display());
            }
            segments += reference.segments.len();
        }
    }
    segments
}

fn full() -> ShadeOptions {
    ShadeOptions {
        shadows: true,
        shade_back: true,
        bounces: 5,
        ..ShadeOptions::default()
    }
}

#[test]
fn both_tracers_record_the_same_trees_on_our_scenes() {
    for path in our_scenes() {
        let n = compare_trees(&path, full());
        assert!(n > 49, "{}: only {n} segments", path.display());
        compare_trees(
            &path,
            ShadeOptions {
                transparent_shadows: true,
                fresnel: true,
                ..full()
            },
        );
    }
}

#[test]
fn both_tracers_record_the_same_trees_on_the_a4_course_scenes() {
    let Some(course) = course_dir() else {
        eprintln!("skipped: WHITTED_COURSE_DIR is not set");
        return;
    };
    let scenes = scene_files(&course.join("assignment4"));
    assert_eq!(scenes.len(), 14);
    for path in scenes {
        compare_trees(&path, full());
    }
}

#[test]
fn with_several_samples_both_tracers_follow_the_sample_nearest_the_centre() {
    use whitted::sampler::{Pattern, Sampler};
    use whitted::scene::Camera;
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.txt");
    let scene = Scene::load(&path).unwrap();
    let sampler = Sampler {
        pattern: Pattern::Jittered,
        count: 9,
        seed: 5,
    };
    let mut opts = RenderOptions {
        width: 120,
        height: 90,
        shade: full(),
        sampler,
        keep_samples: true,
        ..RenderOptions::default()
    };
    let frame = whitted::render(&scene, &opts).unwrap();
    for (x, y) in [(10, 10), (60, 45), (100, 70), (33, 80)] {
        opts.tracer = Tracer::Reference;
        let (reference, ref_color) = trace_ray_tree(&scene, &opts, x, y).unwrap();
        opts.tracer = Tracer::Packet;
        let (packet, color) = trace_ray_tree(&scene, &opts, x, y).unwrap();
        if let Some(diff) = reference.first_difference(&packet, 1e-4) {
            panic!("pixel ({x}, {y}): {diff}");
        }
        // The eye ray is the nearest sample's (jittered: not the pixel centre).
        let offset = sampler.nearest_offset(x, y);
        let ray = scene
            .camera
            .generate_ray(Camera::sample_screen(x, y, offset, 120, 90));
        let eye = &packet.segments[0];
        let dir = (eye.end - eye.origin).normalize();
        assert!((dir - ray.dir).length() < 1e-5, "pixel ({x}, {y})");
        let centre = scene
            .camera
            .generate_ray(Camera::pixel_point(x, y, 120, 90));
        assert!(
            (dir - centre.dir).length() > 1e-6,
            "pixel ({x}, {y}) is the centre"
        );
        // Its colour is that sample's in the render.
        let s = nearest_index(&sampler, x, y);
        let rendered = frame.samples[((y * 120 + x) * 9 + s) as usize];
        assert_eq!(color, rendered, "pixel ({x}, {y})");
        assert!((ref_color - rendered).abs().max_element() < 1e-5);
    }
}

fn nearest_index(sampler: &whitted::sampler::Sampler, x: u32, y: u32) -> u32 {
    let mut offsets = vec![whitted::math::Vec2::ZERO; sampler.count as usize];
    sampler.pixel_offsets(x, y, &mut offsets)
}
