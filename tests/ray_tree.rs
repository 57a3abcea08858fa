//! Claim: the ray tree of one pixel is complete and well formed. A glass-sphere pixel's tree
//! has all four kinds of segments (eye, shadow, reflected, transmitted), a pure mirror pixel's
//! has eye, shadow and reflected ones, and a mirror pixel that reflects glass has all four;
//! every child starts where its parent ends; the tree traced again is that of the rendered
//! pixel (same colour, both tracers); [`RayTree::canonical`] makes any recording order compare equal (as
//! the packet tracer's bounce-by-bounce order must); the JSON parses and holds every segment;
//! the witness picture shows every kind of segment the tree has, in its course colour; and
//! the CLI writes the JSON and a witness PNG of the requested size, refusing pixels outside
//! the image with exit code 2.

mod common;

use std::path::{Path, PathBuf};

use whitted::raytree::{EndKind, RayTree, SegmentKind, TreeSource};
use whitted::render::trace_ray_tree;
use whitted::scene::Scene;
use whitted::{RenderOptions, Tracer};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// `--size 400 300 --shadows --shade-back --bounces 5`.
fn options() -> RenderOptions {
    let mut opts = RenderOptions {
        width: 400,
        height: 300,
        ..RenderOptions::default()
    };
    opts.shade.shadows = true;
    opts.shade.shade_back = true;
    opts.shade.bounces = 5;
    opts
}

/// A pixel on the glass sphere, right of its centre.
const GLASS: (&str, u32, u32) = ("glass_sphere.txt", 230, 150);
/// A pixel on the left mirror of the facing mirrors: its reflections ping-pong.
const MIRROR: (&str, u32, u32) = ("facing_mirrors.txt", 60, 100);
/// A pixel on the showcase's mirror sphere where it reflects the glass sphere.
const MIRROR_SEES_GLASS: (&str, u32, u32) = ("showcase.txt", 275, 162);

fn tree_of((name, x, y): (&str, u32, u32)) -> RayTree {
    let scene = Scene::load(&scene_path(name)).unwrap();
    let (tree, _) = trace_ray_tree(&scene, &options(), x, y).unwrap();
    tree.validate().unwrap();
    tree
}

#[test]
fn a_glass_sphere_pixel_has_all_four_kinds_of_segments() {
    let tree = tree_of(GLASS);
    let [eye, shadow, reflected, transmitted] = tree.kind_counts();
    assert_eq!(eye, 1);
    assert!(
        shadow > 0 && reflected > 0 && transmitted > 0,
        "{:?}",
        tree.kind_counts()
    );
    // The eye ray hits the glass sphere (primitive 5, material 0).
    let root = &tree.segments[0];
    assert_eq!(
        (root.kind, root.prim, root.material),
        (SegmentKind::Eye, Some(5), Some(0))
    );
    // Inside the sphere the shadow rays are blocked by the sphere itself.
    assert!(
        tree.segments
            .iter()
            .any(|s| s.blocked && s.end_kind == EndKind::Occluder)
    );
    assert!(tree.segments.iter().any(|s| s.end_kind == EndKind::Light));
    assert!(
        tree.segments
            .iter()
            .any(|s| s.end_kind == EndKind::DistantLight)
    );
}

#[test]
fn a_mirror_pixel_has_eye_shadow_and_reflected_segments() {
    let tree = tree_of(MIRROR);
    let [eye, shadow, reflected, _] = tree.kind_counts();
    assert_eq!(eye, 1);
    assert!(shadow > 0 && reflected > 0, "{:?}", tree.kind_counts());
    // The eye ray hits the left mirror (triangles 0 and 1); its reflections bounce between
    // the left and the right mirror (triangles 2 and 3) until the bounce limit.
    let side = |prim: Option<u32>| match prim {
        Some(0 | 1) => "left",
        Some(2 | 3) => "right",
        _ => "elsewhere",
    };
    assert_eq!(side(tree.segments[0].prim), "left");
    assert_eq!(reflected, 5, "{:?}", tree.kind_counts());
    for s in tree
        .segments
        .iter()
        .filter(|s| s.kind == SegmentKind::Reflected)
    {
        let parent = &tree.segments[s.parent.unwrap()];
        let pair = (side(parent.prim), side(s.prim));
        assert!(
            pair == ("left", "right") || pair == ("right", "left"),
            "{pair:?}"
        );
    }
}

#[test]
fn every_child_starts_where_its_parent_ends() {
    for pixel in [GLASS, MIRROR] {
        let tree = tree_of(pixel);
        for s in &tree.segments {
            match s.parent {
                None => assert_eq!(s.kind, SegmentKind::Eye),
                Some(p) => {
                    let parent = &tree.segments[p];
                    assert_eq!(parent.end_kind, EndKind::Hit);
                    assert!(
                        (s.origin - parent.end).length() <= 1e-5,
                        "{s:?} under {parent:?}"
                    );
                    let depth = parent.depth + u32::from(s.kind != SegmentKind::Shadow);
                    assert_eq!(s.depth, depth);
                }
            }
        }
    }
}

#[test]
fn the_tree_is_traced_for_the_pixel_the_render_made() {
    // The tree is traced again after the render: its colour must be that pixel's colour, with
    // either tracer (a wrong pixel, camera or option set would show here).
    for (name, x, y) in [GLASS, MIRROR, MIRROR_SEES_GLASS] {
        let scene = Scene::load(&scene_path(name)).unwrap();
        for tracer in [Tracer::Reference, Tracer::Packet] {
            let opts = RenderOptions {
                tracer,
                ..options()
            };
            let frame = whitted::render(&scene, &opts).unwrap();
            let (_, color) = trace_ray_tree(&scene, &opts, x, y).unwrap();
            let pixel = frame.color[(y * opts.width + x) as usize];
            assert_eq!(color, pixel, "{name} ({x}, {y}) with {tracer:?}");
        }
    }
}

/// The tree recorded bounce by bounce, as a wavefront tracer would: all segments of depth 0
/// (eye, then its shadow rays), then depth 1, ..., siblings in reverse order.
fn wavefront_order(tree: &RayTree) -> RayTree {
    let mut order: Vec<usize> = (0..tree.segments.len()).collect();
    order.sort_by_key(|&i| {
        let s = &tree.segments[i];
        (s.depth, s.kind == SegmentKind::Shadow, std::cmp::Reverse(i))
    });
    let mut new_index = vec![0; order.len()];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }
    RayTree {
        segments: order
            .iter()
            .map(|&old| {
                let mut s = tree.segments[old];
                s.parent = s.parent.map(|p| new_index[p]);
                s
            })
            .collect(),
    }
}

#[test]
fn canonical_order_makes_recording_orders_compare_equal() {
    let tree = tree_of(GLASS);
    let shuffled = wavefront_order(&tree);
    assert_ne!(shuffled, tree, "the test must really change the order");
    shuffled.validate().unwrap();
    assert_eq!(shuffled.canonical(), tree.canonical());
    assert!(shuffled.approx_eq(&tree, 1e-4));
    assert_eq!(tree.canonical().canonical(), tree.canonical());
    tree.canonical().validate().unwrap();

    // Within tolerance is equal; beyond it, or a different structure, is not.
    let mut nudged = shuffled.clone();
    let last = nudged.segments.len() - 1;
    nudged.segments[last].end.x += 1e-6;
    assert!(nudged.approx_eq(&tree, 1e-4));
    nudged.segments[last].end.x += 1e-2;
    assert!(!nudged.approx_eq(&tree, 1e-4));
    let mut pruned = tree.clone();
    pruned.segments.pop();
    assert!(
        pruned
            .first_difference(&tree, 1e-4)
            .unwrap()
            .contains("segments")
    );
}

#[test]
fn the_json_parses_and_holds_every_segment() {
    let tree = tree_of(GLASS);
    let text = tree.to_json(&TreeSource {
        scene: "scenes/\"glass\" sphere.txt",
        tracer: "reference",
        pixel: [GLASS.1, GLASS.2],
        image_size: [400, 300],
    });
    let json: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    assert_eq!(json["scene"], "scenes/\"glass\" sphere.txt");
    assert_eq!(json["pixel"], serde_json::json!([230, 150]));
    assert_eq!(json["escape_length"], 100.0);
    let segments = json["segments"].as_array().unwrap();
    assert_eq!(segments.len(), tree.segments.len());
    let counts = tree.kind_counts();
    for (k, kind) in SegmentKind::ALL.iter().enumerate() {
        assert_eq!(json["counts"][kind.name()], counts[k] as u64);
    }
    for (i, (j, s)) in segments.iter().zip(&tree.segments).enumerate() {
        assert_eq!(j["index"], i as u64);
        assert_eq!(j["kind"], s.kind.name());
        assert_eq!(j["end_kind"], s.end_kind.name());
        assert_eq!(j["depth"], s.depth);
        assert_eq!(j["blocked"], s.blocked);
        assert_eq!(j["parent"].as_u64(), s.parent.map(|p| p as u64));
        assert_eq!(j["prim"].as_u64(), s.prim.map(u64::from));
        assert_eq!(j["material"].as_u64(), s.material.map(u64::from));
        assert_eq!(j["light"].as_u64(), s.light.map(u64::from));
        let weight = j["weight"].as_f64().unwrap() as f32;
        assert_eq!(weight, s.weight, "numbers round-trip exactly");
        for (key, v) in [("origin", s.origin), ("end", s.end)] {
            let xyz: Vec<f32> = j[key]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c.as_f64().unwrap() as f32)
                .collect();
            assert_eq!(xyz, v.to_array(), "{key} of segment {i}");
        }
        assert_eq!(
            j.as_object().unwrap().len(),
            12,
            "no missing or extra keys: {j}"
        );
    }
}

/// Runs the binary in `dir`, with `scene` (one of ours) standing for `SCENE` in `args`.
fn run_in(dir: &Path, scene: &str, args: &[&str]) -> common::Run {
    let scene = scene_path(scene);
    let args: Vec<&str> = args
        .iter()
        .map(|a| {
            if *a == "SCENE" {
                scene.to_str().unwrap()
            } else {
                a
            }
        })
        .collect();
    common::whitted(dir, &args)
}

#[test]
fn the_cli_writes_the_tree_and_a_witness_png_of_the_requested_size() {
    let dir = common::scratch_dir("ray_tree_cli");
    let out = run_in(
        &dir,
        "glass_sphere.txt",
        &[
            "render",
            "SCENE",
            "-o",
            "i.png",
            "--size",
            "160",
            "120",
            "--shadows",
            "--shade-back",
            "--bounces",
            "5",
            "--ray-tree",
            "92",
            "60",
            "t.json",
            "--ray-tree-image",
            "t.png",
        ],
    );
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    assert!(
        out.stderr.is_empty(),
        "nothing on piped stderr: {:?}",
        out.stderr
    );
    let picture = whitted::output::read_png(&dir.join("t.png")).unwrap();
    assert_eq!((picture.width, picture.height), (160, 120));
    let main = whitted::output::read_png(&dir.join("i.png")).unwrap();
    assert_ne!(
        picture.data, main.data,
        "the witness sees the scene from elsewhere"
    );
    let tree: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("t.json")).unwrap()).unwrap();
    assert_eq!(tree["image_size"], serde_json::json!([160, 120]));
    let kinds: Vec<&str> = tree["segments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    for kind in ["eye", "shadow", "reflected", "transmitted"] {
        assert!(kinds.contains(&kind), "{kind} missing from {kinds:?}");
    }
}

#[test]
fn the_course_spelling_and_an_explicit_witness_camera_work_too() {
    let dir = common::scratch_dir("ray_tree_course");
    let out = run_in(
        &dir,
        "facing_mirrors.txt",
        &[
            "-input",
            "SCENE",
            "-size",
            "90",
            "60",
            "-shadows",
            "-bounces",
            "3",
            "-ray_tree",
            "10",
            "40",
            "m.json",
            "-ray_tree_image",
            "m.png",
            "-witness_camera",
            "0",
            "5",
            "9",
            "0",
            "0",
            "0",
            "-witness_angle",
            "70",
        ],
    );
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    let picture = whitted::output::read_png(&dir.join("m.png")).unwrap();
    assert_eq!((picture.width, picture.height), (90, 60));
}

#[test]
fn a_pixel_outside_the_image_is_a_usage_error() {
    let dir = common::scratch_dir("ray_tree_outside");
    for (x, y) in [("400", "0"), ("0", "300"), ("-1", "0")] {
        let args = [
            "render",
            "SCENE",
            "--size",
            "400",
            "300",
            "--ray-tree",
            x,
            y,
            "t.json",
        ];
        run_in(&dir, "glass_sphere.txt", &args).assert_error("option --ray-tree");
        assert!(!dir.join("t.json").exists());
    }
    let args = [
        "render",
        "SCENE",
        "--ray-tree-image",
        "t.png",
        "-o",
        "i.png",
    ];
    let msg = run_in(&dir, "glass_sphere.txt", &args).assert_error("option --ray-tree-image");
    assert!(msg.contains("needs --ray-tree"), "{msg}");
}

fn count_color(img: &whitted::output::Rgb8, color: [f32; 3]) -> usize {
    let want = color.map(|c| (c * 255.0 + 0.5) as u8);
    img.data.chunks_exact(3).filter(|p| **p == want).count()
}

#[test]
fn the_witness_picture_shows_every_kind_of_segment_in_the_tree() {
    use whitted::witness::{WitnessSpec, draw_ray_tree, kind_color, witness_camera};
    for (pixel, blocked) in [(GLASS, true), (MIRROR, false), (MIRROR_SEES_GLASS, true)] {
        let scene = Scene::load(&scene_path(pixel.0)).unwrap();
        let opts = options();
        let tree = tree_of(pixel);
        let camera = witness_camera(&scene.camera, &tree, 400, 300, &WitnessSpec::default());
        let witness_scene = Scene {
            camera: camera.clone(),
            root: whitted::witness::cutaway(&scene.root, camera.center),
            ..scene.clone()
        };
        let frame = whitted::render(&witness_scene, &opts).unwrap();
        let size = (opts.width, opts.height);
        let drawn = draw_ray_tree(&frame, &camera, &scene.camera, size, &tree, "t");
        let bare = draw_ray_tree(&frame, &camera, &scene.camera, size, &RayTree::new(), "t");
        let mut kinds: Vec<(SegmentKind, bool)> =
            tree.segments.iter().map(|s| (s.kind, s.blocked)).collect();
        kinds.dedup();
        assert!(kinds.contains(&(SegmentKind::Shadow, blocked)));
        for (kind, blocked) in kinds {
            let color = kind_color(kind, blocked);
            let extra = count_color(&drawn, color) - count_color(&bare, color);
            assert!(
                extra >= 10,
                "{}: {kind:?} (blocked {blocked}) drawn on {extra} pixels",
                pixel.0
            );
        }
    }
}

#[test]
fn a_mirror_pixel_that_sees_glass_has_all_four_kinds_in_both_tracers() {
    // The showcase's mirror sphere (primitive 5, material 1) reflects the glass sphere at this
    // pixel: the tree has eye, shadow, reflected and transmitted segments, and both tracers
    // record the same one.
    let scene = Scene::load(&scene_path("showcase.txt")).unwrap();
    let mut opts = RenderOptions {
        width: 640,
        height: 480,
        ..RenderOptions::default()
    };
    opts.shade.shadows = true;
    opts.shade.shade_back = true;
    opts.shade.bounces = 5;
    let (packet, _) = trace_ray_tree(&scene, &opts, 440, 260).unwrap();
    opts.tracer = whitted::Tracer::Reference;
    let (reference, _) = trace_ray_tree(&scene, &opts, 440, 260).unwrap();
    assert_eq!(
        packet.segments[0].material,
        Some(1),
        "the eye ray hits the mirror sphere"
    );
    let [eye, shadow, reflected, transmitted] = packet.kind_counts();
    assert!(
        eye == 1 && shadow > 0 && reflected > 0 && transmitted > 0,
        "{:?}",
        packet.kind_counts()
    );
    assert!(
        packet.approx_eq(&reference, 1e-4),
        "{:?}",
        packet.first_difference(&reference, 1e-4)
    );
}
