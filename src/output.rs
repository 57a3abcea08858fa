//! From a [`Frame`] to files: colour, depth and normal images as 8-bit RGB, written as PNG, TGA
//! or PPM by extension. Conversions follow the course: a channel is `int(c * 255)` clamped to
//! `[0, 255]` (truncation, not rounding); depth is grey, white at `near` and black at `far` and
//! beyond (and where nothing was hit); normals are `abs(n)` on black. Every file is written to a
//! temporary file in the target folder and renamed into place, so a failed write never leaves a
//! half-written image and an existing file stays intact until the new one is complete.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::math::Vec3;

/// An 8-bit RGB image, rows top to bottom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

/// The course's colour-to-byte rule: truncate `c * 255`, clamp to `[0, 255]` (NaN gives 0).
#[inline]
pub fn to_byte(c: f32) -> u8 {
    (c * 255.0).clamp(0.0, 255.0) as u8
}

fn from_pixels(frame: &Frame, f: impl Fn(usize) -> Vec3) -> Rgb8 {
    let n = frame.width as usize * frame.height as usize;
    let mut data = Vec::with_capacity(n * 3);
    for i in 0..n {
        let c = f(i);
        data.extend_from_slice(&[to_byte(c.x), to_byte(c.y), to_byte(c.z)]);
    }
    Rgb8 {
        width: frame.width,
        height: frame.height,
        data,
    }
}

/// The colour image.
pub fn color_image(frame: &Frame) -> Rgb8 {
    from_pixels(frame, |i| frame.color[i])
}

/// The depth image: grey `(far - t) / (far - near)` clamped to `[0, 1]`; black where nothing was
/// hit.
pub fn depth_image(frame: &Frame, near: f32, far: f32) -> Rgb8 {
    from_pixels(frame, |i| {
        let t = frame.depth[i];
        if t.is_finite() {
            Vec3::splat(((far - t) / (far - near)).clamp(0.0, 1.0))
        } else {
            Vec3::ZERO
        }
    })
}

/// The normal image: `abs(normal)` as RGB, black where nothing was hit.
pub fn normal_image(frame: &Frame) -> Rgb8 {
    from_pixels(frame, |i| frame.normal[i].abs())
}

/// The image formats we write, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Tga,
    Ppm,
}

impl Format {
    /// The format for `path`'s extension (case-insensitive).
    pub fn for_path(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Format::Png),
            Some("tga") => Ok(Format::Tga),
            Some("ppm") => Ok(Format::Ppm),
            _ => Err(Error::Usage(format!(
                "{}: expected an output file ending in .png, .tga or .ppm",
                path.display()
            ))),
        }
    }
}

/// Encodes `img` in `format`.
pub fn encode(img: &Rgb8, format: Format) -> Result<Vec<u8>> {
    let (w, h) = (img.width as usize, img.height as usize);
    match format {
        Format::Ppm => {
            let mut out = format!("P6\n{w} {h}\n255\n").into_bytes();
            out.extend_from_slice(&img.data);
            Ok(out)
        }
        Format::Tga => {
            // Uncompressed true-colour, 24 bits, rows stored bottom to top (origin bottom left).
            let mut out = vec![0u8; 18];
            out[2] = 2;
            out[12..14].copy_from_slice(&(w as u16).to_le_bytes());
            out[14..16].copy_from_slice(&(h as u16).to_le_bytes());
            out[16] = 24;
            for row in (0..h).rev() {
                for px in img.data[row * w * 3..(row + 1) * w * 3].chunks_exact(3) {
                    out.extend_from_slice(&[px[2], px[1], px[0]]);
                }
            }
            Ok(out)
        }
        Format::Png => {
            let mut out = Vec::new();
            let encoder = image::codecs::png::PngEncoder::new(&mut out);
            image::ImageEncoder::write_image(
                encoder,
                &img.data,
                img.width,
                img.height,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| Error::Other(format!("cannot encode PNG: {e}")))?;
            Ok(out)
        }
    }
}

/// Checks, before a render starts, that `path` has a known extension, fits the format, and lies
/// in a folder we can create files in.
pub fn check_writable(path: &Path, width: u32, height: u32) -> Result<()> {
    let format = Format::for_path(path)?;
    if format == Format::Tga && (width > u16::MAX as u32 || height > u16::MAX as u32) {
        return Err(Error::Usage(format!(
            "{}: TGA images are at most 65535 pixels wide and high",
            path.display()
        )));
    }
    check_creatable(path, "write image")
}

/// Checks that a file can be created beside `path` (so a later atomic write of it can
/// succeed, and `path` is not a folder); `action` names the write in the error ("write
/// image", "write ray tree").
pub fn check_creatable(path: &Path, action: &'static str) -> Result<()> {
    if path.is_dir() {
        return Err(Error::io(
            path,
            action,
            std::io::Error::other("it is a folder"),
        ));
    }
    let tmp = temp_path(path);
    let file = fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(|e| Error::io(path, action, e))?;
    drop(file);
    fs::remove_file(&tmp).map_err(|e| Error::io(&tmp, "remove temporary file", e))?;
    Ok(())
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "image".into(), |n| n.to_string_lossy().into_owned());
    let tmp = format!(".{name}.{}.tmp", std::process::id());
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

/// Writes `img` to `path` atomically: a temporary file beside it, flushed, then renamed.
pub fn write_image(img: &Rgb8, path: &Path) -> Result<()> {
    let bytes = encode(img, Format::for_path(path)?)?;
    write_atomic(path, &bytes)
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_as(path, bytes, "write image")
}

/// [`write_atomic`], naming the write `action` in errors ("write ray tree").
pub fn write_atomic_as(path: &Path, bytes: &[u8], action: &'static str) -> Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut file = fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = fs::remove_file(&tmp);
        return Err(Error::io(path, action, e));
    }
    Ok(())
}

/// Reads a PNG (8 or 16 bits per channel, RGB or RGBA or grey) as 8-bit RGB; 16-bit values are
/// rounded to the nearest 8-bit value. Used by tests comparing against reference images.
pub fn read_png(path: &Path) -> Result<Rgb8> {
    let img = image::open(path).map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
    let rgb = img.to_rgb16();
    let (width, height) = rgb.dimensions();
    let data = rgb
        .into_raw()
        .into_iter()
        .map(|v| ((v as u32 * 255 + 32767) / 65535) as u8)
        .collect();
    Ok(Rgb8 {
        width,
        height,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_truncate_like_the_course() {
        assert_eq!(to_byte(0.5), 127);
        assert_eq!(to_byte(0.1), 25);
        assert_eq!(to_byte(1.0), 255);
        assert_eq!(to_byte(7.0), 255);
        assert_eq!(to_byte(-1.0), 0);
        assert_eq!(to_byte(f32::NAN), 0);
    }

    #[test]
    fn tga_is_bottom_up_bgr() {
        let img = Rgb8 {
            width: 1,
            height: 2,
            data: vec![1, 2, 3, 4, 5, 6],
        };
        let out = encode(&img, Format::Tga).unwrap();
        assert_eq!(&out[18..], &[6, 5, 4, 3, 2, 1]);
    }
}
