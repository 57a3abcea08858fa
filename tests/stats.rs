//! Claim: `--stats` prints a readable block and exactly one `stats: key=value ...` line on
//! stderr, with ray counts by kind and bounce that add up (and match the reference tracer's
//! own count); a render that runs past the bar's delay draws a progress bar when stderr is a
//! terminal and nothing when it is not. Never asserts on time: renders grow until one lasts
//! long enough for the bar to be due.

mod common;

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use whitted::raytree::SegmentKind;
use whitted::scene::Scene;
use whitted::{RenderOptions, render};

fn run(args: &[&str]) -> (bool, String) {
    let out = common::whitted(Path::new(env!("CARGO_MANIFEST_DIR")), args);
    (out.code == Some(0), out.stderr)
}

#[test]
fn stats_print_one_parseable_line_whose_counts_add_up() {
    let dir = common::scratch_dir("stats_line");
    let out = dir.join("g.png");
    let (ok, err) = run(&[
        "render",
        "scenes/glass_sphere.txt",
        "-o",
        out.to_str().unwrap(),
        "--size",
        "64",
        "48",
        "--shadows",
        "--shade-back",
        "--stats",
    ]);
    assert!(ok, "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("stats:")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    let pairs: HashMap<&str, &str> = lines[0]["stats:".len()..]
        .split_whitespace()
        .map(|p| {
            p.split_once('=')
                .unwrap_or_else(|| panic!("not key=value: {p}"))
        })
        .collect();
    let int = |k: &str| -> u64 {
        pairs[k]
            .parse()
            .unwrap_or_else(|_| panic!("{k}={}", pairs[k]))
    };
    assert_eq!(int("eye_rays"), 64 * 48);
    assert_eq!(int("pixels"), 64 * 48);
    let by_kind: u64 = ["eye", "shadow", "reflected", "transmitted"]
        .iter()
        .map(|k| int(&format!("{k}_rays")))
        .sum();
    let by_bounce: u64 = (0..)
        .map_while(|b| {
            pairs
                .get(format!("bounce{b}_rays").as_str())
                .map(|v| v.parse::<u64>().unwrap())
        })
        .sum();
    assert_eq!(by_kind, int("rays"));
    assert_eq!(by_bounce, int("rays"));
    assert!(int("shadow_rays") > 0 && int("transmitted_rays") > 0);
    for key in ["parse_ms", "render_ms", "write_ms", "mrays_per_s"] {
        let v: f64 = pairs[key].parse().unwrap();
        assert!(v >= 0.0, "{key}");
    }
    if Path::new("/proc/self/status").exists() {
        assert!(int("peak_kib") > 0);
    }
    // The block for people names every kind.
    for word in [
        "eye",
        "shadow",
        "reflected",
        "transmitted",
        "Mrays/s",
        "peak",
    ] {
        assert!(err.contains(word), "{word} missing from {err}");
    }

    // The binary counts what the library counts.
    let scene = Scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/glass_sphere.txt"
    )))
    .unwrap();
    let mut opts = RenderOptions {
        width: 64,
        height: 48,
        ..RenderOptions::default()
    };
    opts.shade.shadows = true;
    opts.shade.shade_back = true;
    opts.shade.specular_fix = true;
    let frame = render(&scene, &opts).unwrap();
    assert_eq!(frame.rays.total(), int("rays"));
    assert_eq!(frame.rays.of(SegmentKind::Shadow), int("shadow_rays"));
}

#[test]
fn ray_counts_do_not_depend_on_the_thread_count() {
    let scene = Scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/facing_mirrors.txt"
    )))
    .unwrap();
    let mut opts = RenderOptions {
        width: 50,
        height: 40,
        ..RenderOptions::default()
    };
    opts.shade.shadows = true;
    opts.threads = 1;
    let one = render(&scene, &opts).unwrap().rays;
    opts.threads = 3;
    let three = render(&scene, &opts).unwrap().rays;
    assert_eq!(one, three);
    assert!(one.by_bounce.len() > 2, "mirrors bounce: {one:?}");
}

/// The bar appears once a render has run for a second (`SHOW_AFTER` in `src/progress.rs`); the
/// renders below run at least twice as long.
const BAR_DUE: Duration = Duration::from_secs(2);

/// Renders the glass sphere with the reference tracer, larger and larger, until one run lasts
/// [`BAR_DUE`]; returns what that run wrote to stderr. With `terminal`, stderr is a
/// pseudo-terminal (`script` from util-linux) and what it received comes back instead.
fn long_render_stderr(terminal: bool, name: &str) -> String {
    let dir = common::scratch_dir(name);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/glass_sphere.txt");
    let out = dir.join("g.png");
    let (mut w, mut h) = (400u32, 300u32);
    loop {
        let (w_s, h_s) = (w.to_string(), h.to_string());
        let args = [
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--size",
            &w_s,
            &h_s,
            "--shadows",
            "--shade-back",
            "--tracer",
            "reference",
        ];
        let start = Instant::now();
        let stderr = if terminal {
            let line: Vec<String> = std::iter::once(env!("CARGO_BIN_EXE_whitted"))
                .chain(args)
                .map(|a| format!("'{a}'"))
                .collect();
            let run = Command::new("script")
                .args(["-qec", &line.join(" "), "/dev/null"])
                .output()
                .expect("`script` (util-linux) runs");
            assert!(run.status.success(), "{:?}", run);
            String::from_utf8_lossy(&run.stdout).into_owned()
        } else {
            let (ok, err) = run(&args);
            assert!(ok, "{err}");
            err
        };
        if start.elapsed() >= BAR_DUE {
            return stderr;
        }
        assert!(
            w < 12800,
            "a {w}x{h} render still ended before the bar was due"
        );
        (w, h) = (w * 2, h * 2);
    }
}

#[test]
fn a_progress_bar_is_drawn_when_stderr_is_a_terminal() {
    let seen = long_render_stderr(true, "stats_progress_tty");
    assert!(seen.contains(" rows, "), "no bar on the terminal: {seen:?}");
}

#[test]
fn no_progress_bar_is_drawn_when_stderr_is_not_a_terminal() {
    let err = long_render_stderr(false, "stats_no_progress");
    assert!(err.is_empty(), "stderr should be empty: {err:?}");
}
