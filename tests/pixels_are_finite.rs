//! Claim: no NaN or infinite value ever reaches a pixel. Every render here, with both tracers,
//! asserts that each
//! pixel's colour (and depth and normal where the primary ray hit) is finite, under every
//! combination of shading options, for our scenes and for the rays numerics break on first:
//! grazing rays on spheres, rays exactly along a triangle edge or through a vertex, rays
//! starting exactly on a surface, rays parallel to a plane, a camera inside a sphere, and
//! numbers near the ends of the `f32` range.
//!
//! What belongs here: renders checked for finiteness, and the kernel results they rest on.
//! Image correctness against references belongs in `course_images.rs`.

mod common;

use std::path::Path;

use common::assert_finite;
use whitted::intersect::{intersect_plane, intersect_sphere, intersect_triangle};
use whitted::math::{Ray, Vec3};
use whitted::shade::ShadeOptions;
use whitted::{Frame, RenderOptions, Tracer, render};
use whitted::{Scene, scene::parse::parse_str};

/// The shading options every scene is rendered under: the defaults, and everything on.
fn option_sets() -> [ShadeOptions; 3] {
    let plain = ShadeOptions::default();
    let shadows = ShadeOptions {
        shadows: true,
        bounces: 6,
        weight: 0.0,
        ..plain
    };
    let everything = ShadeOptions {
        shade_back: true,
        transparent_shadows: true,
        fresnel: true,
        specular_fix: false,
        ..shadows
    };
    [plain, shadows, everything]
}

/// Renders `scene` at `width` x `height` under every option set with both tracers, asserting
/// finite pixels; returns the frames (reference then packet, per option set).
fn render_all(scene: &Scene, width: u32, height: u32, what: &str) -> Vec<Frame> {
    let mut frames = Vec::new();
    for shade in option_sets() {
        for tracer in [Tracer::Reference, Tracer::Packet] {
            let opts = RenderOptions {
                width,
                height,
                shade,
                tracer,
                threads: 1,
                ..RenderOptions::default()
            };
            let frame = render(scene, &opts).unwrap();
            assert_finite(&frame, &format!("{what} with {tracer:?} and {shade:?}"));
            frames.push(frame);
        }
    }
    frames
}

fn scene(text: &str) -> Scene {
    parse_str(text, Path::new("edge.txt")).unwrap_or_else(|e| panic!("{e}"))
}

/// A white light from the upper left and a glassy, mirroring, specular material 0, so that every
/// kind of ray is spawned.
const LIGHTS_AND_GLASS: &str = "
Lights { numLights 2
    DirectionalLight { direction -1 -1 -1 color 0.8 0.8 0.8 }
    PointLight { position 0 0 3 color 1 1 1 attenuation 1 0.1 0.01 } }
Background { color 0.2 0.3 0.4 ambientLight 0.1 0.1 0.1 }
Materials { numMaterials 1
    PhongMaterial { diffuseColor 0.5 0.5 0.5 specularColor 1 1 1 exponent 20
                    reflectiveColor 0.3 0.3 0.3 transparentColor 0.6 0.6 0.6
                    indexOfRefraction 1.5 } }
";

#[test]
fn every_scene_of_ours_renders_finite() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "txt") {
            let scene = Scene::load(&path).unwrap();
            render_all(&scene, 24, 16, &path.display().to_string());
            count += 1;
        }
    }
    assert!(count >= 6);
}

#[test]
fn grazing_rays_on_a_sphere() {
    // A 2x1 orthographic image of width 4: its two rays run at x = -1 and x = +1, exactly
    // tangent to the unit sphere (discriminant exactly 0).
    let text = format!(
        "OrthographicCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 size 4 }}\n\
         {LIGHTS_AND_GLASS}\
         Group {{ numObjects 1 MaterialIndex 0 Sphere {{ center 0 0 0 radius 1 }} }}"
    );
    let s = scene(&text);
    for frame in render_all(&s, 2, 1, "tangent rays") {
        // The tangent point is hit; its normal is perpendicular to the ray.
        assert_eq!(frame.depth, [10.0, 10.0]);
        assert_eq!(frame.normal, [-Vec3::X, Vec3::X]);
    }
    // And the kernel alone: tangent gives the touching point, just outside gives nothing.
    let tangent = Ray::new(Vec3::new(1.0, 0.0, 10.0), -Vec3::Z);
    assert_eq!(
        intersect_sphere(Vec3::ZERO, 1.0, &tangent, 0.0, f32::INFINITY),
        Some(10.0)
    );
    let outside = Ray::new(Vec3::new(1.001, 0.0, 10.0), -Vec3::Z);
    assert_eq!(
        intersect_sphere(Vec3::ZERO, 1.0, &outside, 0.0, f32::INFINITY),
        None
    );
    // Many near-grazing rays at odd resolutions.
    render_all(&s, 37, 29, "near-grazing rays");
}

/// Material 0 triangle (0,0,0) (1,0,0) (0,1,0) in the plane z = 0, seen by `camera`.
fn triangle_scene(camera: &str) -> Scene {
    scene(&format!(
        "{camera}\n{LIGHTS_AND_GLASS}\
         Group {{ numObjects 1 MaterialIndex 0 \
         Triangle {{ vertex0 0 0 0 vertex1 1 0 0 vertex2 0 1 0 }} }}"
    ))
}

#[test]
fn rays_exactly_along_a_triangle_edge() {
    // In the triangle's plane, along the edge from vertex0 to vertex1: no hit, no NaN.
    let s =
        triangle_scene("OrthographicCamera { center -5 0 0 direction 1 0 0 up 0 0 1 size 1e-3 }");
    for frame in render_all(&s, 1, 1, "ray along an edge") {
        assert_eq!(frame.depth, [f32::INFINITY]);
    }
    let (v0, e1, e2) = (Vec3::ZERO, Vec3::X, Vec3::Y);
    let along = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X);
    assert_eq!(
        intersect_triangle(v0, e1, e2, &along, 0.0, f32::INFINITY),
        None
    );
    // Across the plane, exactly onto the edges: on the boundary counts as a hit.
    let onto = |x: f32, y: f32| Ray::new(Vec3::new(x, y, 1.0), -Vec3::Z);
    for (x, y) in [(0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
        assert_eq!(
            intersect_triangle(v0, e1, e2, &onto(x, y), 0.0, f32::INFINITY),
            Some(1.0),
            "onto the edge at ({x}, {y})"
        );
    }
    // An orthographic 2x1 image of width 1 centred on x = 0.5: its rays land on x = 0.25 and
    // x = 0.75 of the edge y = 0.
    let s =
        triangle_scene("OrthographicCamera { center 0.5 0 5 direction 0 0 -1 up 0 1 0 size 1 }");
    for frame in render_all(&s, 2, 1, "rays onto an edge") {
        assert_eq!(frame.depth, [5.0, 5.0]);
    }
}

#[test]
fn rays_exactly_through_a_triangle_vertex() {
    let (v0, e1, e2) = (Vec3::ZERO, Vec3::X, Vec3::Y);
    for corner in [Vec3::ZERO, Vec3::X, Vec3::Y] {
        let ray = Ray::new(corner + Vec3::Z, -Vec3::Z);
        assert_eq!(
            intersect_triangle(v0, e1, e2, &ray, 0.0, f32::INFINITY),
            Some(1.0),
            "through the vertex {corner}"
        );
    }
    // A one-pixel orthographic image whose only ray goes through vertex1, and a perspective
    // camera whose centre ray does, from an oblique angle.
    let s = triangle_scene("OrthographicCamera { center 1 0 5 direction 0 0 -1 up 0 1 0 size 1 }");
    for frame in render_all(&s, 1, 1, "ray through a vertex") {
        assert_eq!(frame.depth, [5.0]);
    }
    let s =
        triangle_scene("PerspectiveCamera { center 2 2 2 direction -1 -1 -1 up 0 0 1 angle 30 }");
    for frame in render_all(&s, 1, 1, "oblique ray through a vertex") {
        assert!(frame.depth[0].is_finite() || frame.depth[0] == f32::INFINITY);
    }
}

#[test]
fn rays_starting_exactly_on_a_surface() {
    // Cameras whose centre lies on a sphere, on a plane, and on a triangle, looking both into
    // and out of the surface; secondary rays start on surfaces all the time.
    let objects = "Group { numObjects 3 MaterialIndex 0
        Sphere { center 0 0 0 radius 1 }
        Plane { normal 0 1 0 offset -1 }
        Triangle { vertex0 -1 -1 1 vertex1 1 -1 1 vertex2 0 1 1 } }";
    for camera in [
        "PerspectiveCamera { center 0 0 1 direction 0 0 -1 up 0 1 0 angle 60 }",
        "PerspectiveCamera { center 0 0 1 direction 0 0 1 up 0 1 0 angle 60 }",
        "PerspectiveCamera { center 0 -1 3 direction 0 0 -1 up 0 1 0 angle 60 }",
        "PerspectiveCamera { center 0 -1 3 direction 0 1 -1 up 0 1 0 angle 60 }",
        "OrthographicCamera { center 1 0 0 direction -1 0 0 up 0 1 0 size 3 }",
    ] {
        let s = scene(&format!("{camera}\n{LIGHTS_AND_GLASS}{objects}"));
        render_all(&s, 9, 7, camera);
    }
    // The kernels: a ray starting on a sphere, outward and inward, with the epsilon offset.
    let on = Vec3::new(0.0, 0.0, 1.0);
    let eps = whitted::shade::EPSILON;
    assert_eq!(
        intersect_sphere(Vec3::ZERO, 1.0, &Ray::new(on, Vec3::Z), eps, f32::INFINITY),
        None
    );
    let inward = intersect_sphere(Vec3::ZERO, 1.0, &Ray::new(on, -Vec3::Z), eps, f32::INFINITY);
    assert!((inward.unwrap() - 2.0).abs() < 1e-5);
}

#[test]
fn rays_parallel_to_a_plane() {
    // Orthographic rays along +x over the plane y = 0: the middle row lies in the plane, the
    // others run parallel above and below it; the light grazes it too.
    let text = "OrthographicCamera { center -5 0 0 direction 1 0 0 up 0 1 0 size 2 }
        Lights { numLights 1 DirectionalLight { direction 1 0 0 color 1 1 1 } }
        Materials { numMaterials 1 PhongMaterial { diffuseColor 1 1 1 reflectiveColor 0.5 0.5 0.5 } }
        Group { numObjects 1 MaterialIndex 0 Plane { normal 0 1 0 offset 0 } }";
    for frame in render_all(&scene(text), 5, 5, "rays parallel to a plane") {
        assert!(frame.depth.iter().all(|d| *d == f32::INFINITY));
    }
    let parallel = Ray::new(Vec3::ZERO, Vec3::X);
    assert_eq!(
        intersect_plane(Vec3::Y, 0.0, &parallel, -f32::MAX, f32::INFINITY),
        None
    );
}

#[test]
fn camera_inside_a_sphere() {
    let text = format!(
        "PerspectiveCamera {{ center 0 0 0 direction 0 0 -1 up 0 1 0 angle 90 }}\n\
         {LIGHTS_AND_GLASS}\
         Group {{ numObjects 2 MaterialIndex 0 Sphere {{ center 0 0 0 radius 5 }}
             Sphere {{ center 0 0 -2 radius 1 }} }}"
    );
    let s = scene(&text);
    let frames = render_all(&s, 9, 9, "camera inside a sphere");
    // Every primary ray hits (the big sphere from inside, or the small one).
    assert!(frames[0].depth.iter().all(|d| d.is_finite()));
}

#[test]
fn numbers_near_the_ends_of_the_f32_range() {
    // Each of these once gave NaN pixels: an overflow to inf, later multiplied by 0.
    let camera = "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }";
    let sphere = "Group { numObjects 2 MaterialIndex 0 Sphere { center 0 0 0 radius 1 }
                  Plane { normal 0 0 1 offset -1 } }";
    let cases = [
        // Colours whose products overflow, under a light blocked by a shadow.
        "Lights { numLights 1 DirectionalLight { direction 0 0 -1 color 1e30 1e30 0 } }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 1e30 1e30 1e30 specularColor 1e30 0 0 } }",
        // A point light whose attenuation is a subnormal number: its colour divides to inf.
        "Lights { numLights 1 PointLight { position 0 0 3 color 1 0 1 attenuation 1e-39 0 0 } }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 1 1 1 } }",
        // Mirrors and glass amplifying at every bounce.
        "Lights { numLights 1 DirectionalLight { direction -1 -1 -1 color 1 1 1 } }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 1 1 1 reflectiveColor 1e20 1e20 0
                     transparentColor 1e20 0 1e20 indexOfRefraction 1e-30 } }",
        // Transparent shadows multiplying huge transparent colours.
        "Lights { numLights 1 DirectionalLight { direction 0 0 -1 color 1 1 1 } }
         Materials { numMaterials 1 PhongMaterial { transparentColor 1e25 1e25 1e25 } }",
        // Enormous ambient light, and an exponent of 0 with a zero n.h.
        "Lights { numLights 1 DirectionalLight { direction 0 0 1 color 1 1 1 } }
         Background { color 1e38 0 0 ambientLight 3e38 3e38 3e38 }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 3e38 1 0 specularColor 1 1 1 exponent 0 } }",
    ];
    for case in cases {
        render_all(&scene(&format!("{camera}\n{case}\n{sphere}")), 6, 6, case);
    }
    // Geometry at the ends of the range: huge and tiny spheres, a huge camera, a tiny up. The
    // two tiny spheres once gave NaN normals: the centre pixel's ray hits their very centre.
    let lights = "Lights { numLights 1 DirectionalLight { direction -1 -1 -1 color 1 1 1 } }
        Materials { numMaterials 1 PhongMaterial { diffuseColor 1 1 1 reflectiveColor 0.5 0.5 0.5 } }";
    let geometry = [
        "OrthographicCamera { center 0 0 3e38 direction 0 0 -1 up 0 1e-20 0 size 3e38 }
         Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1e18 } }",
        "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 1e-17 }
         Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1e-18 } }",
        "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 179.99 }
         Group { numObjects 1 MaterialIndex 0
             Transform { UniformScale 1e12 Sphere { center 0 0 0 radius 1e-12 } } }",
        "PerspectiveCamera { center 1e30 1e30 1e30 direction -1 -1 -1 up 0 1 0 angle 1e-30 }
         Group { numObjects 1 MaterialIndex 0 Plane { normal 1 1 1 offset 3e38 } }",
        "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }
         Group { numObjects 1 MaterialIndex 0
             Transform { Scale 1e-4 1e4 1 Triangle { vertex0 0 0 0 vertex1 1e4 0 0 vertex2 0 1e-4 0 } } }",
    ];
    for g in geometry {
        render_all(&scene(&format!("{lights}\n{g}")), 5, 5, g);
    }
}
