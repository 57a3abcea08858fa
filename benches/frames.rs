//! Whole frames, both tracers, one thread, 128 x 128: our `scenes/*.txt` (with the options their
//! header's "Render:" line gives), and, when `WHITTED_COURSE_DIR` names the course data,
//! every assignment 4 scene (the options of its last handout command line that writes an image)
//! and the 5k-triangle bunny of assignment 5. Criterion reports Melem/s = Mpixels/s. A last
//! group renders the showcase at 256 x 256 on 1 and 2 threads (thread scaling).

use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use whitted::cli::parse_args;
use whitted::{RenderOptions, Scene, Tracer, render};

/// The allocator of the `whitted` binary (huge pages for big blocks), so the figures match it.
#[global_allocator]
static ALLOCATOR: whitted::hugepages::HugePages = whitted::hugepages::HugePages;

const SIZE: u32 = 128;

/// A scene file and the options to render it with.
struct Frame {
    name: String,
    scene: Scene,
    opts: RenderOptions,
}

/// `whitted render` options from the "Render:" command of a scene file's header comment.
fn header_options(path: &Path) -> RenderOptions {
    let text = std::fs::read_to_string(path).expect("readable scene");
    let header: Vec<&str> = text.lines().map_while(|l| l.strip_prefix('#')).collect();
    let header = header.join(" ");
    let flags = header
        .split_once("Render:")
        .unwrap_or_else(|| panic!("{}: no `# Render:` line in the header", path.display()))
        .1
        .split_whitespace()
        .skip_while(|t| !t.starts_with("--"));
    let mut args = vec![path.display().to_string()];
    args.extend(flags.map(String::from));
    args.extend(["-o".to_string(), "frame.png".to_string()]);
    parse_args(&args, true)
        .unwrap_or_else(|e| panic!("{}: bad Render: line: {e}", path.display()))
        .render
}

fn frame(name: String, path: &Path, mut opts: RenderOptions, size: u32) -> Frame {
    opts.width = size;
    opts.height = size;
    opts.threads = 1;
    let scene = Scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    Frame { name, scene, opts }
}

fn our_scenes() -> Vec<Frame> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .map(|e| e.expect("scenes/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "txt"))
        .collect();
    paths.sort();
    paths
        .iter()
        .map(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            frame(name, p, header_options(p), SIZE)
        })
        .collect()
}

/// The course data folder, or `None` with a note when `WHITTED_COURSE_DIR` is unset.
fn course_dir() -> Option<PathBuf> {
    let Some(dir) = std::env::var_os("WHITTED_COURSE_DIR") else {
        eprintln!("note: WHITTED_COURSE_DIR is unset: skipping the course's frames");
        return None;
    };
    Some(Path::new(env!("CARGO_MANIFEST_DIR")).join(dir))
}

/// Each assignment 4 scene with the options of its last handout command writing an image,
/// and the 5k bunny of assignment 5 with the course's default options.
fn course_scenes(course: &Path) -> Vec<Frame> {
    let commands = std::fs::read_to_string(course.join("COMMANDS.txt")).expect("COMMANDS.txt");
    let mut last: Vec<(String, Vec<String>)> = Vec::new();
    for line in commands.lines() {
        let Some(rest) = line.strip_prefix("raytracer ") else {
            continue;
        };
        let args: Vec<String> = rest.split_whitespace().map(String::from).collect();
        let input = args
            .iter()
            .position(|a| a == "-input")
            .map(|i| &args[i + 1]);
        let Some(input) = input.filter(|i| i.starts_with("scene4_")) else {
            continue;
        };
        if !args.iter().any(|a| a == "-output") {
            continue;
        }
        let name = input.trim_end_matches(".txt").to_string();
        last.retain(|(n, _)| *n != name);
        last.push((name, args));
    }
    let a4 = course.join("assignment4");
    let mut frames: Vec<Frame> = last
        .into_iter()
        .map(|(name, args)| {
            let cmd = parse_args(&args, false).unwrap_or_else(|e| panic!("{name}: {e}"));
            frame(name, &a4.join(&cmd.scene), cmd.render, SIZE)
        })
        .collect();
    let bunny = course.join("assignment5/scene5_08_bunny_mesh_5k.txt");
    let args = ["-input".to_string(), bunny.display().to_string()];
    let opts = parse_args(&args, false).expect("course options").render;
    frames.push(frame("scene5_08_bunny_mesh_5k".into(), &bunny, opts, SIZE));
    frames
}

fn bench_frames(c: &mut Criterion, group_name: &str, frames: &[Frame]) {
    let mut group = c.benchmark_group(group_name);
    for f in frames {
        group.throughput(Throughput::Elements(u64::from(
            f.opts.width * f.opts.height,
        )));
        for tracer in [Tracer::Reference, Tracer::Packet] {
            let opts = RenderOptions {
                tracer,
                ..f.opts.clone()
            };
            let id = format!("{}/{}", f.name, format!("{tracer:?}").to_lowercase());
            group.bench_function(id, |b| b.iter(|| render(&f.scene, &opts).expect("renders")));
        }
    }
    group.finish();
}

fn frames(c: &mut Criterion) {
    // the binary's allocator policy for `whitted render` (`whitted::hugepages`)
    whitted::hugepages::keep_freed_memory();
    whitted::hugepages::share_one_heap();
    bench_frames(c, "frames/ours", &our_scenes());
    if let Some(course) = course_dir() {
        bench_frames(c, "frames/course", &course_scenes(&course));
    }
    let showcase = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/showcase.txt");
    let f = frame("showcase".into(), &showcase, header_options(&showcase), 256);
    let mut group = c.benchmark_group("frames/threads");
    group.throughput(Throughput::Elements(256 * 256));
    for threads in [1, 2] {
        let opts = RenderOptions {
            threads,
            ..f.opts.clone()
        };
        group.bench_function(format!("showcase/packet/{threads}t"), |b| {
            b.iter(|| render(&f.scene, &opts).expect("renders"))
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = frames
}
criterion_main!(benches);
