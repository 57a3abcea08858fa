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
//!
//! A big file is read in parallel, in chunks of whole lines, with exactly the result and the
//! first error (in file order) a single reading gives. A face's indices depend on how many
//! vertices and normals came before it, so reading takes two passes over the chunks:
//!
//! ```text
//! bytes --split at line ends, UTF-8 checked--> chunks --pass 1 (parallel): v, vn, statement checks, f lines counted--> points
//!      --prefix sums: first line, first vertex, first normal of each chunk
//!      --pass 2 (parallel): f lines resolved against the points before them--> triangles
//!      --concatenated in chunk order--> ObjMesh
//! ```
//!
//! Each pass stops a chunk at its first error; the first chunk with one decides the file's
//! error (a face error of pass 2 comes before the pass-1 error of its chunk, as pass 2 reads
//! only the lines before that). A file of one chunk is read the same way, on one thread. The
//! lines themselves are read in `obj_lines.rs`.

use std::path::Path;

use rayon::prelude::*;

use super::input::{decode_text, read_file};
use super::obj_lines::{
    Faces, Points, Stop, flat_corners, out_of_memory, read_faces, read_points, try_collect,
};
use crate::error::{Error, Result};
use crate::math::Vec3;

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
    parse_obj_in_chunks(&bytes, path, CHUNK_BYTES)
}

/// Bytes of text one parallel task reads (then on to the end of the line): a file of at most
/// this size is one chunk. Small enough that a course mesh makes many, so the threads share
/// them out evenly although vertex lines cost more than face lines in pass 1 and less in pass
/// 2. The 1.3 MB bunny, parse at 2 threads: 1 MiB chunks, median 11.1 ms, against 9.9 ms with
/// 256 KiB (25 alternating runs); then, with the workers pinned, 256 KiB 5.71 ms, 128 KiB 5.28
/// ms, 64 KiB 5.13 ms (30 alternating runs; at 1 thread 8.3 ms for all three).
const CHUNK_BYTES: usize = 64 << 10;

/// Parses OBJ text; `path` names it in errors.
pub fn parse_obj(text: &str, path: &Path) -> Result<ObjMesh> {
    parse_obj_in_chunks(text.as_bytes(), path, CHUNK_BYTES)
}

/// Cuts `bytes` into pieces of about `chunk_bytes`, each ending just after a `\n` (the last
/// one at the end): the lines of the pieces are the lines of the text, and a piece never ends
/// inside a character. At least one piece, even for empty text.
fn split_lines(bytes: &[u8], chunk_bytes: usize) -> Vec<&[u8]> {
    let mut chunks = Vec::with_capacity(bytes.len() / chunk_bytes.max(1) + 1);
    let mut start = 0usize;
    loop {
        let end = start.saturating_add(chunk_bytes.max(1)).min(bytes.len());
        let cut = match bytes[end..].iter().position(|&b| b == b'\n') {
            Some(i) => end + i + 1,
            None => bytes.len(),
        };
        chunks.push(&bytes[start..cut]);
        if cut == bytes.len() {
            return chunks;
        }
        start = cut;
    }
}

/// Parses OBJ text in chunks of about `chunk_bytes` (see the module's notes), checking that it
/// is UTF-8 chunk by chunk.
fn parse_obj_in_chunks(bytes: &[u8], path: &Path, chunk_bytes: usize) -> Result<ObjMesh> {
    let pieces = split_lines(bytes, chunk_bytes);
    // One task per chunk, which checks its UTF-8 and reads its points (one parallel phase, not
    // two: the threads are not put to sleep and woken between them). The pieces are UTF-8 if
    // and only if the whole is; `decode_text` names the first bad byte's position.
    let read: Option<Vec<(&str, Points)>> = pieces
        .par_iter()
        .with_max_len(1)
        .map(|p| std::str::from_utf8(p).ok().map(|c| (c, read_points(c))))
        .collect();
    let (chunks, points): (Vec<&str>, Vec<Points>) = match read {
        Some(read) => read.into_iter().unzip(),
        None => {
            let text = decode_text(bytes, path)?;
            (vec![text], vec![read_points(text)])
        }
    };
    // Chunks after the first one that stopped cannot matter: their error would come later.
    let used = points
        .iter()
        .position(|p| p.stop.is_some())
        .map_or(chunks.len(), |k| k + 1);
    let (mut first_line, mut first_vertex, mut first_normal) = (Vec::new(), Vec::new(), Vec::new());
    let (mut line, mut nv, mut nn) = (1, 0, 0);
    for p in &points[..used] {
        first_line.push(line);
        first_vertex.push(nv);
        first_normal.push(nn);
        line += p.lines;
        nv += p.vertices.len();
        nn += p.normals.len();
    }
    let oom = |_| out_of_memory(path);
    let vertices = concat_parts(points[..used].iter().map(|p| &p.vertices[..]), nv).map_err(oom)?;
    let vertex_normals =
        concat_parts(points[..used].iter().map(|p| &p.normals[..]), nn).map_err(oom)?;
    let mut faces: Vec<Faces> = (0..used)
        .into_par_iter()
        .with_max_len(1)
        .map(|k| match points[k].stop.as_ref().map(Stop::line) {
            // Out of memory: the chunk fails as a whole.
            Some(None) => Faces::default(),
            until => read_faces(
                chunks[k],
                until.flatten().unwrap_or(usize::MAX),
                (points[k].first_face, points[k].faces),
                (first_vertex[k], first_normal[k]),
                (&vertices, &vertex_normals),
            ),
        })
        .collect();
    drop((vertices, vertex_normals));
    // The first stop in file order: a chunk's face error comes before its pass-1 stop.
    for (k, (f, p)) in faces.iter_mut().zip(points).enumerate() {
        if let Some(stop) = f.stop.take().or(p.stop) {
            return Err(stop.into_error(path, first_line[k]));
        }
    }
    let count: usize = faces.iter().map(|f| f.triangles.len()).sum();
    if count == 0 {
        return Err(Error::parse(
            path,
            (line - 1).max(1),
            1,
            "expected at least one face (`f` line), found none".to_string(),
        ));
    }
    let triangles = concat_parts(faces.iter().map(|f| &f.triangles[..]), count).map_err(oom)?;
    let mut normals = Vec::new();
    if faces.iter().any(|f| f.smooth) {
        // The chunks without a smooth face get their flat corners now.
        for f in faces.iter_mut().filter(|f| !f.smooth) {
            f.normals = try_collect(f.triangles.iter().map(flat_corners))
                .ok_or_else(|| out_of_memory(path))?;
        }
        normals = concat_parts(faces.iter().map(|f| &f.normals[..]), count).map_err(oom)?;
    }
    Ok(ObjMesh { triangles, normals })
}

/// The concatenation of `parts` (`total` items in all), copied in parallel; `Err` when memory
/// runs out.
fn concat_parts<'p, T: Copy + Send + Sync + 'p>(
    parts: impl Iterator<Item = &'p [T]>,
    total: usize,
) -> std::result::Result<Vec<T>, ()> {
    let parts: Vec<&[T]> = parts.collect();
    let mut starts = Vec::with_capacity(parts.len() + 1);
    let mut n = 0;
    for p in &parts {
        starts.push(n);
        n += p.len();
    }
    debug_assert_eq!(n, total);
    let mut all = Vec::new();
    all.try_reserve_exact(total).map_err(|_| ())?;
    // Each task walks its run of items forward, part by part (`k` is where it is).
    (0..total)
        .into_par_iter()
        .with_min_len(1 << 14)
        .map_init(
            || 0,
            |k, i| {
                if !(starts[*k]..starts[*k] + parts[*k].len()).contains(&i) {
                    *k = starts.partition_point(|&s| s <= i) - 1;
                    while parts[*k].is_empty() || i >= starts[*k] + parts[*k].len() {
                        *k += 1;
                    }
                }
                parts[*k][i - starts[*k]]
            },
        )
        .collect_into_vec(&mut all);
    Ok(all)
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

    #[test]
    fn quick_lines_read_what_the_general_reading_reads() {
        // A line starting with a space is read the general way, so each line is read both
        // ways; a fault's column is then one further along.
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 0 1 1\n";
        let lines = [
            "f 1 2 3",
            "f 1 2 3 4",
            "f\t1 2\t3\r",
            "f 1/1/1 2/2/2 3/3/2",
            "f 1//1 2//2 3//1",
            "f 1/ 2/ 3/",
            "f 1// 2// 3//",
            "f 1/2/ 2/2/ 3/2/",
            "f 1/x/1 2 3",
            "f 1/2/1/4 2 3",
            "f -1 -2 -3",
            "f -0 1 2",
            "f +1 2 3",
            "f 0 1 2",
            "f 1 2 99",
            "f 1 2 4//9",
            "f 1 1 2",
            "f 1 2",
            "f",
            "f ",
            "f 1 2 3 # comment",
            "f 001 2 3",
            "f 1 2 3\u{a0}",
            "f 1 2\u{2003}3",
            "f 1 2 0000000000000000003",
            "f 1 2 -9223372036854775808",
            "f 1 2 3 -1//2",
            "v 1 2 3",
            "v 1 2",
            "v 1 2 3 4",
            "v 1e3 2 3",
            "v 1 2 nan",
            "v 1 2 inf",
            "v 1\u{a0}2 3",
            "v -0 .5 5.",
            "v 1 2 3abc",
            "v 0.1234567 3 16777217",
            "vn 0 0 0",
            "vn 0 0 2",
            "vn 1 2",
            "vn 1 2 x",
        ];
        let mut quick_ok = 0;
        for line in lines {
            let read = |pad: &str| {
                let text = format!("{base}{pad}{line}\nf 1 2 3\n");
                parse_obj(&text, Path::new("m.obj")).map_err(|e| e.to_string())
            };
            match (read(""), read(" ")) {
                (Ok(quick), Ok(general)) => {
                    assert_eq!(quick, general, "{line:?}");
                    quick_ok += 1;
                }
                (Err(quick), Err(general)) => {
                    let (place, msg) = quick.split_at(quick.find(": ").unwrap());
                    let col: usize = place.rsplit(':').next().unwrap().parse().unwrap();
                    let line_no = &place[..place.len() - col.to_string().len()];
                    assert_eq!(general, format!("{line_no}{}{msg}", col + 1), "{line:?}");
                }
                (quick, general) => panic!("{line:?}: {quick:?} / {general:?}"),
            }
        }
        assert!(quick_ok > 15, "{quick_ok}");
    }

    /// A generated mesh of `n` quads with every kind of line: normals, `a//n` and `a/t/n`
    /// corners, negative indices, fans, comments, ignored statements, blank and `\r\n` lines.
    fn big_obj(n: usize) -> String {
        let mut s = String::from("# generated\r\nmtllib m.mtl\n\n");
        for i in 0..n {
            let (x, y) = ((i % 97) as f32 * 0.5, (i / 97) as f32 * 0.25);
            s += &format!(
                "v {x} {y} 0\nv {} {y} 0.5\nv {} {} 0\nv {x} {} 1\n",
                x + 0.5,
                x + 0.5,
                y + 0.25,
                y + 0.25
            );
            s += &format!("vn 0 0 {}\r\nvt 0 0\n", 1 + i % 3);
            match i % 4 {
                0 => s += "f -4 -3 -2 -1\n",
                1 => s += &format!("f {}//{} -3//-1 -2//{}\n  \n", 4 * i + 1, i + 1, i + 1),
                2 => {
                    s += &format!(
                        "g part\nf {}/1/{} {} -1/1/-1\n",
                        4 * i + 2,
                        i + 1,
                        4 * i + 3
                    )
                }
                _ => s += "s off\nf -4 -2 -1\n# quad done\n",
            }
        }
        s
    }

    #[test]
    fn chunks_read_exactly_what_one_reading_reads() {
        let text = big_obj(600);
        let one = parse_obj_in_chunks(text.as_bytes(), Path::new("m.obj"), usize::MAX).unwrap();
        assert_eq!(one.triangles.len(), 600 / 4 * 5);
        assert_eq!(one.normals.len(), one.triangles.len());
        for chunk_bytes in [1, 7, 64, 1000, 4096] {
            let chunked =
                parse_obj_in_chunks(text.as_bytes(), Path::new("m.obj"), chunk_bytes).unwrap();
            assert!(
                split_lines(text.as_bytes(), chunk_bytes).len() > text.len() / (chunk_bytes + 64)
            );
            assert_eq!(chunked, one, "chunks of {chunk_bytes} bytes");
        }
        // A chunk without smooth faces beside chunks with: its triangles get flat corners.
        let flat = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 1 0 0\nf 1 2 3\nf 1//1 2//1 3//1\n";
        let one = parse_obj_in_chunks(flat.as_bytes(), Path::new("m.obj"), usize::MAX).unwrap();
        assert_eq!(one.normals, [[Vec3::Z; 3], [Vec3::X; 3]]);
        assert_eq!(
            parse_obj_in_chunks(flat.as_bytes(), Path::new("m.obj"), 1).unwrap(),
            one
        );
    }

    #[test]
    fn the_first_error_in_file_order_wins_whatever_the_chunks() {
        let text = big_obj(400);
        let lines: Vec<&str> = text.split_inclusive('\n').collect();
        let with = |at: usize, line: &str| {
            let mut l = lines.clone();
            l[at] = line;
            l.concat()
        };
        let late = lines.len() - 7;
        let cases = [
            // Pass 2 (an index past the vertices read so far, a degenerate face), pass 1 (a
            // bad number, an unknown statement, a zero normal), late and early.
            (
                with(late, "f 1 2 99999\n"),
                format!(
                    "m.obj:{}:7: expected a vertex index between 1 and 1598 (or -1 to -1598), found `99999`",
                    late + 1
                ),
            ),
            (
                with(late, "f 1 1 2\n"),
                format!(
                    "m.obj:{}:1: expected a triangle with non-zero area",
                    late + 1
                ),
            ),
            (
                with(late, "v 0 x 0\n"),
                format!("m.obj:{}:5: expected a finite number, found `x`", late + 1),
            ),
            (
                with(late, "  banana\n"),
                format!("m.obj:{}:3: expected an OBJ statement", late + 1),
            ),
            (
                with(40, "vn 0 0 0\n"),
                "m.obj:41:1: expected a normal of non-zero length".to_string(),
            ),
        ];
        for (text, expected) in &cases {
            let one =
                parse_obj_in_chunks(text.as_bytes(), Path::new("m.obj"), usize::MAX).unwrap_err();
            assert!(
                one.to_string().starts_with(expected.as_str()),
                "{one} / {expected}"
            );
            for chunk_bytes in [1, 50, 999, 4096] {
                let e = parse_obj_in_chunks(text.as_bytes(), Path::new("m.obj"), chunk_bytes)
                    .unwrap_err();
                assert_eq!(
                    e.to_string(),
                    one.to_string(),
                    "chunks of {chunk_bytes} bytes"
                );
            }
        }
        // Bad UTF-8 late in the file: the position of the first bad byte.
        let mut bytes = text.clone().into_bytes();
        let at = bytes.len() - 20;
        bytes[at] = 0xff;
        let one = parse_obj_in_chunks(&bytes, Path::new("m.obj"), usize::MAX).unwrap_err();
        assert!(
            one.to_string()
                .contains("expected UTF-8 text, found byte 0xff"),
            "{one}"
        );
        for chunk_bytes in [1, 999] {
            let e = parse_obj_in_chunks(&bytes, Path::new("m.obj"), chunk_bytes).unwrap_err();
            assert_eq!(e.to_string(), one.to_string());
        }
        // A face error before a statement error later in the file, in the same chunk or an
        // earlier one: the face error is reported.
        let both = with(late, "oops\n").replacen("f -4 -3 -2 -1", "f -4 -3 -2 -9999", 2);
        let first = both.find("-9999").unwrap();
        let line = both[..first].matches('\n').count() + 1;
        for chunk_bytes in [1, 999, usize::MAX] {
            let e =
                parse_obj_in_chunks(both.as_bytes(), Path::new("m.obj"), chunk_bytes).unwrap_err();
            assert!(
                e.to_string()
                    .starts_with(&format!("m.obj:{line}:12: expected a vertex index")),
                "{e}"
            );
        }
    }
}
