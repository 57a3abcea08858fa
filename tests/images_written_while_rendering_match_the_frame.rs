//! Claim: the 8-bit images written while the render runs (each band of rows as the film
//! finishes it: a TGA or PPM stored in place, a PNG compressed in order) hold the same pixels,
//! for either tracer, one thread or several, a crop window whose rows do not start on a band,
//! several samples with a filter reaching into the neighbouring bands, and the depth and normal
//! images too. `--stats` counts the images written while rendering, so a silent fallback to
//! encoding afterwards fails here. That each equals the image encoded from the finished frame,
//! byte for byte, whatever order the bands come in, is checked in `src/output/streamed.rs`;
//! for a PNG made in one go against one merged from tiles (encoded afterwards), in
//! `tiles_merge_to_the_one_go_render.rs`.

mod common;

use std::collections::HashMap;
use std::path::Path;

use common::{copy_scene, read_image, scratch_dir, whitted};

/// The `key=value` pairs of the run's `stats:` line.
fn stats(stderr: &str) -> HashMap<String, String> {
    let line = stderr
        .lines()
        .find(|l| l.starts_with("stats:"))
        .unwrap_or_else(|| panic!("no stats line:\n{stderr}"));
    line["stats:".len()..]
        .split_whitespace()
        .filter_map(|kv| kv.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// Renders `scene` in `dir` with `extra` options, writing colour, depth and normal images with
/// extension `ext`; returns how many were written while rendering.
fn render(dir: &Path, scene: &str, ext: &str, extra: &[&str]) -> usize {
    // 61x43 unless `extra` gives a size
    let size: &[&str] = if extra.contains(&"--size") {
        &[]
    } else {
        &["--size", "61", "43"]
    };
    let (color, depth, normals) = (
        format!("color.{ext}"),
        format!("depth.{ext}"),
        format!("normals.{ext}"),
    );
    let mut args = vec![
        "render",
        scene,
        "-o",
        &color,
        "--depth",
        "8",
        "14",
        &depth,
        "--normals",
        &normals,
        "--shadows",
        "--stats",
    ];
    args.extend_from_slice(size);
    args.extend_from_slice(extra);
    let run = whitted(dir, &args);
    assert_eq!(run.code, Some(0), "{args:?}:\n{}", run.stderr);
    stats(&run.stderr)["streamed_images"].parse().unwrap()
}

#[test]
fn tga_ppm_and_png_written_while_rendering_hold_the_same_pixels() {
    let dir = scratch_dir("images_written_while_rendering");
    let scene = copy_scene("mesh.txt", &dir);
    let scene = scene.file_name().unwrap().to_str().unwrap();
    let settings: [&[&str]; 7] = [
        &["--threads", "1"],
        // 1,500 bytes a row: chunks of 174 rows, three of them, each written as it completes
        &["--threads", "2", "--size", "500", "400"],
        &["--threads", "3"],
        &["--threads", "2", "--tracer", "reference"],
        // rows 5..37: the window starts and ends inside bands of 8 rows
        &["--threads", "2", "--crop", "3", "58", "5", "37"],
        &["--threads", "2", "--samples", "4", "--filter", "tent", "9"],
        &[
            "--threads",
            "2",
            "--samples",
            "4",
            "--filter",
            "gaussian",
            "3",
            "--crop",
            "0",
            "61",
            "13",
            "30",
        ],
    ];
    for extra in settings {
        assert_eq!(render(&dir, scene, "png", extra), 3, "{extra:?}: png");
        for ext in ["tga", "ppm"] {
            assert_eq!(render(&dir, scene, ext, extra), 3, "{extra:?}: {ext}");
            for image in ["color", "depth", "normals"] {
                let want = read_image(&dir.join(format!("{image}.png")));
                let got = read_image(&dir.join(format!("{image}.{ext}")));
                assert_eq!(
                    (got.width, got.height),
                    (want.width, want.height),
                    "{extra:?}"
                );
                assert!(
                    got.data == want.data,
                    "{extra:?}: {image}.{ext} differs from the PNG"
                );
            }
        }
    }
}
