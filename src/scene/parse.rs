//! The scene-file grammar: tokens to a [`Scene`]. It reads the MIT 6.837 format, top-level
//! blocks in any order, the material table (plain materials and the solid textures that choose
//! between two of them) and the object tree (groups, transforms and primitives). The blocks
//! that stand alone (cameras, lights, background, Phong materials, transform steps) are in
//! `blocks.rs`; the checks that need the whole file (material indices, texture loops, the
//! default material) run afterwards in `passes.rs`.
//!
//! ```text
//! path --input.rs--> &str --token.rs--> [Token] --Cursor--> this grammar (+ blocks.rs)
//!      --passes.rs--> Scene
//! ```
//!
//! The syntax, in full in `docs/scene-format.md`:
//!
//! ```text
//! <camera> <Lights>? <Background>? <Materials>? Group { ... }     # any order, each at most once
//! Materials { numMaterials n  <material>*n }
//! <material> = Material { ... } | PhongMaterial { ... }           # see blocks.rs
//!     | Checkerboard { Transform { <xform>* } materialIndex i materialIndex j }
//!     | Noise  { Transform { <xform>* } materialIndex i materialIndex j octaves k }
//!     | Marble { Transform { <xform>* } materialIndex i materialIndex j octaves k frequency f amplitude a }
//!     | Wood   { ...same as Marble... }
//! Group { numObjects n  ( [MaterialIndex i] <object> )*n  [MaterialIndex i] }
//! <object> = Sphere { center x y z  radius r }
//!          | Plane { normal x y z  offset d }                  # points p with n.p = d, n unit
//!          | Triangle { vertex0 x y z  vertex1 x y z  vertex2 x y z }
//!          | TriangleMesh { obj_file path.obj }                # relative to the scene file
//!          | Group { ... }
//!          | Transform { <xform>* [MaterialIndex i] <object> [MaterialIndex i] }
//! ```
//!
//! Transforms in a list compose left to right as matrices (`M = M1 M2 ... Mk`), so the last one
//! listed is applied to the object first. `MaterialIndex i` sets the material of every object
//! read after it, in file order across groups, until the next one; an object before any gets
//! the default material (white, diffuse). When a scene has no lights the ambient light is white,
//! as in the course. Every error names its position: `path:line:col: expected ..., found ...`.
//! No input makes the parser panic.

use std::path::{Path, PathBuf};

use super::blocks;
use super::cursor::{Cursor, grow, num_text};
use super::input::{decode_text, read_file};
use super::obj;
use super::passes::{self, NO_MATERIAL};
use super::token::{Token, tokenize};
use super::{Light, Material, Object, Scene, Texture, TextureKind, Transformed};
use crate::error::{Error, Result};
use crate::math::{Mat4, Vec3, is_degenerate};

/// The deepest nesting of groups and transforms the parser accepts.
pub const MAX_NESTING: usize = 256;
/// The most octaves a noise texture may ask for (more would add nothing visible in f32).
pub const MAX_OCTAVES: usize = 24;
/// The smallest sphere radius accepted: its square must stay a normal `f32`.
pub const MIN_RADIUS: f32 = 1e-18;
/// The largest sphere radius accepted: its square must stay finite.
pub const MAX_RADIUS: f32 = 1e18;

/// Reads and parses a scene file.
pub fn parse_file(path: &Path) -> Result<Scene> {
    let bytes = read_file(path, "read scene")?;
    let text = decode_text(&bytes, path)?;
    parse_str(text, path)
}

/// Parses scene text. `path` names the text in errors and anchors relative OBJ paths.
pub fn parse_str(text: &str, path: &Path) -> Result<Scene> {
    match tokenize(text) {
        Some((tokens, eof)) => Parser::new(Cursor::new(tokens, eof, path)).scene(),
        None => Err(Cursor::new(Vec::new(), (1, 1), path).out_of_memory()),
    }
}

const OBJECTS: &str = "an object (Sphere, Plane, Triangle, TriangleMesh, Group or Transform)";

/// The grammar's state while it reads one file.
struct Parser<'a> {
    cur: Cursor<'a>,
    /// The material of the next primitive: the last `MaterialIndex` read, or [`NO_MATERIAL`].
    current_material: u32,
    /// Every material index used, with the token that named it, checked once all are known.
    material_refs: Vec<(usize, Token<'a>)>,
    depth: usize,
    /// The id of the next primitive (see [`Object`]).
    next_id: u32,
}

impl<'a> Parser<'a> {
    fn new(cur: Cursor<'a>) -> Parser<'a> {
        Parser {
            cur,
            current_material: NO_MATERIAL,
            material_refs: Vec::new(),
            depth: 0,
            next_id: 0,
        }
    }

    fn scene(&mut self) -> Result<Scene> {
        let mut camera = None;
        let mut lights: Option<Vec<Light>> = None;
        let mut background = None;
        let mut materials: Option<Vec<Material>> = None;
        let mut root = None;
        while let Some(tok) = self.cur.peek() {
            let dup = |seen: bool, p: &Cursor<'_>| {
                if seen {
                    Err(p.error_at(
                        Some(&tok),
                        format!("expected one `{}` block, found a second", tok.text),
                    ))
                } else {
                    Ok(())
                }
            };
            match tok.text {
                "OrthographicCamera" | "PerspectiveCamera" => {
                    if camera.is_some() {
                        return Err(self.cur.error_at(
                            Some(&tok),
                            format!("expected one camera, found a second (`{}`)", tok.text),
                        ));
                    }
                    camera = Some(blocks::camera(&mut self.cur)?);
                }
                "Lights" => {
                    dup(lights.is_some(), &self.cur)?;
                    lights = Some(blocks::lights(&mut self.cur)?);
                }
                "Background" => {
                    dup(background.is_some(), &self.cur)?;
                    background = Some(blocks::background(&mut self.cur)?);
                }
                "Materials" => {
                    dup(materials.is_some(), &self.cur)?;
                    materials = Some(self.materials()?);
                }
                "Group" => {
                    dup(root.is_some(), &self.cur)?;
                    root = Some(self.group()?);
                }
                _ => {
                    return Err(self.cur.expected(
                        "a top-level block (OrthographicCamera, PerspectiveCamera, Lights, \
                         Background, Materials or Group)",
                    ));
                }
            }
        }
        let Some(camera) = camera else {
            return Err(self
                .cur
                .expected("a camera (OrthographicCamera or PerspectiveCamera)"));
        };
        let Some(mut root) = root else {
            return Err(self.cur.expected("a Group of objects"));
        };
        let lights = lights.unwrap_or_default();
        let (color, ambient) = background.unwrap_or((Vec3::splat(0.5), None));
        // Course rule: with no lights the ambient light is white (flat object colours).
        let ambient = if lights.is_empty() {
            Vec3::ONE
        } else {
            ambient.unwrap_or(Vec3::ZERO)
        };
        let mut materials = materials.unwrap_or_default();
        passes::check_material_refs(&self.cur, &self.material_refs, materials.len())?;
        passes::check_texture_cycles(&self.cur, &self.material_refs, &materials)?;
        passes::assign_default_material(&mut root, &mut materials);
        Ok(Scene {
            camera,
            lights,
            background: color,
            ambient,
            materials,
            root,
        })
    }

    fn materials(&mut self) -> Result<Vec<Material>> {
        self.cur.keyword("Materials")?;
        self.cur.keyword("{")?;
        self.cur.keyword("numMaterials")?;
        let n = self.cur.count("numMaterials")?;
        let mut materials = Vec::new();
        for i in 0..n {
            let m = match self.cur.peek().map(|t| t.text) {
                Some("Material" | "PhongMaterial") => {
                    Material::Phong(blocks::phong(&mut self.cur)?)
                }
                Some("Checkerboard" | "Noise" | "Marble" | "Wood") => self.texture()?,
                None | Some("}") => return Err(self.cur.too_few("material", "numMaterials", n, i)),
                _ => {
                    return Err(self.cur.expected(
                        "a material (Material, PhongMaterial, Checkerboard, Noise, Marble or \
                         Wood)",
                    ));
                }
            };
            materials.push(m);
        }
        if self.cur.peek().is_some_and(|t| t.text != "}") {
            return Err(self.cur.too_many("material", "numMaterials", n));
        }
        self.cur.keyword("}")?;
        Ok(materials)
    }

    fn texture(&mut self) -> Result<Material> {
        let kind = self.cur.next("a texture")?;
        self.cur.keyword("{")?;
        self.cur.keyword("Transform")?;
        self.cur.keyword("{")?;
        let mut matrix = Mat4::IDENTITY;
        while self.cur.peek().is_some_and(|t| t.text != "}") {
            matrix *= blocks::xform(&mut self.cur)?;
        }
        self.cur.keyword("}")?;
        let mut pair = [0u32; 2];
        for m in pair.iter_mut() {
            self.cur.keyword("materialIndex")?;
            let at = self.cur.peek();
            let i = self.cur.count("materialIndex")?;
            *m = i.min(NO_MATERIAL as usize - 1) as u32;
            if let Some(at) = at {
                self.material_refs.push((i, at));
            }
        }
        let mut octaves = || -> Result<u32> {
            self.cur.keyword("octaves")?;
            let at = self.cur.peek();
            let k = self.cur.count("octaves")?;
            if k > MAX_OCTAVES {
                return Err(self.cur.error_at(
                    at.as_ref(),
                    format!("expected at most {MAX_OCTAVES} octaves, found {k}"),
                ));
            }
            Ok(k as u32)
        };
        let kind = match kind.text {
            "Checkerboard" => TextureKind::Checkerboard,
            "Noise" => TextureKind::Noise {
                octaves: octaves()?,
            },
            marble_or_wood => {
                let octaves = octaves()?;
                self.cur.keyword("frequency")?;
                let frequency = self.cur.number("frequency")?;
                self.cur.keyword("amplitude")?;
                let amplitude = self.cur.number("amplitude")?;
                if marble_or_wood == "Marble" {
                    TextureKind::Marble {
                        octaves,
                        frequency,
                        amplitude,
                    }
                } else {
                    TextureKind::Wood {
                        octaves,
                        frequency,
                        amplitude,
                    }
                }
            }
        };
        self.cur.keyword("}")?;
        let det = matrix.determinant();
        if !(det.abs() > 0.0 && det.is_finite()) {
            return Err(self.cur.error_at(
                Some(&self.cur.previous()),
                "expected an invertible texture transform, found a singular one".to_string(),
            ));
        }
        Ok(Material::Texture(Texture {
            kind,
            matrix,
            a: pair[0],
            b: pair[1],
        }))
    }

    fn nest(&mut self) -> Result<()> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(self.cur.expected(&format!(
                "at most {MAX_NESTING} nested groups and transforms"
            )));
        }
        Ok(())
    }

    fn group(&mut self) -> Result<Object> {
        self.nest()?;
        self.cur.keyword("Group")?;
        self.cur.keyword("{")?;
        self.cur.keyword("numObjects")?;
        let n = self.cur.count("numObjects")?;
        let mut children = Vec::new();
        loop {
            self.material_index()?;
            if children.len() == n {
                break;
            }
            if self.cur.peek().is_none_or(|t| t.text == "}") {
                return Err(self.cur.too_few("object", "numObjects", n, children.len()));
            }
            grow(&mut children).map_err(|()| self.cur.out_of_memory())?;
            children.push(self.object()?);
        }
        if self.cur.peek().is_some_and(|t| t.text != "}") {
            return Err(self.cur.too_many("object", "numObjects", n));
        }
        self.cur.keyword("}")?;
        self.depth -= 1;
        Ok(Object::Group(children))
    }

    /// Any number of `MaterialIndex i` (the last one counts).
    fn material_index(&mut self) -> Result<()> {
        while self.cur.peek().is_some_and(|t| t.text == "MaterialIndex") {
            self.cur.advance();
            let at = self.cur.peek();
            let i = self.cur.count("MaterialIndex")?;
            if let Some(at) = at {
                self.material_refs.push((i, at));
            }
            // Out-of-range indices are reported once every material is known.
            self.current_material = i.min(NO_MATERIAL as usize - 1) as u32;
        }
        Ok(())
    }

    fn object(&mut self) -> Result<Object> {
        let Some(tok) = self.cur.peek() else {
            return Err(self.cur.expected(OBJECTS));
        };
        let material = self.current_material;
        match tok.text {
            "Sphere" => {
                self.cur.advance();
                let (mut center, mut radius) = (Vec3::ZERO, 0.0);
                let (seen, close) =
                    self.cur
                        .block_fields("Sphere", &["center", "radius"], &mut |p, name| {
                            if name == "center" {
                                center = p.vec3("center")?;
                            } else {
                                let at = p.peek();
                                radius = p.positive("radius")?;
                                if !(MIN_RADIUS..=MAX_RADIUS).contains(&radius) {
                                    return Err(p.error_at(
                                        at.as_ref(),
                                        format!(
                                            "expected a radius between {MIN_RADIUS:e} and \
                                         {MAX_RADIUS:e}, found {}",
                                            num_text(radius)
                                        ),
                                    ));
                                }
                            }
                            Ok(())
                        })?;
                self.cur.require("Sphere", &seen, &close, "center")?;
                self.cur.require("Sphere", &seen, &close, "radius")?;
                Ok(Object::Sphere {
                    center,
                    radius,
                    material,
                    id: self.take_ids(1)?,
                })
            }
            "Plane" => {
                self.cur.advance();
                let (mut normal, mut offset) = (Vec3::ZERO, 0.0);
                let (seen, close) =
                    self.cur
                        .block_fields("Plane", &["normal", "offset"], &mut |p, name| {
                            if name == "normal" {
                                normal = p.direction("normal")?;
                            } else {
                                offset = p.number("offset")?;
                            }
                            Ok(())
                        })?;
                self.cur.require("Plane", &seen, &close, "normal")?;
                self.cur.require("Plane", &seen, &close, "offset")?;
                let len = normal.length();
                Ok(Object::Plane {
                    normal: normal / len,
                    offset: offset / len,
                    material,
                    id: self.take_ids(1)?,
                })
            }
            "Triangle" => {
                self.cur.advance();
                let mut v = [Vec3::ZERO; 3];
                let (seen, close) = self.cur.block_fields(
                    "Triangle",
                    &["vertex0", "vertex1", "vertex2"],
                    &mut |p, name| {
                        let i = (name.as_bytes()[6] - b'0') as usize;
                        v[i] = p.vec3(name)?;
                        Ok(())
                    },
                )?;
                for name in ["vertex0", "vertex1", "vertex2"] {
                    self.cur.require("Triangle", &seen, &close, name)?;
                }
                if is_degenerate(&v) {
                    return Err(self.cur.error_at(
                        Some(&tok),
                        "expected a triangle with non-zero area, found a degenerate one (its vertices are collinear or coincide)".to_string(),
                    ));
                }
                Ok(Object::Triangle {
                    v,
                    material,
                    id: self.take_ids(1)?,
                })
            }
            "TriangleMesh" => {
                self.cur.advance();
                self.cur.keyword("{")?;
                self.cur.keyword("obj_file")?;
                let file = self.cur.next("an OBJ file name")?;
                self.cur.keyword("}")?;
                let path = self.resolve(file.text);
                let obj::ObjMesh { triangles, normals } =
                    obj::load_obj(&path).map_err(|e| match e {
                        Error::Io { source, .. } => self.cur.error_at(
                            Some(&file),
                            format!("cannot read OBJ file `{}`: {source}", path.display()),
                        ),
                        other => other,
                    })?;
                let first_id = self.take_ids(triangles.len())?;
                Ok(Object::Mesh {
                    triangles,
                    normals,
                    material,
                    first_id,
                })
            }
            "Group" => self.group(),
            "Transform" => {
                self.nest()?;
                self.cur.advance();
                self.cur.keyword("{")?;
                let mut matrix = Mat4::IDENTITY;
                while self.cur.peek().is_some_and(|t| blocks::is_xform(t.text)) {
                    matrix *= blocks::xform(&mut self.cur)?;
                }
                self.material_index()?;
                if !self.cur.peek().is_some_and(|t| is_object(t.text)) {
                    return Err(self.cur.expected(&format!(
                        "a transform (Translate, Scale, UniformScale, XRotate, YRotate, ZRotate, \
                         Rotate or Matrix) or {OBJECTS}"
                    )));
                }
                let child = self.object()?;
                self.material_index()?;
                self.cur.keyword("}")?;
                self.depth -= 1;
                let det = matrix.determinant();
                let inverse = matrix.inverse();
                if !(det.abs() > 1e-12 && det.is_finite() && inverse.is_finite()) {
                    return Err(self.cur.error_at(
                        Some(&tok),
                        format!(
                            "expected an invertible transform, found one with determinant {}",
                            num_text(det)
                        ),
                    ));
                }
                Ok(Object::Transform(Box::new(Transformed::new(matrix, child))))
            }
            _ => Err(self.cur.expected(OBJECTS)),
        }
    }

    /// Reserves `n` consecutive primitive ids.
    fn take_ids(&mut self, n: usize) -> Result<u32> {
        let first = self.next_id;
        match u32::try_from(n).ok().and_then(|n| first.checked_add(n)) {
            Some(next) if next < u32::MAX => {
                self.next_id = next;
                Ok(first)
            }
            _ => Err(self.cur.expected("at most 4294967294 primitives")),
        }
    }

    /// An OBJ path relative to the scene file's folder, else as given (relative to the current
    /// folder).
    fn resolve(&self, name: &str) -> PathBuf {
        let beside = self
            .cur
            .path()
            .parent()
            .map_or_else(|| PathBuf::from(name), |dir| dir.join(name));
        if beside.exists() || Path::new(name).is_absolute() {
            beside
        } else if Path::new(name).exists() {
            PathBuf::from(name)
        } else {
            beside
        }
    }
}

fn is_object(word: &str) -> bool {
    matches!(
        word,
        "Sphere" | "Plane" | "Triangle" | "TriangleMesh" | "Group" | "Transform"
    )
}
