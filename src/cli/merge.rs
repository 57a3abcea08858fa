//! `whitted merge OUT PIECE...`: the command line of [`crate::merge::merge`], and its help.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The usage line of `whitted merge`, for `whitted --help`.
pub const USAGE: &str =
    "    whitted merge OUT PIECE...   assemble the pieces of a render into OUT\n";

/// The text of `whitted merge --help`.
pub fn help() -> String {
    format!(
        "whitted merge: put the pieces of a render back into the full image\n\n\
         USAGE:\n{USAGE}\n\
         Each piece records its place in the full image and its render's fingerprint: an EXR\n\
         in its data window and an attribute, other formats in a sidecar PIECE.piece. The merge\n\
         checks that every piece is readable, in OUT's format and of one render, and that\n\
         together they cover the image exactly once; then it writes OUT atomically, with the\n\
         bytes a one-go render writes. Any refusal is one line naming the piece, exit code 2,\n\
         and nothing is written. See docs/render-farm.md.\n"
    )
}

/// `whitted merge OUT PIECE...`.
pub fn run(args: &[String]) -> Result<()> {
    match args {
        [flag] if matches!(flag.as_str(), "-h" | "--help" | "-help") => {
            print!("{}", help());
            Ok(())
        }
        [out, pieces @ ..] if !out.starts_with('-') => {
            let pieces: Vec<PathBuf> = pieces.iter().map(PathBuf::from).collect();
            crate::merge::merge(Path::new(out), &pieces)
        }
        _ => Err(Error::Usage(
            "expected an output and its pieces: whitted merge OUT PIECE...".to_string(),
        )),
    }
}
