//! File input shared by the scene parser (`parse.rs`) and the OBJ loader (`obj.rs`): reading a
//! whole file safely (regular files only, no abort on a huge one) and checking that it is UTF-8
//! text, naming the position of the first bad byte as `path:line:col`. Both parsers start here.
//!
//! ```text
//! path --read_file--> bytes --decode_text--> &str --> parse.rs / obj.rs
//! ```

use std::path::Path;

use crate::error::{Error, Result};

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
    // std::fs::read reserves the file's size with try_reserve: no abort on a huge file.
    std::fs::read(path).map_err(|e| Error::io(path, action, e))
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
