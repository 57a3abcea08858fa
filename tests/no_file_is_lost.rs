//! Claim: a run never costs a file. An output path that cannot be written fails before the
//! scene is even read (exit 2, nothing left behind); a run that fails for any reason, or is
//! killed while rendering, leaves an existing image byte-identical, even an image being written
//! while the render runs (TGA, PPM); and no temporary file is ever left in the output folder.
//!
//! What belongs here: what happens to output files, through the real binary. Bad scene files
//! as such belong in `bad_input.rs`.

mod common;

use std::path::Path;
use std::process::Command;

use common::{copy_scene, listing, scratch_dir, whitted};

const PREVIOUS: &[u8] = b"the previous image, byte for byte";

/// A folder holding `good.txt` (a valid scene), `bad.txt` (an invalid one), the meshes, and an
/// `out.png` from an earlier run.
fn folder(name: &str) -> std::path::PathBuf {
    let dir = scratch_dir(&format!("no_file_is_lost/{name}"));
    let good = copy_scene("mesh.txt", &dir);
    std::fs::rename(good, dir.join("good.txt")).unwrap();
    std::fs::write(dir.join("bad.txt"), "Group { numObjects 1 }").unwrap();
    std::fs::write(dir.join("out.png"), PREVIOUS).unwrap();
    dir
}

fn assert_previous_intact(dir: &Path) {
    assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), PREVIOUS);
}

#[test]
fn output_in_a_missing_folder_fails_before_the_scene_is_read() {
    let dir = folder("missing_folder");
    let before = listing(&dir);
    // bad.txt would fail too: the output is checked first, so its error is the one reported.
    let run = whitted(&dir, &["render", "bad.txt", "-o", "nowhere/out.png"]);
    assert_eq!(
        run.assert_error("nowhere/out.png"),
        "nowhere/out.png: cannot write image: No such file or directory (os error 2)"
    );
    assert_eq!(listing(&dir), before);
}

#[test]
fn output_below_a_file_fails_before_the_scene_is_read() {
    let dir = folder("below_a_file");
    let before = listing(&dir);
    let run = whitted(&dir, &["render", "bad.txt", "-o", "good.txt/out.png"]);
    run.assert_error("good.txt/out.png: cannot write image: Not a directory");
    assert_eq!(listing(&dir), before);
}

#[test]
fn output_that_is_a_folder_fails_before_the_scene_is_read() {
    let dir = folder("is_a_folder");
    std::fs::create_dir(dir.join("dir.png")).unwrap();
    let before = listing(&dir);
    let run = whitted(&dir, &["render", "bad.txt", "-o", "dir.png"]);
    assert_eq!(
        run.assert_error("dir.png"),
        "dir.png: cannot write image: it is a folder"
    );
    assert_eq!(listing(&dir), before);
    assert!(listing(&dir.join("dir.png")).is_empty());
}

#[test]
fn output_in_a_read_only_folder_fails_before_the_scene_is_read() {
    use std::os::unix::fs::PermissionsExt;
    let dir = folder("read_only");
    let locked = dir.join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    // Root writes into read-only folders anyway; then try a read-only file system instead.
    let target = if !writable(&locked) {
        locked.join("out.png")
    } else if Path::new("/sys").is_dir() && !writable(Path::new("/sys")) {
        Path::new("/sys/out.png").to_path_buf()
    } else {
        eprintln!("skipped: this user can write to every folder tried");
        return;
    };
    let target = target.to_str().unwrap();
    let run = whitted(&dir, &["render", "bad.txt", "-o", target]);
    run.assert_error(&format!("{target}: cannot write image: "));
    assert!(!Path::new(target).exists());
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert!(listing(&locked).is_empty());
}

/// True if a file can be created in `dir` (the probe is removed again).
fn writable(dir: &Path) -> bool {
    let probe = dir.join(".whitted-probe");
    let ok = std::fs::write(&probe, b"").is_ok();
    let _ = std::fs::remove_file(&probe);
    ok
}

#[test]
fn unknown_output_format_fails_before_the_scene_is_read() {
    let dir = folder("format");
    let before = listing(&dir);
    let run = whitted(&dir, &["render", "bad.txt", "-o", "out.jpg"]);
    run.assert_error(
        "out.jpg: expected an output file ending in .png, .tga, .ppm, .exr, .pfm or .hdr",
    );
    let run = whitted(
        &dir,
        &[
            "render", "bad.txt", "-o", "big.tga", "--size", "70000", "10",
        ],
    );
    run.assert_error("big.tga: TGA images are at most 65535 pixels wide and high");
    assert_eq!(listing(&dir), before);
}

#[test]
fn a_bad_scene_leaves_the_previous_image_byte_identical() {
    let dir = folder("bad_scene");
    let before = listing(&dir);
    let run = whitted(&dir, &["render", "bad.txt", "-o", "out.png"]);
    run.assert_error("bad.txt:1:22: expected 1 object (numObjects 1), found `}` after 0");
    assert_previous_intact(&dir);
    assert_eq!(listing(&dir), before);
}

#[test]
fn a_second_unwritable_output_leaves_the_first_untouched() {
    let dir = folder("second_output");
    let before = listing(&dir);
    let run = whitted(
        &dir,
        &[
            "render",
            "good.txt",
            "-o",
            "out.png",
            "--normals",
            "nowhere/n.png",
            "--size",
            "8",
            "8",
        ],
    );
    run.assert_error("nowhere/n.png: cannot write image");
    assert_previous_intact(&dir);
    assert_eq!(listing(&dir), before);
}

#[test]
fn a_scene_refused_at_the_end_of_parsing_leaves_the_previous_image_byte_identical() {
    let dir = folder("texture");
    let scene = "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }\n\
                 Materials { numMaterials 1\n\
                 Wood { Transform { } materialIndex 0 materialIndex 0 octaves 2 frequency 1 amplitude 1 } }\n\
                 Group { numObjects 1 MaterialIndex 0 Sphere { center 0 0 0 radius 1 } }\n";
    std::fs::write(dir.join("wood.txt"), scene).unwrap();
    let before = listing(&dir);
    let run = whitted(&dir, &["render", "wood.txt", "-o", "out.png"]);
    // The texture refers to itself: caught only once every material is known.
    run.assert_error("wood.txt:3:36: expected textures that end in plain materials");
    assert_previous_intact(&dir);
    assert_eq!(listing(&dir), before);
}

#[test]
fn a_good_render_replaces_the_image_and_leaves_no_temporary_file() {
    let dir = folder("good");
    let before = listing(&dir);
    let run = whitted(
        &dir,
        &["render", "good.txt", "-o", "out.png", "--size", "16", "8"],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let img = whitted::output::read_png(&dir.join("out.png")).unwrap();
    assert_eq!((img.width, img.height), (16, 8));
    assert_eq!(listing(&dir), before);
}

#[test]
fn a_good_render_written_while_rendering_replaces_the_image_and_leaves_no_temporary_file() {
    let dir = folder("good_tga");
    std::fs::write(dir.join("out.tga"), PREVIOUS).unwrap();
    let before = listing(&dir);
    let run = whitted(
        &dir,
        &["render", "good.txt", "-o", "out.tga", "--size", "16", "8"],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    let img = common::read_tga(&dir.join("out.tga"));
    assert_eq!((img.width, img.height), (16, 8));
    assert_eq!(listing(&dir), before);
}

/// Starts a render of many seconds (16 megapixels, shadows, mirror bounces) into `out` and kills
/// it a moment later.
fn kill_a_render(dir: &Path, out: &str) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args([
            "render",
            "good.txt",
            "-o",
            out,
            "--size",
            "4000",
            "4000",
            "--shadows",
            "--bounces",
            "20",
        ])
        .current_dir(dir)
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(300));
    child.kill().unwrap();
    child.wait().unwrap();
}

#[test]
fn a_killed_render_leaves_the_previous_image_byte_identical() {
    let dir = folder("killed");
    let before = listing(&dir);
    // The image is written only once it is complete, so nothing has been touched.
    kill_a_render(&dir, "out.png");
    assert_previous_intact(&dir);
    assert_eq!(listing(&dir), before);
}

#[test]
fn a_killed_render_of_an_image_written_while_rendering_leaves_no_file_behind() {
    let dir = folder("killed_tga");
    std::fs::write(dir.join("out.tga"), PREVIOUS).unwrap();
    let before = listing(&dir);
    // A TGA is written band by band as the render runs, into a file that has no name until
    // the image is complete: killing the run loses that file and nothing else.
    kill_a_render(&dir, "out.tga");
    assert_eq!(std::fs::read(dir.join("out.tga")).unwrap(), PREVIOUS);
    assert_eq!(listing(&dir), before);
}
