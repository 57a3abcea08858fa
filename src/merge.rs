//! `whitted merge OUT PIECE...`: puts the pieces of a render (`--crop`, `--tile`) back into the
//! full image. Each piece says where it belongs (an EXR's data and display windows, any other
//! format's sidecar, see [`crate::output::piece`]) and which render it comes from (its
//! fingerprint). The merge checks, before it writes anything, that every piece is readable, in
//! the output's format, from the same render as the first, and that together they cover the full
//! image exactly once; then it copies each piece's stored samples into place and writes the
//! whole atomically, so the result has the bytes a one-go render writes. Every refusal is one
//! line naming the piece.
//!
//! ```text
//! PIECE... --read + decode--> (Raster, Place, fingerprint) --checks--> assemble --> encode --> OUT
//! ```

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::options::Window;
use crate::output::{self, Decoded, Format, Place, Raster, Samples, piece};

/// A piece read and checked on its own.
struct Piece {
    path: PathBuf,
    raster: Raster,
    place: Place,
    fingerprint: String,
}

fn refuse(path: &Path, msg: impl std::fmt::Display) -> Error {
    Error::Other(format!("{}: {msg}", path.display()))
}

/// Reads the piece at `path`, which must be in `format`.
fn read_piece(path: &Path, format: Format, out: &Path) -> Result<Piece> {
    let piece_format = Format::for_path(path).map_err(|_| {
        refuse(
            path,
            "is not an image whitted writes (expected .png, .tga, .ppm, .exr, .pfm or .hdr)",
        )
    })?;
    if piece_format != format {
        return Err(refuse(
            path,
            format!(
                "is a .{} piece, but {} is .{}: expected every piece in the output's format",
                piece_format.extension(),
                out.display(),
                format.extension()
            ),
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            refuse(
                path,
                "is missing (a tile that failed leaves no file: render it again)",
            )
        } else {
            refuse(path, format!("cannot read it: {e}"))
        }
    })?;
    let Decoded {
        raster,
        place,
        fingerprint,
    } = output::decode(&bytes, format).map_err(|e| refuse(path, e))?;
    let (place, fingerprint) = match (place, fingerprint) {
        (Some(place), Some(f)) => (place, f),
        (Some(_), None) => {
            return Err(refuse(
                path,
                format!(
                    "records no `{}` attribute: not a piece of a whitted render",
                    output::FINGERPRINT_ATTRIBUTE
                ),
            ));
        }
        (None, _) => {
            let p = piece::read_sidecar(path).map_err(|e| refuse(path, e))?;
            (p.place, p.fingerprint)
        }
    };
    let win = place.window;
    if !(win.x1 <= place.image_width && win.y1 <= place.image_height) {
        return Err(refuse(
            path,
            format!(
                "its window {win} lies outside its {}x{} image",
                place.image_width, place.image_height
            ),
        ));
    }
    if (raster.width, raster.height) != (win.width(), win.height()) {
        return Err(refuse(
            path,
            format!(
                "is {}x{} pixels, but its place is a {}x{} window",
                raster.width,
                raster.height,
                win.width(),
                win.height()
            ),
        ));
    }
    Ok(Piece {
        path: path.to_path_buf(),
        raster,
        place,
        fingerprint,
    })
}

/// The part two windows share, if any.
fn overlap(a: Window, b: Window) -> Option<Window> {
    let w = Window {
        x0: a.x0.max(b.x0),
        x1: a.x1.min(b.x1),
        y0: a.y0.max(b.y0),
        y1: a.y1.min(b.y1),
    };
    (w.x0 < w.x1 && w.y0 < w.y1).then_some(w)
}

/// The first pixels in no window, in reading order, as a rectangle: the first uncovered run of
/// columns of the first row that has one, and the rows below with the same first run.
fn first_gap(windows: &[Window], width: u32, height: u32) -> Option<Window> {
    let gap_in_row = |y: u32| -> Option<(u32, u32)> {
        let mut spans: Vec<(u32, u32)> = windows
            .iter()
            .filter(|w| w.y0 <= y && y < w.y1)
            .map(|w| (w.x0, w.x1))
            .collect();
        spans.sort_unstable();
        let mut x = 0;
        for (x0, x1) in spans {
            if x0 > x {
                return Some((x, x0));
            }
            x = x.max(x1);
        }
        (x < width).then_some((x, width))
    };
    let y0 = (0..height).find(|&y| gap_in_row(y).is_some())?;
    let (x0, x1) = gap_in_row(y0)?;
    let y1 = (y0 + 1..height)
        .find(|&y| gap_in_row(y) != Some((x0, x1)))
        .unwrap_or(height);
    Some(Window { x0, x1, y0, y1 })
}

/// Checks the pieces (read in order) belong together and cover their image exactly once.
fn check_tiling(pieces: &[Piece]) -> Result<()> {
    let first = &pieces[0];
    let (w, h) = (first.place.image_width, first.place.image_height);
    for p in &pieces[1..] {
        if (p.place.image_width, p.place.image_height) != (w, h) {
            return Err(refuse(
                &p.path,
                format!(
                    "is a piece of a {}x{} image, {} of a {w}x{h} image: pieces of different renders",
                    p.place.image_width,
                    p.place.image_height,
                    first.path.display()
                ),
            ));
        }
        if p.fingerprint != first.fingerprint || p.raster.channels != first.raster.channels {
            return Err(refuse(
                &p.path,
                format!(
                    "is a piece of another render than {} (fingerprint {}, not {}: the scene, \
                     the render options or the kind of image differ)",
                    first.path.display(),
                    p.fingerprint,
                    first.fingerprint
                ),
            ));
        }
    }
    for (j, b) in pieces.iter().enumerate() {
        for a in &pieces[..j] {
            if a.path == b.path {
                return Err(refuse(&b.path, "is given twice"));
            }
            if let Some(o) = overlap(a.place.window, b.place.window) {
                return Err(refuse(
                    &b.path,
                    format!(
                        "overlaps {} (columns {}..{}, rows {}..{}): each pixel must come from one piece",
                        a.path.display(),
                        o.x0,
                        o.x1,
                        o.y0,
                        o.y1
                    ),
                ));
            }
        }
    }
    let windows: Vec<Window> = pieces.iter().map(|p| p.place.window).collect();
    if let Some(g) = first_gap(&windows, w, h) {
        return Err(Error::Other(format!(
            "no piece covers columns {}..{} of rows {}..{} of the {w}x{h} image: a piece is \
             missing (pieces given: {})",
            g.x0,
            g.x1,
            g.y0,
            g.y1,
            pieces.len()
        )));
    }
    Ok(())
}

/// Copies each piece's samples into the full image.
fn assemble(pieces: &[Piece]) -> Result<Raster> {
    let first = &pieces[0];
    let (w, h, c) = (
        first.place.image_width as usize,
        first.place.image_height as usize,
        first.raster.channels as usize,
    );
    let n = w * h * c;
    let too_big = || {
        Error::Limit(format!(
            "the merged {w}x{h} image needs more memory than can be allocated"
        ))
    };
    fn place_rows<T: Copy>(full: &mut [T], part: &[T], win: Window, w: usize, c: usize) {
        let row = win.width() as usize * c;
        for (r, line) in part.chunks_exact(row).enumerate() {
            let start = ((win.y0 as usize + r) * w + win.x0 as usize) * c;
            full[start..start + row].copy_from_slice(line);
        }
    }
    let samples = match &first.raster.samples {
        Samples::U8(_) => {
            let mut full: Vec<u8> = Vec::new();
            full.try_reserve_exact(n).map_err(|_| too_big())?;
            full.resize(n, 0);
            for p in pieces {
                let Samples::U8(part) = &p.raster.samples else {
                    unreachable!("one format, one kind of sample")
                };
                place_rows(&mut full, part, p.place.window, w, c);
            }
            Samples::U8(full)
        }
        Samples::F32(_) => {
            let mut full: Vec<f32> = Vec::new();
            full.try_reserve_exact(n).map_err(|_| too_big())?;
            full.resize(n, 0.0);
            for p in pieces {
                let Samples::F32(part) = &p.raster.samples else {
                    unreachable!("one format, one kind of sample")
                };
                place_rows(&mut full, part, p.place.window, w, c);
            }
            Samples::F32(full)
        }
    };
    Ok(Raster {
        width: w as u32,
        height: h as u32,
        channels: c as u32,
        samples,
    })
}

/// Merges `pieces` into `out`; nothing is written unless every check passes.
pub fn merge(out: &Path, pieces: &[PathBuf]) -> Result<()> {
    let format = Format::for_path(out)?;
    if pieces.is_empty() {
        return Err(Error::Usage(
            "expected pieces to merge: whitted merge OUT PIECE...".to_string(),
        ));
    }
    output::check_creatable(out, "write image")?;
    let pieces: Vec<Piece> = pieces
        .iter()
        .map(|p| read_piece(p, format, out))
        .collect::<Result<_>>()?;
    check_tiling(&pieces)?;
    let whole = assemble(&pieces)?;
    let place = Place::whole(whole.width, whole.height);
    let bytes = output::encode_raster(&whole, format, &place, Some(&pieces[0].fingerprint))?;
    piece::remove_stale_sidecar(out)?;
    output::write_atomic(out, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn win(x0: u32, x1: u32, y0: u32, y1: u32) -> Window {
        Window { x0, x1, y0, y1 }
    }

    #[test]
    fn the_first_gap_is_found_in_reading_order() {
        let full = [win(0, 10, 0, 4), win(0, 10, 4, 8)];
        assert_eq!(first_gap(&full, 10, 8), None);
        assert_eq!(first_gap(&full[..1], 10, 8), Some(win(0, 10, 4, 8)));
        let grid = [win(0, 5, 0, 8), win(7, 10, 0, 8)];
        assert_eq!(first_gap(&grid, 10, 8), Some(win(5, 7, 0, 8)));
        assert_eq!(first_gap(&[], 3, 2), Some(win(0, 3, 0, 2)));
    }

    #[test]
    fn windows_overlap_only_when_they_share_a_pixel() {
        assert_eq!(overlap(win(0, 5, 0, 5), win(5, 9, 0, 5)), None);
        assert_eq!(
            overlap(win(0, 5, 0, 5), win(4, 9, 3, 9)),
            Some(win(4, 5, 3, 5))
        );
    }
}
