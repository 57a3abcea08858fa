//! Claim: the floating-point images hold the linear values of the render, as decoders that share
//! no code with ours read them: EXR through the reference OpenEXR C++ library (the `openexr`
//! crate; we write with the pure-Rust `exr` crate), PFM through `zune-ppm`, Radiance HDR through
//! `zune-hdr`. Colour, depth and normals, whole images and crops (an EXR's data window is the
//! crop, its display window the full image).

mod common;

use std::path::Path;

use common::{our_scenes, scratch_dir};
use whitted::options::Window;
use whitted::output::{self, ImageKind, from_rgbe, piece::RenderFingerprint, to_rgbe};
use whitted::shade::ShadeOptions;
use whitted::{Frame, RenderOptions, Scene, render};

const KINDS: [ImageKind; 3] = [
    ImageKind::Color,
    ImageKind::Depth {
        near: 1.0,
        far: 30.0,
    },
    ImageKind::Normals,
];

/// The values a float image of `kind` holds at pixel `i`: colour, depth, signed normal.
fn expected(frame: &Frame, kind: ImageKind, i: usize) -> Vec<f32> {
    match kind {
        ImageKind::Color => frame.color[i].to_array().to_vec(),
        ImageKind::Depth { .. } => vec![frame.depth[i]],
        ImageKind::Normals => frame.normal[i].to_array().to_vec(),
    }
}

fn glass_sphere(crop: Option<Window>) -> (Scene, RenderOptions, Frame) {
    let path = our_scenes()
        .into_iter()
        .find(|p| p.ends_with("glass_sphere.txt"))
        .unwrap();
    let scene = Scene::load(&path).unwrap();
    let opts = RenderOptions {
        width: 100,
        height: 76,
        crop,
        shade: ShadeOptions {
            shadows: true,
            shade_back: true,
            bounces: 6,
            ..ShadeOptions::default()
        },
        ..RenderOptions::default()
    };
    let frame = render(&scene, &opts).unwrap();
    (scene, opts, frame)
}

/// Reads every channel of an EXR as 32-bit floats with OpenEXR: (data window, display window,
/// channel names, interleaved values).
fn read_with_openexr(path: &Path) -> ([i32; 4], [i32; 4], Vec<String>, Vec<f32>) {
    use openexr::prelude::*;
    let file = InputFile::new(path, 1).unwrap();
    let data = *file.header().data_window::<[i32; 4]>();
    let display = *file.header().display_window::<[i32; 4]>();
    let names: Vec<String> = file
        .header()
        .channels()
        .iter()
        .map(|(name, _)| name.to_string())
        .collect();
    // The file lists channels alphabetically; ask for them in R, G, B order.
    let wanted: Vec<&str> = if names == ["B", "G", "R"] {
        vec!["R", "G", "B"]
    } else {
        names.iter().map(String::as_str).collect()
    };
    let frame = Frame::new::<f32, _, _>(&wanted, data).unwrap();
    let (_, frames) = file
        .into_reader(vec![frame])
        .unwrap()
        .read_pixels(data[1], data[3])
        .unwrap();
    (data, display, names, frames[0].as_slice::<f32>().to_vec())
}

#[test]
fn exr_read_by_openexr_holds_the_linear_values_and_the_place_of_the_crop() {
    let dir = scratch_dir("float_exr");
    let (mut hits, mut misses) = (0, 0);
    for crop in [
        None,
        Some(Window {
            x0: 10,
            x1: 70,
            y0: 8,
            y1: 40,
        }),
    ] {
        let (scene, opts, frame) = glass_sphere(crop);
        let print = RenderFingerprint::new(&scene, &opts);
        for kind in KINDS {
            let path = dir.join(format!("{kind:?}.exr").replace([' ', '{', '}', ':', ','], ""));
            output::write_frame(&frame, kind, &path, &print).unwrap();
            let (data, display, names, values) = read_with_openexr(&path);
            let win = frame.window;
            assert_eq!(
                data,
                [
                    win.x0 as i32,
                    win.y0 as i32,
                    win.x1 as i32 - 1,
                    win.y1 as i32 - 1
                ],
                "{kind:?} {crop:?}: the data window is the crop"
            );
            assert_eq!(
                display,
                [0, 0, 99, 75],
                "{kind:?}: the display window is the image"
            );
            let channels = match kind {
                ImageKind::Depth { .. } => vec!["Z"],
                _ => vec!["B", "G", "R"],
            };
            assert_eq!(names, channels, "{kind:?}");
            let n = channels.len();
            assert_eq!(values.len(), frame.color.len() * n);
            for i in 0..frame.color.len() {
                let want = expected(&frame, kind, i);
                let got = &values[i * n..(i + 1) * n];
                assert!(
                    want.iter()
                        .zip(got)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{kind:?} {crop:?} pixel {i}: {got:?}, expected {want:?}"
                );
                hits += frame.depth[i].is_finite() as usize;
                misses += !frame.depth[i].is_finite() as usize;
            }
        }
    }
    assert!(
        hits > 0 && misses > 0,
        "pixels that hit and pixels that miss are both checked"
    );
}

#[test]
fn pfm_read_by_zune_ppm_holds_the_linear_values() {
    use zune_ppm::zune_core::bytestream::ZCursor;
    let dir = scratch_dir("float_pfm");
    let (scene, opts, frame) = glass_sphere(None);
    let print = RenderFingerprint::new(&scene, &opts);
    for kind in KINDS {
        let path = dir.join("image.pfm");
        output::write_frame(&frame, kind, &path, &print).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // zune-ppm 0.5 skips every whitespace byte after the header's scale, where PFM has
        // exactly one, so it misreads an image whose first sample starts with such a byte; and it
        // turns the rows top down by halves, which misplaces rows of an odd height. This render
        // has an even height and images that start with no such byte (checked, so a change of
        // scene or size says why it fails).
        let start = bytes.windows(5).position(|w| w == b"-1.0\n").unwrap() + 5;
        assert!(
            !bytes[start].is_ascii_whitespace(),
            "{kind:?}: pick an image zune-ppm reads"
        );
        let mut decoder = zune_ppm::PPMDecoder::new(ZCursor::new(&bytes[..]));
        let zune_ppm::zune_core::result::DecodingResult::F32(values) = decoder.decode().unwrap()
        else {
            panic!("{kind:?}: zune-ppm read no float samples");
        };
        assert_eq!(decoder.dimensions(), Some((100, 76)));
        let n = values.len() / frame.color.len();
        for i in 0..frame.color.len() {
            let want = expected(&frame, kind, i);
            let got = &values[i * n..(i + 1) * n];
            assert!(
                want.iter()
                    .zip(got)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{kind:?} pixel {i}: {got:?}, expected {want:?}"
            );
        }
    }
}

#[test]
fn hdr_read_by_zune_hdr_holds_the_values_to_rgbe_precision() {
    use zune_hdr::zune_core::bytestream::ZCursor;
    let dir = scratch_dir("float_hdr");
    let (scene, opts, frame) = glass_sphere(None);
    let print = RenderFingerprint::new(&scene, &opts);
    for kind in KINDS {
        let path = dir.join("image.hdr");
        output::write_frame(&frame, kind, &path, &print).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mut decoder = zune_hdr::HdrDecoder::new(ZCursor::new(&bytes[..]));
        let values = decoder.decode().unwrap();
        assert_eq!(decoder.dimensions(), Some((100, 76)));
        for i in 0..frame.color.len() {
            // HDR has no sign or infinity: depth is 0 where nothing was hit, normals abs().
            let linear: [f32; 3] = match kind {
                ImageKind::Color => frame.color[i].to_array(),
                ImageKind::Depth { .. } => {
                    let t = frame.depth[i];
                    [if t.is_finite() { t } else { 0.0 }; 3]
                }
                ImageKind::Normals => frame.normal[i].abs().to_array(),
            };
            let got = &values[i * 3..i * 3 + 3];
            assert_eq!(
                got,
                from_rgbe(to_rgbe(linear)),
                "{kind:?} pixel {i}: the RGBE value"
            );
            let max = linear.iter().fold(0.0f32, |m, v| m.max(*v));
            for (g, l) in got.iter().zip(linear) {
                assert!(
                    *g <= l && l - g <= max / 128.0,
                    "{kind:?} pixel {i}: {g} for {l}"
                );
            }
        }
    }
}
