//! Claim: the packet tracer renders the same images as the reference tracer. Criterion: at most
//! 0.1% of pixels differ by more than 2/255 in any channel (the tracers differ only in float
//! rounding: the packet tracer bakes transforms into world space and sums a pixel's terms in
//! another order). Checked on every scene of `scenes/`, on every A1-A4 course command (colour,
//! depth and normal images), on every scene file of assignments 5-7 (meshes up to 40k
//! triangles, solid textures), and on at least 100 seeded random scenes per run (meshes with
//! vertex normals and without, some smoothed by `--smooth-normals`; colour and normal images);
//! anti-aliased (every sampler, every filter: both tracers trace the same sample rays) on every
//! scene of ours and on at least 50 seeded random scenes.

mod common;

use std::path::Path;

use common::{
    Rng, assert_equivalent, assert_finite, course_dir, our_scenes, render_both, scene_files,
};
use whitted::filter::{Filter, Shape};
use whitted::output::{color_image, depth_image, normal_image};
use whitted::sampler::{Pattern, Sampler};
use whitted::shade::ShadeOptions;
use whitted::{RenderOptions, Scene};

#[test]
fn every_scene_of_ours_renders_the_same_with_both_tracers() {
    let scenes = our_scenes();
    assert!(scenes.len() >= 6);
    for path in scenes {
        let scene = Scene::load(&path).unwrap();
        for shade in [
            ShadeOptions {
                shadows: true,
                shade_back: true,
                bounces: 6,
                ..ShadeOptions::default()
            },
            ShadeOptions {
                shadows: true,
                shade_back: true,
                bounces: 4,
                transparent_shadows: true,
                fresnel: true,
                ..ShadeOptions::default()
            },
            ShadeOptions {
                specular_fix: false,
                bounces: 2,
                ..ShadeOptions::default()
            },
        ] {
            let opts = RenderOptions {
                width: 160,
                height: 120,
                shade,
                ..RenderOptions::default()
            };
            let (r, p) = render_both(&scene, &opts);
            let what = format!("{} {:?}", path.display(), shade);
            assert_finite(&r, &what);
            assert_finite(&p, &what);
            assert_equivalent(&color_image(&r), &color_image(&p), &what);
        }
    }
}

#[test]
fn every_course_command_renders_the_same_with_both_tracers() {
    let Some(course) = course_dir() else {
        eprintln!("skipped: WHITTED_COURSE_DIR is not set");
        return;
    };
    let text = std::fs::read_to_string(course.join("COMMANDS.txt")).unwrap();
    let mut assignment = 0;
    let mut count = 0;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("# Assignment ") {
            assignment = rest
                .split(':')
                .next()
                .unwrap()
                .trim()
                .parse::<u32>()
                .unwrap();
            continue;
        }
        let Some(rest) = line.strip_prefix("raytracer ") else {
            continue;
        };
        if assignment > 4 {
            continue;
        }
        let args: Vec<String> = rest.split_whitespace().map(String::from).collect();
        let mut cmd = whitted::cli::parse_args(&args, false).unwrap();
        let path = course
            .join(format!("assignment{assignment}"))
            .join(&cmd.scene);
        let scene = Scene::load(&path).unwrap();
        cmd.render.threads = 0;
        let (r, p) = render_both(&scene, &cmd.render);
        assert_finite(&p, line);
        assert_equivalent(&color_image(&r), &color_image(&p), line);
        if let Some((near, far, _)) = cmd.depth {
            assert_equivalent(
                &depth_image(&r, near, far),
                &depth_image(&p, near, far),
                line,
            );
        }
        if cmd.normals.is_some() {
            assert_equivalent(&normal_image(&r), &normal_image(&p), line);
        }
        count += 1;
    }
    assert!(count >= 60, "only {count} course commands");
}

/// A random scene in the course format, using every primitive, transform, material and light.
fn random_scene(rng: &mut Rng) -> String {
    let mut s = String::new();
    let v3 = |rng: &mut Rng, lo: f32, hi: f32| {
        format!(
            "{} {} {}",
            rng.range(lo, hi),
            rng.range(lo, hi),
            rng.range(lo, hi)
        )
    };
    let theta = rng.range(0.0, std::f32::consts::TAU);
    let (cx, cz, cy) = (8.0 * theta.sin(), 8.0 * theta.cos(), rng.range(0.5, 4.0));
    if rng.chance(0.75) {
        s += &format!(
            "PerspectiveCamera {{ center {cx} {cy} {cz} direction {} {} {} up 0 1 0 angle {} }}\n",
            -cx,
            -cy + rng.range(-1.0, 1.0),
            -cz,
            rng.range(25.0, 60.0)
        );
    } else {
        s += &format!(
            "OrthographicCamera {{ center {cx} {cy} {cz} direction {} {} {} up 0 1 0 size {} }}\n",
            -cx,
            -cy,
            -cz,
            rng.range(4.0, 9.0)
        );
    }
    let lights = 1 + rng.below(3);
    s += &format!("Lights {{ numLights {lights}\n");
    for _ in 0..lights {
        if rng.chance(0.5) {
            s += &format!(
                "DirectionalLight {{ direction {} -1 {} color {} }}\n",
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                v3(rng, 0.2, 0.8)
            );
        } else {
            s += &format!(
                "PointLight {{ position {} {} {} color {} attenuation {} {} {} }}\n",
                rng.range(-4.0, 4.0),
                rng.range(2.0, 6.0),
                rng.range(-4.0, 4.0),
                v3(rng, 0.3, 1.0),
                rng.range(0.5, 1.0),
                rng.range(0.0, 0.2),
                rng.range(0.0, 0.05)
            );
        }
    }
    s += "}\n";
    s += &format!(
        "Background {{ color {} ambientLight {} }}\n",
        v3(rng, 0.0, 0.5),
        v3(rng, 0.0, 0.3)
    );
    let phongs = 2 + rng.below(4);
    let textures = rng.below(3);
    let materials = phongs + textures;
    s += &format!("Materials {{ numMaterials {materials}\n");
    for _ in 0..phongs {
        s += &format!(
            "PhongMaterial {{ diffuseColor {} specularColor {} exponent {}",
            v3(rng, 0.0, 1.0),
            v3(rng, 0.0, 1.0),
            rng.range(1.0, 100.0)
        );
        if rng.chance(0.4) {
            s += &format!(" reflectiveColor {}", v3(rng, 0.1, 0.9));
        }
        if rng.chance(0.3) {
            s += &format!(
                " transparentColor {} indexOfRefraction {}",
                v3(rng, 0.2, 0.9),
                rng.range(1.0, 2.0)
            );
        }
        s += " }\n";
    }
    for _ in 0..textures {
        let kind = ["Checkerboard", "Noise", "Marble", "Wood"][rng.below(4) as usize];
        s += &format!(
            "{kind} {{ Transform {{ UniformScale {} YRotate {} }} materialIndex {} materialIndex {}",
            rng.range(0.5, 3.0),
            rng.range(0.0, 90.0),
            rng.below(phongs),
            rng.below(phongs)
        );
        if kind != "Checkerboard" {
            s += &format!(" octaves {}", rng.below(5));
        }
        if kind == "Marble" || kind == "Wood" {
            s += &format!(
                " frequency {} amplitude {}",
                rng.range(1.0, 8.0),
                rng.range(0.5, 4.0)
            );
        }
        s += " }\n";
    }
    s += "}\n";
    let objects = 3 + rng.below(6);
    s += &format!("Group {{ numObjects {}\n", objects + 1);
    s += &format!(
        "MaterialIndex {} Plane {{ normal 0 1 0 offset {} }}\n",
        rng.below(materials),
        rng.range(-2.0, -1.0)
    );
    for _ in 0..objects {
        s += &format!("MaterialIndex {}\n", rng.below(materials));
        s += &random_object(rng, 2);
    }
    s += "}\n";
    s
}

fn random_object(rng: &mut Rng, depth: u32) -> String {
    let p = |rng: &mut Rng| {
        format!(
            "{} {} {}",
            rng.range(-2.5, 2.5),
            rng.range(-1.0, 2.0),
            rng.range(-2.5, 2.5)
        )
    };
    match rng.below(if depth == 0 { 4 } else { 6 }) {
        0 => format!(
            "Sphere {{ center {} radius {} }}\n",
            p(rng),
            rng.range(0.3, 1.2)
        ),
        1 => format!(
            "Triangle {{ vertex0 {} vertex1 {} vertex2 {} }}\n",
            p(rng),
            p(rng),
            p(rng)
        ),
        2 => {
            let mesh = if rng.chance(0.5) {
                "cube.obj"
            } else {
                "torus.obj"
            };
            format!(
                "Transform {{ Translate {} UniformScale {} TriangleMesh {{ obj_file {mesh} }} }}\n",
                p(rng),
                rng.range(0.3, 0.8)
            )
        }
        3 => format!(
            "Sphere {{ center {} radius {} }}\n",
            p(rng),
            rng.range(0.1, 0.5)
        ),
        4 => {
            let n = 1 + rng.below(3);
            let mut s = format!("Group {{ numObjects {n}\n");
            for _ in 0..n {
                s += &random_object(rng, depth - 1);
            }
            s + "}\n"
        }
        _ => {
            let mut s = String::from("Transform {\n");
            for _ in 0..1 + rng.below(3) {
                s += &match rng.below(8) {
                    0 => format!("Translate {} ", p(rng)),
                    1 => format!(
                        "Scale {} {} {} ",
                        rng.range(0.3, 1.5),
                        rng.range(0.3, 1.5),
                        rng.range(0.3, 1.5)
                    ),
                    2 => format!("UniformScale {} ", rng.range(0.4, 1.5)),
                    3 => format!("XRotate {} ", rng.range(-180.0, 180.0)),
                    4 => format!("YRotate {} ", rng.range(-180.0, 180.0)),
                    5 => format!("ZRotate {} ", rng.range(-180.0, 180.0)),
                    6 => format!(
                        "Rotate {{ {} {} {} {} }} ",
                        rng.range(-1.0, 1.0),
                        1.0,
                        rng.range(-1.0, 1.0),
                        rng.range(-90.0, 90.0)
                    ),
                    _ => format!(
                        "Matrix {{ 1 {} 0 0  0 1 {} 0  0 0 1 0  0 0 0 1 }} ",
                        rng.range(-0.5, 0.5),
                        rng.range(-0.5, 0.5)
                    ),
                };
            }
            s += &random_object(rng, depth - 1);
            s + "}\n"
        }
    }
}

#[test]
fn random_scenes_render_the_same_with_both_tracers() {
    let scenes_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut worst = (0.0f64, 0);
    let mut rendered = 0;
    for seed in 0..120u64 {
        let mut rng = Rng::new(seed);
        let text = random_scene(&mut rng);
        let mut scene = match Scene::from_str(&text, &scenes_dir.join(format!("random{seed}.txt")))
        {
            Ok(s) => s,
            // A random triangle can come out degenerate: the parser rejects it, skip that seed.
            Err(e) if e.to_string().contains("degenerate") => continue,
            Err(e) => panic!("seed {seed}: {e}\n{text}"),
        };
        let shade = ShadeOptions {
            shadows: rng.chance(0.8),
            shade_back: rng.chance(0.7),
            bounces: rng.below(6),
            weight: if rng.chance(0.5) { 0.01 } else { 0.0 },
            specular_fix: rng.chance(0.5),
            transparent_shadows: rng.chance(0.3),
            fresnel: rng.chance(0.3),
        };
        // torus.obj has vertex normals, cube.obj none: smoothing gives the cubes some.
        let smooth = rng.chance(0.3);
        if smooth {
            scene.smooth_normals();
        }
        let opts = RenderOptions {
            width: 64,
            height: 48,
            shade,
            ..RenderOptions::default()
        };
        let (r, p) = render_both(&scene, &opts);
        let what = format!("seed {seed} {shade:?} smooth normals {smooth}\n{text}");
        assert_finite(&r, &what);
        assert_finite(&p, &what);
        let d = assert_equivalent(&color_image(&r), &color_image(&p), &what);
        assert_equivalent(&normal_image(&r), &normal_image(&p), &what);
        rendered += 1;
        if d.fraction_over() >= worst.0 {
            worst = (d.fraction_over(), seed);
        }
    }
    eprintln!(
        "{rendered} random scenes; worst: seed {} with {:.3}% of pixels over 2/255",
        worst.1,
        100.0 * worst.0
    );
    assert!(rendered >= 100, "only {rendered} random scenes parsed");
}

#[test]
fn every_later_course_scene_renders_the_same_with_both_tracers() {
    let Some(course) = course_dir() else {
        eprintln!("skipped: WHITTED_COURSE_DIR is not set");
        return;
    };
    let mut count = 0;
    for a in 5..=7 {
        let dir = course.join(format!("assignment{a}"));
        let files = scene_files(&dir);
        for path in files {
            let scene = Scene::load(&path).unwrap();
            let shade = ShadeOptions {
                shadows: true,
                shade_back: true,
                bounces: 3,
                ..ShadeOptions::default()
            };
            // The reference tracer is brute force: keep the big meshes' frames small.
            let size = if scene.primitive_count() > 5000 {
                24
            } else {
                64
            };
            let opts = RenderOptions {
                width: size,
                height: size,
                shade,
                ..RenderOptions::default()
            };
            let (r, p) = render_both(&scene, &opts);
            let what = path.display().to_string();
            assert_finite(&p, &what);
            assert_equivalent(&color_image(&r), &color_image(&p), &what);
            count += 1;
        }
    }
    assert!(count >= 30, "only {count} scenes");
}

/// The samplers and filters the anti-aliased equivalence tests cycle through.
fn sampling(k: u64) -> (Sampler, Filter) {
    let patterns = [Pattern::Jittered, Pattern::Uniform, Pattern::Random];
    let filters = [
        Filter {
            shape: Shape::Box,
            size: 0.5,
        },
        Filter {
            shape: Shape::Tent,
            size: 1.5,
        },
        Filter {
            shape: Shape::Gaussian,
            size: 0.6,
        },
        Filter {
            shape: Shape::Box,
            size: 1.7,
        },
        Filter {
            shape: Shape::Gaussian,
            size: 1.7,
        },
        Filter {
            shape: Shape::Tent,
            size: 2.3,
        },
    ];
    let pattern = patterns[(k % 3) as usize];
    let count = if pattern == Pattern::Random {
        2 + (k % 7) as u32
    } else {
        [4, 9][(k % 2) as usize]
    };
    let sampler = Sampler {
        pattern,
        count,
        seed: k,
    };
    (sampler, filters[(k / 3 % 6) as usize])
}

#[test]
fn every_scene_of_ours_renders_the_same_antialiased_with_both_tracers() {
    for (k, path) in our_scenes().into_iter().enumerate() {
        let scene = Scene::load(&path).unwrap();
        let (sampler, filter) = sampling(k as u64);
        let opts = RenderOptions {
            width: 80,
            height: 60,
            sampler,
            filter,
            shade: ShadeOptions {
                shadows: true,
                shade_back: true,
                bounces: 4,
                ..ShadeOptions::default()
            },
            ..RenderOptions::default()
        };
        let (r, p) = render_both(&scene, &opts);
        let what = format!("{} {sampler:?} {filter:?}", path.display());
        assert_finite(&r, &what);
        assert_finite(&p, &what);
        assert_equivalent(&color_image(&r), &color_image(&p), &what);
        assert_equivalent(
            &depth_image(&r, 2.0, 30.0),
            &depth_image(&p, 2.0, 30.0),
            &what,
        );
        assert_equivalent(&normal_image(&r), &normal_image(&p), &what);
    }
}

#[test]
fn random_scenes_render_the_same_antialiased_with_both_tracers() {
    let scenes_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut rendered = 0;
    let mut seen = std::collections::BTreeSet::new();
    for seed in 1000..1070u64 {
        let mut rng = Rng::new(seed);
        let text = random_scene(&mut rng);
        let scene = match Scene::from_str(&text, &scenes_dir.join(format!("random{seed}.txt"))) {
            Ok(s) => s,
            Err(e) if e.to_string().contains("degenerate") => continue,
            Err(e) => panic!("seed {seed}: {e}\n{text}"),
        };
        let (sampler, filter) = sampling(seed);
        seen.insert((sampler.pattern.name(), filter.shape.name()));
        let opts = RenderOptions {
            width: 32,
            height: 24,
            sampler,
            filter,
            shade: ShadeOptions {
                shadows: rng.chance(0.8),
                shade_back: rng.chance(0.7),
                bounces: rng.below(5),
                transparent_shadows: rng.chance(0.3),
                ..ShadeOptions::default()
            },
            ..RenderOptions::default()
        };
        let (r, p) = render_both(&scene, &opts);
        let what = format!("seed {seed} {sampler:?} {filter:?}\n{text}");
        assert_finite(&r, &what);
        assert_finite(&p, &what);
        assert_equivalent(&color_image(&r), &color_image(&p), &what);
        rendered += 1;
    }
    eprintln!("{rendered} anti-aliased random scenes");
    assert!(rendered >= 50, "only {rendered} random scenes parsed");
    assert_eq!(seen.len(), 9, "every sampler with every filter: {seen:?}");
}
