//! The command line. Two styles, freely mixed: the modern one
//! (`whitted render SCENE -o OUT --size W H --shadows ...`) and the course's own, verbatim with
//! `whitted` in place of `raytracer` (`whitted -input scene.txt -size 200 200 -output out.tga
//! -shadows -bounces 10 -weight 0.01 -shade_back -gui`). Every option has a single-dash course
//! spelling and a double-dash one; `_` and `-` are interchangeable inside names.
//! `main` calls [`run`] and turns its error into exit code 2. [`execute`] runs the phases in
//! order: parse, render (with a progress bar on a terminal), write, then the optional ray tree
//! of one pixel and its witness picture, then `--stats`.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::bench::{self, BenchOptions, BenchScene};
use crate::error::{Error, Result};
use crate::math::Vec3;
use crate::options::{self, RenderOptions, Tracer};
use crate::output;
use crate::progress::RowBar;
use crate::raytree::TreeSource;
use crate::render;
use crate::scene::Scene;
use crate::stats::{RayCounts, StatsReport, peak_memory_kib};
use crate::witness::{self, WitnessPlace, WitnessSpec};

/// The text of `whitted --help`.
pub const HELP: &str = "\
whitted: a Whitted-style ray tracer for the MIT 6.837 scene format

USAGE:
    whitted render SCENE -o OUT.png [OPTIONS]
    whitted render SCENE --ray-tree X Y TREE.json [--ray-tree-image TREE.png] [OPTIONS]
    whitted -input SCENE -size W H -output OUT.tga [COURSE OPTIONS]   (the course's command lines)
    whitted bench [--scene NAME|all] [--threads N] [--reps N] [--width W] [--height H]
                                   (ray throughput; see `whitted bench --help`)

OUTPUT (format by extension: .png, .tga, .ppm; written atomically):
    -o, --output FILE          colour image
    --depth NEAR FAR FILE      depth image: white at NEAR, black at FAR and beyond
    --normals FILE             normal image: abs(normal) as RGB

RENDERING (defaults in brackets):
    --size W H                 image size [512 512]
    --shadows                  cast shadow rays [off]
    --bounces N                maximum mirror/refraction depth [5]
    --weight W                 skip rays whose contribution weight is below W [0.01]
    --shade-back               shade back faces (flip their normal) [off: back faces are black]
    --specular-fix             scale the specular term by max(n.l, 0), the lecture's fix
                               [on for `whitted render`]
    --no-specular-fix          only clamp the specular term to 0 where n.l <= 0, as the handout
                               images do [on for course-style command lines]
    --transparent-shadows      tint shadows by the transparent colour of occluders [off]
    --fresnel                  Schlick Fresnel split of transparent colour [off]
    --tracer reference|packet  which tracer renders [packet]
    --threads N                worker threads [all cores]; output is identical for any N
    --max-pixels N             refuse larger images [67108864]
    --max-bounces N            refuse larger bounce counts [1000]
    --stats                    print ray counts by kind and bounce, time per phase, Mrays/s
                               and peak memory to stderr, then one `stats: key=value ...` line
                               (a progress bar shows on stderr, only when it is a terminal,
                               for renders over a second)

RAY TREE (every ray one pixel spawns; -o is optional with it):
    --ray-tree X Y FILE.json   trace pixel (X, Y) again after the render (x from the left, y from
                               the top, as in the image) and write its tree: per segment the kind
                               (eye, shadow, reflected, transmitted), parent, depth, weight,
                               origin, end, primitive and material hit, light, blocked. Ends: the
                               hit point; the point light; for a blocked shadow ray its nearest
                               occluder; for escaping rays and shadow rays to directional lights,
                               100 units along the ray
    --ray-tree-image FILE.png  with --ray-tree: the scene seen by a witness camera, same size as
                               the image, with the tree drawn over it: eye gray, shadow green
                               (blocked: dashed dark green, X at the occluder), reflected red,
                               transmitted blue, the main camera a white frustum, point lights
                               yellow; parts hidden behind surfaces are drawn fainter; planes
                               and lone triangles the witness sees from behind are left out
                               (to look into rooms)
    --witness-orbit YAW PITCH  default witness placement: it looks at the eye ray's first hit
                               from the main camera's side turned YAW degrees about the vertical
                               axis (positive: to the right) and raised PITCH degrees, as near as
                               keeps the main camera and the tree's hits in view [40 20]
    --witness-camera CX CY CZ LX LY LZ
                               place the witness camera at C looking at L instead
    --witness-angle DEG        witness field of view [60]

COURSE OPTIONS (single dash, as in the handouts): -input -output -size -depth -normals -shadows
    -bounces -weight -shade_back -stats; -gui, -tessellation T P and -gouraud are accepted with a
    note (there is no OpenGL preview); -grid NX NY NZ is accepted and ignored (whitted uses a BVH).

EXIT CODES: 0 success, 2 any error (one line on stderr: `error: path:line:col: expected ...`).
";

/// The text of `whitted bench --help`.
pub const BENCH_HELP: &str = "\
whitted bench: ray throughput on the four procedural scenes of shared/bench/SCENES.md

USAGE:
    whitted bench [--scene NAME|all] [--threads N] [--reps N] [--width W] [--height H]

OPTIONS (defaults in brackets):
    --scene NAME|all    spheres64, spheres4096, torus100k, torus1m or all [all]
    --threads N         worker threads tracing the rays; 0 means all cores [1]
    --reps N            repetitions; each figure is the best of them [3]
    --width W           image width, a multiple of 4 [1024]
    --height H          image height, a multiple of 2 [1024]

Prints `CSV,<scene>,<kernel>,<rays>,<hits>,<ms>,<Mrays/s>` per kernel (primary, shadow, mirror,
diffuse: 8-ray packets; the same with `_scalar`: one ray at a time) and
`CSV,<scene>,build_1t_ms,<primitives>,0,<ms>,<Mprims/s>` for the BVH build on one thread.
";

/// Everything the command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct Command {
    pub scene: PathBuf,
    pub output: Option<PathBuf>,
    pub depth: Option<(f32, f32, PathBuf)>,
    pub normals: Option<PathBuf>,
    pub render: RenderOptions,
    pub stats: bool,
    /// `--ray-tree X Y FILE.json`: the pixel whose ray tree to write, and where.
    pub ray_tree: Option<(u32, u32, PathBuf)>,
    /// `--ray-tree-image FILE`: the witness picture of that tree.
    pub ray_tree_image: Option<PathBuf>,
    /// Where the witness camera of the picture stands.
    pub witness: WitnessSpec,
    /// Notes for stderr about accepted-but-inert options.
    pub notes: Vec<String>,
}

/// Runs the program on `args` (including the program name).
pub fn run(args: Vec<OsString>) -> Result<()> {
    let args: Vec<String> = args
        .into_iter()
        .skip(1)
        .map(|a| {
            a.into_string()
                .map_err(|a| Error::Usage(format!("argument {a:?} is not valid UTF-8")))
        })
        .collect::<Result<_>>()?;
    match args.first().map(String::as_str) {
        None | Some("help" | "-h" | "--help" | "-help") => {
            print!("{HELP}");
            Ok(())
        }
        Some("-V" | "--version") => {
            println!("whitted {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        Some("render") => execute(parse_args(&args[1..], true)?),
        Some("bench") => match parse_bench_args(&args[1..])? {
            Some(opts) => bench::run(&opts),
            None => {
                print!("{BENCH_HELP}");
                Ok(())
            }
        },
        Some(a) if a.starts_with('-') => execute(parse_args(&args, false)?),
        Some(other) => Err(Error::Usage(format!(
            "unknown command `{other}`: expected `render`, `bench` or course options like -input"
        ))),
    }
}

fn value<'a>(option: &str, value: Option<&'a String>, what: &str) -> Result<&'a str> {
    value
        .map(String::as_str)
        .ok_or_else(|| Error::Usage(format!("option {option}: expected {what}, found nothing")))
}

fn number<T: std::str::FromStr>(option: &str, v: Option<&String>, what: &str) -> Result<T> {
    let v = value(option, v, what)?;
    v.parse::<T>()
        .map_err(|_| Error::Usage(format!("option {option}: expected {what}, found `{v}`")))
}

fn finite(option: &str, value: Option<&String>, what: &str) -> Result<f32> {
    let v: f32 = number(option, value, what)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Usage(format!(
            "option {option}: expected {what}, found `{v}`"
        )))
    }
}

fn path(option: &str, value: Option<&String>) -> Result<PathBuf> {
    match value {
        Some(v) if !v.is_empty() => Ok(PathBuf::from(v)),
        _ => Err(Error::Usage(format!(
            "option {option}: expected a file name, found nothing"
        ))),
    }
}

/// Parses options of either style. `modern` allows a positional scene path.
pub fn parse_args(args: &[String], modern: bool) -> Result<Command> {
    let mut scene = None;
    let mut cmd = Command {
        scene: PathBuf::new(),
        output: None,
        depth: None,
        normals: None,
        render: RenderOptions::default(),
        stats: false,
        ray_tree: None,
        ray_tree_image: None,
        witness: WitnessSpec::default(),
        notes: Vec::new(),
    };
    // The course's command lines reproduce the handout images, which clamp the specular term
    // without the lecture's fix; the modern command uses the fix.
    cmd.render.shade.specular_fix = modern;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let name = if let Some(n) = arg.strip_prefix("--") {
            n
        } else if let Some(n) = arg.strip_prefix('-').filter(|n| !n.is_empty()) {
            n
        } else if modern && scene.is_none() {
            scene = Some(PathBuf::from(arg));
            continue;
        } else {
            return Err(Error::Usage(format!("unexpected argument `{arg}`")));
        };
        let name = name.replace('-', "_");
        let opt = arg.as_str();
        let sh = &mut cmd.render.shade;
        match name.as_str() {
            "input" | "i" => scene = Some(path(opt, it.next())?),
            "output" | "o" => cmd.output = Some(path(opt, it.next())?),
            "size" => {
                cmd.render.width = number(opt, it.next(), "a width in pixels")?;
                cmd.render.height = number(opt, it.next(), "a height in pixels")?;
            }
            "depth" => {
                let near = finite(opt, it.next(), "a near distance")?;
                let far = finite(opt, it.next(), "a far distance")?;
                if far == near {
                    return Err(Error::Usage(format!(
                        "option {opt}: expected different near and far distances, found {near} twice"
                    )));
                }
                cmd.depth = Some((near, far, path(opt, it.next())?));
            }
            "normals" => cmd.normals = Some(path(opt, it.next())?),
            "shadows" => sh.shadows = true,
            "bounces" => sh.bounces = number(opt, it.next(), "a bounce count")?,
            "weight" => sh.weight = finite(opt, it.next(), "a weight")?,
            "shade_back" => sh.shade_back = true,
            "no_specular_fix" => sh.specular_fix = false,
            "specular_fix" => sh.specular_fix = true,
            "transparent_shadows" => sh.transparent_shadows = true,
            "fresnel" => sh.fresnel = true,
            "tracer" => {
                let v = it.next();
                cmd.render.tracer = v.and_then(|v| Tracer::from_name(v)).ok_or_else(|| {
                    Error::Usage(format!(
                        "option {opt}: expected `reference` or `packet`, found {}",
                        v.map_or("nothing".into(), |v| format!("`{v}`"))
                    ))
                })?;
            }
            "threads" => cmd.render.threads = number(opt, it.next(), "a thread count")?,
            "max_pixels" => cmd.render.max_pixels = number(opt, it.next(), "a pixel count")?,
            "max_bounces" => cmd.render.max_bounces = number(opt, it.next(), "a bounce count")?,
            "stats" => cmd.stats = true,
            "ray_tree" => {
                let x = number(opt, it.next(), "a pixel column X")?;
                let y = number(opt, it.next(), "a pixel row Y")?;
                cmd.ray_tree = Some((x, y, path(opt, it.next())?));
            }
            "ray_tree_image" => cmd.ray_tree_image = Some(path(opt, it.next())?),
            "witness_orbit" => {
                let yaw_deg = finite(opt, it.next(), "a yaw angle in degrees")?;
                let pitch_deg = finite(opt, it.next(), "a pitch angle in degrees")?;
                cmd.witness.place = WitnessPlace::Orbit { yaw_deg, pitch_deg };
            }
            "witness_camera" => {
                let mut v = [0.0f32; 6];
                for (k, what) in ["CX", "CY", "CZ", "LX", "LY", "LZ"].iter().enumerate() {
                    v[k] = finite(opt, it.next(), &format!("coordinate {what}"))?;
                }
                let center = Vec3::new(v[0], v[1], v[2]);
                let look_at = Vec3::new(v[3], v[4], v[5]);
                if center == look_at {
                    return Err(Error::Usage(format!(
                        "option {opt}: expected a look-at point different from the position"
                    )));
                }
                cmd.witness.place = WitnessPlace::At { center, look_at };
            }
            "witness_angle" => {
                let a = finite(opt, it.next(), "a field of view in degrees")?;
                if !(a > 0.0 && a < 180.0) {
                    return Err(Error::Usage(format!(
                        "option {opt}: expected a field of view between 0 and 180 degrees, found {a}"
                    )));
                }
                cmd.witness.angle_deg = a;
            }
            "gui" | "gouraud" => cmd.notes.push(format!(
                "note: {opt} ignored: whitted has no OpenGL preview"
            )),
            "tessellation" => {
                let _: u32 = number(opt, it.next(), "theta steps")?;
                let _: u32 = number(opt, it.next(), "phi steps")?;
                cmd.notes.push(format!(
                    "note: {opt} ignored: whitted has no OpenGL preview"
                ));
            }
            "grid" => {
                for what in ["nx", "ny", "nz"] {
                    let _: u32 = number(opt, it.next(), what)?;
                }
            }
            "visualize_grid" | "visualize_grid_count" => {
                return Err(Error::Usage(format!(
                    "option {opt} is not supported: whitted accelerates with a BVH, not a grid"
                )));
            }
            "random_samples" | "uniform_samples" | "jittered_samples" | "box_filter"
            | "tent_filter" | "gaussian_filter" | "render_samples" | "render_filter" => {
                return Err(Error::Usage(format!(
                    "option {opt} (assignment 7 sampling and filtering) is not supported yet"
                )));
            }
            _ => return Err(Error::Usage(format!("unknown option `{arg}`"))),
        }
    }
    cmd.scene = scene.ok_or_else(|| {
        Error::Usage(if modern {
            "expected a scene file: whitted render SCENE -o OUT.png".to_string()
        } else {
            "expected a scene file: -input SCENE".to_string()
        })
    })?;
    if modern
        && cmd.output.is_none()
        && cmd.depth.is_none()
        && cmd.normals.is_none()
        && cmd.ray_tree.is_none()
    {
        return Err(Error::Usage(
            "expected an output file: -o OUT.png (or --depth/--normals/--ray-tree)".to_string(),
        ));
    }
    if cmd.ray_tree_image.is_some() && cmd.ray_tree.is_none() {
        return Err(Error::Usage(
            "option --ray-tree-image needs --ray-tree X Y FILE.json to say which pixel".to_string(),
        ));
    }
    if let Some((x, y, _)) = &cmd.ray_tree {
        options::check_pixel(*x, *y, &cmd.render)
            .map_err(|e| Error::Usage(format!("option --ray-tree: {}", usage_text(e))))?;
    }
    Ok(cmd)
}

/// Parses the arguments after `bench`; `None` asks for the help text.
pub fn parse_bench_args(args: &[String]) -> Result<Option<BenchOptions>> {
    let mut opts = BenchOptions::default();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let opt = arg.as_str();
        match opt {
            "-h" | "--help" | "-help" => return Ok(None),
            "--scene" => {
                let v = value(opt, it.next(), "a scene name or `all`")?;
                opts.scenes = if v == "all" {
                    BenchScene::ALL.to_vec()
                } else {
                    vec![BenchScene::from_name(v).ok_or_else(|| {
                        Error::Usage(format!(
                            "option --scene: expected one of spheres64, spheres4096, \
                             torus100k, torus1m or all, found `{v}`"
                        ))
                    })?]
                };
            }
            "--threads" => opts.threads = number(opt, it.next(), "a thread count")?,
            "--reps" => {
                opts.reps = number(opt, it.next(), "a repetition count")?;
                if !(1..=1000).contains(&opts.reps) {
                    return Err(Error::Usage(format!(
                        "option --reps: expected 1 to 1000 repetitions, found {}",
                        opts.reps
                    )));
                }
            }
            "--width" => opts.width = number(opt, it.next(), "a width in pixels")?,
            "--height" => opts.height = number(opt, it.next(), "a height in pixels")?,
            _ => return Err(Error::Usage(format!("bench: unknown option `{arg}`"))),
        }
    }
    bench::check_size(opts.width, opts.height)?;
    Ok(Some(opts))
}

/// The message of a usage error without the `--help` hint (it is added once, outside).
fn usage_text(e: Error) -> String {
    match e {
        Error::Usage(msg) => msg,
        e => e.to_string(),
    }
}

/// Loads the scene, renders it and writes the requested images, ray tree and statistics.
/// Notes about inert course options follow a success (an error stays the only line).
pub fn execute(cmd: Command) -> Result<()> {
    let notes = cmd.notes.clone();
    execute_quietly(cmd)?;
    for note in &notes {
        eprintln!("{note}");
    }
    Ok(())
}

fn execute_quietly(cmd: Command) -> Result<()> {
    options::check_options(&cmd.render)?;
    let (w, h) = (cmd.render.width, cmd.render.height);
    let outputs: Vec<&Path> = cmd
        .output
        .iter()
        .chain(cmd.depth.as_ref().map(|d| &d.2))
        .chain(cmd.normals.iter())
        .map(PathBuf::as_path)
        .collect();
    for out in outputs.iter().chain(cmd.ray_tree_image.as_deref().iter()) {
        output::check_writable(out, w, h)?;
    }
    if let Some((_, _, json)) = &cmd.ray_tree {
        output::check_creatable(json, "write ray tree")?;
    }
    let mut phases: Vec<(&'static str, Duration)> = Vec::new();
    let t0 = Instant::now();
    let scene = Scene::load(&cmd.scene)?;
    phases.push(("parse", t0.elapsed()));
    if outputs.is_empty() && cmd.ray_tree.is_none() {
        eprintln!("note: no -output, -depth or -normals given: the scene parsed, nothing to write");
        return Ok(());
    }
    let mut rays = RayCounts::default();
    let (mut accel, mut bounce_time) = (None, Vec::new());
    if !outputs.is_empty() {
        let t1 = Instant::now();
        let bar = RowBar::new("render", h);
        let frame = render::render_with_progress(&scene, &cmd.render, &|rows| bar.rows_done(rows))?;
        bar.finish();
        phases.push(("render", t1.elapsed()));
        let t2 = Instant::now();
        if let Some(out) = &cmd.output {
            output::write_image(&output::color_image(&frame), out)?;
        }
        if let Some((near, far, out)) = &cmd.depth {
            output::write_image(&output::depth_image(&frame, *near, *far), out)?;
        }
        if let Some(out) = &cmd.normals {
            output::write_image(&output::normal_image(&frame), out)?;
        }
        phases.push(("write", t2.elapsed()));
        rays = frame.rays;
        accel = frame.accel;
        bounce_time = frame.bounce_time;
    }
    if let Some((x, y, json)) = &cmd.ray_tree {
        let t3 = Instant::now();
        write_ray_tree(&cmd, &scene, *x, *y, json)?;
        phases.push(("ray_tree", t3.elapsed()));
    }
    if cmd.stats {
        let report = StatsReport {
            scene: cmd.scene.display().to_string(),
            primitives: scene.primitive_count(),
            lights: scene.lights.len(),
            width: w,
            height: h,
            tracer: cmd.render.tracer.name(),
            threads: match cmd.render.threads {
                0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
                n => n,
            },
            rays,
            phases,
            peak_kib: peak_memory_kib(),
            accel,
            bounce_time,
        };
        eprint!("{}", report.human());
        eprintln!("{}", report.line());
    }
    Ok(())
}

/// Traces pixel `(x, y)` again, recording its ray tree; writes it as JSON to `json` and, when
/// asked, renders the witness view and draws the tree over it.
fn write_ray_tree(cmd: &Command, scene: &Scene, x: u32, y: u32, json: &Path) -> Result<()> {
    let opts = &cmd.render;
    let (tree, _) = render::trace_ray_tree(scene, opts, x, y)?;
    let scene_name = cmd.scene.display().to_string();
    let source = TreeSource {
        scene: &scene_name,
        tracer: opts.tracer.name(),
        pixel: [x, y],
        image_size: [opts.width, opts.height],
    };
    output::write_atomic_as(json, tree.to_json(&source).as_bytes(), "write ray tree")?;
    let Some(image) = &cmd.ray_tree_image else {
        return Ok(());
    };
    let camera =
        witness::witness_camera(&scene.camera, &tree, opts.width, opts.height, &cmd.witness);
    let witness_scene = Scene {
        camera: camera.clone(),
        root: witness::cutaway(&scene.root, camera.center),
        ..scene.clone()
    };
    let bar = RowBar::new("witness", opts.height);
    let frame = render::render_with_progress(&witness_scene, opts, &|rows| bar.rows_done(rows))?;
    bar.finish();
    let title = format!("ray tree of pixel ({x}, {y})");
    let picture = witness::draw_ray_tree(
        &frame,
        &camera,
        &scene.camera,
        (opts.width, opts.height),
        &tree,
        &title,
    );
    output::write_image(&picture, image)
}
