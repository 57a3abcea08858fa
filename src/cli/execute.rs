//! Running a parsed `whitted render` command: load the scene, render (with a progress bar on
//! a terminal), write the images (and assignment 7's pictures of the samples and the filter),
//! then the optional heatmap, the optional ray tree of one pixel
//! and its witness picture, then `--stats`. Reads the [`Command`] of `render.rs`.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::render_options::Command;
use crate::error::{Error, Result};
use crate::heatmap;
use crate::options::{self, RenderOptions};
use crate::output::{self, Content, ImageKind, StreamedImage, piece::RenderFingerprint};
use crate::progress::RowBar;
use crate::raytree::TreeSource;
use crate::render;
use crate::sample_images;
use crate::scene::Scene;
use crate::stats::{RayCounts, StatsReport, peak_memory_kib};
use crate::witness;

/// Loads the scene, renders it and writes the requested images, ray tree and statistics.
/// Notes about inert course options follow a success (an error stays the only line). Sets the
/// process's malloc to one heap for all threads first ([`crate::hugepages::share_one_heap`]).
pub fn execute(cmd: Command) -> Result<()> {
    let notes = cmd.notes.clone();
    execute_quietly(cmd)?;
    for note in &notes {
        eprintln!("{note}");
    }
    Ok(())
}

/// `frame`, or when some image of `streams` is not complete (encoded from the frame after the
/// render) and `frame` kept no pixels, the frame `render` makes.
fn with_pixels_for(
    streams: &[Option<StreamedImage>],
    frame: crate::Frame,
    render: impl FnOnce() -> Result<crate::Frame>,
) -> Result<crate::Frame> {
    let incomplete = streams
        .iter()
        .any(|s| !s.as_ref().is_some_and(StreamedImage::complete));
    if incomplete && frame.color.is_empty() {
        render()
    } else {
        Ok(frame)
    }
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
    let win = cmd.render.window();
    for out in &outputs {
        output::check_writable(out, win.width(), win.height())?;
    }
    if let Some(out) = &cmd.ray_tree_image {
        output::check_writable(out, w, h)?;
    }
    if let Some(out) = &cmd.heatmap {
        output::check_writable(out, w, h + heatmap::legend_height(w))?;
    }
    let sampling = &cmd.sampling;
    if let Some((file, zoom)) = &sampling.render_samples {
        let side = |n: u32| n.saturating_mul(*zoom);
        output::check_writable(file, side(win.width()), side(win.height()))?;
    }
    if let Some((file, zoom)) = &sampling.render_filter {
        let side = |n: u32| n.saturating_mul(*zoom).saturating_add(1);
        output::check_writable(file, side(w), side(h))?;
    }
    if let Some((_, _, json)) = &cmd.ray_tree {
        output::check_creatable(json, "write ray tree")?;
    }
    // One heap for every worker started below: a frame reuses what its phases free.
    crate::hugepages::share_one_heap();
    let mut phases: Vec<(&'static str, Duration)> = Vec::new();
    let t0 = Instant::now();
    // The OBJ loader reads big meshes in parallel, and the images are converted and encoded in
    // parallel: on the render's own threads (`--threads`), never rayon's global pool.
    let pool = render::worker_pool(&cmd.render)?;
    let mut scene = pool.install(|| Scene::load(&cmd.scene))?;
    if cmd.smooth_normals {
        scene.smooth_normals();
    }
    phases.push(("parse", t0.elapsed()));
    let traced = !outputs.is_empty() || sampling.render_samples.is_some();
    if !traced
        && cmd.ray_tree.is_none()
        && cmd.heatmap.is_none()
        && sampling.render_filter.is_none()
    {
        eprintln!("note: no -output, -depth or -normals given: the scene parsed, nothing to write");
        return Ok(());
    }
    let mut rays = RayCounts::default();
    let (mut accel, mut bounce_time, mut grid) = (None, Vec::new(), None);
    let mut streamed_images = 0;
    let mut files = Vec::new();
    if let Some((file, zoom)) = &sampling.render_filter {
        // The filter's picture depends on the filter and the image size alone: nothing to trace.
        let picture = sample_images::render_filter(w, h, *zoom, &cmd.render.filter);
        files.push((
            file.clone(),
            Content::Bytes(
                pool.install(|| output::encode(&picture, output::Format::for_path(file)?))?,
            ),
        ));
    }
    if traced {
        let t1 = Instant::now();
        let images: Vec<(ImageKind, &PathBuf)> = [
            cmd.output.as_ref().map(|p| (ImageKind::Color, p)),
            cmd.depth.as_ref().map(|(near, far, p)| {
                let (near, far) = (*near, *far);
                (ImageKind::Depth { near, far }, p)
            }),
            cmd.normals.as_ref().map(|p| (ImageKind::Normals, p)),
        ]
        .into_iter()
        .flatten()
        .collect();
        // 8-bit images are made as the render finishes their rows (the options name a
        // different file for each image).
        let mut streams: Vec<Option<StreamedImage>> = images
            .iter()
            .map(|&(kind, path)| StreamedImage::create(path, kind, win.width(), win.height()))
            .collect();
        // When every image is written as its rows come, the frame keeps no pixels: for the
        // course bunny's 800x800 frame, a peak of 16-19 MiB instead of 24-27, and no 1.4-2.7 ms
        // of filling them (PERF.md, sitting 57).
        let opts = RenderOptions {
            keep_pixels: !streams.iter().all(Option::is_some),
            ..cmd.render.clone()
        };
        let bar = RowBar::new("render", win.height());
        let frame = render::render_on(&pool, &scene, &opts, &|rows| {
            bar.rows_done(rows.count);
            if let Some(px) = &rows.pixels {
                for stream in streams.iter().flatten() {
                    stream.rows(px);
                }
            }
        })?;
        bar.finish();
        // An image whose file failed while the render ran is encoded from the frame instead:
        // without its pixels, the frame is rendered again with them.
        let frame = with_pixels_for(&streams, frame, || {
            render::render_on(&pool, &scene, &cmd.render, &|_| {})
        })?;
        phases.push(("render", t1.elapsed()));
        let t2 = Instant::now();
        streamed_images = streams.iter().flatten().filter(|s| s.complete()).count();
        // Every image is encoded before any is written: a failed run leaves none.
        files.extend(pool.install(|| {
            let print = RenderFingerprint::new(&scene, &cmd.render);
            let mut files = Vec::new();
            for ((kind, path), stream) in images.iter().zip(&mut streams) {
                files.extend(output::frame_files(
                    &frame,
                    *kind,
                    path,
                    &print,
                    stream.take(),
                )?);
            }
            Ok::<_, Error>(files)
        })?);
        if let Some((file, zoom)) = &sampling.render_samples {
            let picture = sample_images::render_samples(&frame, &cmd.render.sampler, *zoom);
            files.push((
                file.clone(),
                Content::Bytes(
                    pool.install(|| output::encode(&picture, output::Format::for_path(file)?))?,
                ),
            ));
        }
        output::write_files(&files)?;
        files.clear();
        phases.push(("write", t2.elapsed()));
        rays = frame.rays;
        accel = frame.accel;
        bounce_time = frame.bounce_time;
        grid = frame.grid;
    }
    if !files.is_empty() {
        output::write_files(&files)?;
    }
    if let Some(out) = &cmd.heatmap {
        let t4 = Instant::now();
        pool.install(|| write_heatmap(&cmd, &scene, out))?;
        phases.push(("heatmap", t4.elapsed()));
    }
    if let Some((x, y, json)) = &cmd.ray_tree {
        let t3 = Instant::now();
        pool.install(|| write_ray_tree(&cmd, &scene, *x, *y, json))?;
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
            streamed_images,
            peak_kib: peak_memory_kib(),
            accel,
            bounce_time,
            grid,
        };
        eprint!("{}", report.human());
        eprintln!("{}", report.line());
    }
    Ok(())
}

/// Traces the eye rays again counting their traversal work, writes the heatmap to `out` and
/// prints its maximum.
fn write_heatmap(cmd: &Command, scene: &Scene, out: &Path) -> Result<()> {
    // The heatmap is of the full image, whatever the crop.
    let opts = RenderOptions {
        crop: None,
        ..cmd.render.clone()
    };
    let bar = RowBar::new("heatmap", opts.height);
    let costs = render::eye_ray_costs(scene, &opts, &|rows| bar.rows_done(rows.count))?;
    bar.finish();
    output::write_image(&heatmap::draw_heatmap(&costs), out)?;
    let ((x, y), max) = costs.max();
    let mean = costs.cost.iter().map(|&c| c as f64).sum::<f64>() / costs.cost.len() as f64;
    eprintln!(
        "heatmap: eye-ray cost (BVH nodes entered + primitives tested) at most {max}, at pixel \
         ({x}, {y}); mean {mean:.1}"
    );
    Ok(())
}

/// Traces pixel `(x, y)` again, recording its ray tree; writes it as JSON to `json` and, when
/// asked, renders the witness view and draws the tree over it.
fn write_ray_tree(cmd: &Command, scene: &Scene, x: u32, y: u32, json: &Path) -> Result<()> {
    // The tree's pixel and the witness picture belong to the full image, whatever the crop.
    let opts = &RenderOptions {
        crop: None,
        ..cmd.render.clone()
    };
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
    // The picture hides what lies behind the witness frame's surfaces: it needs their depths.
    let witness_opts = RenderOptions {
        depth_normal: true,
        keep_samples: false,
        ..opts.clone()
    };
    let frame = render::render_with_progress(&witness_scene, &witness_opts, &|rows| {
        bar.rows_done(rows.count)
    })?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::options::RowPixels;

    /// A 4x3 frame, with its pixels or without.
    fn frame(pixels: bool) -> crate::Frame {
        let mut frame = crate::Frame::new(4, 3);
        if !pixels {
            (frame.color, frame.depth, frame.normal) = (Vec::new(), Vec::new(), Vec::new());
        }
        frame
    }

    /// A 4x3 TGA written while rendering, given all its rows or none.
    fn stream(name: &str, rows: bool) -> Option<StreamedImage> {
        let path = std::env::temp_dir().join(format!("whitted-{}-{name}.tga", std::process::id()));
        let stream = StreamedImage::create(&path, ImageKind::Color, 4, 3)?;
        if rows {
            stream.rows(&RowPixels {
                rows: 0..3,
                color: &[Vec3::splat(0.5); 12],
                depth: &[],
                normal: &[],
            });
        }
        Some(stream)
    }

    #[test]
    fn a_frame_without_pixels_is_rendered_again_only_for_an_image_not_written_while_rendering() {
        let (done, undone) = (stream("done", true), stream("undone", false));
        assert!(done.as_ref().is_some_and(StreamedImage::complete));
        assert!(undone.as_ref().is_some_and(|s| !s.complete()));
        let again = || Ok(crate::Frame::new(5, 5));
        let width = |streams: Vec<Option<StreamedImage>>, pixels: bool| {
            with_pixels_for(&streams, frame(pixels), again)
                .unwrap()
                .width
        };
        // Every image complete: the frame as it is, pixels or not.
        assert_eq!(width(vec![stream("a", true), stream("b", true)], false), 4);
        // An image not complete, or not written while rendering at all: encoded from the
        // frame, rendered again if it has no pixels.
        assert_eq!(width(vec![stream("c", true), stream("d", false)], false), 5);
        assert_eq!(width(vec![stream("e", true), None], false), 5);
        assert_eq!(width(vec![stream("f", false)], true), 4);
        assert_eq!(width(vec![None], true), 4);
    }
}
