//! Claim: a render cut into tiles by `whitted tiles`, run by GNU parallel and put back together
//! by its merge line has the bytes of the render made in one go: the showcase at 1024x768 in 16
//! tiles, colour, depth and normals, as PNG and as EXR; and anti-aliased, with a filter whose
//! support crosses the tiles' borders (each tile traces its filter halo). `.ci/run` installs GNU
//! parallel.

mod common;

use std::path::Path;
use std::process::Command;

use common::{our_scenes, scratch_dir};

const WHITTED: &str = env!("CARGO_BIN_EXE_whitted");

/// Runs `script` with `sh -c` in `dir`; panics with its output unless it succeeds.
fn sh(dir: &Path, script: &str) -> String {
    let out = Command::new("sh")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .env("W", WHITTED)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "`{script}` failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn have_parallel() -> bool {
    Command::new("parallel")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn sixteen_tiles_run_by_gnu_parallel_merge_to_the_bytes_of_the_one_go_render() {
    let opts = "--size 1024 768 --shadows --shade-back --transparent-shadows --bounces 8";
    tiles_merge_to_the_one_go_render("tiles_parallel", opts, &["png", "exr"]);
}

#[test]
fn anti_aliased_tiles_merge_to_the_bytes_of_the_one_go_render() {
    // A Gaussian of sigma 1.0 reads the samples of the pixels 2 rows into the next tile.
    let opts = "--size 1024 768 --shadows --shade-back --bounces 3 --samples 4 --filter gaussian 1";
    tiles_merge_to_the_one_go_render("tiles_parallel_aa", opts, &["png"]);
}

/// Renders the showcase with `opts` in 16 tiles run by GNU parallel, merges them and checks
/// the bytes against the one-go render, for colour, depth and normals in each format of `exts`.
fn tiles_merge_to_the_one_go_render(name: &str, opts: &str, exts: &[&str]) {
    assert!(
        have_parallel(),
        "GNU parallel is not installed: `apt-get install parallel` (.ci/run installs it)"
    );
    let dir = scratch_dir(name);
    let scene = our_scenes()
        .into_iter()
        .find(|p| p.ends_with("showcase.txt"))
        .unwrap();
    let scene = scene.display();
    for ext in exts {
        let outputs = format!("-o c.{ext} --depth 5 20 d.{ext} --normals n.{ext}");
        let tiles = format!("\"$W\" tiles 16 {scene} {opts} {outputs}");
        let lines = sh(&dir, &tiles);
        let lines: Vec<&str> = lines.lines().collect();
        assert_eq!(lines.len(), 17, "16 render lines and the merge line");
        for (i, line) in lines[..16].iter().enumerate() {
            assert!(line.ends_with(&format!("--tile {i}/16")), "{line}");
        }
        sh(&dir, &format!("{tiles} | head -n 16 | parallel"));
        sh(&dir, &format!("{tiles} | tail -n 1 | sh"));
        let one_go = format!("-o C.{ext} --depth 5 20 D.{ext} --normals N.{ext}");
        sh(&dir, &format!("\"$W\" render {scene} {opts} {one_go}"));
        for (tiled, whole) in [("c", "C"), ("d", "D"), ("n", "N")] {
            let a = std::fs::read(dir.join(format!("{tiled}.{ext}"))).unwrap();
            let b = std::fs::read(dir.join(format!("{whole}.{ext}"))).unwrap();
            assert!(
                a == b,
                "{tiled}.{ext}: the merged tiles differ from the one-go render"
            );
        }
        assert!(
            !dir.join(format!("c.{ext}.piece")).exists(),
            "a merged image is whole: no sidecar"
        );
    }
}
