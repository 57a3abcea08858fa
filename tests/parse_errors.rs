//! Claim: every malformed scene gets one exact, positioned message,
//! `path:line:col: expected ..., found ...`, naming what was wanted and what was there.
//!
//! One test per kind of mistake; each asserts the whole message, so a change of wording or of
//! position is a deliberate edit here. Scenes are built from a valid camera and material
//! block plus the broken part; line 1 is the camera, line 2 the materials, the group opens on
//! line 3 and its body starts on line 4. Messages of the CLI as a whole (exit code, one line
//! on stderr, no file written) belong in `bad_input.rs`.

mod common;

use std::path::Path;

use common::{CAMERA, SPHERE, in_group};
use whitted::scene::parse::parse_str;

/// The message `text` fails with.
fn error(text: &str) -> String {
    match parse_str(text, Path::new("scene.txt")) {
        Ok(_) => panic!("parsed, but should not have:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A scene with `block` on line 2, after the camera.
fn after_camera(block: &str) -> String {
    format!("{CAMERA}{block}\n")
}

#[test]
fn empty_file() {
    assert_eq!(
        error(""),
        "scene.txt:1:1: expected a camera (OrthographicCamera or PerspectiveCamera), found end of file"
    );
}

#[test]
fn unknown_top_level_keyword() {
    assert_eq!(
        error("Camera { }"),
        "scene.txt:1:1: expected a top-level block (OrthographicCamera, PerspectiveCamera, Lights, \
         Background, Materials or Group), found `Camera`"
    );
}

#[test]
fn stray_closing_brace() {
    assert_eq!(
        error(&after_camera("}")),
        "scene.txt:2:1: expected a top-level block (OrthographicCamera, PerspectiveCamera, Lights, \
         Background, Materials or Group), found `}`"
    );
}

#[test]
fn missing_opening_brace() {
    assert_eq!(
        error(&after_camera("Group numObjects 0 }")),
        "scene.txt:2:7: expected `{`, found `numObjects`"
    );
}

#[test]
fn truncated_inside_a_vector() {
    assert_eq!(
        error(&format!(
            "{CAMERA}Group {{ numObjects 1\nSphere {{ center 0 0"
        )),
        "scene.txt:3:20: expected a number for center, found end of file"
    );
}

#[test]
fn no_group() {
    assert_eq!(
        error(CAMERA),
        "scene.txt:2:1: expected a Group of objects, found end of file"
    );
}

#[test]
fn second_camera() {
    assert_eq!(
        error(&format!("{CAMERA}{CAMERA}")),
        "scene.txt:2:1: expected one camera, found a second (`OrthographicCamera`)"
    );
}

#[test]
fn negative_radius() {
    assert_eq!(
        error(&in_group("Sphere { center 0 0 0 radius -1 }")),
        "scene.txt:4:30: expected a positive number for radius, found -1"
    );
}

#[test]
fn zero_radius() {
    assert_eq!(
        error(&in_group("Sphere { center 0 0 0 radius 0 }")),
        "scene.txt:4:30: expected a positive number for radius, found 0"
    );
}

#[test]
fn radius_too_small_to_square() {
    assert_eq!(
        error(&in_group("Sphere { center 0 0 0 radius 1e-30 }")),
        "scene.txt:4:30: expected a radius between 1e-18 and 1e18, found 1e-30"
    );
}

#[test]
fn nan() {
    assert_eq!(
        error(&in_group("Sphere { center 0 0 0 radius nan }")),
        "scene.txt:4:30: expected a finite number for radius, found `nan`"
    );
}

#[test]
fn number_beyond_f32() {
    assert_eq!(
        error(&in_group("Sphere { center 0 1e39 0 radius 1 }")),
        "scene.txt:4:19: expected a finite number for center, found `1e39`"
    );
}

#[test]
fn infinity() {
    assert_eq!(
        error(&in_group("Plane { normal 0 1 0 offset -inf }")),
        "scene.txt:4:29: expected a finite number for offset, found `-inf`"
    );
}

#[test]
fn long_token_is_cut_short() {
    assert_eq!(
        error(&in_group(
            "Sphere { center 0 0 0 radius 1234567890123456789012345678901234567890abc }"
        )),
        "scene.txt:4:30: expected a number for radius, found `123456789012345678901234...`"
    );
}

#[test]
fn too_few_objects() {
    let text = format!("{CAMERA}Group {{ numObjects 3\n{SPHERE}\n{SPHERE}\n}}\n");
    assert_eq!(
        error(&text),
        "scene.txt:5:1: expected 3 objects (numObjects 3), found `}` after 2"
    );
}

#[test]
fn too_many_objects() {
    let text = format!("{CAMERA}Group {{ numObjects 1\n{SPHERE}\n{SPHERE}\n}}\n");
    assert_eq!(
        error(&text),
        "scene.txt:4:1: expected `}` after 1 object (numObjects 1), found `Sphere`"
    );
}

#[test]
fn enormous_object_count() {
    assert_eq!(
        error(&after_camera("Group { numObjects 4000000000 }")),
        "scene.txt:2:31: expected 4000000000 objects (numObjects 4000000000), found `}` after 0"
    );
}

#[test]
fn object_count_beyond_u32() {
    assert_eq!(
        error(&after_camera("Group { numObjects 99999999999 }")),
        "scene.txt:2:20: expected a whole number for numObjects of at most 4294967295, found \
         `99999999999`"
    );
}

#[test]
fn negative_count() {
    assert_eq!(
        error(&after_camera("Group { numObjects -1 }")),
        "scene.txt:2:20: expected a whole number for numObjects, found `-1`"
    );
}

#[test]
fn too_few_materials() {
    let text = after_camera("Materials { numMaterials 2\nMaterial { diffuseColor 1 0 0 }\n}");
    assert_eq!(
        error(&text),
        "scene.txt:4:1: expected 2 materials (numMaterials 2), found `}` after 1"
    );
}

#[test]
fn too_many_materials() {
    let m = "Material { diffuseColor 1 0 0 }";
    let text = after_camera(&format!("Materials {{ numMaterials 1\n{m}\n{m}\n}}"));
    assert_eq!(
        error(&text),
        "scene.txt:4:1: expected `}` after 1 material (numMaterials 1), found `Material`"
    );
}

#[test]
fn too_few_lights() {
    let text =
        after_camera("Lights { numLights 2\nDirectionalLight { direction 0 -1 0 color 1 1 1 }\n}");
    assert_eq!(
        error(&text),
        "scene.txt:4:1: expected 2 lights (numLights 2), found `}` after 1"
    );
}

#[test]
fn too_many_lights() {
    let text =
        after_camera("Lights { numLights 0\nDirectionalLight { direction 0 -1 0 color 1 1 1 }\n}");
    assert_eq!(
        error(&text),
        "scene.txt:3:1: expected `}` after 0 lights (numLights 0), found `DirectionalLight`"
    );
}

#[test]
fn material_index_out_of_range() {
    assert_eq!(
        error(&in_group(&format!("MaterialIndex 3 {SPHERE}"))),
        "scene.txt:4:15: expected a material index below 1 (numMaterials 1), found 3"
    );
}

#[test]
fn largest_material_index_is_reported_as_written() {
    assert_eq!(
        error(&in_group(&format!("MaterialIndex 4294967295 {SPHERE}"))),
        "scene.txt:4:15: expected a material index below 1 (numMaterials 1), found 4294967295"
    );
}

#[test]
fn material_index_without_materials() {
    let text = format!("{CAMERA}Group {{ numObjects 1\nMaterialIndex 0 {SPHERE} }}");
    assert_eq!(
        error(&text),
        "scene.txt:3:15: expected a Materials block to define material 0, found none"
    );
}

#[test]
fn zero_camera_direction() {
    assert_eq!(
        error("PerspectiveCamera { center 0 0 10 direction 0 0 0 up 0 1 0 angle 30 }"),
        "scene.txt:1:45: expected a non-zero vector for direction, found (0 0 0)"
    );
}

#[test]
fn camera_direction_too_long_to_normalise() {
    assert_eq!(
        error("PerspectiveCamera { center 0 0 10 direction 3e38 3e38 0 up 0 1 0 angle 30 }"),
        "scene.txt:1:45: expected a finite-length vector for direction, found (3e38 3e38 0)"
    );
}

#[test]
fn zero_up() {
    assert_eq!(
        error("PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 0 0 angle 30 }"),
        "scene.txt:1:55: expected a non-zero vector for up, found (0 0 0)"
    );
}

#[test]
fn up_parallel_to_direction() {
    let text = "PerspectiveCamera {\n center 0 0 10\n direction 0 2 0\n up 0 1 0\n angle 30 }";
    assert_eq!(
        error(text),
        "scene.txt:3:12: expected `up` not parallel to `direction` in PerspectiveCamera, found \
         both along (0 2 0)"
    );
}

#[test]
fn straight_angle() {
    assert_eq!(
        error("PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 180 }"),
        "scene.txt:1:67: expected an angle between 0 and 180 degrees, found 180"
    );
}

#[test]
fn zero_plane_normal() {
    assert_eq!(
        error(&in_group("Plane { normal 0 0 0 offset 1 }")),
        "scene.txt:4:16: expected a non-zero vector for normal, found (0 0 0)"
    );
}

#[test]
fn degenerate_triangle() {
    assert_eq!(
        error(&in_group(
            "Triangle { vertex0 0 0 0 vertex1 1 1 1 vertex2 2 2 2 }"
        )),
        "scene.txt:4:1: expected a triangle with non-zero area, found a degenerate one (its \
         vertices are collinear or coincide)"
    );
}

#[test]
fn zero_scale() {
    assert_eq!(
        error(&in_group(&format!("Transform {{ Scale 1 0 1 {SPHERE} }}"))),
        "scene.txt:4:19: expected non-zero scale factors, found (1 0 1)"
    );
}

#[test]
fn singular_matrix() {
    let m = "Matrix { 1 0 0 0  0 1 0 0  0 0 0 0  0 0 0 1 }";
    assert_eq!(
        error(&in_group(&format!("Transform {{ {m} {SPHERE} }}"))),
        "scene.txt:4:1: expected an invertible transform, found one with determinant 0"
    );
}

#[test]
fn overflowing_transform() {
    assert_eq!(
        error(&in_group(&format!(
            "Transform {{ UniformScale 1e20 {SPHERE} }}"
        ))),
        "scene.txt:4:1: expected an invertible transform, found one with determinant inf"
    );
}

#[test]
fn zero_rotation_axis() {
    assert_eq!(
        error(&in_group(&format!(
            "Transform {{ Rotate {{ 0 0 0 45 }} {SPHERE} }}"
        ))),
        "scene.txt:4:22: expected a non-zero vector for the Rotate axis, found (0 0 0)"
    );
}

#[test]
fn short_matrix() {
    assert_eq!(
        error(&in_group(&format!(
            "Transform {{ Matrix {{ 1 0 0 }} {SPHERE} }}"
        ))),
        "scene.txt:4:28: expected a number for Matrix, found `}`"
    );
}

#[test]
fn unknown_transform() {
    assert_eq!(
        error(&in_group(&format!("Transform {{ Shear 1 2 3 {SPHERE} }}"))),
        "scene.txt:4:13: expected a transform (Translate, Scale, UniformScale, XRotate, YRotate, \
         ZRotate, Rotate or Matrix) or an object (Sphere, Plane, Triangle, TriangleMesh, Group or \
         Transform), found `Shear`"
    );
}

#[test]
fn unknown_object() {
    assert_eq!(
        error(&in_group("Cube { }")),
        "scene.txt:4:1: expected an object (Sphere, Plane, Triangle, TriangleMesh, Group or \
         Transform), found `Cube`"
    );
}

#[test]
fn misspelt_field() {
    assert_eq!(
        error(&in_group("Sphere { centre 0 0 0 radius 1 }")),
        "scene.txt:4:10: expected `center`, `radius` or `}` in Sphere, found `centre`"
    );
}

#[test]
fn missing_field() {
    assert_eq!(
        error(&in_group("Sphere { center 0 0 0 }")),
        "scene.txt:4:23: expected `radius` in Sphere, found `}`"
    );
}

#[test]
fn repeated_field() {
    assert_eq!(
        error(&in_group("Sphere { center 0 0 0 radius 1 radius 2 }")),
        "scene.txt:4:32: expected `radius` once in Sphere, found it twice"
    );
}

#[test]
fn negative_colour() {
    assert_eq!(
        error(&after_camera("Background { color 0 -0.5 0 }")),
        "scene.txt:2:20: expected a colour with no negative channel for color, found (0 -0.5 0)"
    );
}

#[test]
fn negative_exponent() {
    assert_eq!(
        error(&after_camera(
            "Materials { numMaterials 1 PhongMaterial { exponent -2 } }"
        )),
        "scene.txt:2:53: expected a non-negative exponent, found -2"
    );
}

#[test]
fn zero_index_of_refraction() {
    assert_eq!(
        error(&after_camera(
            "Materials { numMaterials 1 PhongMaterial { indexOfRefraction 0 } }"
        )),
        "scene.txt:2:62: expected a positive number for indexOfRefraction, found 0"
    );
}

#[test]
fn zero_attenuation() {
    let light = "PointLight { position 0 0 0 color 1 1 1 attenuation 0 0 0 }";
    assert_eq!(
        error(&after_camera(&format!("Lights {{ numLights 1 {light} }}"))),
        "scene.txt:2:74: expected non-negative attenuation constants, not all zero, found (0 0 0)"
    );
}

#[test]
fn missing_obj_file() {
    assert_eq!(
        error(&in_group("TriangleMesh { obj_file missing.obj }")),
        "scene.txt:4:25: cannot read OBJ file `missing.obj`: No such file or directory (os error 2)"
    );
}

#[test]
fn nesting_deeper_than_the_limit() {
    // 100000 levels: the parser stops at level 257 instead of overflowing the stack.
    let mut text = String::from(CAMERA);
    for _ in 0..100_000 {
        text.push_str("Group { numObjects 1\n");
    }
    assert_eq!(
        error(&text),
        "scene.txt:258:1: expected at most 256 nested groups and transforms, found `Group`"
    );
}

#[test]
fn nesting_at_the_limit_parses() {
    // The root group, 254 transforms and an inner group: 256 levels.
    let transforms = whitted::scene::parse::MAX_NESTING - 2;
    let mut text = format!("{CAMERA}Group {{ numObjects 1 ");
    for _ in 0..transforms {
        text.push_str("Transform { Translate 0 0 0 ");
    }
    text.push_str("Group { numObjects 1 Sphere { center 0 0 0 radius 1 } }");
    for _ in 0..transforms {
        text.push_str(" }");
    }
    text.push_str(" }");
    let scene = parse_str(&text, Path::new("scene.txt")).expect("256 levels parse");
    assert_eq!(scene.primitive_count(), 1);
}

#[test]
fn binary_garbage_names_the_first_bad_byte() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("parse_errors");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("garbage.txt");
    std::fs::write(&path, b"OrthographicCamera {\n  center \xff\xfe 0 0").unwrap();
    let e = whitted::Scene::load(&path).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}:2:10: expected UTF-8 text, found byte 0xff",
            path.display()
        )
    );
}
