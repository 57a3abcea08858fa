//! The checks and fix-ups that run over a scene once the grammar (`parse.rs`) has read all of
//! it, because they need the whole file: material indices may point forward to materials the
//! file defines later, textures may refer to each other, and the default material exists only
//! if some object needs it. Errors still point at the token that caused them.
//!
//! ```text
//! grammar --> (materials, object tree, material references)
//!         --> check_material_refs --> check_texture_cycles --> assign_default_material --> Scene
//! ```
//!
//! Scene-file rules enforced here: every `MaterialIndex i` (objects) and `materialIndex i`
//! (textures) must name a material of the `Materials` block, `0 <= i < numMaterials`; a texture
//! must not reach itself through its two materials; an object read before the file's first
//! `MaterialIndex` gets a default material appended after the file's own (white diffuse, the
//! course's `Phong` defaults).

use super::cursor::Cursor;
use super::token::Token;
use super::{Material, Object, Phong};
use crate::error::Result;

/// The material of a primitive read before any `MaterialIndex`, until
/// [`assign_default_material`] replaces it.
pub(super) const NO_MATERIAL: u32 = u32::MAX;

/// Every material index used (`refs`: the index and the token that named it) is below the
/// number of materials defined.
pub(super) fn check_material_refs(
    cur: &Cursor<'_>,
    refs: &[(usize, Token<'_>)],
    defined: usize,
) -> Result<()> {
    for (index, tok) in refs {
        if *index >= defined {
            let msg = match defined {
                0 => {
                    format!("expected a Materials block to define material {index}, found none")
                }
                n => {
                    format!("expected a material index below {n} (numMaterials {n}), found {index}")
                }
            };
            return Err(cur.error_at(Some(tok), msg));
        }
    }
    Ok(())
}

/// No texture reaches itself through the materials it chooses between. The error points at the
/// first reference to the material that starts the loop. Needs indices already checked by
/// [`check_material_refs`].
pub(super) fn check_texture_cycles(
    cur: &Cursor<'_>,
    refs: &[(usize, Token<'_>)],
    materials: &[Material],
) -> Result<()> {
    match texture_cycle(materials) {
        None => Ok(()),
        Some(start) => {
            let tok = refs.iter().find(|(i, _)| *i == start).map(|(_, t)| *t);
            Err(cur.error_at(
                tok.as_ref(),
                format!("expected textures that end in plain materials, found material {start} referring back to itself"),
            ))
        }
    }
}

/// Gives every primitive still marked [`NO_MATERIAL`] a default material, appended to
/// `materials`, if there is any such primitive.
pub(super) fn assign_default_material(root: &mut Object, materials: &mut Vec<Material>) {
    if uses_material(root, NO_MATERIAL) {
        let default = materials.len() as u32;
        materials.push(Material::Phong(Phong::default()));
        set_default_material(root, default);
    }
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
