//! Claim: `whitted merge` writes nothing unless its pieces are one render's and cover the image
//! exactly once; each bad input is one line naming the piece, exit 2: overlapping pieces, a gap,
//! pieces of another render (options, size) or another kind of image, mixed formats, unreadable
//! pieces, a missing piece, a piece without its sidecar, an EXR that is no piece, a piece given
//! twice. And a tile whose render fails leaves no piece.

mod common;

use std::path::{Path, PathBuf};

use common::{our_scenes, scratch_dir, whitted};

/// A folder with `scene.txt` and the three tiles of a 64x48 render, as `t0.EXT` .. `t2.EXT`.
fn tiled(name: &str, ext: &str) -> PathBuf {
    let dir = scratch_dir(name);
    let scene = our_scenes()
        .into_iter()
        .find(|p| p.ends_with("glass_sphere.txt"))
        .unwrap();
    std::fs::copy(scene, dir.join("scene.txt")).unwrap();
    for i in 0..3 {
        let tile = format!("{i}/3");
        let out = format!("t{i}.{ext}");
        render(&dir, &["--tile", &tile, "-o", &out]);
    }
    dir
}

/// Renders `scene.txt` at 64x48 with `extra` options.
fn render(dir: &Path, extra: &[&str]) {
    let mut args = vec!["render", "scene.txt", "--size", "64", "48", "--shadows"];
    args.extend_from_slice(extra);
    let run = whitted(dir, &args);
    assert_eq!(run.code, Some(0), "{args:?}: {}", run.stderr);
}

/// Runs `whitted merge OUT PIECES...` and returns its one error line; checks OUT was not
/// written.
fn refused(dir: &Path, out: &str, pieces: &[&str]) -> String {
    let mut args = vec!["merge", out];
    args.extend_from_slice(pieces);
    let msg = whitted(dir, &args).assert_error("");
    assert!(!dir.join(out).exists(), "{out} was written despite: {msg}");
    msg
}

fn fingerprint(dir: &Path, piece: &str) -> String {
    let text = std::fs::read_to_string(dir.join(format!("{piece}.piece"))).unwrap();
    text.lines()
        .find_map(|l| l.strip_prefix("fingerprint "))
        .unwrap()
        .to_string()
}

#[test]
fn good_pieces_merge_in_any_order() {
    for ext in ["png", "tga", "ppm", "exr", "pfm", "hdr"] {
        let dir = tiled(&format!("merge_good_{ext}"), ext);
        let out = format!("all.{ext}");
        let (t0, t1, t2) = (
            format!("t0.{ext}"),
            format!("t1.{ext}"),
            format!("t2.{ext}"),
        );
        let run = whitted(&dir, &["merge", &out, &t2, &t0, &t1]);
        assert_eq!(run.code, Some(0), "{ext}: {}", run.stderr);
        let one = format!("one.{ext}");
        render(&dir, &["-o", &one]);
        assert!(
            std::fs::read(dir.join(&out)).unwrap() == std::fs::read(dir.join(&one)).unwrap(),
            "{ext}: merged differs from one go"
        );
    }
}

#[test]
fn overlaps_gaps_and_repeats_are_refused() {
    let dir = tiled("merge_cover", "png");
    render(&dir, &["--crop", "0", "64", "0", "20", "-o", "top.png"]);
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "top.png", "t1.png", "t2.png"]),
        "top.png: overlaps t0.png (columns 0..64, rows 0..16): each pixel must come from one piece"
    );
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "t2.png"]),
        "no piece covers columns 0..64 of rows 16..32 of the 64x48 image: a piece is missing \
         (pieces given: 2)"
    );
    render(&dir, &["--crop", "0", "40", "16", "32", "-o", "left.png"]);
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "left.png", "t2.png"]),
        "no piece covers columns 40..64 of rows 16..32 of the 64x48 image: a piece is missing \
         (pieces given: 3)"
    );
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "t1.png", "t2.png", "t1.png"]),
        "t1.png: is given twice"
    );
    assert_eq!(
        refused(&dir, "out.png", &[]),
        "expected pieces to merge: whitted merge OUT PIECE... (see `whitted merge --help`)"
    );
}

#[test]
fn pieces_of_other_renders_are_refused() {
    let dir = tiled("merge_renders", "exr");
    render(&dir, &["--bounces", "2", "--tile", "1/3", "-o", "b1.exr"]);
    render(&dir, &["--tile", "1/3", "--normals", "n1.exr"]);
    let run = whitted(
        &dir,
        &[
            "render",
            "scene.txt",
            "--size",
            "64",
            "40",
            "--shadows",
            "--tile",
            "1/3",
            "-o",
            "s1.exr",
        ],
    );
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    // EXR pieces hold their fingerprint; read it back through a PNG twin's sidecar.
    render(&dir, &["--tile", "0/3", "-o", "t0.png"]);
    render(&dir, &["--bounces", "2", "--tile", "1/3", "-o", "b1.png"]);
    let (good, other) = (fingerprint(&dir, "t0.png"), fingerprint(&dir, "b1.png"));
    assert_ne!(good, other);
    let msg = refused(&dir, "out.exr", &["t0.exr", "b1.exr", "t2.exr"]);
    assert!(
        msg.starts_with("b1.exr: is a piece of another render than t0.exr (fingerprint ")
            && msg.ends_with(": the scene, the render options or the kind of image differ)"),
        "{msg}"
    );
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "b1.png"]),
        format!(
            "b1.png: is a piece of another render than t0.png (fingerprint {other}, not {good}: \
             the scene, the render options or the kind of image differ)"
        )
    );
    let msg = refused(&dir, "out.exr", &["t0.exr", "n1.exr", "t2.exr"]);
    assert!(
        msg.starts_with("n1.exr: is a piece of another render than t0.exr"),
        "{msg}"
    );
    assert_eq!(
        refused(&dir, "out.exr", &["t0.exr", "s1.exr", "t2.exr"]),
        "s1.exr: is a piece of a 64x40 image, t0.exr of a 64x48 image: pieces of different renders"
    );
}

#[test]
fn mixed_unreadable_and_missing_pieces_are_refused() {
    let dir = tiled("merge_files", "png");
    render(
        &dir,
        &[
            "--tile", "1/3", "-o", "t1.tga", "--depth", "1", "20", "d1.exr",
        ],
    );
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "t1.tga", "t2.png"]),
        "t1.tga: is a .tga piece, but out.png is .png: expected every piece in the output's format"
    );
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "notes.txt"]),
        "notes.txt: is not an image whitted writes (expected .png, .tga, .ppm, .exr, .pfm or .hdr)"
    );
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "t1.png", "t9.png"]),
        "t9.png: is missing (a tile that failed leaves no file: render it again)"
    );
    std::fs::copy(dir.join("t1.png"), dir.join("bare.png")).unwrap();
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "bare.png", "t2.png"]),
        "bare.png: has no sidecar bare.png.piece to say where it belongs"
    );
    std::fs::write(
        dir.join("bare.png.piece"),
        "whitted-piece 1\nfingerprint 0\n",
    )
    .unwrap();
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "bare.png", "t2.png"]),
        "bare.png: sidecar bare.png.piece: expected a line `image` with 2 values, found ``"
    );
    std::fs::write(dir.join("t1.png"), b"not a png").unwrap();
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "t1.png", "t2.png"]),
        "t1.png: not a readable 8-bit RGB PNG image"
    );
    std::fs::write(dir.join("bad.exr"), b"not an exr").unwrap();
    assert_eq!(
        refused(&dir, "out.exr", &["bad.exr"]),
        "bad.exr: not a readable EXR image (invalid: file identifier missing)"
    );
    // An EXR that records no render: the witness picture's writer makes one.
    let img = whitted::output::Rgb8 {
        width: 64,
        height: 48,
        data: vec![7; 64 * 48 * 3],
    };
    whitted::output::write_image(&img, &dir.join("plain.exr")).unwrap();
    assert_eq!(
        refused(&dir, "out.exr", &["plain.exr"]),
        "plain.exr: records no `whittedFingerprint` attribute: not a piece of a whitted render"
    );
    assert!(!dir.join("out.exr").exists());
}

#[test]
fn a_tile_whose_render_fails_leaves_no_piece() {
    let dir = tiled("merge_failed_tile", "png");
    std::fs::remove_file(dir.join("t1.png")).unwrap();
    std::fs::remove_file(dir.join("t1.png.piece")).unwrap();
    let run = whitted(
        &dir,
        &[
            "render",
            "scene.txt",
            "--size",
            "64",
            "48",
            "--tile",
            "1/3",
            "-o",
            "t1.png",
            "--normals",
            "no/such/folder/n1.png",
        ],
    );
    run.assert_error("no/such/folder/n1.png: cannot write image");
    assert!(!dir.join("t1.png").exists() && !dir.join("t1.png.piece").exists());
    assert_eq!(
        refused(&dir, "out.png", &["t0.png", "t1.png", "t2.png"]),
        "t1.png: is missing (a tile that failed leaves no file: render it again)"
    );
}
