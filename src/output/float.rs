//! The floating-point formats, encoded from and decoded to a [`Raster`] of stored samples
//! without loss, so that a merge of pieces re-encodes exactly what the pieces hold:
//!
//! - OpenEXR `.exr` through the `exr` crate: one scan-line part of 32-bit float channels
//!   (`R`, `G`, `B`, or `Z` for depth), ZIP-compressed (lossless), lines in increasing order.
//!   Its data window is the piece's window of the full image, its display window the full image,
//!   and one text attribute `whittedFingerprint` names the render it belongs to.
//! - Portable Float Map `.pfm`: `PF` (RGB) or `Pf` (one channel), little-endian 32-bit floats,
//!   rows bottom to top, as the format defines.
//! - Radiance `.hdr`: RGBE pixels (8-bit mantissas sharing an exponent), written as flat
//!   (uncompressed) scan lines, which every Radiance reader reads. Hand-written rather than
//!   `image`'s codec: that one re-quantises on decode and encode and hides the RGBE bytes, so a
//!   merge through it could change a piece's bytes; here the RGBE bytes are the stored samples.

use std::io::Cursor;

use super::{Place, Raster, Samples};
use crate::error::Result;
use crate::options::Window;

/// The EXR attribute holding a piece's fingerprint.
pub const FINGERPRINT_ATTRIBUTE: &str = "whittedFingerprint";

/// The EXR channel names for a raster of `channels` channels (as the file lists them:
/// alphabetically).
fn exr_channel_names(channels: u32) -> &'static [&'static str] {
    match channels {
        1 => &["Z"],
        _ => &["R", "G", "B"],
    }
}

/// Encodes a 1- or 3-channel float raster as EXR, placed at `place` in the full image.
pub fn encode_exr(raster: &Raster, place: &Place, fingerprint: Option<&str>) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let Samples::F32(values) = &raster.samples else {
        unreachable!("EXR holds float samples");
    };
    let (w, h, n) = (
        raster.width as usize,
        raster.height as usize,
        raster.channels as usize,
    );
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = exr_channel_names(raster.channels)
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let plane: Vec<f32> = values.iter().skip(c).step_by(n).copied().collect();
            AnyChannel::new(*name, FlatSamples::F32(plane))
        })
        .collect();
    let mut attributes = LayerAttributes {
        layer_position: Vec2(place.window.x0 as i32, place.window.y0 as i32),
        ..LayerAttributes::default()
    };
    if let Some(f) = fingerprint {
        attributes.other.insert(
            Text::from(FINGERPRINT_ATTRIBUTE),
            AttributeValue::Text(Text::from(f)),
        );
    }
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new((w, h), attributes, encoding, AnyChannels::sort(channels));
    let mut image = Image::from_layer(layer);
    image.attributes.display_window =
        IntegerBounds::from_dimensions((place.image_width as usize, place.image_height as usize));
    let mut out = Cursor::new(Vec::new());
    image
        .write()
        .non_parallel()
        .to_buffered(&mut out)
        .map_err(|e| crate::error::Error::Other(format!("cannot encode EXR: {e}")))?;
    Ok(out.into_inner())
}

/// What an EXR file holds: its samples, its place and its fingerprint attribute.
pub struct ExrPiece {
    pub raster: Raster,
    pub place: Place,
    pub fingerprint: Option<String>,
}

/// Decodes an EXR written by [`encode_exr`]; the error says what is wrong with it.
pub fn decode_exr(bytes: &[u8]) -> std::result::Result<ExrPiece, String> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| format!("not a readable EXR image ({e})"))?;
    let layer = &image.layer_data;
    let names: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    // The file lists channels alphabetically; the raster interleaves them as R, G, B.
    let order: &[usize] = match names.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        ["B", "G", "R"] => &[2, 1, 0],
        ["Z"] => &[0],
        _ => {
            return Err(format!(
                "holds channels {}, not whitted's R, G, B or Z",
                names.join(", ")
            ));
        }
    };
    let (w, h) = (layer.size.width(), layer.size.height());
    let mut values = vec![0.0f32; w * h * order.len()];
    for (slot, &c) in order.iter().enumerate() {
        let FlatSamples::F32(plane) = &layer.channel_data.list[c].sample_data else {
            return Err("holds samples that are not 32-bit floats".to_string());
        };
        for (i, v) in plane.iter().enumerate() {
            values[i * order.len() + slot] = *v;
        }
    }
    let display = image.attributes.display_window;
    let pos = layer.attributes.layer_position;
    if display.position != Vec2(0, 0) || pos.x() < 0 || pos.y() < 0 {
        return Err("has a display window or data window outside whitted's images".to_string());
    }
    let (x0, y0) = (pos.x() as u32, pos.y() as u32);
    let fingerprint = match layer
        .attributes
        .other
        .get(&Text::from(FINGERPRINT_ATTRIBUTE))
    {
        Some(AttributeValue::Text(t)) => Some(t.to_string()),
        _ => None,
    };
    Ok(ExrPiece {
        raster: Raster {
            width: w as u32,
            height: h as u32,
            channels: order.len() as u32,
            samples: Samples::F32(values),
        },
        place: Place {
            window: Window {
                x0,
                x1: x0 + w as u32,
                y0,
                y1: y0 + h as u32,
            },
            image_width: display.size.width() as u32,
            image_height: display.size.height() as u32,
        },
        fingerprint,
    })
}

/// Encodes a 1- or 3-channel float raster as PFM.
pub fn encode_pfm(raster: &Raster) -> Vec<u8> {
    let Samples::F32(values) = &raster.samples else {
        unreachable!("PFM holds float samples");
    };
    let tag = if raster.channels == 1 { "Pf" } else { "PF" };
    let mut out = format!("{tag}\n{} {}\n-1.0\n", raster.width, raster.height).into_bytes();
    let row = (raster.width * raster.channels) as usize;
    for line in values.chunks_exact(row.max(1)).rev() {
        for v in line {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// The header fields of a PNM-style text header: `count` whitespace-separated tokens, and the
/// offset just past the single whitespace byte that ends the last.
fn header_tokens(bytes: &[u8], count: usize) -> Option<(Vec<&str>, usize)> {
    let mut tokens = Vec::new();
    let mut i = 0;
    while tokens.len() < count {
        while bytes.get(i)?.is_ascii_whitespace() {
            i += 1;
        }
        let start = i;
        while !bytes.get(i)?.is_ascii_whitespace() {
            i += 1;
        }
        tokens.push(std::str::from_utf8(&bytes[start..i]).ok()?);
    }
    Some((tokens, i + 1))
}

/// Decodes a PFM (either byte order).
pub fn decode_pfm(bytes: &[u8]) -> std::result::Result<Raster, String> {
    let bad = || "not a readable PFM image".to_string();
    let (tokens, start) = header_tokens(bytes, 4).ok_or_else(bad)?;
    let channels = match tokens[0] {
        "PF" => 3,
        "Pf" => 1,
        _ => return Err(bad()),
    };
    let width: u32 = tokens[1].parse().map_err(|_| bad())?;
    let height: u32 = tokens[2].parse().map_err(|_| bad())?;
    let scale: f32 = tokens[3].parse().map_err(|_| bad())?;
    let row = width as usize * channels;
    let data = &bytes[start.min(bytes.len())..];
    if data.len() != row * height as usize * 4 {
        return Err(format!(
            "not a readable PFM image (its {width}x{height} pixels need {} bytes, it has {})",
            row * height as usize * 4,
            data.len()
        ));
    }
    let mut values = Vec::with_capacity(row * height as usize);
    for line in data.chunks_exact((row * 4).max(1)).rev() {
        for b in line.chunks_exact(4) {
            let b = [b[0], b[1], b[2], b[3]];
            values.push(if scale < 0.0 {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            });
        }
    }
    Ok(Raster {
        width,
        height,
        channels: channels as u32,
        samples: Samples::F32(values),
    })
}

/// The RGBE pixel of a linear colour: the exponent `e` of the largest component `m`
/// (`m = f * 2^e`, `f` in `[0.5, 1)`), each component truncated to `c * 2^(8 - e)`, and `e + 128`.
/// Negative and NaN components count as 0; colours too dark for the exponent are black, too
/// bright ones the brightest RGBE value.
pub fn to_rgbe(rgb: [f32; 3]) -> [u8; 4] {
    let c = rgb.map(|v| if v > 0.0 { v as f64 } else { 0.0 });
    let m = c[0].max(c[1]).max(c[2]);
    if m <= 0.0 {
        return [0; 4];
    }
    if !m.is_finite() || m >= 2f64.powi(127) {
        return [255, 255, 255, 255];
    }
    // f64 holds every f32 as a normal number: its exponent field gives floor(log2 m) exactly.
    let e = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1022;
    if e < -127 {
        return [0; 4];
    }
    let scale = 2f64.powi(8 - e);
    let q = c.map(|v| (v * scale).floor().min(255.0) as u8);
    [q[0], q[1], q[2], (e + 128) as u8]
}

/// The linear colour of an RGBE pixel (`c * 2^(e - 136)`; exponent 0 is black).
pub fn from_rgbe(p: [u8; 4]) -> [f32; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    let scale = 2f64.powi(p[3] as i32 - 136);
    [p[0], p[1], p[2]].map(|c| (c as f64 * scale) as f32)
}

/// Encodes a 4-channel RGBE raster as Radiance HDR with flat scan lines.
pub fn encode_hdr(raster: &Raster) -> Vec<u8> {
    let Samples::U8(rgbe) = &raster.samples else {
        unreachable!("HDR holds RGBE bytes");
    };
    let mut out = format!(
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {} +X {}\n",
        raster.height, raster.width
    )
    .into_bytes();
    out.extend_from_slice(rgbe);
    out
}

/// Decodes a Radiance HDR with flat scan lines, as [`encode_hdr`] writes it.
pub fn decode_hdr(bytes: &[u8]) -> std::result::Result<Raster, String> {
    let bad = || "not a Radiance HDR image as whitted writes them".to_string();
    if !bytes.starts_with(b"#?RADIANCE\n") && !bytes.starts_with(b"#?RGBE\n") {
        return Err(bad());
    }
    let blank = bytes
        .windows(2)
        .position(|w| w == b"\n\n")
        .ok_or_else(bad)?
        + 2;
    let (tokens, start) = header_tokens(&bytes[blank..], 4).ok_or_else(bad)?;
    if tokens[0] != "-Y" || tokens[2] != "+X" {
        return Err(bad());
    }
    let height: u32 = tokens[1].parse().map_err(|_| bad())?;
    let width: u32 = tokens[3].parse().map_err(|_| bad())?;
    let data = &bytes[(blank + start).min(bytes.len())..];
    if data.len() != width as usize * height as usize * 4 {
        return Err(format!(
            "not a Radiance HDR image as whitted writes them (flat scan lines of {width}x{height} \
             pixels need {} bytes, it has {})",
            width as usize * height as usize * 4,
            data.len()
        ));
    }
    Ok(Raster {
        width,
        height,
        channels: 4,
        samples: Samples::U8(data.to_vec()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgbe_keeps_eight_bits_of_the_largest_component() {
        assert_eq!(to_rgbe([1.0, 0.5, 0.0]), [128, 64, 0, 129]);
        assert_eq!(to_rgbe([0.0; 3]), [0; 4]);
        assert_eq!(to_rgbe([-1.0, f32::NAN, 0.0]), [0; 4]);
        assert_eq!(from_rgbe([128, 64, 0, 129]), [1.0, 0.5, 0.0]);
        for v in [1e-30f32, 0.001, 0.3, 0.999_999_94, 1.0, 3.7, 1e20] {
            let p = to_rgbe([v, v * 0.25, 0.0]);
            assert!(p[0] >= 128, "{v}: mantissa normalised");
            let back = from_rgbe(p)[0];
            assert!(back <= v && v - back <= v / 128.0, "{v} -> {back}");
            assert_eq!(
                to_rgbe(from_rgbe(p)),
                p,
                "{v}: decoding and encoding again is exact"
            );
        }
    }

    #[test]
    fn pfm_and_hdr_decode_what_they_encode() {
        let raster = Raster {
            width: 3,
            height: 2,
            channels: 3,
            samples: Samples::F32((0..18).map(|v| v as f32 * 0.37 - 2.0).collect()),
        };
        assert_eq!(decode_pfm(&encode_pfm(&raster)).unwrap(), raster);
        let rgbe = Raster {
            width: 2,
            height: 2,
            channels: 4,
            samples: Samples::U8((0..16).map(|v| v * 9).collect()),
        };
        assert_eq!(decode_hdr(&encode_hdr(&rgbe)).unwrap(), rgbe);
    }
}
