//! Claim: every example of `docs/scene-format.md` parses, every keyword of the format appears in
//! one of them, and the examples mean what the text beside them says (the plane's offset, the
//! order of transforms, the direction of rotations, how `Matrix` is read, the material carried
//! across groups, the default material, the mesh path resolved beside the scene file).
//!
//! Examples are the fenced blocks whose info string starts with `scene`: `scene` is a complete
//! file; `scene-top` holds top-level blocks, completed with a camera and an empty group if it has
//! none; `scene-object` is one object, put in a group after a camera and four plain materials.
//! A second word in the info string labels an example for the checks below. Examples are parsed
//! as if they sat in `scenes/`, so `obj_file cube.obj` finds `scenes/cube.obj`.

use std::path::{Path, PathBuf};

use whitted::Scene;
use whitted::math::Vec3;
use whitted::scene::parse::parse_str;
use whitted::scene::{Material, Object, Phong};

const CAMERA: &str = "OrthographicCamera { center 0 0 10  direction 0 0 -1  up 0 1 0  size 5 }\n";
const FOUR_MATERIALS: &str = "Materials { numMaterials 4 Material { } Material { } Material { } \
                              Material { } }\n";

/// Every keyword of the scene format: each must appear in some example.
const KEYWORDS: &[&str] = &[
    "OrthographicCamera",
    "PerspectiveCamera",
    "center",
    "direction",
    "up",
    "size",
    "angle",
    "Lights",
    "numLights",
    "DirectionalLight",
    "PointLight",
    "position",
    "color",
    "attenuation",
    "Background",
    "ambientLight",
    "Materials",
    "numMaterials",
    "Material",
    "PhongMaterial",
    "diffuseColor",
    "specularColor",
    "exponent",
    "reflectiveColor",
    "transparentColor",
    "indexOfRefraction",
    "Checkerboard",
    "Noise",
    "Marble",
    "Wood",
    "materialIndex",
    "octaves",
    "frequency",
    "amplitude",
    "Group",
    "numObjects",
    "MaterialIndex",
    "Sphere",
    "radius",
    "Plane",
    "normal",
    "offset",
    "Triangle",
    "vertex0",
    "vertex1",
    "vertex2",
    "TriangleMesh",
    "obj_file",
    "Transform",
    "Translate",
    "Scale",
    "UniformScale",
    "XRotate",
    "YRotate",
    "ZRotate",
    "Rotate",
    "Matrix",
];

struct Example {
    kind: String,
    label: String,
    /// The line of the opening fence in the document.
    line: usize,
    text: String,
}

fn doc_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md")
}

/// The fenced blocks of the document whose info string starts with `scene`.
fn examples() -> Vec<Example> {
    let doc = std::fs::read_to_string(doc_path()).expect("docs/scene-format.md");
    let mut out = Vec::new();
    let mut open: Option<Example> = None;
    for (i, line) in doc.lines().enumerate() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(info)) => {
                let mut words = info.split_whitespace();
                let kind = words.next().unwrap_or("").to_string();
                let label = words.next().unwrap_or("").to_string();
                open = Some(Example {
                    kind,
                    label,
                    line: i + 1,
                    text: String::new(),
                });
            }
            (Some(_), Some(_)) => {
                let ex = open.take().unwrap();
                if ex.kind.starts_with("scene") {
                    out.push(ex);
                }
            }
            (Some(ex), None) => {
                ex.text.push_str(line);
                ex.text.push('\n');
            }
            (None, None) => {}
        }
    }
    assert!(open.is_none(), "an unclosed code fence in the document");
    out
}

/// The complete scene text of an example.
fn scene_text(ex: &Example) -> String {
    let has = |word: &str| ex.text.split_whitespace().any(|w| w == word);
    match ex.kind.as_str() {
        "scene" => ex.text.clone(),
        "scene-top" => {
            let camera = if has("OrthographicCamera") || has("PerspectiveCamera") {
                ""
            } else {
                CAMERA
            };
            let group = if has("Group") {
                ""
            } else {
                "Group { numObjects 0 }\n"
            };
            format!("{camera}{}{group}", ex.text)
        }
        "scene-object" => {
            format!(
                "{CAMERA}{FOUR_MATERIALS}Group {{ numObjects 1\n{}}}\n",
                ex.text
            )
        }
        other => panic!(
            "docs/scene-format.md:{}: unknown example kind `{other}` (scene, scene-top or \
             scene-object)",
            ex.line
        ),
    }
}

/// Parses an example as if it were `scenes/<line>.txt`.
fn parse(ex: &Example) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("scene-format-example-{}.txt", ex.line));
    parse_str(&scene_text(ex), &path).unwrap_or_else(|e| {
        panic!(
            "docs/scene-format.md:{}: the example does not parse: {e}\n{}",
            ex.line, ex.text
        )
    })
}

fn labelled(label: &str) -> Scene {
    let all = examples();
    let ex = all
        .iter()
        .find(|ex| ex.label == label)
        .unwrap_or_else(|| panic!("no example labelled `{label}` in docs/scene-format.md"));
    parse(ex)
}

/// The children of the scene's top-level group.
fn children(scene: &Scene) -> &[Object] {
    match &scene.root {
        Object::Group(children) => children,
        other => panic!("the root is not a group: {other:?}"),
    }
}

fn material_of(obj: &Object) -> u32 {
    match obj {
        Object::Sphere { material, .. }
        | Object::Plane { material, .. }
        | Object::Triangle { material, .. }
        | Object::Mesh { material, .. } => *material,
        Object::Group(children) => material_of(&children[0]),
        Object::Transform(t) => material_of(&t.child),
    }
}

#[test]
fn every_example_parses() {
    let all = examples();
    for ex in &all {
        parse(ex);
    }
    // Not vacuous: the document has an example for every block it describes.
    assert!(all.len() >= 15, "only {} examples found", all.len());
}

#[test]
fn every_keyword_appears_in_an_example() {
    let all = examples();
    let words: Vec<&str> = all
        .iter()
        .flat_map(|ex| {
            ex.text
                .split(|c: char| c.is_whitespace() || c == '{' || c == '}')
        })
        .collect();
    let missing: Vec<&&str> = KEYWORDS.iter().filter(|k| !words.contains(k)).collect();
    assert!(
        missing.is_empty(),
        "keywords without an example: {missing:?}"
    );
}

#[test]
fn plane_offset_uses_the_normal_as_written() {
    // `Plane { normal 0 2 0  offset 2 }` is the plane 2y = 2, that is y = 1.
    let scene = labelled("plane-offset");
    let Object::Plane { normal, offset, .. } = &children(&scene)[0] else {
        panic!("not a plane");
    };
    assert_eq!(*normal, Vec3::Y);
    assert_eq!(*offset, 1.0);
}

/// The world position of the object-space point `p` under the example's one transform.
fn transformed(scene: &Scene, p: Vec3) -> Vec3 {
    let Object::Transform(t) = &children(scene)[0] else {
        panic!("not a transform");
    };
    t.matrix.transform_point3(p)
}

#[test]
fn the_transform_written_last_applies_first() {
    let scene = labelled("transform-order-translate-first");
    assert_eq!(transformed(&scene, Vec3::ZERO), Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(transformed(&scene, Vec3::X), Vec3::new(3.0, 0.0, 0.0));
    assert_eq!(transformed(&scene, -Vec3::X), Vec3::new(-1.0, 0.0, 0.0));
    let scene = labelled("transform-order-scale-first");
    assert_eq!(transformed(&scene, Vec3::ZERO), Vec3::new(2.0, 0.0, 0.0));
    assert_eq!(transformed(&scene, Vec3::X), Vec3::new(4.0, 0.0, 0.0));
    assert_eq!(transformed(&scene, -Vec3::X), Vec3::new(0.0, 0.0, 0.0));
}

#[test]
fn rotations_are_right_handed_and_matrices_read_row_by_row() {
    let scene = labelled("z-rotate-90");
    let p = transformed(&scene, Vec3::X);
    assert!(
        (p - Vec3::Y).length() < 1e-6,
        "ZRotate 90 took (1 0 0) to {p}"
    );
    let scene = labelled("matrix-row-by-row");
    assert_eq!(transformed(&scene, Vec3::ZERO), Vec3::new(5.0, 6.0, 7.0));
}

#[test]
fn mesh_paths_are_resolved_beside_the_scene_file() {
    // Tests run in the repository root, which has no `cube.obj`: only the scene's folder has one.
    let scene = labelled("mesh-path");
    let Object::Mesh { triangles, .. } = &children(&scene)[0] else {
        panic!("not a mesh");
    };
    assert_eq!(triangles.len(), 12, "scenes/cube.obj has 12 triangles");
}

/// The complete-file examples, by the text the document puts in them.
fn example_containing(needle: &str) -> Scene {
    let all = examples();
    let ex = all
        .iter()
        .find(|ex| ex.kind == "scene" && ex.text.contains(needle))
        .unwrap_or_else(|| panic!("no complete example containing `{needle}`"));
    parse(ex)
}

#[test]
fn material_index_carries_across_group_boundaries() {
    let scene = example_containing("MaterialIndex 1\n        Sphere { center -1 0 0");
    let kids = children(&scene);
    assert_eq!(material_of(&kids[0]), 1);
    assert_eq!(
        material_of(&kids[1]),
        1,
        "the outer sphere keeps material 1"
    );
}

#[test]
fn objects_before_any_material_index_get_the_appended_white_default() {
    let scene = example_containing("Plane { normal 0 0 1  offset -1 }\n    MaterialIndex 0");
    let kids = children(&scene);
    assert_eq!(scene.materials.len(), 2, "one defined, one appended");
    assert_eq!(
        material_of(&kids[0]),
        1,
        "the plane has the appended material"
    );
    assert_eq!(material_of(&kids[1]), 0);
    assert_eq!(scene.materials[1], Material::Phong(Phong::default()));
    assert_eq!(Phong::default().diffuse, Vec3::ONE);
}
