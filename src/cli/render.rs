//! `whitted render` and the course's command lines: [`parse_args`] runs a command line through
//! the table of `render_options.rs` into a [`Command`], then checks what no single option can
//! (a scene and an output are given, no file is given for two outputs, the ray-tree pixel lies
//! in the image); [`help`] prints the table. `execute.rs` runs the parsed [`Command`].

use std::path::{Component, Path, PathBuf};

pub use super::render_options::{Command, OPTIONS};
use super::sampling_options::Sampling;
use super::table::{self, Parsed};
use crate::error::{Error, Result};
use crate::options::{self, GridOptions, Window};

/// The usage lines of `whitted render`, shared with the overview of `whitted --help`.
pub const USAGE: &str = concat!(
    "    whitted render SCENE -o OUT.png [OPTIONS]\n",
    "    whitted render SCENE --ray-tree X Y TREE.json [--ray-tree-image TREE.png] [OPTIONS]\n",
    "    whitted -input SCENE -size W H -output OUT.tga [OPTIONS]   (the course's command lines)\n",
);

/// The last paragraph of the render help and the overview.
pub const EXIT_CODES: &str = "EXIT CODES: 0 success, 2 any error (one line on stderr: \
                              `error: path:line:col: expected ...`).\n";

/// The text of `whitted render --help`: the usage and every option of [`OPTIONS`].
pub fn help() -> String {
    format!(
        "whitted render: render a scene file of the MIT 6.837 format to images\n\n\
         USAGE:\n{USAGE}\n{}",
        options_help()
    )
}

/// The option sections of the render help, the course's spellings and the exit codes; the
/// overview of `whitted --help` shows them too.
pub fn options_help() -> String {
    let course: Vec<&str> = OPTIONS
        .options
        .iter()
        .filter(|o| !o.long.is_empty() && !o.course.is_empty())
        .map(|o| o.course)
        .collect();
    let note = format!(
        "Every option takes one dash or two, and `_` or `-` inside its name: the course's \
         spellings {} are those of the options above.",
        course.join(" ")
    );
    format!(
        "{}{}\n\n{EXIT_CODES}",
        table::help(&OPTIONS),
        table::wrap(&note, 100).join("\n")
    )
}

/// Parses options of either style. `modern` allows a positional scene path and turns the
/// lecture's specular fix on; `None` asks for the help text.
pub fn parse_render_args(args: &[String], modern: bool) -> Result<Option<Command>> {
    let mut cmd = Command::new(modern);
    let positional = modern.then_some("--input");
    if table::parse(&OPTIONS, args, &mut cmd, positional)? == Parsed::Help {
        return Ok(None);
    }
    (cmd.render.sampler, cmd.render.filter) = cmd.sampling.resolve()?;
    // Depth and normals cost 16 bytes a pixel: keep them only for the images that show them.
    cmd.render.depth_normal = cmd.depth.is_some() || cmd.normals.is_some();
    cmd.render.keep_samples = cmd.sampling.render_samples.is_some();
    check(&cmd, modern)?;
    cmd.render.grid = grid_options(&cmd)?;
    if let Some((i, n)) = cmd.tile {
        if cmd.render.crop.is_some() {
            return Err(Error::Usage(
                "options --crop and --tile both pick the window to render: expected one of them"
                    .to_string(),
            ));
        }
        cmd.render.crop = Some(Window::tile(i, n, cmd.render.width, cmd.render.height)?);
    }
    if let (Some((_, typed)), true) = (&cmd.grid_view, cmd.sampling != Sampling::default()) {
        return Err(Error::Usage(format!(
            "option {typed} draws the grid with one ray per pixel: expected no sampling, \
             filter or sample picture options with it"
        )));
    }
    if cmd.render.crop.is_some() && cmd.render.grid.is_some_and(|g| g.view.is_some()) {
        return Err(Error::Usage(
            "options --crop and --tile render pieces of the scene's image, not of the grid \
             picture: expected no --visualize-grid with them"
                .to_string(),
        ));
    }
    Ok(Some(cmd))
}

/// The grid the options ask for: `--grid` with the view of `--visualize-grid(-count)`, which
/// needs it.
fn grid_options(cmd: &Command) -> Result<Option<GridOptions>> {
    match (cmd.grid, &cmd.grid_view) {
        (Some(cells), view) => Ok(Some(GridOptions {
            cells,
            view: view.as_ref().map(|v| v.0),
            max_cells: cmd.max_grid_cells,
        })),
        (None, Some((_, typed))) => Err(Error::Usage(format!(
            "option {typed} needs -grid NX NY NZ to say which grid to draw"
        ))),
        (None, None) => Ok(None),
    }
}

/// [`parse_render_args`] for a command line that must render (`--help` is an error).
pub fn parse_args(args: &[String], modern: bool) -> Result<Command> {
    parse_render_args(args, modern)?
        .ok_or_else(|| Error::Usage("expected a render, found --help".to_string()))
}

/// The checks across options, once every option is read.
fn check(cmd: &Command, modern: bool) -> Result<()> {
    if cmd.scene.as_os_str().is_empty() {
        return Err(Error::Usage(if modern {
            "expected a scene file: whitted render SCENE -o OUT.png".to_string()
        } else {
            "expected a scene file: -input SCENE".to_string()
        }));
    }
    if modern
        && cmd.output.is_none()
        && cmd.depth.is_none()
        && cmd.normals.is_none()
        && cmd.ray_tree.is_none()
        && cmd.heatmap.is_none()
        && cmd.sampling.render_samples.is_none()
        && cmd.sampling.render_filter.is_none()
    {
        return Err(Error::Usage(
            "expected an output file: -o OUT.png (or --depth/--normals/--ray-tree/--heatmap/\
             --render-samples/--render-filter)"
                .to_string(),
        ));
    }
    for (option, picture, extra) in [
        ("--render-samples", &cmd.sampling.render_samples, 0),
        ("--render-filter", &cmd.sampling.render_filter, 1),
    ] {
        if let Some((_, zoom)) = picture {
            let spelling = OPTIONS.get(option).map_or(option, |o| o.spelling(!modern));
            check_picture(spelling, &cmd.render, *zoom, extra)?;
        }
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
    check_distinct_outputs(cmd, !modern)
}

/// Refuses a picture of the image zoomed `zoom` times (plus `extra` pixels on each axis) with
/// more pixels than `--max-pixels` allows.
fn check_picture(option: &str, opts: &options::RenderOptions, zoom: u32, extra: u64) -> Result<()> {
    let (w, h) = (
        opts.width as u64 * zoom as u64 + extra,
        opts.height as u64 * zoom as u64 + extra,
    );
    if w.saturating_mul(h) > opts.max_pixels || w > u32::MAX as u64 || h > u32::MAX as u64 {
        return Err(Error::Limit(format!(
            "option {option}: a {}x{} image zoomed {zoom} times is {w}x{h} pixels, over the limit \
             of {} (raise it with --max-pixels N)",
            opts.width, opts.height, opts.max_pixels
        )));
    }
    Ok(())
}

/// Refuses one file given for two outputs (the second write would replace the first).
fn check_distinct_outputs(cmd: &Command, course_style: bool) -> Result<()> {
    let outputs: Vec<(&str, &Path)> = [
        ("--output", cmd.output.as_deref()),
        ("--depth", cmd.depth.as_ref().map(|d| d.2.as_path())),
        ("--normals", cmd.normals.as_deref()),
        ("--ray-tree", cmd.ray_tree.as_ref().map(|r| r.2.as_path())),
        ("--ray-tree-image", cmd.ray_tree_image.as_deref()),
        ("--heatmap", cmd.heatmap.as_deref()),
        (
            "--render-samples",
            cmd.sampling.render_samples.as_ref().map(|p| p.0.as_path()),
        ),
        (
            "--render-filter",
            cmd.sampling.render_filter.as_ref().map(|p| p.0.as_path()),
        ),
    ]
    .into_iter()
    .filter_map(|(option, path)| {
        let spelling = OPTIONS
            .get(option)
            .map_or(option, |o| o.spelling(course_style));
        Some((spelling, path?))
    })
    .collect();
    for (i, (first, a)) in outputs.iter().enumerate() {
        if let Some((second, _)) = outputs[i + 1..].iter().find(|(_, b)| same_file(a, b)) {
            return Err(Error::Usage(format!(
                "options {first} and {second}: expected different files, found `{}` for both",
                a.display()
            )));
        }
    }
    Ok(())
}

/// Whether `a` and `b` name one file: equal once `.` components are dropped, or once their
/// folders (where they exist) are resolved.
fn same_file(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| -> PathBuf {
        let lexical: PathBuf = p.components().filter(|c| *c != Component::CurDir).collect();
        let folder = match lexical.parent() {
            Some(f) if !f.as_os_str().is_empty() => f.to_path_buf(),
            _ => PathBuf::from("."),
        };
        match (folder.canonicalize(), lexical.file_name()) {
            (Ok(folder), Some(name)) => folder.join(name),
            _ => lexical,
        }
    };
    resolved(a) == resolved(b)
}

/// The message of a usage error without the `--help` hint (it is added once, outside).
fn usage_text(e: Error) -> String {
    match e {
        Error::Usage(msg) => msg,
        e => e.to_string(),
    }
}
