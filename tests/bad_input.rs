//! Claim: bad input never crashes `whitted` and never costs a file. Every malformed scene or
//! mesh, run through the real binary as `whitted render BAD -o out.png`, exits with code 2 and
//! prints exactly one line on stderr, `error: path:line:col: ...` (or `error: path: cannot ...`
//! when the file itself cannot be read), with no panic and no output or temporary file left.
//!
//! Each case is written into its own scratch folder from the strings below (no bad input is a
//! committed file). What belongs here: whole-program behaviour on bad input files. Exact parser
//! wording belongs in `parse_errors.rs`; bad command lines and limits in `resource_limits.rs`.

mod common;

use std::path::Path;

use common::{CAMERA, SPHERE, in_group, listing, scratch_dir};

const CUBE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// A scene whose group holds one mesh loaded from `mesh.obj`, named on line 4 column 25.
fn with_mesh() -> String {
    in_group("TriangleMesh { obj_file mesh.obj }")
}

/// Runs `whitted render bad.txt -o out.png` in a fresh folder holding `files` (`bad.txt` is the
/// scene unless `scene` names another path) and checks the claim. `at` is how the message must
/// start after `error: `.
fn check_in(name: &str, files: &[(&str, &[u8])], scene: &str, at: &str) {
    let dir = scratch_dir(&format!("bad_input/{name}"));
    for (file, bytes) in files {
        std::fs::write(dir.join(file), bytes).unwrap();
    }
    check_scene_in(name, &dir, scene, at);
}

/// Runs `whitted render SCENE -o out.png` in `dir` (already filled) and checks the claim.
fn check_scene_in(name: &str, dir: &Path, scene: &str, at: &str) {
    let before = listing(dir);
    let out = common::whitted(dir, &["render", scene, "-o", "out.png", "--size", "8", "8"]);
    let msg = out.assert_error(at);
    assert!(
        out.stderr.ends_with('\n'),
        "{name}: the line must end with a newline"
    );
    assert!(
        positioned(&msg) || msg.contains(": cannot "),
        "{name}: expected `path:line:col: ...` or `path: cannot ...`, found `{msg}`"
    );
    assert_eq!(
        listing(dir),
        before,
        "{name}: the folder changed (an output or temporary file was left)"
    );
    assert!(out.stdout.is_empty(), "{name}: nothing belongs on stdout");
}

/// `check_in` with the scene text as `bad.txt`.
fn check(name: &str, scene: impl AsRef<[u8]>, at: &str) {
    check_in(name, &[("bad.txt", scene.as_ref())], "bad.txt", at);
}

/// `check_in` with a scene loading `mesh.obj` and the given mesh text.
fn check_mesh(name: &str, obj: impl AsRef<[u8]>, at: &str) {
    let scene = with_mesh();
    check_in(
        name,
        &[("bad.txt", scene.as_bytes()), ("mesh.obj", obj.as_ref())],
        "bad.txt",
        at,
    );
}

/// True for `path:line:col: ...` with a non-empty path and numeric line and column.
fn positioned(msg: &str) -> bool {
    let mut parts = msg.splitn(4, ':');
    let (Some(path), Some(line), Some(col), Some(rest)) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return false;
    };
    let number = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    !path.is_empty() && number(line) && number(col) && rest.starts_with(' ')
}

#[test]
fn empty_and_blank_files() {
    check("empty", "", "bad.txt:1:1: expected a camera");
    check(
        "only_comments",
        "# a scene\n   \n# nothing else\n",
        "bad.txt:4:1: expected a camera",
    );
}

#[test]
fn truncated_files() {
    check(
        "truncated_camera",
        "OrthographicCamera { center 0 0",
        "bad.txt:1:32: expected a number for center",
    );
    check(
        "truncated_group",
        format!("{CAMERA}Group {{ numObjects 2\n{SPHERE}"),
        "bad.txt:3:33: expected 2 objects",
    );
    check(
        "truncated_sphere",
        format!("{CAMERA}Group {{ numObjects 1\nSphere {{ center 0 0 0 radius"),
        "bad.txt:3:29: expected a number for radius",
    );
    check(
        "missing_last_brace",
        format!("{CAMERA}Group {{ numObjects 1\n{SPHERE}\n"),
        "bad.txt:4:1: expected `}`",
    );
}

#[test]
fn wrong_counts() {
    let light = "DirectionalLight { direction 0 -1 0 color 1 1 1 }";
    let material = "Material { diffuseColor 1 0 0 }";
    check(
        "objects_too_many",
        format!("{CAMERA}Group {{ numObjects 3\n{SPHERE}\n}}\n"),
        "bad.txt:4:1: expected 3 objects",
    );
    check(
        "objects_too_few",
        format!("{CAMERA}Group {{ numObjects 1\n{SPHERE}\n{SPHERE}\n}}\n"),
        "bad.txt:4:1: expected `}` after 1 object",
    );
    check(
        "materials_too_many",
        format!("{CAMERA}Materials {{ numMaterials 2\n{material}\n}}\n"),
        "bad.txt:4:1: expected 2 materials",
    );
    check(
        "materials_too_few",
        format!("{CAMERA}Materials {{ numMaterials 1\n{material}\n{material}\n}}\n"),
        "bad.txt:4:1: expected `}` after 1 material",
    );
    check(
        "lights_too_many",
        format!("{CAMERA}Lights {{ numLights 2\n{light}\n}}\n"),
        "bad.txt:4:1: expected 2 lights",
    );
    check(
        "lights_too_few",
        format!("{CAMERA}Lights {{ numLights 1\n{light}\n{light}\n}}\n"),
        "bad.txt:4:1: expected `}` after 1 light",
    );
    check(
        "count_not_a_number",
        format!("{CAMERA}Group {{ numObjects two }}"),
        "bad.txt:2:20: expected a whole number for numObjects",
    );
}

#[test]
fn enormous_counts_allocate_nothing() {
    check(
        "objects_4e9",
        format!("{CAMERA}Group {{ numObjects 4000000000\n{SPHERE}\n}}\n"),
        "bad.txt:4:1: expected 4000000000 objects",
    );
    check(
        "materials_4e9",
        format!("{CAMERA}Materials {{ numMaterials 4294967295 }}\n"),
        "bad.txt:2:37: expected 4294967295 materials",
    );
    check(
        "lights_beyond_u32",
        format!("{CAMERA}Lights {{ numLights 18446744073709551616 }}\n"),
        "bad.txt:2:20: expected a whole number for numLights of at most 4294967295",
    );
}

#[test]
fn unknown_keywords() {
    check(
        "unknown_top_level",
        format!("{CAMERA}Fog {{ density 1 }}"),
        "bad.txt:2:1: expected a top-level block",
    );
    check(
        "unknown_object",
        in_group("Cone { apex 0 0 0 }"),
        "bad.txt:4:1: expected an object",
    );
    check(
        "unknown_field",
        in_group("Sphere { center 0 0 0 radius 1 colour 1 0 0 }"),
        "bad.txt:4:32: expected `center`, `radius` or `}` in Sphere",
    );
    check(
        "unknown_transform",
        in_group(&format!("Transform {{ Shear 1 0 0 {SPHERE} }}")),
        "bad.txt:4:13: expected a transform",
    );
    check(
        "unknown_material",
        format!("{CAMERA}Materials {{ numMaterials 1 Metal {{ }} }}"),
        "bad.txt:2:28: expected a material",
    );
    check(
        "unknown_light",
        format!("{CAMERA}Lights {{ numLights 1 SpotLight {{ }} }}"),
        "bad.txt:2:22: expected a light",
    );
}

#[test]
fn material_indices_out_of_range() {
    check(
        "material_index_high",
        in_group(&format!("MaterialIndex 5 {SPHERE}")),
        "bad.txt:4:15: expected a material index below 1",
    );
    check(
        "material_index_without_materials",
        format!("{CAMERA}Group {{ numObjects 1\nMaterialIndex 0 {SPHERE} }}"),
        "bad.txt:3:15: expected a Materials block",
    );
    check(
        "texture_index_high",
        format!(
            "{CAMERA}Materials {{ numMaterials 1\n\
             Checkerboard {{ Transform {{ }} materialIndex 0 materialIndex 7 }} }}\n\
             Group {{ numObjects 0 }}"
        ),
        "bad.txt:3:60: expected a material index below 1",
    );
    check(
        "texture_cycle",
        format!(
            "{CAMERA}Materials {{ numMaterials 2\nMaterial {{ diffuseColor 1 1 1 }}\n\
             Checkerboard {{ Transform {{ }} materialIndex 0 materialIndex 1 }} }}\n\
             Group {{ numObjects 1 MaterialIndex 1 {SPHERE} }}"
        ),
        "bad.txt:4:60: expected textures that end in plain materials, found material 1 \
         referring back to itself",
    );
}

#[test]
fn nan_infinite_and_enormous_numbers() {
    check(
        "nan_radius",
        in_group("Sphere { center 0 0 0 radius NaN }"),
        "bad.txt:4:30: expected a finite number for radius",
    );
    check(
        "infinite_offset",
        in_group("Plane { normal 0 1 0 offset inf }"),
        "bad.txt:4:29: expected a finite number for offset",
    );
    check(
        "enormous_center",
        in_group("Sphere { center 0 1e39 0 radius 1 }"),
        "bad.txt:4:19: expected a finite number for center",
    );
    check(
        "enormous_negative_vertex",
        in_group("Triangle { vertex0 -1e39 0 0 vertex1 1 0 0 vertex2 0 1 0 }"),
        "bad.txt:4:20: expected a finite number for vertex0",
    );
    check(
        "enormous_colour",
        format!("{CAMERA}Background {{ color 1e999 0 0 }}"),
        "bad.txt:2:20: expected a finite number for color",
    );
    check(
        "enormous_radius",
        in_group("Sphere { center 0 0 0 radius 1e30 }"),
        "bad.txt:4:30: expected a radius between",
    );
    check(
        "malformed_number",
        in_group("Sphere { center 0 1.2.3 0 radius 1 }"),
        "bad.txt:4:19: expected a number for center",
    );
    check(
        "negative_colour",
        in_group("Sphere { center 0 0 0 radius 1 }")
            .replace("diffuseColor 1 0 0", "diffuseColor -1 0 0"),
        "bad.txt:2:52: expected a colour with no negative channel",
    );
}

#[test]
fn zero_and_parallel_vectors() {
    check(
        "zero_camera_direction",
        "PerspectiveCamera { center 0 0 5 direction 0 0 0 up 0 1 0 angle 30 }",
        "bad.txt:1:44: expected a non-zero vector for direction",
    );
    check(
        "zero_camera_up",
        "PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 0 0 angle 30 }",
        "bad.txt:1:54: expected a non-zero vector for up",
    );
    check(
        "up_parallel_to_direction",
        "PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 0 3 angle 30 }",
        "bad.txt:1:44: expected `up` not parallel to `direction`",
    );
    check(
        "zero_plane_normal",
        in_group("Plane { normal 0 0 0 offset 0 }"),
        "bad.txt:4:16: expected a non-zero vector for normal",
    );
    check(
        "zero_light_direction",
        format!(
            "{CAMERA}Lights {{ numLights 1 DirectionalLight {{ direction 0 0 0 color 1 1 1 }} }}"
        ),
        "bad.txt:2:51: expected a non-zero vector for direction",
    );
    check(
        "zero_rotation_axis",
        in_group(&format!("Transform {{ Rotate {{ 0 0 0 90 }} {SPHERE} }}")),
        "bad.txt:4:22: expected a non-zero vector for the Rotate axis",
    );
}

#[test]
fn degenerate_geometry() {
    check(
        "zero_radius",
        in_group("Sphere { center 0 0 0 radius 0 }"),
        "bad.txt:4:30: expected a positive number for radius",
    );
    check(
        "negative_radius",
        in_group("Sphere { center 0 0 0 radius -2.5 }"),
        "bad.txt:4:30: expected a positive number for radius",
    );
    check(
        "collinear_triangle",
        in_group("Triangle { vertex0 0 0 0 vertex1 1 1 0 vertex2 2 2 0 }"),
        "bad.txt:4:1: expected a triangle with non-zero area",
    );
    check(
        "repeated_vertex_triangle",
        in_group("Triangle { vertex0 1 2 3 vertex1 1 2 3 vertex2 0 0 0 }"),
        "bad.txt:4:1: expected a triangle with non-zero area",
    );
    check(
        "zero_scale",
        in_group(&format!("Transform {{ UniformScale 0 {SPHERE} }}")),
        "bad.txt:4:26: expected a non-zero scale factor",
    );
    check(
        "singular_matrix",
        in_group(&format!(
            "Transform {{ Matrix {{ 1 1 0 0 1 1 0 0 0 0 1 0 0 0 0 1 }} {SPHERE} }}"
        )),
        "bad.txt:4:1: expected an invertible transform",
    );
}

#[test]
fn bad_obj_files() {
    check_mesh(
        "obj_face_index_high",
        format!("{CUBE_OBJ}f 1 2 4\n"),
        "mesh.obj:5:7: expected a vertex index between 1 and 3",
    );
    check_mesh(
        "obj_face_index_zero",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
        "mesh.obj:4:3: expected a vertex index between 1 and 3",
    );
    check_mesh(
        "obj_face_index_most_negative",
        format!("{CUBE_OBJ}f 1 2 -9223372036854775808\n"),
        "mesh.obj:5:7: expected a vertex index",
    );
    check_mesh(
        "obj_face_index_before_its_vertex",
        "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n",
        "mesh.obj:1:3: expected a vertex index between 1 and 0",
    );
    check_mesh(
        "obj_face_too_short",
        format!("{CUBE_OBJ}f 1 2\n"),
        "mesh.obj:5:1: expected a face with at least 3 vertices",
    );
    check_mesh(
        "obj_nan_vertex",
        "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
        "mesh.obj:2:5: expected a finite number",
    );
    check_mesh(
        "obj_degenerate_face",
        "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n",
        "mesh.obj:4:1: expected a triangle with non-zero area",
    );
    check_mesh(
        "obj_unknown_statement",
        format!("{CUBE_OBJ}bevel 1 2 3\n"),
        "mesh.obj:5:1: expected an OBJ statement",
    );
    check_mesh("obj_empty", "", "mesh.obj:1:1: expected at least one face");
    check_mesh(
        "obj_binary_garbage",
        b"v 0 0 0\n\x89PNG\r\n\x1a\n\x00\x00\xff\xd8",
        "mesh.obj:2:1: expected UTF-8 text, found byte 0x89",
    );
}

#[test]
fn missing_and_unreadable_obj_files() {
    let scene = with_mesh();
    check_in(
        "obj_missing",
        &[("bad.txt", scene.as_bytes())],
        "bad.txt",
        "bad.txt:4:25: cannot read OBJ file `mesh.obj`: No such file",
    );
    let dir = scratch_dir("bad_input/obj_is_a_folder");
    std::fs::create_dir(dir.join("mesh.obj")).unwrap();
    std::fs::write(dir.join("bad.txt"), &scene).unwrap();
    check_existing(
        "obj_is_a_folder",
        &dir,
        "bad.txt:4:25: cannot read OBJ file `mesh.obj`: it is a folder",
    );
    // A device would never end: only regular files are read.
    check(
        "obj_is_a_device",
        in_group("TriangleMesh { obj_file /dev/zero }"),
        "bad.txt:4:25: cannot read OBJ file `/dev/zero`: it is not a regular file",
    );
}

#[test]
fn a_mesh_too_large_for_memory_is_an_error_not_an_abort() {
    // A sparse file of 1 TiB takes no disk space; reading it must fail cleanly. (Unless the
    // kernel grants any allocation, vm.overcommit_memory = 1: then reading would go on.)
    if std::fs::read_to_string("/proc/sys/vm/overcommit_memory").is_ok_and(|s| s.trim() == "1") {
        eprintln!("skipped: vm.overcommit_memory = 1 grants any request");
        return;
    }
    let dir = scratch_dir("bad_input/obj_huge");
    std::fs::write(dir.join("bad.txt"), with_mesh()).unwrap();
    let file = std::fs::File::create(dir.join("mesh.obj")).unwrap();
    file.set_len(1 << 40).unwrap();
    drop(file);
    check_existing(
        "obj_huge",
        &dir,
        "bad.txt:4:25: cannot read OBJ file `mesh.obj`:",
    );
}

/// `check_in` on a folder the caller has already filled, with the scene `bad.txt`.
fn check_existing(name: &str, dir: &Path, at: &str) {
    check_scene_in(name, dir, "bad.txt", at);
}

#[test]
fn unreadable_scene_files() {
    check_in(
        "scene_missing",
        &[],
        "absent.txt",
        "absent.txt: cannot read scene: No such file",
    );
    check_in(
        "scene_is_a_folder",
        &[],
        ".",
        ".: cannot read scene: it is a folder",
    );
    check_in(
        "scene_is_a_device",
        &[],
        "/dev/zero",
        "/dev/zero: cannot read scene: it is not a regular file",
    );
}

#[test]
fn binary_garbage() {
    let mut garbage = Vec::new();
    let mut x: u32 = 0x1234_5678;
    for _ in 0..4096 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        garbage.push((x >> 24) as u8);
    }
    let first_bad = std::str::from_utf8(&garbage).unwrap_err().valid_up_to();
    assert!(first_bad < 64, "the garbage starts with invalid UTF-8");
    check("binary_garbage", &garbage, "bad.txt:");
    check(
        "png_bytes",
        b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR",
        "bad.txt:1:1: expected UTF-8 text, found byte 0x89",
    );
    // NUL bytes are valid UTF-8: they reach the tokenizer and come out escaped.
    check(
        "nul_bytes",
        b"\x00\x00\x00 Group",
        "bad.txt:1:1: expected a top-level block",
    );
}

#[test]
fn deeply_nested_groups_do_not_overflow_the_stack() {
    let mut text = String::from(CAMERA);
    for _ in 0..100_000 {
        text.push_str("Group { numObjects 1\n");
    }
    check(
        "nested_groups",
        text,
        "bad.txt:258:1: expected at most 256 nested groups and transforms",
    );
    let mut text = format!("{CAMERA}Group {{ numObjects 1\n");
    for _ in 0..100_000 {
        text.push_str("Transform { ");
    }
    check(
        "nested_transforms",
        text,
        "bad.txt:3:3061: expected at most 256 nested groups and transforms",
    );
}
