//! One line of an OBJ file at a time, for the two passes of the chunked reading in `obj.rs`:
//! pass 1 reads a chunk's `v` and `vn` lines, checks every statement but faces, notes where
//! its first `f` line is and counts its `f` lines ([`read_points`]); pass 2 reads its `f`
//! lines, from that one on, against the points before them, into room made for a triangle
//! per line ([`read_faces`]). A pass stops its chunk at the first fault, with its position in
//! the chunk ([`Stop`]); `obj.rs` turns the first stop in file order into the file's error.
//!
//! The lines mesh exporters write (`v x y z`, `vn x y z`, `f a b c` with plain or `a/t/n`
//! corners) are read without splitting them into words first; any other line, and any of
//! these the quick reading cannot take (a fault among them), is read the general way, which
//! gives the same result and names the fault.
//!
//! ```text
//! chunk --read_points--> Points { vertices, normals, lines, first face, faces, stop }
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
    /// Where the chunk's first `f` line is, if pass 1 met one: pass 2 starts there.
    pub(super) first_face: Option<FirstFace>,
    /// The chunk's `f` lines (before the stop, if any): pass 2 makes room for a triangle each.
    pub(super) faces: usize,
    pub(super) stop: Option<Stop>,
}

/// A chunk's first `f` line: its byte offset and line (from 0) in the chunk, and the vertices
/// and normals of the chunk before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct FirstFace {
    pub(super) byte: usize,
    pub(super) line: usize,
    pub(super) vertices: usize,
    pub(super) normals: usize,
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
    for (line, text) in lines(chunk).enumerate() {
        p.lines = line + 1;
        // An `f` line, however read: counted, and where the first one is noted.
        let note_face = |p: &mut Points| {
            if p.first_face.is_none() {
                p.first_face = Some(FirstFace {
                    byte: text.as_ptr() as usize - chunk.as_ptr() as usize,
                    line,
                    vertices: p.vertices.len(),
                    normals: p.normals.len(),
                });
            }
            p.faces += 1;
        };
        // The common lines the quick way (see the module's notes), the rest the general way.
        let quick = match text.as_bytes() {
            [b'f', s, ..] if is_ascii_space(*s) => {
                note_face(&mut p);
                continue;
            }
            [b'v', s, ..] if is_ascii_space(*s) => {
                quick_coordinates(&text[2..]).map(|v| (&mut p.vertices, v))
            }
            [b'v', b'n', s, ..] if is_ascii_space(*s) => quick_coordinates(&text[3..])
                .and_then(Vec3::try_normalize)
                .map(|n| (&mut p.normals, n)),
            _ => None,
        };
        if let Some((list, point)) = quick {
            if push(list, point).is_none() {
                p.stop = Some(Stop::OutOfMemory);
                return p;
            }
            continue;
        }
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
            "f" => {
                note_face(&mut p);
                Ok(())
            }
            "vt" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p" => Ok(()),
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

/// Pass 2 over a chunk's lines before `until`, from its first face on (`from`, found by pass
/// 1; none: nothing to read): its faces, as triangles. `faces` is pass 1's count of the chunk's
/// `f` lines: room for that many triangles is made first, so that the list of a triangulated
/// mesh's chunk never grows (growing copies it, inside the lock of the one heap the workers
/// share: torus1m's parse at 2 threads took 8–14 ms longer so, PERF.md sitting 58). `before`
/// counts the vertices and normals of the earlier chunks, `points` holds all those read (a
/// face may name only the ones before it).
pub(super) fn read_faces(
    chunk: &str,
    until: usize,
    (from, faces): (Option<FirstFace>, usize),
    before: (usize, usize),
    (vertices, normals): (&[Vec3], &[Vec3]),
) -> Faces {
    let mut out = Faces::default();
    let Some(from) = from else {
        return out;
    };
    // No room is no error yet: the first triangle that finds none stops the chunk.
    let _ = out.triangles.try_reserve_exact(faces);
    let (mut nv, mut nn) = (before.0 + from.vertices, before.1 + from.normals);
    let mut corners: Vec<(usize, Option<usize>)> = Vec::new();
    let lines = lines(&chunk[from.byte..])
        .enumerate()
        .map(|(k, text)| (from.line + k, text));
    for (line, text) in lines.take_while(|&(line, _)| line < until) {
        // As in pass 1: the common lines first, without splitting them into words.
        let result = match text.as_bytes() {
            [b'v', s, ..] if is_ascii_space(*s) => {
                nv += 1;
                continue;
            }
            [b'v', b'n', s, ..] if is_ascii_space(*s) => {
                nn += 1;
                continue;
            }
            [b'f', s, ..]
                if is_ascii_space(*s)
                    && quick_corners(&text[2..], (nv, nn), &mut corners).is_some() =>
            {
                add_fan(&corners, 1, (vertices, normals), &mut out)
            }
            _ => {
                let mut words = words_with_columns(text);
                match words.next() {
                    Some((_, "v")) => {
                        nv += 1;
                        Ok(())
                    }
                    Some((_, "vn")) => {
                        nn += 1;
                        Ok(())
                    }
                    Some((col, "f")) => {
                        let known = (&vertices[..nv], &normals[..nn]);
                        face(words, col, known, &mut corners, &mut out)
                    }
                    _ => Ok(()),
                }
            }
        };
        if let Err(fault) = result {
            out.stop = Some(stop_at(line, fault));
            return out;
        }
    }
    out
}

/// Reads the corners of an `f` line's `rest` (after `f` and one space) the quick way: every
/// corner `a`, `a/t`, `a//n` or `a/t/n`, with indices of digits (or `-` and digits) among the
/// `nv` vertices and `nn` normals read so far, and texture indices of digits. `None` for
/// anything else, which the general reading ([`face`]) then reads, or reports.
pub(super) fn quick_corners(
    rest: &str,
    (nv, nn): (usize, usize),
    corners: &mut Vec<(usize, Option<usize>)>,
) -> Option<()> {
    corners.clear();
    let b = rest.as_bytes();
    let mut i = 0;
    loop {
        i = skip_spaces(b, i);
        if i == b.len() {
            return Some(());
        }
        let vertex = quick_index(b, &mut i, nv)?;
        let mut normal = None;
        if b.get(i) == Some(&b'/') {
            i += 1;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            if b.get(i) == Some(&b'/') {
                i += 1;
                if i < b.len() && !is_ascii_space(b[i]) {
                    normal = Some(quick_index(b, &mut i, nn)?);
                }
            }
        }
        if i < b.len() && !is_ascii_space(b[i]) {
            return None;
        }
        corners.push((vertex, normal));
    }
}

/// The index at `b[*i..]` (digits, or `-` and digits), resolved as [`resolve`] does into a
/// list of `n`, moving `*i` past it; `None` when it is not one or is out of range.
fn quick_index(b: &[u8], i: &mut usize, n: usize) -> Option<usize> {
    let negative = b.get(*i) == Some(&b'-');
    let start = *i + usize::from(negative);
    let mut end = start;
    let mut value: u64 = 0;
    while end < b.len() && b[end].is_ascii_digit() {
        // At most 18 digits: no overflow (the general reading takes longer ones).
        if end - start == 18 {
            return None;
        }
        value = value * 10 + u64::from(b[end] - b'0');
        end += 1;
    }
    if end == start || value == 0 || value > n as u64 {
        return None;
    }
    *i = end;
    let value = value as usize;
    Some(if negative { n - value } else { value - 1 })
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
    add_fan(corners, col, (vertices, normals), out)
}

/// Adds the triangles (a fan) of a face with `corners` (indices into `vertices` and
/// `normals`) to `out`; `col` is the column of its `f`, where its faults are reported.
pub(super) fn add_fan(
    corners: &[(usize, Option<usize>)],
    col: usize,
    (vertices, normals): (&[Vec3], &[Vec3]),
    out: &mut Faces,
) -> std::result::Result<(), Option<(usize, String)>> {
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
            // The chunk's first smooth face: the flat triangles before it get their corners,
            // and the normals as much room as the triangles.
            out.smooth = true;
            out.normals = try_collect(out.triangles.iter().map(flat_corners)).ok_or(None)?;
            let _ = out
                .normals
                .try_reserve_exact(out.triangles.capacity() - out.normals.len());
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

/// The three numbers at the start of `rest` (after `v ` or `vn `) the quick way: split at
/// ASCII white space, each one finite; what follows them is ignored, as [`coordinates`] does.
/// `None` when there are fewer or one is not a finite number: [`coordinates`] then says which.
pub(super) fn quick_coordinates(rest: &str) -> Option<Vec3> {
    let b = rest.as_bytes();
    let mut xyz = [0.0f32; 3];
    let mut i = 0;
    for c in &mut xyz {
        let start = skip_spaces(b, i);
        i = start;
        while i < b.len() && !is_ascii_space(b[i]) {
            i += 1;
        }
        let word = &b[start..i];
        *c = match quick_number(word) {
            Some(v) => v,
            // `start..i` lies between ASCII bytes (or the ends), so on character boundaries.
            None => rest[start..i]
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())?,
        };
    }
    Some(Vec3::from_array(xyz))
}

/// `word` as `str::parse::<f32>` reads it, when it is a decimal `[-]digits[.digits]` whose
/// digits make an integer `m` of at most 2^24 with at most 10 after the point; `None` for
/// anything else. Then `m` and 10^k are both exact `f32`s and one division, rounded once to
/// nearest, gives the nearest `f32` to the decimal: the correctly rounded value the standard
/// parser returns (Clinger's fast path, which it takes too, after more checking).
pub(super) fn quick_number(word: &[u8]) -> Option<f32> {
    const TENS: [f32; 11] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];
    let (negative, digits) = match word {
        [b'-', rest @ ..] => (true, rest),
        _ => (false, word),
    };
    let (mut m, mut after_point, mut point, mut any) = (0u64, 0usize, false, false);
    for &b in digits {
        if b == b'.' && !point {
            point = true;
            continue;
        }
        if !b.is_ascii_digit() {
            return None;
        }
        m = m.checked_mul(10)?.checked_add(u64::from(b - b'0'))?;
        after_point += usize::from(point);
        any = true;
    }
    if !any || m > 1 << 24 || after_point >= TENS.len() {
        return None;
    }
    let v = m as f32 / TENS[after_point];
    Some(if negative { -v } else { v })
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

/// The lines of `text`, as `str::lines` gives them (without their `\n` or `\r\n`), each end
/// found 8 bytes at a time ([`newline`]): a mesh's lines are some 30 bytes, too short for
/// `str::lines`' wide search to pay for its setting up (a fifth of a warm bunny parse, with the
/// words read quickly).
pub(super) fn lines(text: &str) -> impl Iterator<Item = &str> {
    let mut rest = text;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        let Some(end) = newline(rest.as_bytes()) else {
            return Some(std::mem::take(&mut rest));
        };
        let line = &rest[..end];
        rest = &rest[end + 1..];
        Some(line.strip_suffix('\r').unwrap_or(line))
    })
}

/// The position of the first `\n` in `bytes`, found a word of 8 bytes at a time: a byte is
/// zero in `w ^ 0x0a..0a` exactly where `w` has a `\n`, and the lowest byte whose top bit
/// `(x - 0x01..01) & !x & 0x80..80` sets is the first zero byte of `x` (a borrow only runs
/// upwards from a zero byte, so bytes above the first may be flagged too, never below it).
fn newline(bytes: &[u8]) -> Option<usize> {
    const ONES: u64 = u64::from_ne_bytes([0x01; 8]);
    const HIGHS: u64 = u64::from_ne_bytes([0x80; 8]);
    const NEWLINES: u64 = u64::from_ne_bytes([b'\n'; 8]);
    let mut words = bytes.chunks_exact(8);
    for (k, word) in words.by_ref().enumerate() {
        let x = u64::from_le_bytes(word.try_into().expect("8 bytes")) ^ NEWLINES;
        let found = x.wrapping_sub(ONES) & !x & HIGHS;
        if found != 0 {
            return Some(8 * k + found.trailing_zeros() as usize / 8);
        }
    }
    let tail = words.remainder();
    let at = bytes.len() - tail.len();
    tail.iter().position(|&b| b == b'\n').map(|i| at + i)
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

/// The position of the first byte of `b` at or after `i` that is not ASCII white space
/// (`b.len()` if none).
#[inline(always)]
fn skip_spaces(b: &[u8], i: usize) -> usize {
    b[i..]
        .iter()
        .position(|&c| !is_ascii_space(c))
        .map_or(b.len(), |k| i + k)
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

    /// Pass 1 counts every `f` line, read the quick way or the general one, and pass 2 makes
    /// room for that many triangles first: a triangulated chunk's list is never grown, and
    /// once a chunk turns smooth its normals get as much room as its triangles.
    #[test]
    fn pass_2_makes_room_for_a_triangle_per_face_line_that_pass_1_counted() {
        let read = |chunk: &str| {
            let p = read_points(chunk);
            let faces = (p.first_face, p.faces);
            (
                p.faces,
                read_faces(chunk, usize::MAX, faces, (0, 0), (&p.vertices, &p.normals)),
            )
        };
        let flat =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n  f 1 2 4\nf\t1 3 4\nvn 0 0 1\nf 2 3 4\n";
        let (counted, faces) = read(flat);
        assert_eq!(counted, 4);
        assert!(faces.stop.is_none());
        assert_eq!(faces.triangles.len(), 4);
        assert_eq!(faces.triangles.capacity(), 4, "the triangles' list grew");
        let smooth =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1 2 3\nf 1//1 2//1 3//1\n f 3//1 2//1 1//1\n";
        let (counted, faces) = read(smooth);
        assert_eq!(counted, 3);
        assert!(faces.smooth && faces.stop.is_none());
        assert_eq!((faces.triangles.len(), faces.normals.len()), (3, 3));
        assert_eq!(faces.triangles.capacity(), 3, "the triangles' list grew");
        assert_eq!(faces.normals.capacity(), 3, "the normals' list grew");
        // A fan makes more triangles than lines: its list grows, as before.
        let (counted, faces) = read("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
        assert_eq!((counted, faces.triangles.len()), (1, 2));
    }

    #[test]
    fn lines_are_those_of_str_lines() {
        let texts = [
            "",
            "\n",
            "a",
            "a\n",
            "a\r\nbb\r\n\r\nccc",
            "v 1 2 3\nf 1 2 3\n\n\nlonger than eight bytes\r\n\r",
            "x\r",
            "\r\n\r\n",
            "0123456\n01234567\n012345678\n",
        ];
        for text in texts {
            assert_eq!(
                lines(text).collect::<Vec<_>>(),
                text.lines().collect::<Vec<_>>(),
                "{text:?}"
            );
        }
        // Every position of the first newline, in and across the 8-byte words.
        for n in 0..40 {
            let mut bytes = vec![b'x'; 40];
            bytes[n] = b'\n';
            bytes[(n + 9).min(39)] = b'\n';
            assert_eq!(newline(&bytes), Some(n));
            assert_eq!(newline(&bytes[..n]), None);
        }
    }

    #[test]
    fn quick_numbers_are_what_the_standard_parser_reads() {
        let mut words: Vec<String> = [
            "",
            "-",
            ".",
            "-.",
            "1.",
            ".5",
            "-.5",
            "-0",
            "0",
            "00000001",
            "16777216",
            "16777217",
            "1677721.6",
            "0.16777217",
            "0.0000000001",
            "0.00000000001",
            "1e5",
            "+1",
            "1..2",
            "1.2.3",
            "99999999999999999999999",
            "-0.0766682",
            "0.000960624",
            "0.256122",
            "12a",
            "nan",
            "inf",
            "-inf",
        ]
        .map(String::from)
        .to_vec();
        // Random decimals: 1-12 digits, the point anywhere or nowhere, either sign.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % n
        };
        for _ in 0..200_000 {
            let len = 1 + next(12) as usize;
            let mut w: String = (0..len)
                .map(|_| char::from(b'0' + next(10) as u8))
                .collect();
            if next(4) > 0 {
                w.insert(next(len as u64 + 1) as usize, '.');
            }
            if next(2) == 0 {
                w.insert(0, '-');
            }
            words.push(w);
        }
        let mut quick = 0;
        for w in &words {
            if let Some(v) = quick_number(w.as_bytes()) {
                quick += 1;
                assert_eq!(v.to_bits(), w.parse::<f32>().unwrap().to_bits(), "{w:?}");
            }
        }
        // The quick reading takes most of them (the course meshes' numbers among them).
        assert!(quick > words.len() / 2, "{quick} of {}", words.len());
        for w in ["-0.0766682", "0.000960624", "16777216", "-0", "1.", ".5"] {
            assert!(quick_number(w.as_bytes()).is_some(), "{w}");
        }
        for w in [
            "16777217",
            "0.00000000001",
            "1e5",
            "+1",
            "-",
            ".",
            "1..2",
            "nan",
        ] {
            assert!(quick_number(w.as_bytes()).is_none(), "{w}");
        }
    }

    #[test]
    fn quick_corners_take_the_common_forms_and_leave_the_rest() {
        type Corners<'c> = &'c [(usize, Option<usize>)];
        let mut corners = Vec::new();
        let cases: [(&str, Option<Corners>); 12] = [
            ("1 2 3", Some(&[(0, None), (1, None), (2, None)])),
            ("\t1  2 3 \r", Some(&[(0, None), (1, None), (2, None)])),
            (
                "1/5/2 2//1 -1/",
                Some(&[(0, Some(1)), (1, Some(0)), (3, None)]),
            ),
            ("1/2/ 004 -4", Some(&[(0, None), (3, None), (0, None)])),
            ("", Some(&[])),
            ("1 2 5", None),
            ("0 1 2", None),
            ("+1 2 3", None),
            ("1/x/1 2 3", None),
            ("1/2/3/4 2 3", None),
            ("1 2 3\u{a0}", None),
            ("1 2 0000000000000000003", None),
        ];
        for (rest, expected) in cases {
            let got = quick_corners(rest, (4, 2), &mut corners).map(|()| corners.clone());
            assert_eq!(got.as_deref(), expected, "{rest:?}");
        }
    }
}
