//! One line of an OBJ file at a time, for the two passes of the chunked reading in `obj.rs`:
//! pass 1 reads a chunk's `v` and `vn` lines and checks every statement but faces
//! ([`read_points`]); pass 2 reads its `f` lines against the points before them
//! ([`read_faces`]). A pass stops its chunk at the first fault, with its position in the
//! chunk ([`Stop`]); `obj.rs` turns the first stop in file order into the file's error.
//!
//! ```text
//! chunk --read_points--> Points { vertices, normals, lines, stop }
//! chunk + all points --read_faces--> Faces { triangles, corner normals, stop }
//! ```

use std::path::Path;

use crate::error::Error;
use crate::math::{Vec3, is_degenerate};

/// Why a chunk's pass stopped: at `line` (counted from 0 in the chunk), at column `col`, with
/// `msg`; or out of memory.
pub(super) enum Stop {
    At {
        line: usize,
        col: usize,
        msg: String,
    },
    OutOfMemory,
}

impl Stop {
    /// The local line the stop is at (`None`: out of memory, the whole chunk failed).
    pub(super) fn line(&self) -> Option<usize> {
        match self {
            Stop::At { line, .. } => Some(*line),
            Stop::OutOfMemory => None,
        }
    }

    pub(super) fn into_error(self, path: &Path, first_line: usize) -> Error {
        match self {
            Stop::At { line, col, msg } => Error::parse(path, first_line + line, col, msg),
            Stop::OutOfMemory => out_of_memory(path),
        }
    }
}

pub(super) fn out_of_memory(path: &Path) -> Error {
    Error::Limit(format!(
        "{}: cannot load: the mesh does not fit in memory",
        path.display()
    ))
}

/// What pass 1 read in one chunk.
#[derive(Default)]
pub(super) struct Points {
    pub(super) vertices: Vec<Vec3>,
    /// Unit vertex normals.
    pub(super) normals: Vec<Vec3>,
    /// The number of lines of the chunk (read to its end, or up to the stop).
    pub(super) lines: usize,
    pub(super) stop: Option<Stop>,
}

/// What pass 2 read in one chunk.
#[derive(Default)]
pub(super) struct Faces {
    pub(super) triangles: Vec<[Vec3; 3]>,
    /// Corner normals parallel to `triangles` once `smooth` (the flat triangles before the
    /// chunk's first smooth face filled in then); empty before.
    pub(super) normals: Vec<[Vec3; 3]>,
    /// True from the chunk's first face that names normals at every corner on.
    pub(super) smooth: bool,
    pub(super) stop: Option<Stop>,
}

/// A flat triangle's corner normals: its own unit normal at every corner.
pub(super) fn flat_corners(t: &[Vec3; 3]) -> [Vec3; 3] {
    [super::normals::face_normal(t); 3]
}

/// Pass 1 over a chunk: its vertices and normals, and the checks of every line but faces.
pub(super) fn read_points(chunk: &str) -> Points {
    let mut p = Points::default();
    for (line, text) in chunk.lines().enumerate() {
        p.lines = line + 1;
        let mut words = words_with_columns(text);
        let Some((col, keyword)) = words.next() else {
            continue;
        };
        let result = match keyword {
            "v" => {
                coordinates(&mut words, "v", col).and_then(|v| push(&mut p.vertices, v).ok_or(None))
            }
            "vn" => coordinates(&mut words, "vn", col).and_then(|n| match n.try_normalize() {
                Some(unit) => push(&mut p.normals, unit).ok_or(None),
                None => Err(Some((
                    col,
                    "expected a normal of non-zero length, found a zero vector".to_string(),
                ))),
            }),
            "f" | "vt" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => Ok(()),
            k if k.starts_with('#') => Ok(()),
            other => Err(Some((
                col,
                format!(
                    "expected an OBJ statement (v, f, vt, vn, o, g, s, usemtl, mtllib or a # comment), found `{}`",
                    short(other)
                ),
            ))),
        };
        if let Err(fault) = result {
            p.stop = Some(stop_at(line, fault));
            return p;
        }
    }
    p
}

/// A fault of one line (`None`: out of memory) as the stop of its chunk's pass.
pub(super) fn stop_at(line: usize, fault: Option<(usize, String)>) -> Stop {
    match fault {
        Some((col, msg)) => Stop::At { line, col, msg },
        None => Stop::OutOfMemory,
    }
}

/// Pass 2 over a chunk's lines before `until`: its faces, as triangles. `before` counts the
/// vertices and normals of the earlier chunks, `points` holds all those read (a face may name
/// only the ones before it).
pub(super) fn read_faces(
    chunk: &str,
    until: usize,
    before: (usize, usize),
    (vertices, normals): (&[Vec3], &[Vec3]),
) -> Faces {
    let mut out = Faces::default();
    let (mut nv, mut nn) = before;
    let mut corners: Vec<(usize, Option<usize>)> = Vec::new();
    for (line, text) in chunk.lines().enumerate().take(until) {
        let mut words = words_with_columns(text);
        match words.next() {
            Some((_, "v")) => nv += 1,
            Some((_, "vn")) => nn += 1,
            Some((col, "f")) => {
                let known = (&vertices[..nv], &normals[..nn]);
                if let Err(fault) = face(words, col, known, &mut corners, &mut out) {
                    out.stop = Some(stop_at(line, fault));
                    return out;
                }
            }
            _ => {}
        }
    }
    out
}

/// Reads the corners of one `f` line (after the keyword at `col`) against the points `known`
/// so far and adds its triangles (a fan) to `out`. `corners` is scratch space.
pub(super) fn face<'a>(
    words: impl Iterator<Item = (usize, &'a str)>,
    col: usize,
    (vertices, normals): (&[Vec3], &[Vec3]),
    corners: &mut Vec<(usize, Option<usize>)>,
    out: &mut Faces,
) -> std::result::Result<(), Option<(usize, String)>> {
    corners.clear();
    // a `what` out of `1..=n` (or `-n..=-1`) at column `col_i` of `word`; `place` says where
    let out_of_range = |col_i: usize, what: &str, n: usize, place: &str, word: &str| {
        let word = short(word);
        let msg =
            format!("expected a {what} between 1 and {n} (or -1 to -{n}){place}, found `{word}`");
        Some((col_i, msg))
    };
    for (col_i, word) in words {
        let mut parts = word.split('/');
        let index_text = parts.next().unwrap_or("");
        let Some(index) = resolve(index_text, vertices.len()) else {
            return Err(out_of_range(
                col_i,
                "vertex index",
                vertices.len(),
                "",
                word,
            ));
        };
        let normal = match parts.nth(1) {
            None | Some("") => None,
            Some(text) => match resolve(text, normals.len()) {
                Some(k) => Some(k),
                None => {
                    let place = " after the second `/`";
                    return Err(out_of_range(
                        col_i,
                        "normal index",
                        normals.len(),
                        place,
                        word,
                    ));
                }
            },
        };
        corners.push((index, normal));
    }
    if corners.len() < 3 {
        return Err(Some((
            col,
            format!(
                "expected a face with at least 3 vertices, found {}",
                corners.len()
            ),
        )));
    }
    let smooth = corners.iter().all(|c| c.1.is_some());
    for k in 1..corners.len() - 1 {
        let fan = [corners[0], corners[k], corners[k + 1]];
        let tri = fan.map(|c| vertices[c.0]);
        if is_degenerate(&tri) {
            return Err(Some((
                col,
                "expected a triangle with non-zero area, found a degenerate face (collinear or repeated vertices)".to_string(),
            )));
        }
        if smooth && !out.smooth {
            // The chunk's first smooth face: the flat triangles before it get their corners.
            out.smooth = true;
            out.normals = try_collect(out.triangles.iter().map(flat_corners)).ok_or(None)?;
        }
        push(&mut out.triangles, tri).ok_or(None)?;
        if out.smooth {
            let n = if smooth {
                fan.map(|c| normals[c.1.expect("smooth")])
            } else {
                flat_corners(&tri)
            };
            push(&mut out.normals, n).ok_or(None)?;
        }
    }
    Ok(())
}

/// Reads the three numbers after `v` or `vn` at column `col`.
pub(super) fn coordinates<'a>(
    words: &mut impl Iterator<Item = (usize, &'a str)>,
    keyword: &str,
    col: usize,
) -> std::result::Result<Vec3, Option<(usize, String)>> {
    let mut xyz = [0.0f32; 3];
    for (i, c) in xyz.iter_mut().enumerate() {
        let Some((col_n, word)) = words.next() else {
            return Err(Some((
                col,
                format!("expected 3 coordinates after `{keyword}`, found {i}"),
            )));
        };
        *c = match word.parse::<f32>() {
            Ok(v) if v.is_finite() => v,
            _ => {
                return Err(Some((
                    col_n,
                    format!("expected a finite number, found `{}`", short(word)),
                )));
            }
        };
    }
    Ok(Vec3::from_array(xyz))
}

/// Resolves a 1-based (or negative, relative) OBJ index into a list of `n` items.
pub(super) fn resolve(text: &str, n: usize) -> Option<usize> {
    let n = n as i64;
    match text.parse::<i64>() {
        Ok(i) if i >= 1 && i <= n => Some((i - 1) as usize),
        Ok(i) if i < 0 && i >= -n => Some((n + i) as usize),
        _ => None,
    }
}

/// Collects `items`, failing cleanly (`None`) when memory runs out.
pub(super) fn try_collect<T>(items: impl ExactSizeIterator<Item = T>) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(items.len()).ok()?;
    v.extend(items);
    Some(v)
}

/// Adds `item`, failing cleanly (`None`) when memory runs out (a huge OBJ file is an error,
/// not an abort).
pub(super) fn push<T>(items: &mut Vec<T>, item: T) -> Option<()> {
    if items.len() == items.capacity() {
        items.try_reserve(items.len().max(64)).ok()?;
    }
    items.push(item);
    Some(())
}

/// Whitespace-separated words of a line with their 1-based character columns.
///
/// An ASCII line (every line of the course's meshes) is split byte by byte, its columns being
/// byte offsets; only a line with other characters counts them. Counting characters for every
/// word was a third of the bunny's parse.
pub(super) fn words_with_columns(line: &str) -> impl Iterator<Item = (usize, &str)> {
    words(line, line.is_ascii())
}

/// [`words_with_columns`], split byte by byte when `ascii` (which the line must then be).
fn words(line: &str, ascii: bool) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = line;
    let mut col = 1;
    std::iter::from_fn(move || {
        if ascii {
            let bytes = rest.as_bytes();
            let start = bytes.iter().position(|&b| !is_ascii_space(b))?;
            let len = bytes[start..]
                .iter()
                .position(|&b| is_ascii_space(b))
                .unwrap_or(bytes.len() - start);
            let (at, word) = (col + start, &rest[start..start + len]);
            col = at + len;
            rest = &rest[start + len..];
            return Some((at, word));
        }
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

/// The ASCII characters `char::is_whitespace` accepts (`u8::is_ascii_whitespace` leaves out
/// the vertical tab).
#[inline(always)]
fn is_ascii_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | 0x0B | 0x0C | b'\r')
}

pub(super) fn short(word: &str) -> String {
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

    #[test]
    fn ascii_lines_split_into_the_same_words_and_columns_as_any_line() {
        let lines = [
            "",
            "   ",
            "v 1 2 3",
            "  f 1/2/3\t4//5  6 ",
            "\tvn\x0b0.5\x0c1e-3\r",
            "# comment  with   gaps",
            "f 1 2 3\r",
        ];
        for line in lines {
            let fast: Vec<_> = words(line, true).collect();
            let general: Vec<_> = words(line, false).collect();
            assert_eq!(fast, general, "{line:?}");
        }
        assert_eq!(
            words_with_columns(" é v  2").collect::<Vec<_>>(),
            [(2, "é"), (4, "v"), (7, "2")]
        );
        assert_eq!(
            words_with_columns("f\t1 22").collect::<Vec<_>>(),
            [(1, "f"), (3, "1"), (5, "22")]
        );
    }
}
