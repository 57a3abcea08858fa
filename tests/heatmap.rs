//! Claim: `--heatmap` measures the packet tracer's work per eye ray (BVH nodes entered plus
//! primitives tested): pixels whose rays cross more geometry cost more, a ray that meets
//! nothing costs nothing but the planes every ray tests, the counts do not depend on the
//! thread count, and the command line writes the picture (the render's size plus the legend
//! strip) and prints the maximum.

mod common;

use std::fmt::Write as _;
use std::path::Path;

use whitted::heatmap::legend_height;
use whitted::render::eye_ray_costs;
use whitted::{CostMap, RenderOptions, Scene};

/// Two unit spheres at x = -2 and x = 2 seen head on by an orthographic camera; with
/// `cluster`, a lattice of 6^3 small spheres behind the left one's half of the picture.
fn scene(cluster: bool, plane: bool) -> Scene {
    let mut objects = vec![
        "Sphere { center -2 0 0 radius 1 }".to_string(),
        "Sphere { center 2 0 0 radius 1 }".to_string(),
    ];
    if cluster {
        for i in 0..6 {
            for j in 0..6 {
                for k in 0..6 {
                    let (x, y, z) = (
                        -3.6 + 0.6 * i as f32,
                        -1.5 + 0.6 * j as f32,
                        -3.0 - k as f32,
                    );
                    objects.push(format!("Sphere {{ center {x} {y} {z} radius 0.08 }}"));
                }
            }
        }
    }
    if plane {
        objects.push("Plane { normal 0 0 1 offset -20 }".to_string());
    }
    let mut text = String::from(
        "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 8 }
         Lights { numLights 0 }
         Background { color 0 0 0 }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 1 1 1 } }\n",
    );
    let _ = writeln!(
        text,
        "Group {{ numObjects {} MaterialIndex 0",
        objects.len()
    );
    text += &objects.join("\n");
    text += "\n}\n";
    Scene::from_str(&text, Path::new("heatmap.txt")).unwrap()
}

fn costs(scene: &Scene, threads: usize) -> CostMap {
    let opts = RenderOptions {
        width: 80,
        height: 80,
        threads,
        ..RenderOptions::default()
    };
    eye_ray_costs(scene, &opts, &|_| {}).unwrap()
}

/// The mean cost over columns `x0..x1` of the middle rows.
fn mean(c: &CostMap, x0: u32, x1: u32) -> f64 {
    let mut sum = 0u64;
    let mut n = 0u64;
    for y in 30..50 {
        for x in x0..x1 {
            sum += c.cost[(y * c.width + x) as usize] as u64;
            n += 1;
        }
    }
    sum as f64 / n as f64
}

#[test]
fn pixels_whose_rays_cross_more_geometry_cost_more() {
    let plain = costs(&scene(false, false), 0);
    let crowded = costs(&scene(true, false), 0);
    // Left half: the cluster lies behind it (rays that miss the big sphere cross it).
    let (before, after) = (mean(&plain, 0, 40), mean(&crowded, 0, 40));
    assert!(after > 2.0 * before, "left half: {before} -> {after}");
    // The right half's rays do not cross the cluster: they cost less than the left half's.
    let right = mean(&crowded, 44, 80);
    assert!(right < after / 2.0, "right {right}, left {after}");
    assert!(crowded.max().1 > plain.max().1);
}

#[test]
fn a_ray_that_meets_nothing_costs_only_the_planes() {
    // The corner pixel's ray misses every box (the top-left of an 8-unit-wide view).
    let c = costs(&scene(false, false), 0);
    assert_eq!(c.cost[0], 0);
    let c = costs(&scene(false, true), 0);
    assert_eq!(c.cost[0], 1);
    // A ray that hits a sphere entered at least the root and tested at least that sphere.
    assert!(c.cost[(40 * 80 + 20) as usize] >= 2);
}

#[test]
fn the_counts_do_not_depend_on_the_thread_count() {
    let s = scene(true, true);
    assert_eq!(costs(&s, 1), costs(&s, 2));
    assert_eq!(costs(&s, 1), costs(&s, 3));
}

#[test]
fn the_command_line_writes_the_picture_and_prints_the_maximum() {
    let dir = common::scratch_dir("heatmap_cli");
    let out = dir.join("heat.png");
    let run = common::whitted(
        Path::new(env!("CARGO_MANIFEST_DIR")),
        &[
            "render",
            "scenes/showcase.txt",
            "--heatmap",
            out.to_str().unwrap(),
            "--size",
            "96",
            "64",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let img = whitted::output::read_png(&out).unwrap();
    assert_eq!((img.width, img.height), (96, 64 + legend_height(96)));
    let scene =
        Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.txt")).unwrap();
    let opts = RenderOptions {
        width: 96,
        height: 64,
        ..RenderOptions::default()
    };
    let ((x, y), max) = eye_ray_costs(&scene, &opts, &|_| {}).unwrap().max();
    let line = run
        .stderr
        .lines()
        .find(|l| l.starts_with("heatmap:"))
        .unwrap_or_else(|| panic!("no heatmap line: {}", run.stderr));
    assert!(
        line.contains(&format!("at most {max}, at pixel ({x}, {y})")),
        "{line}"
    );
}
