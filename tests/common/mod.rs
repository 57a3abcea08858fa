//! Helpers shared by the integration tests: the course data folder, image loading and comparison.
#![allow(dead_code)] // reason: each test binary uses a different subset of these helpers

use std::path::{Path, PathBuf};

use whitted::output::Rgb8;

/// The course data folder named by `WHITTED_COURSE_DIR`, or `None` (the caller prints a skip).
pub fn course_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("WHITTED_COURSE_DIR")?;
    let dir = PathBuf::from(dir);
    let dir = if dir.is_relative() {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(dir)
    } else {
        dir
    };
    assert!(
        dir.join("COMMANDS.txt").is_file(),
        "WHITTED_COURSE_DIR={} has no COMMANDS.txt",
        dir.display()
    );
    Some(dir)
}

/// Reads an uncompressed 24-bit TGA as written by `whitted` (bottom-up or top-down).
pub fn read_tga(path: &Path) -> Rgb8 {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(bytes[2], 2, "uncompressed true-colour TGA expected");
    assert_eq!(bytes[16], 24, "24-bit TGA expected");
    let id_len = bytes[0] as usize;
    let w = u16::from_le_bytes([bytes[12], bytes[13]]) as usize;
    let h = u16::from_le_bytes([bytes[14], bytes[15]]) as usize;
    let top_down = bytes[17] & 0x20 != 0;
    let pixels = &bytes[18 + id_len..];
    let mut data = vec![0u8; w * h * 3];
    for row in 0..h {
        let src_row = if top_down { row } else { h - 1 - row };
        for x in 0..w {
            let s = (src_row * w + x) * 3;
            let d = (row * w + x) * 3;
            data[d] = pixels[s + 2];
            data[d + 1] = pixels[s + 1];
            data[d + 2] = pixels[s];
        }
    }
    Rgb8 {
        width: w as u32,
        height: h as u32,
        data,
    }
}

/// Reads a PNG, TGA or PPM written by `whitted`.
pub fn read_image(path: &Path) -> Rgb8 {
    match path.extension().and_then(|e| e.to_str()) {
        Some("tga") => read_tga(path),
        Some("ppm") => {
            let bytes = std::fs::read(path).unwrap();
            let text_end = bytes
                .iter()
                .enumerate()
                .filter(|(_, b)| **b == b'\n')
                .nth(2)
                .unwrap()
                .0;
            let header = std::str::from_utf8(&bytes[..text_end]).unwrap();
            let dims: Vec<u32> = header
                .split_whitespace()
                .skip(1)
                .take(2)
                .map(|v| v.parse().unwrap())
                .collect();
            Rgb8 {
                width: dims[0],
                height: dims[1],
                data: bytes[text_end + 1..].to_vec(),
            }
        }
        _ => whitted::output::read_png(path).unwrap(),
    }
}

/// How two images differ: the share of pixels with some channel off by more than `tol`, and
/// the largest channel difference.
#[derive(Clone, Copy, Debug)]
pub struct Diff {
    pub pixels: usize,
    pub over: usize,
    pub max: u8,
}

impl Diff {
    pub fn fraction_over(&self) -> f64 {
        self.over as f64 / self.pixels.max(1) as f64
    }
}

/// Compares two images of the same size channel by channel.
pub fn diff(a: &Rgb8, b: &Rgb8, tol: u8) -> Diff {
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "image sizes differ"
    );
    let mut over = 0;
    let mut max = 0;
    for (pa, pb) in a.data.chunks_exact(3).zip(b.data.chunks_exact(3)) {
        let d = pa
            .iter()
            .zip(pb)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        max = max.max(d);
        if d > tol {
            over += 1;
        }
    }
    Diff {
        pixels: a.data.len() / 3,
        over,
        max,
    }
}

/// The scene files (`*.txt`) of `dir`, sorted.
pub fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "txt"))
        .collect();
    files.sort();
    files
}

/// Our own scenes, `scenes/*.txt`.
pub fn our_scenes() -> Vec<PathBuf> {
    scene_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes"))
}

/// A fresh empty folder under the target directory for one test.
pub fn scratch_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Renders `scene` with both tracers and returns (reference, packet) frames.
pub fn render_both(
    scene: &whitted::Scene,
    opts: &whitted::RenderOptions,
) -> (whitted::Frame, whitted::Frame) {
    let mut o = opts.clone();
    o.tracer = whitted::Tracer::Reference;
    let reference = whitted::render(scene, &o).expect("reference render");
    o.tracer = whitted::Tracer::Packet;
    let packet = whitted::render(scene, &o).expect("packet render");
    (reference, packet)
}

/// The equivalence criterion between the two tracers: at most 0.1% of pixels differ by more
/// than 2/255 in any channel. Returns the difference for reporting.
pub fn assert_equivalent(a: &Rgb8, b: &Rgb8, what: &str) -> Diff {
    let d = diff(a, b, 2);
    assert!(
        d.fraction_over() <= 0.001,
        "{what}: {} of {} pixels ({:.3}%) differ by more than 2/255 (max {})",
        d.over,
        d.pixels,
        100.0 * d.fraction_over(),
        d.max
    );
    d
}

/// A small deterministic random number generator (PCG32) for seeded test scenes.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        let mut r = Rng(seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407));
        r.next_u32();
        r
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform integer in [0, n).
    pub fn below(&mut self, n: u32) -> u32 {
        self.next_u32() % n
    }

    pub fn chance(&mut self, p: f32) -> bool {
        self.f32() < p
    }
}

/// What one run of the `whitted` binary did.
pub struct Run {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
}

/// Runs the `whitted` binary with `args` in `dir`.
pub fn whitted(dir: &Path, args: &[&str]) -> Run {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    Run {
        code: out.status.code(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

impl Run {
    /// Asserts the run failed with exit code 2 and one line `error: {start}...` on stderr, and
    /// returns that line without `error: `.
    pub fn assert_error(&self, start: &str) -> String {
        assert_eq!(self.code, Some(2), "expected exit code 2:\n{}", self.stderr);
        assert!(
            !self.stderr.contains("panicked"),
            "panicked:\n{}",
            self.stderr
        );
        assert_eq!(
            self.stderr.lines().count(),
            1,
            "expected one line on stderr:\n{}",
            self.stderr
        );
        let msg = self.stderr.trim_end().strip_prefix("error: ").unwrap_or("");
        assert!(
            msg.starts_with(start),
            "expected `error: {start}...`, found:\n{}",
            self.stderr
        );
        msg.to_string()
    }
}

/// The sorted names of the entries of `dir`.
pub fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Asserts that no pixel of `frame` holds a NaN or infinite value (colour anywhere; depth and
/// normal where the primary ray hit).
pub fn assert_finite(frame: &whitted::Frame, what: &str) {
    if let Some((x, y)) = frame.non_finite_pixel() {
        let i = (y * frame.width + x) as usize;
        panic!(
            "{what}: pixel ({x}, {y}) is not finite: colour {} depth {} normal {}",
            frame.color[i], frame.depth[i], frame.normal[i]
        );
    }
}

/// Copies `scenes/NAME` (and every mesh beside it) into `dir`, returning the scene's path.
pub fn copy_scene(name: &str, dir: &Path) -> PathBuf {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "obj") {
            std::fs::copy(&path, dir.join(path.file_name().unwrap())).unwrap();
        }
    }
    let to = dir.join(name);
    std::fs::copy(scenes.join(name), &to).unwrap();
    to
}

/// A valid camera line for scenes built in tests (line 1 of [`in_group`]).
pub const CAMERA: &str = "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }\n";
/// A valid one-material block (line 2 of [`in_group`]).
pub const MATERIALS: &str = "Materials { numMaterials 1 Material { diffuseColor 1 0 0 } }\n";
/// A unit sphere at the origin.
pub const SPHERE: &str = "Sphere { center 0 0 0 radius 1 }";

/// A scene: camera on line 1, materials on line 2, `Group {` on line 3, `body` from line 4 (so
/// errors in `body` have known positions).
pub fn in_group(body: &str) -> String {
    format!("{CAMERA}{MATERIALS}Group {{ numObjects 1\n{body}\n}}\n")
}
