//! The OBJ loader behind `TriangleMesh { obj_file name.obj }`: vertices and faces to a list of
//! triangles. It reads the subset of Wavefront OBJ that meshes use:
//!
//! ```text
//! v x y z [w]          # a vertex
//! f a b c ...          # a face: 1-based indices (negative = relative to the end so far),
//!                      # each optionally `a/t`, `a/t/n` or `a//n`; polygons become fans
//! # comment, vt, vn, vp, o, g, s, usemtl, mtllib, l, p   (ignored)
//! ```
//!
//! Anything else, an index out of range, a face with fewer than three vertices, a degenerate
//! triangle or a file with no face at all is an error at `path:line:col`.

use std::path::Path;

use super::input::{decode_text, read_file};
use crate::error::{Error, Result};
use crate::math::{Vec3, is_degenerate};

/// Loads the triangles of the OBJ file at `path`.
pub fn load_obj(path: &Path) -> Result<Vec<[Vec3; 3]>> {
    let bytes = read_file(path, "read OBJ file")?;
    let text = decode_text(&bytes, path)?;
    parse_obj(text, path)
}

/// Parses OBJ text; `path` names it in errors.
pub fn parse_obj(text: &str, path: &Path) -> Result<Vec<[Vec3; 3]>> {
    let mut vertices: Vec<Vec3> = Vec::new();
    let mut triangles = Vec::new();
    for (line_index, line) in text.lines().enumerate() {
        let line_no = line_index + 1;
        let mut words = words_with_columns(line);
        let Some((col, keyword)) = words.next() else {
            continue;
        };
        let err = |col: usize, msg: String| Error::parse(path, line_no, col, msg);
        match keyword {
            "v" => {
                let mut xyz = [0.0f32; 3];
                for (i, c) in xyz.iter_mut().enumerate() {
                    let Some((col_n, word)) = words.next() else {
                        return Err(err(
                            col,
                            format!("expected 3 coordinates after `v`, found {i}"),
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
                grow(&mut vertices, path)?;
                vertices.push(Vec3::from_array(xyz));
            }
            "f" => {
                let mut corners: Vec<(usize, usize)> = Vec::new(); // (vertex index, column)
                for (col_i, word) in words {
                    let index_text = word.split('/').next().unwrap_or("");
                    let n = vertices.len() as i64;
                    let index = match index_text.parse::<i64>() {
                        Ok(i) if i >= 1 && i <= n => (i - 1) as usize,
                        Ok(i) if i < 0 && i >= -n => (n + i) as usize,
                        _ => {
                            return Err(err(
                                col_i,
                                format!(
                                    "expected a vertex index between 1 and {n} (or -1 to -{n}), found `{}`",
                                    short(word)
                                ),
                            ));
                        }
                    };
                    corners.push((index, col_i));
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
                for k in 1..corners.len() - 1 {
                    let tri = [
                        vertices[corners[0].0],
                        vertices[corners[k].0],
                        vertices[corners[k + 1].0],
                    ];
                    if is_degenerate(&tri) {
                        return Err(err(
                            col,
                            "expected a triangle with non-zero area, found a degenerate face (collinear or repeated vertices)".to_string(),
                        ));
                    }
                    grow(&mut triangles, path)?;
                    triangles.push(tri);
                }
            }
            "vt" | "vn" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => {}
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
    Ok(triangles)
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
        parse_obj(text, Path::new("m.obj"))
    }

    #[test]
    fn reads_vertices_faces_slashes_negatives_and_fans() {
        let tris =
            parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2//2 3\nf -4 -2 -1\nf 1 2 3 4\n")
                .unwrap();
        assert_eq!(tris.len(), 4);
        assert_eq!(tris[1][2], Vec3::new(0.0, 1.0, 0.0));
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
