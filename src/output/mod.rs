//! From a [`Frame`] to files: colour, depth and normal images in the format the output file's
//! extension names, 8-bit (PNG, TGA, PPM: `rgb8.rs`) or floating point (OpenEXR, PFM, Radiance
//! HDR: `float.rs`), and a render's pieces ([`piece`]: the place of a cropped image in the full
//! one, and the fingerprint of the render it belongs to). Every file is written to a temporary
//! file in the target folder and renamed into place, so a failed write never leaves a
//! half-written image and an existing file stays intact until the new one is complete. An
//! 8-bit image may instead be written while the render runs ([`StreamedImage`]): a TGA or PPM
//! into an unnamed file that gets the temporary name, then the real one, the same way; a PNG
//! compressed band by band, its bytes then written as any file's.
//!
//! ```text
//! Frame --frame_raster(kind, format)--> Raster (the samples a file stores) --encode--> bytes
//! bytes --decode--> Raster (merge.rs assembles pieces' rasters, then encodes the whole)
//! ```
//!
//! What the float formats hold, by image: colour is the linear colour as rendered (the 8-bit
//! images truncate `c * 255` of the same values); depth is the distance along the primary ray in
//! world units (EXR channel `Z`, PFM one channel; `+inf` where nothing was hit; HDR, which has
//! neither infinity nor negative values, holds it in all three channels with 0 there); normals
//! are the signed unit normal x, y, z (EXR channels R, G, B; zero where nothing was hit; HDR holds
//! `abs(n)` as the 8-bit image does). `--depth NEAR FAR` only maps depth to grey in 8-bit images.

mod float;
pub mod piece;
mod png_rows;
mod rgb8;
mod streamed;

use std::fs;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::options::Window;
pub use float::{FINGERPRINT_ATTRIBUTE, from_rgbe, to_rgbe};
pub use rgb8::{Rgb8, color_image, depth_image, normal_image, read_png, to_byte};
pub use streamed::StreamedImage;

/// The image formats we write, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Png,
    Tga,
    Ppm,
    Exr,
    Pfm,
    Hdr,
}

/// What a format stores per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredSamples {
    /// 8-bit RGB.
    Rgb8,
    /// 32-bit floats, one or three channels.
    Float,
    /// RGBE bytes.
    Rgbe,
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
            Some("exr") => Ok(Format::Exr),
            Some("pfm") => Ok(Format::Pfm),
            Some("hdr") => Ok(Format::Hdr),
            _ => Err(Error::Usage(format!(
                "{}: expected an output file ending in .png, .tga, .ppm, .exr, .pfm or .hdr",
                path.display()
            ))),
        }
    }

    /// The extension naming the format.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Png => "png",
            Format::Tga => "tga",
            Format::Ppm => "ppm",
            Format::Exr => "exr",
            Format::Pfm => "pfm",
            Format::Hdr => "hdr",
        }
    }

    /// What the format stores per pixel.
    pub fn samples(self) -> StoredSamples {
        match self {
            Format::Png | Format::Tga | Format::Ppm => StoredSamples::Rgb8,
            Format::Exr | Format::Pfm => StoredSamples::Float,
            Format::Hdr => StoredSamples::Rgbe,
        }
    }

    /// True when the file itself records a piece's place and render (EXR's data window and
    /// attribute); the other formats get a sidecar file ([`piece`]).
    pub fn records_its_place(self) -> bool {
        self == Format::Exr
    }
}

/// Which image of a frame a file holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ImageKind {
    Color,
    /// 8-bit images map depth `near..far` to white..black.
    Depth {
        near: f32,
        far: f32,
    },
    Normals,
}

/// Where an image lies in the full image of its render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    pub window: Window,
    pub image_width: u32,
    pub image_height: u32,
}

impl Place {
    /// The whole of a `width` x `height` image.
    pub fn whole(width: u32, height: u32) -> Place {
        Place {
            window: Window::full(width, height),
            image_width: width,
            image_height: height,
        }
    }

    /// A frame's place.
    pub fn of(frame: &Frame) -> Place {
        Place {
            window: frame.window,
            image_width: frame.image_width,
            image_height: frame.image_height,
        }
    }

    /// True when the place is all of the image.
    pub fn is_whole(&self) -> bool {
        self.window == Window::full(self.image_width, self.image_height)
    }
}

/// The samples an image file stores, rows top to bottom, channels interleaved: what is read
/// back from a file is exactly what was written, so pieces merge without loss.
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    pub width: u32,
    pub height: u32,
    /// 3 for RGB, 1 for float depth, 4 for RGBE.
    pub channels: u32,
    pub samples: Samples,
}

/// Stored samples: bytes (8-bit RGB, RGBE) or 32-bit floats.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    U8(Vec<u8>),
    F32(Vec<f32>),
}

impl Raster {
    /// An 8-bit RGB raster: `img`'s bytes, moved, not copied.
    pub fn from_rgb8(img: Rgb8) -> Raster {
        Raster {
            width: img.width,
            height: img.height,
            channels: 3,
            samples: Samples::U8(img.data),
        }
    }

    /// A float raster whose pixel `i` (row-major) `f` fills.
    fn from_pixels(
        width: u32,
        height: u32,
        channels: u32,
        f: impl Fn(usize, &mut [f32]),
    ) -> Raster {
        let mut values = vec![0.0f32; width as usize * height as usize * channels as usize];
        for (i, px) in values.chunks_exact_mut(channels as usize).enumerate() {
            f(i, px);
        }
        Raster {
            width,
            height,
            channels,
            samples: Samples::F32(values),
        }
    }
}

/// An RGBE raster of the colours `f` gives pixel `i`.
fn rgbe_raster(width: u32, height: u32, f: impl Fn(usize) -> [f32; 3]) -> Raster {
    let n = width as usize * height as usize;
    Raster {
        width,
        height,
        channels: 4,
        samples: Samples::U8((0..n).flat_map(|i| to_rgbe(f(i))).collect()),
    }
}

/// The samples `format` stores for the `kind` image of `frame`.
pub fn frame_raster(frame: &Frame, kind: ImageKind, format: Format) -> Raster {
    let (w, h) = (frame.width, frame.height);
    match format.samples() {
        StoredSamples::Rgb8 => Raster::from_rgb8(match kind {
            ImageKind::Color => color_image(frame),
            ImageKind::Depth { near, far } => depth_image(frame, near, far),
            ImageKind::Normals => normal_image(frame),
        }),
        StoredSamples::Float => match kind {
            ImageKind::Color => Raster::from_pixels(w, h, 3, |i, px| {
                px.copy_from_slice(&frame.color[i].to_array());
            }),
            ImageKind::Depth { .. } => Raster::from_pixels(w, h, 1, |i, px| px[0] = frame.depth[i]),
            ImageKind::Normals => Raster::from_pixels(w, h, 3, |i, px| {
                px.copy_from_slice(&frame.normal[i].to_array());
            }),
        },
        StoredSamples::Rgbe => match kind {
            ImageKind::Color => rgbe_raster(w, h, |i| frame.color[i].to_array()),
            ImageKind::Depth { .. } => rgbe_raster(w, h, |i| {
                let t = frame.depth[i];
                [if t.is_finite() { t } else { 0.0 }; 3]
            }),
            ImageKind::Normals => rgbe_raster(w, h, |i| frame.normal[i].abs().to_array()),
        },
    }
}

/// Encodes `raster` as `format`; an EXR records `place` and `fingerprint` in itself.
pub fn encode_raster(
    raster: &Raster,
    format: Format,
    place: &Place,
    fingerprint: Option<&str>,
) -> Result<Vec<u8>> {
    match format {
        Format::Png | Format::Tga | Format::Ppm => {
            let Samples::U8(data) = &raster.samples else {
                unreachable!("8-bit formats store bytes");
            };
            rgb8::encode_rgb8(raster.width, raster.height, data, format)
        }
        Format::Exr => float::encode_exr(raster, place, fingerprint),
        Format::Pfm => Ok(float::encode_pfm(raster)),
        Format::Hdr => Ok(float::encode_hdr(raster)),
    }
}

/// What [`decode`] found in a file: its samples and, for EXR, the place and fingerprint it
/// records.
pub struct Decoded {
    pub raster: Raster,
    pub place: Option<Place>,
    pub fingerprint: Option<String>,
}

/// Decodes the bytes of a file in `format` as `whitted` writes it; the error says what is wrong
/// (the caller names the file).
pub fn decode(bytes: &[u8], format: Format) -> std::result::Result<Decoded, String> {
    let plain = |raster| Decoded {
        raster,
        place: None,
        fingerprint: None,
    };
    match format {
        Format::Png | Format::Tga | Format::Ppm => rgb8::decode_rgb8(bytes, format)
            .map(|img| plain(Raster::from_rgb8(img)))
            .ok_or_else(|| {
                format!(
                    "not a readable 8-bit RGB {} image",
                    format.extension().to_ascii_uppercase()
                )
            }),
        Format::Exr => float::decode_exr(bytes).map(|p| Decoded {
            raster: p.raster,
            place: Some(p.place),
            fingerprint: p.fingerprint,
        }),
        Format::Pfm => float::decode_pfm(bytes).map(plain),
        Format::Hdr => float::decode_hdr(bytes).map(plain),
    }
}

/// A file to write: its path and what it holds.
pub type FileBytes = (PathBuf, Content);

/// What a file to write holds.
pub enum Content {
    /// Bytes to write.
    Bytes(Vec<u8>),
    /// An unnamed file already written whole ([`StreamedImage`]).
    Written(fs::File),
}

impl Content {
    fn source(&self) -> Source<'_> {
        match self {
            Content::Bytes(b) => Source::Bytes(b),
            Content::Written(f) => Source::Written(f),
        }
    }
}

/// What [`write_atomic_files`] puts in a file: bytes, or an unnamed file already written.
#[derive(Clone, Copy)]
pub(crate) enum Source<'a> {
    Bytes(&'a [u8]),
    Written(&'a fs::File),
}

/// The files that hold the `kind` image of `frame` at `path`, in the format its extension
/// names: the image, preceded by its sidecar ([`piece`]) when the frame is a piece of a larger
/// image in a format that cannot record its place itself. An EXR records its place and
/// fingerprint in itself. The fingerprint is hashed only for a file that records it.
/// `streamed`, the image written during the render, stands for the image when it holds every
/// row ([`StreamedImage::into_content`]); otherwise the image is encoded from the frame.
pub fn frame_files(
    frame: &Frame,
    kind: ImageKind,
    path: &Path,
    print: &piece::RenderFingerprint<'_>,
    streamed: Option<StreamedImage>,
) -> Result<Vec<FileBytes>> {
    let format = Format::for_path(path)?;
    let place = Place::of(frame);
    let sidecar = !format.records_its_place() && !place.is_whole();
    let fingerprint = (sidecar || format.records_its_place()).then(|| print.of(kind));
    let content = match streamed.and_then(StreamedImage::into_content) {
        Some(content) => content,
        None => {
            let raster = frame_raster(frame, kind, format);
            Content::Bytes(encode_raster(
                &raster,
                format,
                &place,
                fingerprint.as_deref(),
            )?)
        }
    };
    let mut files = Vec::with_capacity(2);
    if let (true, Some(fingerprint)) = (sidecar, fingerprint) {
        let text = piece::sidecar_text(&piece::Piece { fingerprint, place });
        files.push((piece::sidecar_path(path), Content::Bytes(text.into_bytes())));
    }
    files.push((path.to_path_buf(), content));
    Ok(files)
}

/// Writes `files` atomically and in order (`write_atomic_files`): if any cannot be written,
/// none is left. An image written without a sidecar loses the stale sidecar an earlier piece of
/// the same name left.
pub fn write_files(files: &[FileBytes]) -> Result<()> {
    let refs: Vec<(&Path, Source)> = files
        .iter()
        .map(|(p, c)| (p.as_path(), c.source()))
        .collect();
    write_atomic_files(&refs, "write image")?;
    for (path, _) in files {
        let side = piece::sidecar_path(path);
        let is_sidecar = path.to_string_lossy().ends_with(".piece");
        if !is_sidecar && !files.iter().any(|(p, _)| *p == side) {
            piece::remove_stale_sidecar(path)?;
        }
    }
    Ok(())
}

/// Writes the `kind` image of `frame` to `path` ([`frame_files`], [`write_files`]).
pub fn write_frame(
    frame: &Frame,
    kind: ImageKind,
    path: &Path,
    print: &piece::RenderFingerprint<'_>,
) -> Result<()> {
    write_files(&frame_files(frame, kind, path, print, None)?)
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

/// Encodes the 8-bit image `img` (a witness picture, say) as `format`; float formats get its
/// values divided by 255, and an EXR records no render.
pub fn encode(img: &Rgb8, format: Format) -> Result<Vec<u8>> {
    let b = &img.data;
    let raster = match format.samples() {
        // the bytes as they are, not copied into a raster first
        StoredSamples::Rgb8 => return rgb8::encode_rgb8(img.width, img.height, b, format),
        StoredSamples::Float => Raster::from_pixels(img.width, img.height, 3, |i, px| {
            px.copy_from_slice(&[0, 1, 2].map(|c| b[i * 3 + c] as f32 / 255.0));
        }),
        StoredSamples::Rgbe => rgbe_raster(img.width, img.height, |i| {
            [0, 1, 2].map(|c| b[i * 3 + c] as f32 / 255.0)
        }),
    };
    encode_raster(&raster, format, &Place::whole(img.width, img.height), None)
}

/// Writes the 8-bit image `img` to `path` atomically ([`encode`], [`write_atomic`]).
pub fn write_image(img: &Rgb8, path: &Path) -> Result<()> {
    write_atomic(path, &encode(img, Format::for_path(path)?)?)
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_as(path, bytes, "write image")
}

/// [`write_atomic`], naming the write `action` in errors ("write ray tree").
pub fn write_atomic_as(path: &Path, bytes: &[u8], action: &'static str) -> Result<()> {
    write_atomic_files(&[(path, Source::Bytes(bytes))], action)
}

/// Writes several files atomically, in order: every temporary file is written and flushed
/// first (a file already written is flushed and named), then each is renamed into place, so
/// the last file appears only once the others are complete. On failure every temporary file,
/// and every file this call already renamed into place, is removed.
pub(crate) fn write_atomic_files(files: &[(&Path, Source)], action: &'static str) -> Result<()> {
    let temps: Vec<PathBuf> = files.iter().map(|(p, _)| temp_path(p)).collect();
    let mut renamed = 0;
    let result = files
        .iter()
        .zip(&temps)
        .try_for_each(|((path, content), tmp)| match content {
            Source::Bytes(bytes) => {
                let mut file = fs::File::create(tmp).map_err(|e| (*path, e))?;
                file.write_all(bytes).map_err(|e| (*path, e))?;
                file.sync_all().map_err(|e| (*path, e))
            }
            Source::Written(file) => {
                file.sync_all().map_err(|e| (*path, e))?;
                if streamed::link_unnamed(file, tmp).is_ok() {
                    return Ok(());
                }
                // Not linked (no /proc in some sandboxes, or the name taken): copy the bytes.
                let mut named = fs::File::create(tmp).map_err(|e| (*path, e))?;
                let mut from: &fs::File = file;
                from.seek(SeekFrom::Start(0)).map_err(|e| (*path, e))?;
                std::io::copy(&mut from, &mut named).map_err(|e| (*path, e))?;
                named.sync_all().map_err(|e| (*path, e))
            }
        });
    let result = result.and_then(|()| {
        files.iter().zip(&temps).try_for_each(|((path, _), tmp)| {
            fs::rename(tmp, path).map_err(|e| (*path, e))?;
            renamed += 1;
            Ok(())
        })
    });
    if let Err((path, e)) = result {
        for (i, tmp) in temps.iter().enumerate() {
            let _ = fs::remove_file(if i < renamed { files[i].0 } else { tmp });
        }
        return Err(Error::io(path, action, e));
    }
    Ok(())
}
