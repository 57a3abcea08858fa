//! The 8-bit images: a [`Frame`]'s colour, depth and normal images as 8-bit RGB, and their PNG,
//! TGA and PPM encodings and decodings. Conversions follow the course: a channel is
//! `int(c * 255)` clamped to `[0, 255]` (truncation, not rounding); depth is grey, white at
//! `near` and black at `far` and beyond (and where nothing was hit); normals are `abs(n)` on
//! black.

use std::path::Path;

use rayon::prelude::*;

use super::{Format, ImageKind};
use crate::error::{Error, Result};
use crate::fill::filled;
use crate::frame::Frame;
use crate::math::Vec3;
use crate::simd::{LANES, load_partial, unit_to_bytes};

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

/// Pixels converted per parallel task.
const PIXELS_PER_TASK: usize = 1 << 14;

/// Pixels converted together: 24 channels, three vectors of [`LANES`].
const GROUP: usize = LANES;

/// The pixels an 8-bit image is made from: a whole frame's, or some of its rows'. Depth and
/// normals may be empty when the image is the colour one.
#[derive(Clone, Copy)]
pub(super) struct Pixels<'a> {
    pub color: &'a [Vec3],
    pub depth: &'a [f32],
    pub normal: &'a [Vec3],
}

impl Pixels<'_> {
    fn of(frame: &Frame) -> Pixels<'_> {
        Pixels {
            color: &frame.color,
            depth: &frame.depth,
            normal: &frame.normal,
        }
    }
}

/// Writes the RGB bytes of pixels `first..first + out.len() / 3` of the `kind` image of `px`
/// into `out`. Every conversion of a frame to 8 bits, whole or a few rows at a time, is this.
pub(super) fn kind_to_bytes(kind: ImageKind, px: Pixels<'_>, first: usize, out: &mut [u8]) {
    match kind {
        ImageKind::Color => to_bytes(|i| px.color[i], first, out),
        ImageKind::Depth { near, far } => to_bytes(
            |i| {
                let t = px.depth[i];
                if t.is_finite() {
                    Vec3::splat(((far - t) / (far - near)).clamp(0.0, 1.0))
                } else {
                    Vec3::ZERO
                }
            },
            first,
            out,
        ),
        ImageKind::Normals => to_bytes(|i| px.normal[i].abs(), first, out),
    }
}

/// The RGB bytes of `f(first..)` into `bytes`: groups of [`GROUP`] pixels gathered, then
/// converted [`LANES`] channels at a time; the last few one by one.
fn to_bytes(f: impl Fn(usize) -> Vec3, first: usize, bytes: &mut [u8]) {
    let done = first + bytes.len() / 3 / GROUP * GROUP;
    let mut groups = bytes.chunks_exact_mut(3 * GROUP);
    for (g, out) in (&mut groups).enumerate() {
        let mut channels = [0.0f32; 3 * GROUP];
        for (k, ch) in channels.chunks_exact_mut(3).enumerate() {
            ch.copy_from_slice(&f(first + g * GROUP + k).to_array());
        }
        for (o, c) in out
            .chunks_exact_mut(LANES)
            .zip(channels.chunks_exact(LANES))
        {
            o.copy_from_slice(&unit_to_bytes(load_partial(c, 0.0)));
        }
    }
    for (j, px) in groups.into_remainder().chunks_exact_mut(3).enumerate() {
        let c = f(done + j);
        px.copy_from_slice(&[to_byte(c.x), to_byte(c.y), to_byte(c.z)]);
    }
}

/// The `kind` 8-bit image of `frame`, converted in parallel (a serial phase of every render
/// otherwise: ~10 ms a megapixel).
pub(super) fn frame_image(frame: &Frame, kind: ImageKind) -> Rgb8 {
    let n = frame.width as usize * frame.height as usize;
    let mut data = filled(n * 3, 0u8);
    let px = Pixels::of(frame);
    data.par_chunks_mut(3 * PIXELS_PER_TASK)
        .enumerate()
        .for_each(|(task, bytes)| kind_to_bytes(kind, px, task * PIXELS_PER_TASK, bytes));
    Rgb8 {
        width: frame.width,
        height: frame.height,
        data,
    }
}

/// The colour image.
pub fn color_image(frame: &Frame) -> Rgb8 {
    frame_image(frame, ImageKind::Color)
}

/// The depth image: grey `(far - t) / (far - near)` clamped to `[0, 1]`; black where nothing was
/// hit.
pub fn depth_image(frame: &Frame, near: f32, far: f32) -> Rgb8 {
    frame_image(frame, ImageKind::Depth { near, far })
}

/// The normal image: `abs(normal)` as RGB, black where nothing was hit.
pub fn normal_image(frame: &Frame) -> Rgb8 {
    frame_image(frame, ImageKind::Normals)
}

/// The bytes before the pixels of a `w` x `h` image in `format`, for the formats that store
/// rows uncompressed at fixed places (TGA, PPM); `None` for the others.
pub(super) fn fixed_header(format: Format, w: u32, h: u32) -> Option<Vec<u8>> {
    match format {
        Format::Ppm => Some(format!("P6\n{w} {h}\n255\n").into_bytes()),
        Format::Tga => {
            // Uncompressed true-colour, 24 bits, rows stored bottom to top (origin bottom left).
            let mut header = vec![0u8; 18];
            header[2] = 2;
            header[12..14].copy_from_slice(&(w as u16).to_le_bytes());
            header[14..16].copy_from_slice(&(h as u16).to_le_bytes());
            header[16] = 24;
            Some(header)
        }
        _ => None,
    }
}

/// Where a fixed-layout `format` ([`fixed_header`]) of `h` rows stores image row `y` (0 at the
/// top): its index among the stored rows.
pub(super) fn stored_row(format: Format, h: u32, y: u32) -> u32 {
    if format == Format::Tga { h - 1 - y } else { y }
}

/// One image row's RGB bytes as a fixed-layout `format` stores them (TGA: BGR).
pub(super) fn store_row(format: Format, rgb: &[u8], dst: &mut [u8]) {
    if format == Format::Tga {
        for (d, s) in dst.chunks_exact_mut(3).zip(rgb.chunks_exact(3)) {
            d.copy_from_slice(&[s[2], s[1], s[0]]);
        }
    } else {
        dst.copy_from_slice(rgb);
    }
}

/// Encodes the 8-bit RGB image `data` (`w` x `h`, rows top to bottom) as PNG, TGA or PPM.
pub(super) fn encode_rgb8(w: u32, h: u32, data: &[u8], format: Format) -> Result<Vec<u8>> {
    if let Some(header) = fixed_header(format, w, h) {
        let mut out = filled(header.len() + data.len(), 0u8);
        out[..header.len()].copy_from_slice(&header);
        // In parallel, as the colour conversion (a serial loop here was part of every frame's
        // serial tail). Each stored row is its image row's bytes as the format stores them.
        let row = (w as usize * 3).max(1);
        let rows_per_task = (PIXELS_PER_TASK / (w as usize).max(1)).max(1);
        out[header.len()..]
            .par_chunks_mut(row * rows_per_task)
            .enumerate()
            .for_each(|(task, stored)| {
                for (j, dst) in stored.chunks_exact_mut(row).enumerate() {
                    let y = stored_row(format, h, (task * rows_per_task + j) as u32) as usize;
                    store_row(format, &data[y * row..(y + 1) * row], dst);
                }
            });
        return Ok(out);
    }
    match format {
        Format::Png => super::png_rows::encode_png(w, h, data),
        _ => unreachable!("not an 8-bit format"),
    }
}

/// Decodes an 8-bit RGB PNG, TGA or PPM (as `whitted` writes them); `None` if `bytes` are not
/// one, or hold another kind of pixel.
pub(super) fn decode_rgb8(bytes: &[u8], format: Format) -> Option<Rgb8> {
    let fmt = match format {
        Format::Png => image::ImageFormat::Png,
        Format::Tga => image::ImageFormat::Tga,
        Format::Ppm => image::ImageFormat::Pnm,
        Format::Exr | Format::Pfm | Format::Hdr => return None,
    };
    match image::load_from_memory_with_format(bytes, fmt).ok()? {
        image::DynamicImage::ImageRgb8(img) => Some(Rgb8 {
            width: img.width(),
            height: img.height(),
            data: img.into_raw(),
        }),
        _ => None,
    }
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

    /// Channel values where the conversion could go wrong: NaN of either sign, infinities,
    /// signed zeros, the clamps' edges and every byte's boundary `k / 255` with its neighbours.
    fn awkward_channels() -> Vec<f32> {
        let mut v = vec![
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1.0,
            1.0f32.next_up(),
            1.0f32.next_down(),
            7.0,
            -1.0,
            f32::MAX,
            f32::MIN,
        ];
        for k in 0..=256 {
            let b = k as f32 / 255.0;
            v.extend([b.next_down(), b, b.next_up()]);
        }
        v
    }

    #[test]
    fn every_pixel_of_an_image_converts_as_to_byte_does() {
        // 1 pixel (no full group of 8), 15 (a group and 7 more), a task and 9 pixels more
        // (a full task, then a group and a remainder), the awkward values cycled through them.
        let values = awkward_channels();
        for (w, h) in [
            (1u32, 1u32),
            (3, 5),
            (PIXELS_PER_TASK as u32 + 9, 1),
            (4, 0),
        ] {
            let mut frame = Frame::new(w, h);
            let n = frame.color.len();
            let channel = |i: usize| values[i % values.len()];
            for (i, c) in frame.color.iter_mut().enumerate() {
                *c = Vec3::new(channel(3 * i), channel(3 * i + 1), channel(3 * i + 2));
            }
            for (i, m) in frame.normal.iter_mut().enumerate() {
                *m = -Vec3::new(channel(3 * i + 2), channel(3 * i), channel(3 * i + 1));
            }
            let checks: [(Rgb8, &dyn Fn(usize) -> Vec3); 2] = [
                (color_image(&frame), &|i| frame.color[i]),
                (normal_image(&frame), &|i| frame.normal[i].abs()),
            ];
            for (k, (img, pixel)) in checks.iter().enumerate() {
                assert_eq!(img.data.len(), 3 * n, "{w}x{h}");
                for i in 0..n {
                    let c = pixel(i);
                    let want = [to_byte(c.x), to_byte(c.y), to_byte(c.z)];
                    assert_eq!(
                        img.data[3 * i..3 * i + 3],
                        want,
                        "image {k}, {w}x{h}, pixel {i}"
                    );
                }
            }
        }
    }

    #[test]
    fn tga_is_bottom_up_bgr() {
        let img = Rgb8 {
            width: 1,
            height: 2,
            data: vec![1, 2, 3, 4, 5, 6],
        };
        let out = encode_rgb8(img.width, img.height, &img.data, Format::Tga).unwrap();
        assert_eq!(&out[18..], &[6, 5, 4, 3, 2, 1]);
    }

    #[test]
    fn tga_rows_split_over_tasks_are_each_stored_once_bottom_up() {
        // 100 pixels wide: 163 rows a task, so 400 rows make two full tasks and a partial one.
        for (w, h) in [
            (100u32, 400u32),
            (1, 3),
            (PIXELS_PER_TASK as u32 + 1, 2),
            (7, 0),
        ] {
            let data: Vec<u8> = (0..w * h * 3).map(|v| (v * 7 % 251) as u8).collect();
            let out = encode_rgb8(w, h, &data, Format::Tga).unwrap();
            let (w, h) = (w as usize, h as usize);
            let mut want = Vec::new();
            for row in (0..h).rev() {
                for px in data[row * w * 3..(row + 1) * w * 3].chunks_exact(3) {
                    want.extend_from_slice(&[px[2], px[1], px[0]]);
                }
            }
            assert_eq!(out.len(), 18 + want.len(), "{w}x{h}");
            assert!(out[18..] == want[..], "{w}x{h}");
        }
    }

    #[test]
    fn each_8_bit_format_decodes_what_it_encoded() {
        let img = Rgb8 {
            width: 3,
            height: 2,
            data: (0..18).map(|v| v * 13).collect(),
        };
        for format in [Format::Png, Format::Tga, Format::Ppm] {
            let bytes = encode_rgb8(img.width, img.height, &img.data, format).unwrap();
            assert_eq!(decode_rgb8(&bytes, format), Some(img.clone()), "{format:?}");
        }
    }
}
