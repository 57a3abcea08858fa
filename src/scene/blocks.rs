//! The grammar of the scene blocks that stand alone, needing nothing from the rest of the
//! file: the camera, the lights, the background, one Phong material, and one step of a
//! transform list. The main grammar (`parse.rs`) calls these while it reads a file; each reads
//! its block through the cursor (`cursor.rs`) and returns the finished value.
//!
//! ```text
//! OrthographicCamera { center x y z  direction x y z  up x y z  size s }
//! PerspectiveCamera  { center x y z  direction x y z  up x y z  angle degrees }
//! Lights { numLights n
//!     DirectionalLight { direction x y z  color r g b }
//!     PointLight { position x y z  color r g b  [attenuation c l q] } }
//! Background { color r g b  [ambientLight r g b] }
//! Material | PhongMaterial { [diffuseColor r g b] [specularColor r g b] [exponent e]
//!     [reflectiveColor r g b] [transparentColor r g b] [indexOfRefraction n] }
//! <xform> = Translate x y z | Scale x y z | UniformScale s | XRotate deg | YRotate deg
//!         | ZRotate deg | Rotate { ax ay az deg } | Matrix { 16 numbers, row by row }
//! ```
//!
//! Fields inside braces come in any order (`Cursor::block_fields`); those in `[ ]` may be left
//! out. A camera's `up` must not be parallel to its `direction`; a perspective `angle` is the
//! full field of view across the square screen (the larger side of a non-square image),
//! strictly between 0 and 180 degrees. Attenuation constants are
//! non-negative and not all zero (default `1 0 0`: no fall-off). A missing material field keeps
//! the course default (white diffuse, no specular, exponent 1, no mirror, opaque, index 1).
//! `docs/scene-format.md` describes every field for users.

use super::cursor::{Cursor, num_text, vec_text};
use super::{Camera, Light, Phong, Projection};
use crate::error::Result;
use crate::math::{Mat4, Vec3};

/// `OrthographicCamera { ... }` or `PerspectiveCamera { ... }`, at the cursor.
pub(super) fn camera(c: &mut Cursor<'_>) -> Result<Camera> {
    let kind = c.next("a camera")?;
    let block = kind.text;
    let ortho = block == "OrthographicCamera";
    let extra = if ortho { "size" } else { "angle" };
    let (mut center, mut direction, mut up, mut value) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0);
    let mut dir_tok = None;
    let (seen, close) = c.block_fields(
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
        c.require(block, &seen, &close, name)?;
    }
    let cross = direction.normalize().cross(up.normalize());
    if cross.length() < 1e-6 {
        return Err(c.error_at(
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

/// `Lights { numLights n <light>*n }`.
pub(super) fn lights(c: &mut Cursor<'_>) -> Result<Vec<Light>> {
    c.keyword("Lights")?;
    c.keyword("{")?;
    c.keyword("numLights")?;
    let n = c.count("numLights")?;
    let mut lights = Vec::new();
    for i in 0..n {
        let light = match c.peek().map(|t| t.text) {
            Some("DirectionalLight") => directional_light(c)?,
            Some("PointLight") => point_light(c)?,
            None | Some("}") => return Err(c.too_few("light", "numLights", n, i)),
            _ => return Err(c.expected("a light (DirectionalLight or PointLight)")),
        };
        lights.push(light);
    }
    if c.peek().is_some_and(|t| t.text != "}") {
        return Err(c.too_many("light", "numLights", n));
    }
    c.keyword("}")?;
    Ok(lights)
}

/// `DirectionalLight { direction x y z  color r g b }` (the keyword at the cursor).
fn directional_light(c: &mut Cursor<'_>) -> Result<Light> {
    c.advance();
    let (mut direction, mut color) = (Vec3::ZERO, Vec3::ZERO);
    let (seen, close) = c.block_fields(
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
    c.require("DirectionalLight", &seen, &close, "direction")?;
    c.require("DirectionalLight", &seen, &close, "color")?;
    Ok(Light::Directional { direction, color })
}

/// `PointLight { position x y z  color r g b  [attenuation c l q] }` (the keyword at the cursor).
fn point_light(c: &mut Cursor<'_>) -> Result<Light> {
    c.advance();
    let (mut position, mut color, mut attenuation) = (Vec3::ZERO, Vec3::ZERO, [1.0, 0.0, 0.0]);
    let (seen, close) = c.block_fields(
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
    c.require("PointLight", &seen, &close, "position")?;
    c.require("PointLight", &seen, &close, "color")?;
    Ok(Light::Point {
        position,
        color,
        attenuation,
    })
}

/// `Background { color r g b  [ambientLight r g b] }`: the colour, and the ambient light if given.
pub(super) fn background(c: &mut Cursor<'_>) -> Result<(Vec3, Option<Vec3>)> {
    c.keyword("Background")?;
    let (mut color, mut ambient) = (Vec3::ZERO, None);
    let (seen, close) =
        c.block_fields("Background", &["color", "ambientLight"], &mut |p, name| {
            if name == "color" {
                color = p.color("color")?;
            } else {
                ambient = Some(p.color("ambientLight")?);
            }
            Ok(())
        })?;
    c.require("Background", &seen, &close, "color")?;
    Ok((color, ambient))
}

/// `Material { ... }` or `PhongMaterial { ... }` (the two spellings are one material).
pub(super) fn phong(c: &mut Cursor<'_>) -> Result<Phong> {
    let kind = c.next("a material")?;
    let mut m = Phong::default();
    c.block_fields(
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

/// One step of a transform list, as its matrix.
pub(super) fn xform(c: &mut Cursor<'_>) -> Result<Mat4> {
    let tok = c.next("a transform")?;
    let m = match tok.text {
        "Translate" => Mat4::from_translation(c.vec3("Translate")?),
        "Scale" => {
            let at = c.peek();
            let s = c.vec3("Scale")?;
            if s.x == 0.0 || s.y == 0.0 || s.z == 0.0 {
                return Err(c.error_at(
                    at.as_ref(),
                    format!("expected non-zero scale factors, found {}", vec_text(s)),
                ));
            }
            Mat4::from_scale(s)
        }
        "UniformScale" => {
            let at = c.peek();
            let s = c.number("UniformScale")?;
            if s == 0.0 {
                return Err(c.error_at(
                    at.as_ref(),
                    "expected a non-zero scale factor, found 0".to_string(),
                ));
            }
            Mat4::from_scale(Vec3::splat(s))
        }
        "XRotate" => Mat4::from_rotation_x(c.number("XRotate")?.to_radians()),
        "YRotate" => Mat4::from_rotation_y(c.number("YRotate")?.to_radians()),
        "ZRotate" => Mat4::from_rotation_z(c.number("ZRotate")?.to_radians()),
        "Rotate" => {
            c.keyword("{")?;
            let axis = c.direction("the Rotate axis")?.normalize();
            let angle = c.number("the Rotate angle")?.to_radians();
            c.keyword("}")?;
            Mat4::from_axis_angle(axis, angle)
        }
        "Matrix" => {
            c.keyword("{")?;
            let mut rows = [0.0f32; 16];
            for v in rows.iter_mut() {
                *v = c.number("Matrix")?;
            }
            c.keyword("}")?;
            Mat4::from_cols_array(&rows).transpose()
        }
        _ => {
            c.back();
            return Err(c.expected(
                "a transform (Translate, Scale, UniformScale, XRotate, YRotate, ZRotate, \
                 Rotate or Matrix)",
            ));
        }
    };
    Ok(m)
}

/// Whether `word` starts a transform step (see [`xform`]).
pub(super) fn is_xform(word: &str) -> bool {
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
