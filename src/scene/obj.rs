//! The OBJ loader behind `TriangleMesh { obj_file name.obj }`: vertices, vertex normals and
//! faces to a list of triangles, each with its three corner normals when the file gives them.
//! It reads the subset of Wavefront OBJ that meshes use:
//!
//! ```text
//! v x y z [w]          # a vertex
//! vn x y z             # a vertex normal (need not be unit length; it is normalised)
//! f a b c ...          # a face: 1-based indices (negative = relative to the end so far),
//!                      # each optionally `a/t`, `a/t/n` or `a//n`; polygons become fans
//! # comment, vt, vp, o, g, s, usemtl, mtllib, l, p   (ignored)
//! ```
//!
//! A face whose every corner names a normal (`a//n`, `a/t/n`) is shaded smoothly with them
//! (see [`super::normals`]); the triangles of a face where some corner names none are flat.
//! Anything else, an index out of range, a face with fewer than three vertices, a degenerate
//! triangle, a zero or non-finite normal or a file with no face at all is an error at
//! `path:line:col`.

use std::path::Path;

use super::input::{decode_text, read_file};
use crate::error::{Error, Result};
use crate::math::{Vec3, is_degenerate};

/// The triangles of an OBJ file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjMesh {
    pub triangles: Vec<[Vec3; 3]>,
    /// Unit corner normals of each triangle, parallel to `triangles`; empty when no face of
    /// the file names normals. A flat triangle in a mesh that has some carries its own unit
    /// geometric normal at all three corners.
    pub normals: Vec<[Vec3; 3]>,
}

/// Loads the triangles of the OBJ file at `path`.
pub fn load_obj(path: &Path) -> Result<ObjMesh> {
    let bytes = read_file(path, "read OBJ file")?;
    let text = decode_text(&bytes, path)?;
    parse_obj(text, path)
}

/// Reads the three numbers after `v` or `vn` at column `col`.
fn coordinates<'a>(
    words: &mut impl Iterator<Item = (usize, &'a str)>,
    keyword: &str,
    col: usize,
    err: &dyn Fn(usize, String) -> Error,
) -> Result<Vec3> {
    let mut xyz = [0.0f32; 3];
    for (i, c) in xyz.iter_mut().enumerate() {
        let Some((col_n, word)) = words.next() else {
            return Err(err(
                col,
                format!("expected 3 coordinates after `{keyword}`, found {i}"),
            ));
        };
        *c = match word.parse::<f32>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                return Err(err(
                    col_n,
                    format!("expected a finite number, found `{}`", short(word)),
                ));
            }
        };
    }
    Ok(Vec3::from_array(xyz))
}

/// Resolves a 1-based (or negative, relative) OBJ index into a list of `n` items.
fn resolve(text: &str, n: usize) -> Option<usize> {
    let n = n as i64;
    match text.parse::<i64>() {
        Ok(i) if i >= 1 && i <= n => Some((i - 1) as usize),
        Ok(i) if i < 0 && i >= -n => Some((n + i) as usize),
        _ => None,
    }
}

/// Parses OBJ text; `path` names it in errors.
pub fn parse_obj(text: &str, path: &Path) -> Result<ObjMesh> {
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut vertex_normals: Vec<Vec3> = Vec::new();
    let mut triangles = Vec::new();
    // Corner normals per triangle, `None` for flat ones (filled in at the end).
    let mut corner_normals: Vec<Option<[Vec3; 3]>> = Vec::new();
    for (line_index, line) in text.lines().enumerate() {
        let line_no = line_index + 1;
        let mut words = words_with_columns(line);
        let Some((col, keyword)) = words.next() else {
            continue;
        };
        let err = |col: usize, msg: String| Error::parse(path, line_no, col, msg);
        match keyword {
            "v" => {
                let v = coordinates(&mut words, "v", col, &err)?;
                grow(&mut vertices, path)?;
                vertices.push(v);
            }
            "vn" => {
                let n = coordinates(&mut words, "vn", col, &err)?;
                let Some(unit) = n.try_normalize() else {
                    return Err(err(
                        col,
                        "expected a normal of non-zero length, found a zero vector".to_string(),
                    ));
                };
                grow(&mut vertex_normals, path)?;
                vertex_normals.push(unit);
            }
            "f" => {
                // (vertex index, normal index if given, column)
                let mut corners: Vec<(usize, Option<usize>, usize)> = Vec::new();
                for (col_i, word) in words {
                    let mut parts = word.split('/');
                    let index_text = parts.next().unwrap_or("");
                    let Some(index) = resolve(index_text, vertices.len()) else {
                        let n = vertices.len();
                        return Err(err(
                            col_i,
                            format!(
                                "expected a vertex index between 1 and {n} (or -1 to -{n}), found `{}`",
                                short(word)
                            ),
                        ));
                    };
                    let normal = match parts.nth(1) {
                        None | Some("") => None,
                        Some(text) => match resolve(text, vertex_normals.len()) {
                            Some(k) => Some(k),
                            None => {
                                let n = vertex_normals.len();
                                return Err(err(
                                    col_i,
                                    format!(
                                        "expected a normal index between 1 and {n} (or -1 to -{n}) after the second `/`, found `{}`",
                                        short(word)
                                    ),
                                ));
                            }
                        },
                    };
                    corners.push((index, normal, col_i));
                }
                if corners.len() < 3 {
                    return Err(err(
                        col,
                        format!(
                            "expected a face with at least 3 vertices, found {}",
                            corners.len()
                        ),
                    ));
                }
                let smooth = corners.iter().all(|c| c.1.is_some());
                for k in 1..corners.len() - 1 {
                    let fan = [corners[0], corners[k], corners[k + 1]];
                    let tri = fan.map(|c| vertices[c.0]);
                    if is_degenerate(&tri) {
                        return Err(err(
                            col,
                            "expected a triangle with non-zero area, found a degenerate face (collinear or repeated vertices)".to_string(),
                        ));
                    }
                    grow(&mut triangles, path)?;
                    grow(&mut corner_normals, path)?;
                    triangles.push(tri);
                    corner_normals
                        .push(smooth.then(|| fan.map(|c| vertex_normals[c.1.expect("smooth")])));
                }
            }
            "vt" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => {}
            k if k.starts_with('#') => {}
            other => {
                return Err(err(
                    col,
                    format!(
                        "expected an OBJ statement (v, f, vt, vn, o, g, s, usemtl, mtllib or a # comment), found `{}`",
                        short(other)
                    ),
                ));
            }
        }
    }
    if triangles.is_empty() {
        let lines = text.lines().count();
        return Err(Error::parse(
            path,
            lines.max(1),
            1,
            "expected at least one face (`f` line), found none".to_string(),
        ));
    }
    let normals = if corner_normals.iter().any(Option::is_some) {
        triangles
            .iter()
            .zip(corner_normals)
            .map(|(t, n)| n.unwrap_or_else(|| [super::normals::face_normal(t); 3]))
            .collect()
    } else {
        Vec::new()
    };
    Ok(ObjMesh { triangles, normals })
}

/// Makes room for one more item, failing cleanly when memory runs out (a huge OBJ file is an
/// error, not an abort).
fn grow<T>(items: &mut Vec<T>, path: &Path) -> Result<()> {
    if items.len() == items.capacity() {
        items.try_reserve(items.len().max(64)).map_err(|_| {
            Error::Limit(format!(
                "{}: cannot load: the mesh does not fit in memory",
                path.display()
            ))
        })?;
    }
    Ok(())
}

/// Whitespace-separated words of a line with their 1-based character columns.
fn words_with_columns(line: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = line;
    let mut col = 1;
    std::iter::from_fn(move || {
        let trimmed = rest.trim_start();
        col += rest[..rest.len() - trimmed.len()].chars().count();
        if trimmed.is_empty() {
            return None;
        }
        let end = trimmed.find(char::is_whitespace).unwrap_or(trimmed.len());
        let word = &trimmed[..end];
        let at = col;
        col += word.chars().count();
        rest = &trimmed[end..];
        Some((at, word))
    })
}

fn short(word: &str) -> String {
    let mut s: String = word
        .chars()
        .take(24)
        .flat_map(char::escape_default)
        .collect();
    if word.chars().count() > 24 {
        s.push_str("...");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<[Vec3; 3]>> {
        parse_obj(text, Path::new("m.obj")).map(|m| m.triangles)
    }

    #[test]
    fn reads_vertices_faces_slashes_negatives_and_fans() {
        let tris =
            parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nf 1/1/1 2//2 3\nf -4 -2 -1\nf 1 2 3 4\n")
                .unwrap();
        assert_eq!(tris.len(), 4);
        assert_eq!(tris[1][2], Vec3::new(0.0, 1.0, 0.0));
    }

    #[test]
    fn faces_naming_normals_carry_them_unit_length_and_others_are_flat() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 2\nvn 0 1 1\n\
                    f 1//1 2//1 3//2\nf 1/7/2 3/7/-1 4/7/1\nf 1 2 4\n";
        let m = parse_obj(text, Path::new("m.obj")).unwrap();
        assert_eq!(m.triangles.len(), 3);
        let s = 0.5f32.sqrt();
        assert_eq!(m.normals[0], [Vec3::Z, Vec3::Z, Vec3::new(0.0, s, s)]);
        assert_eq!(m.normals[1][1], Vec3::new(0.0, s, s));
        // The face without normals is flat: its own normal at every corner.
        assert_eq!(m.normals[2], [Vec3::Z; 3]);
        // A file without normals has none.
        let m = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", Path::new("m.obj")).unwrap();
        assert!(m.normals.is_empty());
    }

    #[test]
    fn bad_normals_are_errors_at_their_position() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n";
        let e = parse(&format!("{base}f 1//1 2//1 3//2\n")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:5:13: expected a normal index between 1 and 1 (or -1 to -1) after the second \
             `/`, found `3//2`"
        );
        let e = parse("vn 0 0 0\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:1:1: expected a normal of non-zero length, found a zero vector"
        );
        let e = parse("vn 0 inf 1\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:1:6: expected a finite number, found `inf`"
        );
        let e = parse("vn 0 1\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:1:1: expected 3 coordinates after `vn`, found 2"
        );
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:4:7: expected a vertex index between 1 and 3 (or -1 to -3), found `9`"
        );
        let e = parse("v 0 0 nan\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:1:7: expected a finite number, found `nan`"
        );
        let e = parse("v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("m.obj:4:1: expected a triangle with non-zero area")
        );
        let e = parse("").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:1:1: expected at least one face (`f` line), found none"
        );
        // The most negative index: no overflow when negating it.
        let e = parse("v 0 0 0\nf 1 1 -9223372036854775808\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "m.obj:2:7: expected a vertex index between 1 and 1 (or -1 to -1), found \
             `-9223372036854775808`"
        );
        let e = parse("v 1 2 3\nbanana 4\n").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("m.obj:2:1: expected an OBJ statement")
        );
    }
}
