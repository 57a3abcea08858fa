//! Claim: a mesh with vertex normals (OBJ `vn`, or computed by `--smooth-normals`) shades
//! smoothly in both tracers: a finely tessellated sphere with its analytic normals shades like
//! the analytic sphere (where its flat twin does not), and a smooth low-poly mesh shows no
//! shadow acne: on a convex mesh alone, shadow rays change no pixel, because the geometric
//! normal, not the shading one, decides whether a light is above the surface.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use common::{assert_equivalent, render_both, scratch_dir};
use whitted::output::{color_image, normal_image};
use whitted::shade::ShadeOptions;
use whitted::{Frame, RenderOptions, Scene};

/// A UV sphere of radius 1 around the origin, `slices` around the y axis and `stacks` from
/// pole to pole, counter-clockwise seen from outside; with its analytic normals as `vn` when
/// `normals`.
fn uv_sphere(slices: u32, stacks: u32, normals: bool) -> String {
    let mut obj = String::new();
    let point = |i: u32, j: u32| {
        let theta = std::f32::consts::TAU * i as f32 / slices as f32;
        let phi = std::f32::consts::PI * j as f32 / stacks as f32;
        [phi.sin() * theta.cos(), phi.cos(), -phi.sin() * theta.sin()]
    };
    // Vertex k = 1 + i * (stacks + 1) + j (poles repeated per slice; faces at the poles are
    // triangles).
    for i in 0..slices {
        for j in 0..=stacks {
            let [x, y, z] = point(i, j);
            let _ = writeln!(obj, "v {x} {y} {z}");
            if normals {
                let _ = writeln!(obj, "vn {x} {y} {z}");
            }
        }
    }
    let index = |i: u32, j: u32| 1 + (i % slices) * (stacks + 1) + j;
    let corner = |k: u32| {
        if normals {
            format!("{k}//{k}")
        } else {
            k.to_string()
        }
    };
    for i in 0..slices {
        for j in 0..stacks {
            let (a, b) = (index(i, j), index(i, j + 1));
            let (c, d) = (index(i + 1, j + 1), index(i + 1, j));
            if j > 0 {
                let _ = writeln!(obj, "f {} {} {}", corner(a), corner(b), corner(d));
            }
            if j + 1 < stacks {
                let _ = writeln!(obj, "f {} {} {}", corner(b), corner(c), corner(d));
            }
        }
    }
    obj
}

/// A scene holding `object` in front of an orthographic camera, lit by a directional light
/// from the upper left and a point light; written with `files` beside it.
fn scene_with(name: &str, object: &str, files: &[(&str, String)]) -> (Scene, PathBuf) {
    let dir = scratch_dir(name);
    for (file, text) in files {
        std::fs::write(dir.join(file), text).unwrap();
    }
    let text = format!(
        "OrthographicCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 size 2.4 }}
         Lights {{ numLights 2
             DirectionalLight {{ direction 0.6 -0.5 -0.6 color 0.7 0.7 0.7 }}
             PointLight {{ position -3 1 4 color 0.5 0.4 0.3 attenuation 1 0 0 }} }}
         Background {{ color 0 0 0 ambientLight 0.1 0.1 0.1 }}
         Materials {{ numMaterials 1
             PhongMaterial {{ diffuseColor 0.8 0.6 0.4 specularColor 0.5 0.5 0.5 exponent 20 }} }}
         Group {{ numObjects 1 MaterialIndex 0 {object} }}"
    );
    let path = dir.join("scene.txt");
    std::fs::write(&path, &text).unwrap();
    (Scene::load(&path).unwrap(), dir)
}

fn options(shadows: bool) -> RenderOptions {
    RenderOptions {
        width: 120,
        height: 120,
        shade: ShadeOptions {
            shadows,
            ..ShadeOptions::default()
        },
        ..RenderOptions::default()
    }
}

/// The share of pixels lit in both frames, away from the sphere's outline (where the
/// tessellation's silhouette differs), whose colours differ by more than `tol`/255.
fn interior_mismatch(a: &Frame, b: &Frame, tol: u8) -> f64 {
    let (ia, ib) = (color_image(a), color_image(b));
    let (mut pixels, mut over) = (0, 0);
    for i in 0..a.color.len() {
        // The analytic frame's normal faces the camera by at least 0.3 there.
        if a.depth[i].is_finite() && b.depth[i].is_finite() && b.normal[i].z > 0.3 {
            pixels += 1;
            let d = (0..3)
                .map(|c| ia.data[3 * i + c].abs_diff(ib.data[3 * i + c]))
                .max()
                .unwrap();
            if d > tol {
                over += 1;
            }
        }
    }
    assert!(pixels > 5000, "only {pixels} interior pixels");
    over as f64 / pixels as f64
}

#[test]
fn a_tessellated_sphere_with_normals_shades_like_the_analytic_sphere() {
    let (analytic, _) = scene_with("smooth_analytic", "Sphere { center 0 0 0 radius 1 }", &[]);
    let mesh = "TriangleMesh { obj_file sphere.obj }";
    let (smooth, _) = scene_with(
        "smooth_vn",
        mesh,
        &[("sphere.obj", uv_sphere(64, 32, true))],
    );
    let (flat, dir) = scene_with(
        "smooth_flat",
        mesh,
        &[("sphere.obj", uv_sphere(64, 32, false))],
    );
    // --smooth-normals gives the flat file area-weighted normals: on a regular sphere they
    // are close to the analytic ones.
    let mut computed = Scene::load(&dir.join("scene.txt")).unwrap();
    computed.smooth_normals();
    for shadows in [false, true] {
        let opts = options(shadows);
        let (reference, _) = render_both(&analytic, &opts);
        for (what, scene, least) in [
            ("vn", &smooth, 0.99),
            ("computed", &computed, 0.99),
            ("flat", &flat, 0.0),
        ] {
            let (r, p) = render_both(scene, &opts);
            assert_equivalent(&color_image(&r), &color_image(&p), what);
            assert_equivalent(&normal_image(&r), &normal_image(&p), what);
            let within = 1.0 - interior_mismatch(&r, &reference, 4);
            eprintln!(
                "{what} shadows={shadows}: {:.2}% within 4/255",
                100.0 * within
            );
            if what == "flat" {
                // The faceted twin is far off: the criterion can fail.
                assert!(within < 0.75, "flat: {within}");
            } else {
                assert!(within >= least, "{what} shadows={shadows}: {within}");
            }
        }
    }
}

#[test]
fn smooth_low_poly_meshes_show_no_shadow_acne() {
    // 8 x 4 facets: the shading normal is far from the geometric one near the terminator.
    let mesh = "Transform { YRotate 20 TriangleMesh { obj_file low.obj } }";
    let (with_vn, dir) = scene_with("acne_vn", mesh, &[("low.obj", uv_sphere(8, 4, true))]);
    std::fs::write(dir.join("flat.obj"), uv_sphere(8, 4, false)).unwrap();
    let text = std::fs::read_to_string(dir.join("scene.txt"))
        .unwrap()
        .replace("low.obj", "flat.obj");
    let mut computed = Scene::from_str(&text, &dir.join("scene.txt")).unwrap();
    computed.smooth_normals();
    for (what, scene) in [("vn", &with_vn), ("computed", &computed)] {
        let (plain_r, plain_p) = render_both(scene, &options(false));
        let (shadow_r, shadow_p) = render_both(scene, &options(true));
        // Alone, a convex mesh cannot shadow itself: shadows change nothing.
        assert_eq!(plain_r.color, shadow_r.color, "{what}: reference");
        assert_eq!(plain_p.color, shadow_p.color, "{what}: packet");
        assert_equivalent(&color_image(&shadow_r), &color_image(&shadow_p), what);
        // And it is smooth: the shading differs from the flat mesh's.
        let (flat, _) = render_both(
            &Scene::from_str(&text, &dir.join("scene.txt")).unwrap(),
            &options(true),
        );
        assert_ne!(flat.color, shadow_r.color, "{what}");
    }
}

#[test]
fn obj_normals_and_smooth_normals_reach_the_command_line() {
    let dir = scratch_dir("smooth_cli");
    std::fs::write(dir.join("flat.obj"), uv_sphere(12, 6, false)).unwrap();
    let (_, scene_dir) = scene_with(
        "smooth_cli_scene",
        "TriangleMesh { obj_file flat.obj }",
        &[("flat.obj", uv_sphere(12, 6, false))],
    );
    let scene = scene_dir.join("scene.txt");
    let render = |extra: &[&str], out: &str| {
        let out = dir.join(out);
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--size",
            "40",
            "40",
        ];
        args.extend_from_slice(extra);
        let run = common::whitted(Path::new(env!("CARGO_MANIFEST_DIR")), &args);
        assert_eq!(run.code, Some(0), "{}", run.stderr);
        std::fs::read(out).unwrap()
    };
    let flat = render(&[], "flat.png");
    let smooth = render(&["--smooth-normals"], "smooth.png");
    assert_ne!(flat, smooth);
    // The course spelling too.
    assert_eq!(smooth, render(&["-smooth_normals"], "smooth2.png"));
}
