//! A piece of a render: an image of a window of the full image (`--crop`, `--tile`), with what
//! `whitted merge` needs to put it back: its place in the full image and the fingerprint of the
//! render it belongs to. An EXR records both in itself (data window, display window and the
//! `whittedFingerprint` attribute); a piece in any other format gets a sidecar beside it, named
//! after it with `.piece` appended (`tile-03.png` -> `tile-03.png.piece`), four lines of text:
//!
//! ```text
//! whitted-piece 1
//! fingerprint 5d1c0e9a7b3f2468
//! image 1024 768
//! window 0 1024 144 192
//! ```
//!
//! (`image W H` is the full image's size, `window X0 X1 Y0 Y1` the piece's columns and rows,
//! half-open, as `--crop` takes them.) The fingerprint is a 64-bit FNV-1a hash of the version of
//! whitted, the parsed scene (so meshes it loads count too), every render option that decides
//! pixels (size, shading, tracer, sampling; not threads, limits or the crop) and the image kind
//! (colour, depth with its near and far, normals): pieces of different renders never merge.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::{ImageKind, Place};
use crate::error::{Error, Result};
use crate::options::{RenderOptions, Window};
use crate::scene::Scene;

/// The first line of every sidecar.
const SIDECAR_MAGIC: &str = "whitted-piece 1";

/// What a piece records about itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Piece {
    /// 16 hexadecimal digits.
    pub fingerprint: String,
    pub place: Place,
}

/// The sidecar of the image at `path`: `path` with `.piece` appended.
pub fn sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".piece");
    PathBuf::from(name)
}

/// The sidecar's text.
pub fn sidecar_text(piece: &Piece) -> String {
    let p = &piece.place;
    format!(
        "{SIDECAR_MAGIC}\nfingerprint {}\nimage {} {}\nwindow {}\n",
        piece.fingerprint, p.image_width, p.image_height, p.window
    )
}

/// Parses a sidecar's text; the error says what is wrong with it.
pub fn parse_sidecar(text: &str) -> std::result::Result<Piece, String> {
    let bad = |what: &str| format!("expected {what}");
    let mut lines = text.lines();
    if lines.next() != Some(SIDECAR_MAGIC) {
        return Err(bad(&format!("`{SIDECAR_MAGIC}` on its first line")));
    }
    let mut field = |key: &str, count: usize| -> std::result::Result<Vec<String>, String> {
        let line = lines.next().unwrap_or("");
        let mut words = line.split_whitespace();
        let values: Vec<String> = words.by_ref().skip(1).map(str::to_string).collect();
        if !line.starts_with(&format!("{key} ")) || values.len() != count {
            return Err(bad(&format!(
                "a line `{key}` with {count} values, found `{line}`"
            )));
        }
        Ok(values)
    };
    let fingerprint = field("fingerprint", 1)?.remove(0);
    let numbers = |v: Vec<String>| -> std::result::Result<Vec<u32>, String> {
        v.iter()
            .map(|s| {
                s.parse()
                    .map_err(|_| bad(&format!("a whole number, found `{s}`")))
            })
            .collect()
    };
    let image = numbers(field("image", 2)?)?;
    let w = numbers(field("window", 4)?)?;
    let window = Window {
        x0: w[0],
        x1: w[1],
        y0: w[2],
        y1: w[3],
    };
    if !(window.x0 < window.x1 && window.y0 < window.y1) {
        return Err(format!("window {window} is empty"));
    }
    Ok(Piece {
        fingerprint,
        place: Place {
            window,
            image_width: image[0],
            image_height: image[1],
        },
    })
}

/// Reads the sidecar of the image at `path`; the error says what is wrong (the caller names
/// the piece).
pub fn read_sidecar(path: &Path) -> std::result::Result<Piece, String> {
    let side = sidecar_path(path);
    let text = std::fs::read_to_string(&side).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            format!("has no sidecar {} to say where it belongs", side.display())
        } else {
            format!("cannot read its sidecar {}: {e}", side.display())
        }
    })?;
    parse_sidecar(&text).map_err(|e| format!("sidecar {}: {e}", side.display()))
}

/// Removes the sidecar an earlier piece left under the name of a whole image written now.
pub fn remove_stale_sidecar(path: &Path) -> Result<()> {
    let side = sidecar_path(path);
    match std::fs::remove_file(&side) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(Error::io(&side, "remove stale sidecar", e))
        }
        _ => Ok(()),
    }
}

/// 64-bit FNV-1a, fed through `fmt::Write` so a scene is hashed as it is formatted.
#[derive(Clone, Copy)]
struct Fnv1a(u64);

impl Fnv1a {
    fn new() -> Fnv1a {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl std::fmt::Write for Fnv1a {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        for b in s.bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
        Ok(())
    }
}

/// The hash of a render (whitted's version, the scene, the options that decide pixels), from
/// which each of its images' fingerprints follows. It is computed when first asked for: hashing
/// a big scene takes a while (about 0.9 s for a million triangles, on one thread), and only a
/// piece or an EXR file records a fingerprint.
pub struct RenderFingerprint<'a> {
    scene: &'a Scene,
    opts: &'a RenderOptions,
    hash: std::cell::OnceCell<Fnv1a>,
}

impl<'a> RenderFingerprint<'a> {
    /// The fingerprint of `scene` rendered with `opts` (not hashed yet).
    pub fn new(scene: &'a Scene, opts: &'a RenderOptions) -> RenderFingerprint<'a> {
        RenderFingerprint {
            scene,
            opts,
            hash: std::cell::OnceCell::new(),
        }
    }

    /// Hashes the scene and the options.
    fn hash(&self) -> Fnv1a {
        *self.hash.get_or_init(|| hash_render(self.scene, self.opts))
    }

    /// The fingerprint of the render's `kind` image: 16 hex digits.
    pub fn of(&self, kind: ImageKind) -> String {
        let mut h = self.hash();
        let _ = write!(h, "{kind:?}");
        format!("{:016x}", h.0)
    }
}

/// The hash of `scene` rendered with `opts`.
fn hash_render(scene: &Scene, opts: &RenderOptions) -> Fnv1a {
    {
        // What does not decide pixels is left out: the crop, threads, limits, which images
        // the frame keeps besides colour.
        let pixels = RenderOptions {
            crop: None,
            threads: 0,
            max_pixels: 0,
            max_bounces: 0,
            max_samples: 0,
            max_filter_radius: 0,
            depth_normal: false,
            keep_samples: false,
            keep_pixels: true,
            ..opts.clone()
        };
        let mut h = Fnv1a::new();
        let _ = write!(
            h,
            "whitted {}\n{scene:?}\n{pixels:?}\n",
            env!("CARGO_PKG_VERSION")
        );
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sidecar_reads_back() {
        let piece = Piece {
            fingerprint: "0123456789abcdef".into(),
            place: Place {
                window: Window {
                    x0: 0,
                    x1: 1024,
                    y0: 144,
                    y1: 192,
                },
                image_width: 1024,
                image_height: 768,
            },
        };
        let text = sidecar_text(&piece);
        assert_eq!(
            text,
            "whitted-piece 1\nfingerprint 0123456789abcdef\nimage 1024 768\nwindow 0 1024 144 192\n"
        );
        assert_eq!(parse_sidecar(&text), Ok(piece));
        assert!(parse_sidecar("whitted-piece 1\nfingerprint x\nimage 1 2\n").is_err());
        assert!(parse_sidecar("hello").is_err());
    }

    #[test]
    fn fnv1a_matches_its_published_value() {
        let mut h = Fnv1a::new();
        let _ = h.write_str("a");
        assert_eq!(h.0, 0xaf63_dc4c_8601_ec8c);
    }
}
