//! File input shared by the scene parser (`parse.rs`) and the OBJ loader (`obj.rs`): reading a
//! whole file safely (regular files only, no abort on a huge one) and checking that it is UTF-8
//! text, naming the position of the first bad byte as `path:line:col`. Both parsers start here.
//!
//! ```text
//! path --read_file--> bytes --decode_text--> &str --> parse.rs / obj.rs
//! ```
//!
//! A big file (a mesh of millions of triangles) is read and checked in parallel pieces on
//! rayon's threads: copying it out of the page cache and checking its UTF-8 would otherwise be
//! a serial phase of every render of it.

use std::path::Path;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::fill::try_filled;

/// Files of at least this many bytes are read in pieces of this size, in parallel. Small enough
/// that the course's 1.3 MB bunny is read in pieces: read whole, it was a serial 0.7 ms of every
/// parse (0.46 ms at 2 threads in pieces; 20 runs each, medians).
const PIECE_BYTES: usize = 256 << 10;

/// Reads a whole input file. Only regular files are read (a device such as `/dev/zero` would
/// never end), and a file too large for memory is an error, not an abort.
pub(crate) fn read_file(path: &Path, action: &'static str) -> Result<Vec<u8>> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, action, e))?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a folder"
        } else {
            "not a regular file"
        };
        return Err(Error::io(
            path,
            action,
            std::io::Error::other(format!("it is {kind}")),
        ));
    }
    if let Ok(len) = usize::try_from(meta.len())
        && len >= PIECE_BYTES
        && let Some(bytes) = read_in_pieces(path, len)
    {
        return Ok(bytes);
    }
    // std::fs::read reserves the file's size with try_reserve: no abort on a huge file.
    std::fs::read(path).map_err(|e| Error::io(path, action, e))
}

/// Reads the `len` bytes of the file at `path` in parallel pieces; `None` if that fails in any
/// way (the file changed size, no memory, ...): the caller then reads it the plain way, which
/// reports the error if there is one.
#[cfg(unix)]
fn read_in_pieces(path: &Path, len: usize) -> Option<Vec<u8>> {
    use std::os::unix::fs::FileExt;
    let file = std::fs::File::open(path).ok()?;
    // Zeroed in parallel too: the pages of a fresh buffer are touched by the threads that read
    // into them.
    let mut bytes = try_filled(len, 0u8)?;
    bytes
        .par_chunks_mut(PIECE_BYTES)
        .enumerate()
        .try_for_each(|(i, piece)| file.read_exact_at(piece, (i * PIECE_BYTES) as u64))
        .ok()?;
    // The file grew while it was read: read it again the plain way.
    match file.read_at(&mut [0u8], len as u64) {
        Ok(0) => Some(bytes),
        _ => None,
    }
}

#[cfg(not(unix))]
fn read_in_pieces(_path: &Path, _len: usize) -> Option<Vec<u8>> {
    None
}

/// Checks that `bytes` are UTF-8 text, naming the first offending byte's position otherwise.
pub(crate) fn decode_text<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str> {
    match std::str::from_utf8(bytes) {
        Ok(text) => Ok(text),
        Err(e) => {
            let good = &bytes[..e.valid_up_to()];
            let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
            let line_start = good.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
            let col = String::from_utf8_lossy(&good[line_start..]).chars().count() + 1;
            Err(Error::parse(
                path,
                line,
                col,
                format!(
                    "expected UTF-8 text, found byte 0x{:02x}",
                    bytes[e.valid_up_to()]
                ),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_big_file_read_in_pieces_is_the_file() {
        let path = std::env::temp_dir().join(format!("whitted-input-{}.bin", std::process::id()));
        let bytes: Vec<u8> = (0..2 * PIECE_BYTES + 12345)
            .map(|i| (i * 7 % 251) as u8)
            .collect();
        std::fs::write(&path, &bytes).unwrap();
        let read = read_file(&path, "read");
        let _ = std::fs::remove_file(&path);
        assert!(read.unwrap() == bytes);
    }
}
