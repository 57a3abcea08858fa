//! The scene-file parser: text to [`Scene`]. It reads the MIT 6.837 format, whitespace-separated
//! tokens with `{ }` blocks (braces need no spaces around them, and `#` starts a comment that
//! runs to the end of the line):
//!
//! ```text
//! OrthographicCamera { center x y z  direction x y z  up x y z  size s }
//! PerspectiveCamera  { center x y z  direction x y z  up x y z  angle degrees }
//! Lights { numLights n
//!     DirectionalLight { direction x y z  color r g b }
//!     PointLight { position x y z  color r g b  [attenuation c l q] } }
//! Background { color r g b  [ambientLight r g b] }
//! Materials { numMaterials n
//!     Material { diffuseColor r g b }
//!     PhongMaterial { [diffuseColor r g b] [specularColor r g b] [exponent e]
//!                     [reflectiveColor r g b] [transparentColor r g b] [indexOfRefraction n] }
//!     Checkerboard { Transform { <xform>* } materialIndex i materialIndex j }
//!     Noise  { Transform { <xform>* } materialIndex i materialIndex j octaves k }
//!     Marble { Transform { <xform>* } materialIndex i materialIndex j octaves k frequency f amplitude a }
//!     Wood   { ...same as Marble... } }
//! Group { numObjects n  ( [MaterialIndex i] <object> )*n }
//! <object> = Sphere { center x y z  radius r }
//!          | Plane { normal x y z  offset d }
//!          | Triangle { vertex0 x y z  vertex1 x y z  vertex2 x y z }
//!          | TriangleMesh { obj_file path.obj }         # relative to the scene file
//!          | Group { ... } | Transform { <xform>* <object> }
//! <xform>  = Translate x y z | Scale x y z | UniformScale s | XRotate deg | YRotate deg
//!          | ZRotate deg | Rotate { ax ay az deg } | Matrix { 16 numbers, row by row }
//! ```
//!
//! Top-level blocks may come in any order; fields inside camera, light, background and Phong
//! blocks may too. Transforms compose left to right (the first listed is applied last). An
//! object before any `MaterialIndex` gets the default material (white, diffuse). When a scene
//! has no lights the ambient light is white, as in the course. Every error names its position:
//! `path:line:col: expected ..., found ...`. No input makes the parser panic.

use std::path::{Path, PathBuf};

use super::input::{decode_text, read_file};
use super::obj;
use super::{
    Camera, Light, Material, Object, Phong, Projection, Scene, Texture, TextureKind, Transformed,
};
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
        Some((tokens, eof)) => Parser::new(tokens, eof, path).scene(),
        None => Err(Parser::new(Vec::new(), (1, 1), path).out_of_memory()),
    }
}

#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    line: usize,
    col: usize,
}

/// Splits `text` into tokens; also returns the position just past the end. `None` when the
/// token list does not fit in memory (a huge file fails cleanly instead of aborting).
fn tokenize<'a>(text: &'a str) -> Option<(Vec<Token<'a>>, (usize, usize))> {
    fn push<'a>(tokens: &mut Vec<Token<'a>>, token: Token<'a>) -> Option<()> {
        if tokens.len() == tokens.capacity() {
            tokens.try_reserve(tokens.len().max(256)).ok()?;
        }
        tokens.push(token);
        Some(())
    }
    let mut tokens = Vec::new();
    let (mut line, mut col) = (1, 1);
    let mut start: Option<(usize, usize, usize)> = None; // byte offset, line, col
    let mut in_comment = false;
    let flush = |tokens: &mut Vec<Token<'a>>,
                 start: &mut Option<(usize, usize, usize)>,
                 end: usize|
     -> Option<()> {
        match start.take() {
            Some((s, line, col)) => push(
                tokens,
                Token {
                    text: &text[s..end],
                    line,
                    col,
                },
            ),
            None => Some(()),
        }
    };
    for (i, ch) in text.char_indices() {
        if in_comment {
            if ch == '\n' {
                in_comment = false;
            }
        } else if ch.is_whitespace() {
            flush(&mut tokens, &mut start, i)?;
        } else if ch == '{' || ch == '}' {
            flush(&mut tokens, &mut start, i)?;
            let text = &text[i..i + 1];
            push(&mut tokens, Token { text, line, col })?;
        } else if ch == '#' && start.is_none() {
            in_comment = true;
        } else if start.is_none() {
            start = Some((i, line, col));
        }
        if ch == '\n' {
            line += 1;
            col = 1;
        } else {
            col += 1;
        }
    }
    flush(&mut tokens, &mut start, text.len())?;
    Some((tokens, (line, col)))
}

/// How a token is shown in "found ..." messages: quoted, escaped, and cut short if long.
fn describe(tok: Option<&Token<'_>>) -> String {
    match tok {
        None => "end of file".to_string(),
        Some(t) => {
            let mut s: String = t
                .text
                .chars()
                .take(24)
                .flat_map(char::escape_default)
                .collect();
            if t.text.chars().count() > 24 {
                s.push_str("...");
            }
            format!("`{s}`")
        }
    }
}

const OBJECTS: &str = "an object (Sphere, Plane, Triangle, TriangleMesh, Group or Transform)";
const NO_MATERIAL: u32 = u32::MAX;

struct Parser<'a> {
    path: &'a Path,
    tokens: Vec<Token<'a>>,
    pos: usize,
    eof: (usize, usize),
    current_material: u32,
    /// Every material index used, with the token that named it, checked once all are known.
    material_refs: Vec<(usize, Token<'a>)>,
    depth: usize,
    /// The id of the next primitive (see [`Object`]).
    next_id: u32,
}

impl<'a> Parser<'a> {
    fn new(tokens: Vec<Token<'a>>, eof: (usize, usize), path: &'a Path) -> Parser<'a> {
        Parser {
            path,
            tokens,
            pos: 0,
            eof,
            current_material: NO_MATERIAL,
            material_refs: Vec::new(),
            depth: 0,
            next_id: 0,
        }
    }

    fn peek(&self) -> Option<Token<'a>> {
        self.tokens.get(self.pos).copied()
    }

    fn error_at(&self, tok: Option<&Token<'_>>, msg: String) -> Error {
        let (line, col) = tok.map_or(self.eof, |t| (t.line, t.col));
        Error::parse(self.path, line, col, msg)
    }

    fn out_of_memory(&self) -> Error {
        Error::Limit(format!(
            "{}: cannot parse: the scene does not fit in memory",
            self.path.display()
        ))
    }

    /// "expected {what}, found {the token at the cursor}".
    fn expected(&self, what: &str) -> Error {
        let tok = self.peek();
        self.error_at(
            tok.as_ref(),
            format!("expected {what}, found {}", describe(tok.as_ref())),
        )
    }

    /// A count promised more items than the block holds: "expected 3 objects (numObjects 3),
    /// found `}` after 2".
    fn too_few(&self, noun: &str, field: &str, n: usize, got: usize) -> Error {
        let tok = self.peek();
        self.error_at(
            tok.as_ref(),
            format!(
                "expected {} ({field} {n}), found {} after {got}",
                plural(n, noun),
                describe(tok.as_ref())
            ),
        )
    }

    /// A block holds more items than its count: "expected `}` after 1 object (numObjects 1),
    /// found `Sphere`".
    fn too_many(&self, noun: &str, field: &str, n: usize) -> Error {
        self.expected(&format!("`}}` after {} ({field} {n})", plural(n, noun)))
    }

    fn next(&mut self, what: &str) -> Result<Token<'a>> {
        match self.peek() {
            Some(t) => {
                self.pos += 1;
                Ok(t)
            }
            None => Err(self.expected(what)),
        }
    }

    fn keyword(&mut self, word: &str) -> Result<Token<'a>> {
        match self.peek() {
            Some(t) if t.text == word => {
                self.pos += 1;
                Ok(t)
            }
            _ => Err(self.expected(&format!("`{word}`"))),
        }
    }

    fn number(&mut self, what: &str) -> Result<f32> {
        let tok = self.peek();
        match tok.map(|t| t.text.parse::<f32>()) {
            Some(Ok(v)) if v.is_finite() => {
                self.pos += 1;
                Ok(v)
            }
            Some(Ok(_)) => Err(self.error_at(
                tok.as_ref(),
                format!(
                    "expected a finite number for {what}, found {}",
                    describe(tok.as_ref())
                ),
            )),
            _ => Err(self.expected(&format!("a number for {what}"))),
        }
    }

    fn vec3(&mut self, what: &str) -> Result<Vec3> {
        Ok(Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// A vector that must not be zero (directions, normals, axes).
    fn direction(&mut self, what: &str) -> Result<Vec3> {
        let at = self.peek();
        let v = self.vec3(what)?;
        if v.try_normalize().is_some() {
            Ok(v)
        } else {
            let kind = if v.length().is_finite() {
                "non-zero"
            } else {
                "finite-length"
            };
            Err(self.error_at(
                at.as_ref(),
                format!("expected a {kind} vector for {what}, found {}", vec_text(v)),
            ))
        }
    }

    /// A colour: three non-negative numbers (a negative channel is meaningless, and would let
    /// an overflow to infinity turn into NaN).
    fn color(&mut self, what: &str) -> Result<Vec3> {
        let at = self.peek();
        let c = self.vec3(what)?;
        if c.min_element() >= 0.0 {
            Ok(c)
        } else {
            Err(self.error_at(
                at.as_ref(),
                format!(
                    "expected a colour with no negative channel for {what}, found {}",
                    vec_text(c)
                ),
            ))
        }
    }

    fn positive(&mut self, what: &str) -> Result<f32> {
        let at = self.peek();
        let v = self.number(what)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.error_at(
                at.as_ref(),
                format!(
                    "expected a positive number for {what}, found {}",
                    num_text(v)
                ),
            ))
        }
    }

    fn count(&mut self, what: &str) -> Result<usize> {
        let tok = self.peek();
        match tok.map(|t| t.text.parse::<u32>()) {
            Some(Ok(n)) => {
                self.pos += 1;
                Ok(n as usize)
            }
            Some(Err(e)) if *e.kind() == std::num::IntErrorKind::PosOverflow => Err(self.expected(
                &format!("a whole number for {what} of at most {}", u32::MAX),
            )),
            _ => Err(self.expected(&format!("a whole number for {what}"))),
        }
    }

    fn scene(&mut self) -> Result<Scene> {
        let mut camera = None;
        let mut lights: Option<Vec<Light>> = None;
        let mut background = None;
        let mut materials: Option<Vec<Material>> = None;
        let mut root = None;
        while let Some(tok) = self.peek() {
            let dup = |seen: bool, p: &Self| {
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
                        return Err(self.error_at(
                            Some(&tok),
                            format!("expected one camera, found a second (`{}`)", tok.text),
                        ));
                    }
                    camera = Some(self.camera()?);
                }
                "Lights" => {
                    dup(lights.is_some(), self)?;
                    lights = Some(self.lights()?);
                }
                "Background" => {
                    dup(background.is_some(), self)?;
                    background = Some(self.background()?);
                }
                "Materials" => {
                    dup(materials.is_some(), self)?;
                    materials = Some(self.materials()?);
                }
                "Group" => {
                    dup(root.is_some(), self)?;
                    root = Some(self.group()?);
                }
                _ => {
                    return Err(self.expected(
                        "a top-level block (OrthographicCamera, PerspectiveCamera, Lights, \
                         Background, Materials or Group)",
                    ));
                }
            }
        }
        let Some(camera) = camera else {
            return Err(self.expected("a camera (OrthographicCamera or PerspectiveCamera)"));
        };
        let Some(mut root) = root else {
            return Err(self.expected("a Group of objects"));
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
        for (index, tok) in &self.material_refs {
            if *index >= materials.len() {
                let msg = match materials.len() {
                    0 => {
                        format!("expected a Materials block to define material {index}, found none")
                    }
                    n => format!(
                        "expected a material index below {n} (numMaterials {n}), found {index}"
                    ),
                };
                return Err(self.error_at(Some(tok), msg));
            }
        }
        if let Some(start) = texture_cycle(&materials) {
            let tok = self
                .material_refs
                .iter()
                .find(|(i, _)| *i == start)
                .map(|(_, t)| *t);
            return Err(self.error_at(
                tok.as_ref(),
                format!("expected textures that end in plain materials, found material {start} referring back to itself"),
            ));
        }
        if uses_material(&root, NO_MATERIAL) {
            let default = materials.len() as u32;
            materials.push(Material::Phong(Phong::default()));
            set_default_material(&mut root, default);
        }
        Ok(Scene {
            camera,
            lights,
            background: color,
            ambient,
            materials,
            root,
        })
    }

    /// Reads `{ field value ... }` with fields in any order, each at most once; `read` parses the
    /// value of one field. Returns the names seen and the closing brace.
    fn block_fields(
        &mut self,
        block: &str,
        names: &[&'static str],
        read: &mut dyn FnMut(&mut Self, &str) -> Result<()>,
    ) -> Result<(Vec<&'static str>, Token<'a>)> {
        self.keyword("{")?;
        let mut seen: Vec<&'static str> = Vec::new();
        loop {
            let Some(tok) = self.peek() else {
                return Err(self.expected(&format!("`}}` closing {block}")));
            };
            if tok.text == "}" {
                self.pos += 1;
                return Ok((seen, tok));
            }
            match names.iter().find(|n| **n == tok.text) {
                Some(name) => {
                    if seen.contains(name) {
                        return Err(self.error_at(
                            Some(&tok),
                            format!("expected `{name}` once in {block}, found it twice"),
                        ));
                    }
                    seen.push(name);
                    self.pos += 1;
                    read(self, name)?;
                }
                None => {
                    let list: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
                    return Err(self.expected(&format!("{} or `}}` in {block}", list.join(", "))));
                }
            }
        }
    }

    fn require(&self, block: &str, seen: &[&str], close: &Token<'_>, name: &str) -> Result<()> {
        if seen.contains(&name) {
            Ok(())
        } else {
            Err(self.error_at(
                Some(close),
                format!("expected `{name}` in {block}, found `}}`"),
            ))
        }
    }

    fn camera(&mut self) -> Result<Camera> {
        let kind = self.next("a camera")?;
        let block = kind.text;
        let ortho = block == "OrthographicCamera";
        let extra = if ortho { "size" } else { "angle" };
        let (mut center, mut direction, mut up, mut value) =
            (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0);
        let mut dir_tok = None;
        let (seen, close) = self.block_fields(
            block,
            &["center", "direction", "up", extra],
            &mut |p, name| {
                match name {
                    "center" => center = p.vec3("center")?,
                    "direction" => {
                        dir_tok = p.peek();
                        direction = p.direction("direction")?;
                    }
                    "up" => up = p.direction("up")?,
                    "size" => value = p.positive("size")?,
                    _ => {
                        let at = p.peek();
                        let a = p.number("angle")?;
                        if !(a > 0.0 && a < 180.0) {
                            return Err(p.error_at(
                                at.as_ref(),
                                format!(
                                    "expected an angle between 0 and 180 degrees, found {}",
                                    num_text(a)
                                ),
                            ));
                        }
                        value = a.to_radians();
                    }
                }
                Ok(())
            },
        )?;
        for name in ["center", "direction", "up", extra] {
            self.require(block, &seen, &close, name)?;
        }
        let cross = direction.normalize().cross(up.normalize());
        if cross.length() < 1e-6 {
            return Err(self.error_at(
                dir_tok.as_ref(),
                format!(
                    "expected `up` not parallel to `direction` in {block}, found both along {}",
                    vec_text(direction)
                ),
            ));
        }
        let projection = if ortho {
            Projection::Orthographic { size: value }
        } else {
            Projection::Perspective { angle: value }
        };
        Ok(Camera::new(projection, center, direction, up))
    }

    fn lights(&mut self) -> Result<Vec<Light>> {
        self.keyword("Lights")?;
        self.keyword("{")?;
        self.keyword("numLights")?;
        let n = self.count("numLights")?;
        let mut lights = Vec::new();
        for i in 0..n {
            let light = match self.peek().map(|t| t.text) {
                Some("DirectionalLight") => self.directional_light()?,
                Some("PointLight") => self.point_light()?,
                None | Some("}") => return Err(self.too_few("light", "numLights", n, i)),
                _ => return Err(self.expected("a light (DirectionalLight or PointLight)")),
            };
            lights.push(light);
        }
        if self.peek().is_some_and(|t| t.text != "}") {
            return Err(self.too_many("light", "numLights", n));
        }
        self.keyword("}")?;
        Ok(lights)
    }

    fn directional_light(&mut self) -> Result<Light> {
        self.pos += 1;
        let (mut direction, mut color) = (Vec3::ZERO, Vec3::ZERO);
        let (seen, close) = self.block_fields(
            "DirectionalLight",
            &["direction", "color"],
            &mut |p, name| {
                if name == "direction" {
                    direction = p.direction("direction")?.normalize();
                } else {
                    color = p.color("color")?;
                }
                Ok(())
            },
        )?;
        self.require("DirectionalLight", &seen, &close, "direction")?;
        self.require("DirectionalLight", &seen, &close, "color")?;
        Ok(Light::Directional { direction, color })
    }

    fn point_light(&mut self) -> Result<Light> {
        self.pos += 1;
        let (mut position, mut color, mut attenuation) = (Vec3::ZERO, Vec3::ZERO, [1.0, 0.0, 0.0]);
        let (seen, close) = self.block_fields(
            "PointLight",
            &["position", "color", "attenuation"],
            &mut |p, name| {
                match name {
                    "position" => position = p.vec3("position")?,
                    "color" => color = p.color("color")?,
                    _ => {
                        let at = p.peek();
                        let a = p.vec3("attenuation")?;
                        if a.min_element() < 0.0 || a.max_element() <= 0.0 {
                            return Err(p.error_at(
                                at.as_ref(),
                                format!(
                                    "expected non-negative attenuation constants, not all zero, \
                                     found {}",
                                    vec_text(a)
                                ),
                            ));
                        }
                        attenuation = a.to_array();
                    }
                }
                Ok(())
            },
        )?;
        self.require("PointLight", &seen, &close, "position")?;
        self.require("PointLight", &seen, &close, "color")?;
        Ok(Light::Point {
            position,
            color,
            attenuation,
        })
    }

    fn background(&mut self) -> Result<(Vec3, Option<Vec3>)> {
        self.keyword("Background")?;
        let (mut color, mut ambient) = (Vec3::ZERO, None);
        let (seen, close) =
            self.block_fields("Background", &["color", "ambientLight"], &mut |p, name| {
                if name == "color" {
                    color = p.color("color")?;
                } else {
                    ambient = Some(p.color("ambientLight")?);
                }
                Ok(())
            })?;
        self.require("Background", &seen, &close, "color")?;
        Ok((color, ambient))
    }

    fn materials(&mut self) -> Result<Vec<Material>> {
        self.keyword("Materials")?;
        self.keyword("{")?;
        self.keyword("numMaterials")?;
        let n = self.count("numMaterials")?;
        let mut materials = Vec::new();
        for i in 0..n {
            let m = match self.peek().map(|t| t.text) {
                Some("Material" | "PhongMaterial") => Material::Phong(self.phong()?),
                Some("Checkerboard" | "Noise" | "Marble" | "Wood") => self.texture()?,
                None | Some("}") => return Err(self.too_few("material", "numMaterials", n, i)),
                _ => {
                    return Err(self.expected(
                        "a material (Material, PhongMaterial, Checkerboard, Noise, Marble or \
                         Wood)",
                    ));
                }
            };
            materials.push(m);
        }
        if self.peek().is_some_and(|t| t.text != "}") {
            return Err(self.too_many("material", "numMaterials", n));
        }
        self.keyword("}")?;
        Ok(materials)
    }

    fn phong(&mut self) -> Result<Phong> {
        let kind = self.next("a material")?;
        let mut m = Phong::default();
        self.block_fields(
            kind.text,
            &[
                "diffuseColor",
                "specularColor",
                "exponent",
                "reflectiveColor",
                "transparentColor",
                "indexOfRefraction",
            ],
            &mut |p, name| {
                match name {
                    "diffuseColor" => m.diffuse = p.color(name)?,
                    "specularColor" => m.specular = p.color(name)?,
                    "reflectiveColor" => m.reflective = p.color(name)?,
                    "transparentColor" => m.transparent = p.color(name)?,
                    "exponent" => {
                        let at = p.peek();
                        m.exponent = p.number(name)?;
                        if m.exponent < 0.0 {
                            return Err(p.error_at(
                                at.as_ref(),
                                format!(
                                    "expected a non-negative exponent, found {}",
                                    num_text(m.exponent)
                                ),
                            ));
                        }
                    }
                    _ => m.ior = p.positive(name)?,
                }
                Ok(())
            },
        )?;
        Ok(m)
    }

    fn texture(&mut self) -> Result<Material> {
        let kind = self.next("a texture")?;
        self.keyword("{")?;
        self.keyword("Transform")?;
        self.keyword("{")?;
        let mut matrix = Mat4::IDENTITY;
        while self.peek().is_some_and(|t| t.text != "}") {
            matrix *= self.xform()?;
        }
        self.keyword("}")?;
        let mut pair = [0u32; 2];
        for m in pair.iter_mut() {
            self.keyword("materialIndex")?;
            let at = self.peek();
            let i = self.count("materialIndex")?;
            *m = i.min(NO_MATERIAL as usize - 1) as u32;
            if let Some(at) = at {
                self.material_refs.push((i, at));
            }
        }
        let mut octaves = || -> Result<u32> {
            self.keyword("octaves")?;
            let at = self.peek();
            let k = self.count("octaves")?;
            if k > MAX_OCTAVES {
                return Err(self.error_at(
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
                self.keyword("frequency")?;
                let frequency = self.number("frequency")?;
                self.keyword("amplitude")?;
                let amplitude = self.number("amplitude")?;
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
        self.keyword("}")?;
        let det = matrix.determinant();
        if !(det.abs() > 0.0 && det.is_finite()) {
            return Err(self.error_at(
                Some(&kind_token(&self.tokens, self.pos)),
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
            return Err(self.expected(&format!(
                "at most {MAX_NESTING} nested groups and transforms"
            )));
        }
        Ok(())
    }

    fn group(&mut self) -> Result<Object> {
        self.nest()?;
        self.keyword("Group")?;
        self.keyword("{")?;
        self.keyword("numObjects")?;
        let n = self.count("numObjects")?;
        let mut children = Vec::new();
        loop {
            self.material_index()?;
            if children.len() == n {
                break;
            }
            if self.peek().is_none_or(|t| t.text == "}") {
                return Err(self.too_few("object", "numObjects", n, children.len()));
            }
            grow(&mut children).map_err(|()| self.out_of_memory())?;
            children.push(self.object()?);
        }
        if self.peek().is_some_and(|t| t.text != "}") {
            return Err(self.too_many("object", "numObjects", n));
        }
        self.keyword("}")?;
        self.depth -= 1;
        Ok(Object::Group(children))
    }

    /// Any number of `MaterialIndex i` (the last one counts).
    fn material_index(&mut self) -> Result<()> {
        while self.peek().is_some_and(|t| t.text == "MaterialIndex") {
            self.pos += 1;
            let at = self.peek();
            let i = self.count("MaterialIndex")?;
            if let Some(at) = at {
                self.material_refs.push((i, at));
            }
            // Out-of-range indices are reported once every material is known.
            self.current_material = i.min(NO_MATERIAL as usize - 1) as u32;
        }
        Ok(())
    }

    fn object(&mut self) -> Result<Object> {
        let Some(tok) = self.peek() else {
            return Err(self.expected(OBJECTS));
        };
        let material = self.current_material;
        match tok.text {
            "Sphere" => {
                self.pos += 1;
                let (mut center, mut radius) = (Vec3::ZERO, 0.0);
                let (seen, close) =
                    self.block_fields("Sphere", &["center", "radius"], &mut |p, name| {
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
                self.require("Sphere", &seen, &close, "center")?;
                self.require("Sphere", &seen, &close, "radius")?;
                Ok(Object::Sphere {
                    center,
                    radius,
                    material,
                    id: self.take_ids(1)?,
                })
            }
            "Plane" => {
                self.pos += 1;
                let (mut normal, mut offset) = (Vec3::ZERO, 0.0);
                let (seen, close) =
                    self.block_fields("Plane", &["normal", "offset"], &mut |p, name| {
                        if name == "normal" {
                            normal = p.direction("normal")?;
                        } else {
                            offset = p.number("offset")?;
                        }
                        Ok(())
                    })?;
                self.require("Plane", &seen, &close, "normal")?;
                self.require("Plane", &seen, &close, "offset")?;
                let len = normal.length();
                Ok(Object::Plane {
                    normal: normal / len,
                    offset: offset / len,
                    material,
                    id: self.take_ids(1)?,
                })
            }
            "Triangle" => {
                self.pos += 1;
                let mut v = [Vec3::ZERO; 3];
                let (seen, close) = self.block_fields(
                    "Triangle",
                    &["vertex0", "vertex1", "vertex2"],
                    &mut |p, name| {
                        let i = (name.as_bytes()[6] - b'0') as usize;
                        v[i] = p.vec3(name)?;
                        Ok(())
                    },
                )?;
                for name in ["vertex0", "vertex1", "vertex2"] {
                    self.require("Triangle", &seen, &close, name)?;
                }
                if is_degenerate(&v) {
                    return Err(self.error_at(
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
                self.pos += 1;
                self.keyword("{")?;
                self.keyword("obj_file")?;
                let file = self.next("an OBJ file name")?;
                self.keyword("}")?;
                let path = self.resolve(file.text);
                let triangles = obj::load_obj(&path).map_err(|e| match e {
                    Error::Io { source, .. } => self.error_at(
                        Some(&file),
                        format!("cannot read OBJ file `{}`: {source}", path.display()),
                    ),
                    other => other,
                })?;
                let first_id = self.take_ids(triangles.len())?;
                Ok(Object::Mesh {
                    triangles,
                    material,
                    first_id,
                })
            }
            "Group" => self.group(),
            "Transform" => {
                self.nest()?;
                self.pos += 1;
                self.keyword("{")?;
                let mut matrix = Mat4::IDENTITY;
                while self.peek().is_some_and(|t| is_xform(t.text)) {
                    matrix *= self.xform()?;
                }
                self.material_index()?;
                if !self.peek().is_some_and(|t| is_object(t.text)) {
                    return Err(self.expected(&format!(
                        "a transform (Translate, Scale, UniformScale, XRotate, YRotate, ZRotate, \
                         Rotate or Matrix) or {OBJECTS}"
                    )));
                }
                let child = self.object()?;
                self.material_index()?;
                self.keyword("}")?;
                self.depth -= 1;
                let det = matrix.determinant();
                let inverse = matrix.inverse();
                if !(det.abs() > 1e-12 && det.is_finite() && inverse.is_finite()) {
                    return Err(self.error_at(
                        Some(&tok),
                        format!(
                            "expected an invertible transform, found one with determinant {}",
                            num_text(det)
                        ),
                    ));
                }
                Ok(Object::Transform(Box::new(Transformed::new(matrix, child))))
            }
            _ => Err(self.expected(OBJECTS)),
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
            _ => Err(self.expected("at most 4294967294 primitives")),
        }
    }

    fn xform(&mut self) -> Result<Mat4> {
        let tok = self.next("a transform")?;
        let m = match tok.text {
            "Translate" => Mat4::from_translation(self.vec3("Translate")?),
            "Scale" => {
                let at = self.peek();
                let s = self.vec3("Scale")?;
                if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
                    return Err(self.error_at(
                        at.as_ref(),
                        format!("expected non-zero scale factors, found {}", vec_text(s)),
                    ));
                }
                Mat4::from_scale(s)
            }
            "UniformScale" => {
                let at = self.peek();
                let s = self.number("UniformScale")?;
                if s == 0.0 {
                    return Err(self.error_at(
                        at.as_ref(),
                        "expected a non-zero scale factor, found 0".to_string(),
                    ));
                }
                Mat4::from_scale(Vec3::splat(s))
            }
            "XRotate" => Mat4::from_rotation_x(self.number("XRotate")?.to_radians()),
            "YRotate" => Mat4::from_rotation_y(self.number("YRotate")?.to_radians()),
            "ZRotate" => Mat4::from_rotation_z(self.number("ZRotate")?.to_radians()),
            "Rotate" => {
                self.keyword("{")?;
                let axis = self.direction("the Rotate axis")?.normalize();
                let angle = self.number("the Rotate angle")?.to_radians();
                self.keyword("}")?;
                Mat4::from_axis_angle(axis, angle)
            }
            "Matrix" => {
                self.keyword("{")?;
                let mut rows = [0.0f32; 16];
                for v in rows.iter_mut() {
                    *v = self.number("Matrix")?;
                }
                self.keyword("}")?;
                Mat4::from_cols_array(&rows).transpose()
            }
            _ => {
                self.pos -= 1;
                return Err(self.expected(
                    "a transform (Translate, Scale, UniformScale, XRotate, YRotate, ZRotate, \
                     Rotate or Matrix)",
                ));
            }
        };
        Ok(m)
    }

    /// An OBJ path relative to the scene file's folder, else as given (relative to the current
    /// folder).
    fn resolve(&self, name: &str) -> PathBuf {
        let beside = self
            .path
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

/// "1 object", "2 objects".
fn plural(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// A number as messages show it: plain, or in exponent form when very large or small.
fn num_text(x: f32) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e7).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// A vector as messages show it: `(x y z)`.
fn vec_text(v: Vec3) -> String {
    format!("({} {} {})", num_text(v.x), num_text(v.y), num_text(v.z))
}

/// Makes room for one more item; `Err` when memory runs out.
fn grow<T>(items: &mut Vec<T>) -> std::result::Result<(), ()> {
    if items.len() == items.capacity() {
        items.try_reserve(items.len().max(4)).map_err(|_| ())?;
    }
    Ok(())
}

fn is_object(word: &str) -> bool {
    matches!(
        word,
        "Sphere" | "Plane" | "Triangle" | "TriangleMesh" | "Group" | "Transform"
    )
}

fn is_xform(word: &str) -> bool {
    matches!(
        word,
        "Translate"
            | "Scale"
            | "UniformScale"
            | "XRotate"
            | "YRotate"
            | "ZRotate"
            | "Rotate"
            | "Matrix"
    )
}

fn uses_material(obj: &Object, index: u32) -> bool {
    match obj {
        Object::Sphere { material, .. }
        | Object::Plane { material, .. }
        | Object::Triangle { material, .. }
        | Object::Mesh { material, .. } => *material == index,
        Object::Group(children) => children.iter().any(|c| uses_material(c, index)),
        Object::Transform(t) => uses_material(&t.child, index),
    }
}

fn set_default_material(obj: &mut Object, default: u32) {
    match obj {
        Object::Sphere { material, .. }
        | Object::Plane { material, .. }
        | Object::Triangle { material, .. }
        | Object::Mesh { material, .. } => {
            if *material == NO_MATERIAL {
                *material = default;
            }
        }
        Object::Group(children) => children
            .iter_mut()
            .for_each(|c| set_default_material(c, default)),
        Object::Transform(t) => set_default_material(&mut t.child, default),
    }
}

/// The token just before position `pos` (the closing brace of a block just read).
fn kind_token<'a>(tokens: &[Token<'a>], pos: usize) -> Token<'a> {
    tokens[pos.saturating_sub(1)]
}

/// The first material that reaches itself through texture references, if any.
fn texture_cycle(materials: &[Material]) -> Option<usize> {
    // 0 = unvisited, 1 = on the current path, 2 = done.
    fn visit(m: usize, materials: &[Material], state: &mut [u8]) -> bool {
        match state[m] {
            1 => return true,
            2 => return false,
            _ => {}
        }
        state[m] = 1;
        if let Material::Texture(t) = &materials[m] {
            for next in [t.a as usize, t.b as usize] {
                if visit(next, materials, state) {
                    return true;
                }
            }
        }
        state[m] = 2;
        false
    }
    let mut state = vec![0u8; materials.len()];
    (0..materials.len()).find(|&m| visit(m, materials, &mut state))
}
