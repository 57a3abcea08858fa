//! Claim: every input that crashed one of the fuzz targets in `fuzz/` (or would have: some were
//! found in review first) now goes through that target's checks cleanly. Each case is the
//! minimised input, run through the same calls and assertions as its target, and must take the
//! path it crashed on: an input that crashed a parser is refused with a positioned error, not a
//! panic; an input that crashed a render parses (else the test would check nothing), and an
//! 8x8 render with shadows and 3 bounces, plain and with every option, with both tracers, has
//! only finite pixels.
//!
//! What belongs here: one test per crash, named by what it was, with the input inline.

mod common;

use std::path::Path;

use whitted::RenderOptions;
use whitted::options::check_options;
use whitted::reference::render_reference;
use whitted::shade::ShadeOptions;

/// The `parse_obj` target's checks, for an input that must be refused: an error, no panic.
/// Returns the message.
fn parse_obj_refused(text: &str) -> String {
    match whitted::scene::obj::parse_obj(text, Path::new("fuzz.obj")) {
        Ok(mesh) => panic!(
            "expected an error, parsed {} triangles",
            mesh.triangles.len()
        ),
        Err(e) => e.to_string(),
    }
}

/// The `render_tiny` target (which includes everything `parse_scene` checks).
fn render_tiny_target(text: &str) {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fuzz.txt"));
    // A regression input that stopped parsing would check nothing: it must parse.
    let scene = whitted::scene::parse::parse_str(text, path)
        .unwrap_or_else(|e| panic!("the regression input must parse: {e}\n{text}"));
    let plain = ShadeOptions {
        shadows: true,
        bounces: 3,
        ..ShadeOptions::default()
    };
    let everything = ShadeOptions {
        shade_back: true,
        transparent_shadows: true,
        fresnel: true,
        specular_fix: false,
        ..plain
    };
    for shade in [plain, everything] {
        let opts = RenderOptions {
            width: 8,
            height: 8,
            shade,
            threads: 1,
            ..RenderOptions::default()
        };
        check_options(&opts).unwrap();
        let geometry = whitted::geometry::Geometry::from_scene(&scene);
        common::assert_finite(&render_reference(&scene, &opts, &|_| {}).unwrap(), text);
        let packet = whitted::wavefront::render_packet(&scene, &geometry, &opts, &|_| {}).unwrap();
        common::assert_finite(&packet, text);
    }
}

#[test]
fn obj_index_i64_min_overflowed_when_negated() {
    // Found in review: `-i` on i64::MIN panics with overflow checks, and without them wraps to
    // a negative index that passes the range test and indexes out of bounds.
    let msg = parse_obj_refused("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n");
    assert!(msg.starts_with("fuzz.obj:4:"), "{msg}");
}

#[test]
fn overflowing_colours_times_a_zero_shadow_were_nan() {
    // Found in review (tests/pixels_are_finite.rs): inf colour * 0 visibility = NaN.
    render_tiny_target(
        "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }
         Lights { numLights 1 DirectionalLight { direction 0 0 -1 color 1e30 1e30 0 } }
         Materials { numMaterials 1 PhongMaterial { diffuseColor 1e30 1e30 1e30 } }
         Group { numObjects 2 MaterialIndex 0 Sphere { center 0 0 0 radius 1 }
             Plane { normal 0 0 1 offset -1 } }",
    );
}

#[test]
fn the_centre_of_a_tiny_sphere_had_a_nan_normal() {
    // Found in review: an 8x8 image has no centre pixel, so this one is offset onto a ray.
    render_tiny_target(
        "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 8e-18 }
         Group { numObjects 1 Sphere { center 5e-19 5e-19 0 radius 1e-18 } }",
    );
}
