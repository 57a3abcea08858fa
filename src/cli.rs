//! The command line. Two styles, freely mixed: the modern one
//! (`whitted render SCENE -o OUT --size W H --shadows ...`) and the course's own, verbatim with
//! `whitted` in place of `raytracer` (`whitted -input scene.txt -size 200 200 -output out.tga
//! -shadows -bounces 10 -weight 0.01 -shade_back -gui`). Every option has a single-dash course
//! spelling and a double-dash one; `_` and `-` are interchangeable inside names.
//! `main` calls [`run`] and turns its error into exit code 2.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::output;
use crate::render::{self, RenderOptions, Tracer};
use crate::scene::Scene;

/// The text of `whitted --help`.
pub const HELP: &str = "\
whitted: a Whitted-style ray tracer for the MIT 6.837 scene format

USAGE:
    whitted render SCENE -o OUT.png [OPTIONS]
    whitted -input SCENE -size W H -output OUT.tga [COURSE OPTIONS]   (the course's command lines)

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
    --tracer reference|packet  which tracer renders [reference]
    --threads N                worker threads [all cores]; output is identical for any N
    --max-pixels N             refuse larger images [67108864]
    --max-bounces N            refuse larger bounce counts [1000]
    --stats                    print timings and ray counts to stderr

COURSE OPTIONS (single dash, as in the handouts): -input -output -size -depth -normals -shadows
    -bounces -weight -shade_back -stats; -gui, -tessellation T P and -gouraud are accepted with a
    note (there is no OpenGL preview); -grid NX NY NZ is accepted and ignored (whitted uses a BVH).

EXIT CODES: 0 success, 2 any error (one line on stderr: `error: path:line:col: expected ...`).
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
        Some(a) if a.starts_with('-') => execute(parse_args(&args, false)?),
        Some(other) => Err(Error::Usage(format!(
            "unknown command `{other}`: expected `render`, `bench` or course options like -input"
        ))),
    }
}

fn number<T: std::str::FromStr>(option: &str, value: Option<&String>, what: &str) -> Result<T> {
    let Some(v) = value else {
        return Err(Error::Usage(format!(
            "option {option}: expected {what}, found nothing"
        )));
    };
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
    if modern && cmd.output.is_none() && cmd.depth.is_none() && cmd.normals.is_none() {
        return Err(Error::Usage(
            "expected an output file: -o OUT.png (or --depth/--normals)".to_string(),
        ));
    }
    Ok(cmd)
}

/// Loads the scene, renders it and writes the requested images.
pub fn execute(cmd: Command) -> Result<()> {
    for note in &cmd.notes {
        eprintln!("{note}");
    }
    render::check_options(&cmd.render)?;
    let outputs: Vec<&Path> = cmd
        .output
        .iter()
        .chain(cmd.depth.as_ref().map(|d| &d.2))
        .chain(cmd.normals.iter())
        .map(PathBuf::as_path)
        .collect();
    for out in &outputs {
        output::check_writable(out, cmd.render.width, cmd.render.height)?;
    }
    let t0 = Instant::now();
    let scene = Scene::load(&cmd.scene)?;
    render::check_scene(&scene, &cmd.scene)?;
    let load_time = t0.elapsed();
    if outputs.is_empty() {
        eprintln!("note: no -output, -depth or -normals given: the scene parsed, nothing to write");
        return Ok(());
    }
    let t1 = Instant::now();
    let frame = render::render(&scene, &cmd.render)?;
    let render_time = t1.elapsed();
    if let Some(out) = &cmd.output {
        output::write_image(&output::color_image(&frame), out)?;
    }
    if let Some((near, far, out)) = &cmd.depth {
        output::write_image(&output::depth_image(&frame, *near, *far), out)?;
    }
    if let Some(out) = &cmd.normals {
        output::write_image(&output::normal_image(&frame), out)?;
    }
    if cmd.stats {
        let pixels = frame.width as u64 * frame.height as u64;
        eprintln!(
            "scene: {} primitives, loaded in {:.1} ms\nrender: {}x{} with the {:?} tracer in {:.1} ms",
            scene.primitive_count(),
            load_time.as_secs_f64() * 1e3,
            frame.width,
            frame.height,
            cmd.render.tracer,
            render_time.as_secs_f64() * 1e3
        );
        eprintln!(
            "stats: primitives={} load_ms={:.3} render_ms={:.3} pixels={pixels}",
            scene.primitive_count(),
            load_time.as_secs_f64() * 1e3,
            render_time.as_secs_f64() * 1e3
        );
    }
    Ok(())
}
