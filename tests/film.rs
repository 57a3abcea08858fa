//! Claim: the streamed film makes the image a whole film would. Every pixel equals the
//! weighted average of the samples of its support computed directly from all samples at once
//! (bit for bit, on small images with filters whose halo crosses several bands, windows of odd
//! sizes, both tracers); a uniform-sampled, box-filtered flat-coloured scene equals its
//! 1-sample image; a pixel whose weights are all zero is black; the depth and normal images
//! show the sample nearest the pixel centre; a band's samples lie where the sampler puts each
//! pixel's own; column pieces of a band join into the band's block, and on several threads the
//! last band of each thread comes in such pieces without changing a pixel; a render that keeps
//! no pixels shows its progress hook every pixel, depth and normal a kept frame holds.

mod common;

use std::path::Path;

use whitted::filter::{Filter, Shape};
use whitted::math::Vec3;
use whitted::output::{color_image, depth_image, normal_image};
use whitted::sampler::{Pattern, Sampler};
use whitted::shade::ShadeOptions;
use whitted::{Frame, RenderOptions, Scene, Tracer};

fn scene(name: &str) -> Scene {
    Scene::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name),
    )
    .unwrap()
}

fn sampler(pattern: Pattern, count: u32) -> Sampler {
    Sampler {
        pattern,
        count,
        seed: 7,
    }
}

fn filter(shape: Shape, size: f32) -> Filter {
    Filter { shape, size }
}

/// A `width` x `height` render on 2 threads through `s` and `f`, with shadows and 3 bounces.
fn small_render(width: u32, height: u32, s: Sampler, f: Filter, tracer: Tracer) -> RenderOptions {
    RenderOptions {
        width,
        height,
        sampler: s,
        filter: f,
        tracer,
        threads: 2,
        shade: ShadeOptions {
            shadows: true,
            bounces: 3,
            ..ShadeOptions::default()
        },
        ..RenderOptions::default()
    }
}

/// Pixel `(i, j)` computed from all of `frame`'s kept samples at once, straight from the
/// definition: rows, then columns, then samples; the support cropped at the border.
fn whole_film_pixel(frame: &Frame, s: &Sampler, f: &Filter, i: i64, j: i64) -> Vec3 {
    let (w, h) = (frame.width as i64, frame.height as i64);
    let r = f.support_radius() as i64;
    let n = s.count as usize;
    let (mut acc, mut wsum) = ([0f64; 3], 0f64);
    for y in (j - r).max(0)..=(j + r).min(h - 1) {
        for x in (i - r).max(0)..=(i + r).min(w - 1) {
            for k in 0..n {
                let o = s.offset(x as u32, y as u32, k as u32);
                let c = frame.samples[(y * w + x) as usize * n + k];
                let wt = f.weight((x - i) as f32 - 0.5 + o.x, (j - y) as f32 - 0.5 + o.y) as f64;
                acc[0] += wt * c.x as f64;
                acc[1] += wt * c.y as f64;
                acc[2] += wt * c.z as f64;
                wsum += wt;
            }
        }
    }
    if wsum > 0.0 {
        Vec3::new(
            (acc[0] / wsum) as f32,
            (acc[1] / wsum) as f32,
            (acc[2] / wsum) as f32,
        )
    } else {
        Vec3::ZERO
    }
}

#[test]
fn the_streamed_film_equals_the_whole_film() {
    let scene = scene("showcase.txt");
    let cases = [
        (
            23,
            17,
            sampler(Pattern::Jittered, 4),
            filter(Shape::Gaussian, 1.7),
        ),
        (
            9,
            41,
            sampler(Pattern::Random, 5),
            filter(Shape::Gaussian, 2.3),
        ),
        (
            40,
            9,
            sampler(Pattern::Uniform, 9),
            filter(Shape::Tent, 2.3),
        ),
        (
            1,
            30,
            sampler(Pattern::Jittered, 9),
            filter(Shape::Box, 1.7),
        ),
        (31, 1, sampler(Pattern::Random, 3), filter(Shape::Tent, 1.5)),
        (
            16,
            16,
            sampler(Pattern::Uniform, 1),
            filter(Shape::Gaussian, 4.0),
        ),
        (
            12,
            12,
            sampler(Pattern::Jittered, 16),
            filter(Shape::Box, 0.5),
        ),
    ];
    for (w, h, s, f) in cases {
        for tracer in [Tracer::Packet, Tracer::Reference] {
            let opts = RenderOptions {
                keep_samples: true,
                ..small_render(w, h, s, f, tracer)
            };
            let frame = whitted::render(&scene, &opts).unwrap();
            assert_eq!(frame.samples.len(), (w * h * s.count) as usize);
            for j in 0..h as i64 {
                for i in 0..w as i64 {
                    let want = whole_film_pixel(&frame, &s, &f, i, j);
                    let got = frame.color[(j * w as i64 + i) as usize];
                    assert_eq!(got, want, "{w}x{h} {s:?} {f:?} {tracer:?} pixel ({i}, {j})");
                }
            }
        }
    }
}

#[test]
fn a_bands_samples_lie_where_the_sampler_puts_each_pixels_own() {
    use whitted::film::SampleBlock;
    use whitted::math::Vec2;
    for (pattern, count) in [
        (Pattern::Uniform, 1),
        (Pattern::Uniform, 4),
        (Pattern::Jittered, 9),
        (Pattern::Random, 1),
        (Pattern::Random, 5),
    ] {
        let s = sampler(pattern, count);
        let (x0, y0, width, rows) = (3, 5, 7, 4);
        let block = SampleBlock::new(x0, y0, width, rows, 20, 12, &s, false);
        let n = count as usize;
        assert_eq!(block.offsets.len(), (width * rows) as usize * n);
        assert_eq!(block.nearest.len(), (width * rows) as usize);
        for (p, (chunk, &near)) in block.offsets.chunks(n).zip(&block.nearest).enumerate() {
            let (x, y) = (x0 + p as u32 % width, y0 + p as u32 / width);
            let mut want = vec![Vec2::ZERO; n];
            let want_near = s.pixel_offsets(x, y, &mut want);
            assert_eq!(chunk, &want[..], "{pattern:?} x{count}: pixel ({x}, {y})");
            assert_eq!(near, want_near, "{pattern:?} x{count}: pixel ({x}, {y})");
        }
    }
    // An empty band holds nothing.
    let empty = SampleBlock::new(0, 0, 0, 8, 10, 10, &sampler(Pattern::Uniform, 4), false);
    assert!(empty.offsets.is_empty() && empty.nearest.is_empty());
}

/// A flat colour filling the view: a plane lit by ambient light only, a background around it.
const FLAT: &str = "
OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 5 }
Lights { numLights 0 }
Background { color 0.4 0.2 0.8 ambientLight 0.6 0.3 0.9 }
Materials { numMaterials 1 PhongMaterial { diffuseColor 0.5 0.7 0.3 } }
Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset 0 } }
";

#[test]
fn a_flat_scene_sampled_uniformly_through_a_box_is_its_one_sample_image() {
    let empty = FLAT.replace(
        "Group { numObjects 1 MaterialIndex 0 Plane { normal 0 0 1 offset 0 } }",
        "Group { numObjects 0 }",
    );
    for text in [FLAT.to_string(), empty] {
        let scene = Scene::from_str(&text, Path::new("flat.txt")).unwrap();
        for tracer in [Tracer::Packet, Tracer::Reference] {
            let one = RenderOptions {
                width: 19,
                height: 13,
                tracer,
                ..RenderOptions::default()
            };
            let base = color_image(&whitted::render(&scene, &one).unwrap());
            for count in [4, 9, 16, 36] {
                for size in [0.5, 1.0, 1.7, 2.3] {
                    let opts = RenderOptions {
                        sampler: sampler(Pattern::Uniform, count),
                        filter: filter(Shape::Box, size),
                        ..one.clone()
                    };
                    let img = color_image(&whitted::render(&scene, &opts).unwrap());
                    assert!(img == base, "{tracer:?} uniform {count} box {size}");
                }
            }
        }
    }
}

#[test]
fn a_pixel_without_weight_is_black() {
    let scene = Scene::from_str(FLAT, Path::new("flat.txt")).unwrap();
    // Uniform 4 puts the samples 0.25 from the centre on both axes: a box of radius 0.2 and a
    // tent of radius 0.3 (0.354 away) weigh them all zero.
    for f in [filter(Shape::Box, 0.2), filter(Shape::Tent, 0.3)] {
        let opts = RenderOptions {
            width: 5,
            height: 4,
            sampler: sampler(Pattern::Uniform, 4),
            filter: f,
            ..RenderOptions::default()
        };
        let frame = whitted::render(&scene, &opts).unwrap();
        assert!(frame.color.iter().all(|c| *c == Vec3::ZERO), "{f:?}");
    }
}

#[test]
fn depth_and_normals_show_the_sample_nearest_the_centre() {
    let scene = scene("showcase.txt");
    for tracer in [Tracer::Packet, Tracer::Reference] {
        let one = RenderOptions {
            width: 40,
            height: 30,
            tracer,
            ..RenderOptions::default()
        };
        let base = whitted::render(&scene, &one).unwrap();
        // Uniform 9's middle sample is the pixel centre, whatever the filter.
        let nine = RenderOptions {
            sampler: sampler(Pattern::Uniform, 9),
            filter: filter(Shape::Gaussian, 1.0),
            ..one.clone()
        };
        let frame = whitted::render(&scene, &nine).unwrap();
        assert_eq!(frame.depth, base.depth, "{tracer:?}");
        assert_eq!(frame.normal, base.normal, "{tracer:?}");
        assert!(
            frame.color != base.color,
            "{tracer:?}: the colour is filtered"
        );
        assert!(depth_image(&frame, 5.0, 20.0) == depth_image(&base, 5.0, 20.0));
        assert!(normal_image(&frame) == normal_image(&base));
        // Without depth and normals, the frame keeps none and the colour is unchanged.
        let lean = RenderOptions {
            depth_normal: false,
            ..nine
        };
        let colour_only = whitted::render(&scene, &lean).unwrap();
        assert!(colour_only.depth.is_empty() && colour_only.normal.is_empty());
        assert_eq!(colour_only.color, frame.color);
    }
}

/// A deterministic colour for each sample, from its pixel, index and offset; depths and
/// normals from the pixel (what a tracer's closure would fill, without tracing).
fn fill_block(b: &mut whitted::film::SampleBlock) {
    let spp = b.spp as usize;
    for slot in 0..b.len() {
        let (x, y) = b.pixel_of(slot);
        let o = b.offsets[slot];
        b.color[slot] = Vec3::new(x as f32 + o.x, y as f32 + o.y, (slot % spp) as f32);
    }
    for p in 0..b.depth.len() {
        let (x, y) = b.pixel_of(p * spp);
        b.depth[p] = (x * 1000 + y) as f32;
        b.normal[p] = Vec3::new(1.0, x as f32, y as f32);
    }
}

#[test]
fn column_pieces_join_into_the_block_of_their_band() {
    use whitted::film::SampleBlock;
    for (pattern, count, depth_normal) in [
        (Pattern::Uniform, 1, false),
        (Pattern::Jittered, 4, true),
        (Pattern::Random, 3, true),
    ] {
        let s = sampler(pattern, count);
        let block = |x0: u32, width: u32| {
            let mut b = SampleBlock::new(x0, 16, width, 8, 64, 48, &s, depth_normal);
            fill_block(&mut b);
            b
        };
        let whole = block(5, 30);
        // Columns 5..17, 17..29, 29..33 and 33..35, handed over out of order.
        let pieces = vec![block(29, 4), block(5, 12), block(33, 2), block(17, 12)];
        assert_eq!(
            SampleBlock::join_columns(pieces),
            whole,
            "{pattern:?} x{count}"
        );
        assert_eq!(SampleBlock::join_columns(vec![whole.clone()]), whole);
    }
}

#[test]
fn the_last_band_of_each_thread_comes_in_column_pieces_and_no_pixel_changes() {
    use std::sync::Mutex;
    use whitted::film::{BAND_ROWS, FilmSpec, TAIL_PIECES, render_film};
    let opts = RenderOptions {
        width: 45,
        height: 37,
        sampler: sampler(Pattern::Jittered, 4),
        filter: filter(Shape::Gaussian, 2.3),
        depth_normal: true,
        keep_samples: true,
        ..RenderOptions::default()
    };
    let spec = FilmSpec::for_options(&opts);
    let bands = 37u32.div_ceil(BAND_ROWS);
    let render = |threads: usize| {
        let blocks = Mutex::new(Vec::new());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (out, results) = pool
            .install(|| {
                render_film(
                    &spec,
                    &|_| {},
                    || (),
                    |_, b| {
                        fill_block(b);
                        blocks.lock().unwrap().push((b.y0, b.x0, b.width));
                        Ok((b.y0, b.x0, b.width))
                    },
                )
            })
            .unwrap();
        let mut blocks = blocks.into_inner().unwrap();
        blocks.sort();
        // What the trace returned, one for each block, bands in order, pieces left to right.
        assert_eq!(results, blocks, "{threads} threads");
        (out, blocks)
    };
    let (one, blocks) = render(1);
    let whole: Vec<_> = (0..bands).map(|k| (k * BAND_ROWS, 0, 45)).collect();
    assert_eq!(blocks, whole, "one thread: every band whole");
    for threads in [2, 3, 8] {
        let (out, blocks) = render(threads);
        assert!(
            out == one,
            "{threads} threads: the output differs from 1 thread's"
        );
        // The last `threads` bands (all of them when fewer) in pieces of 12 columns, the
        // last piece what is left; the others whole.
        let split = bands.saturating_sub(threads as u32);
        let mut want: Vec<_> = whole[..split as usize].to_vec();
        for k in split..bands {
            for x0 in [0, 12, 24, 36] {
                want.push((k * BAND_ROWS, x0, if x0 == 36 { 9 } else { 12 }));
            }
        }
        assert_eq!(TAIL_PIECES, 4);
        assert_eq!(blocks, want, "{threads} threads");
    }
}

#[test]
fn without_its_pixels_kept_the_frame_shows_the_hook_every_pixel_it_would_hold() {
    use std::sync::Mutex;
    use whitted::render::render_with_progress;
    let scene = scene("showcase.txt");
    for tracer in [Tracer::Packet, Tracer::Reference] {
        let opts = RenderOptions {
            depth_normal: true,
            ..small_render(
                41,
                29,
                sampler(Pattern::Jittered, 4),
                filter(Shape::Gaussian, 2.3),
                tracer,
            )
        };
        let kept = whitted::render(&scene, &opts).unwrap();
        let n = kept.color.len();
        let seen = Mutex::new((vec![Vec3::NAN; n], vec![f32::NAN; n], vec![Vec3::NAN; n]));
        let frame = render_with_progress(
            &scene,
            &RenderOptions {
                keep_pixels: false,
                ..opts.clone()
            },
            &|rows| {
                let px = rows.pixels.as_ref().expect("the rows' pixels");
                let span = px.rows.start as usize * 41..px.rows.end as usize * 41;
                let mut seen = seen.lock().unwrap();
                seen.0[span.clone()].copy_from_slice(px.color);
                seen.1[span.clone()].copy_from_slice(px.depth);
                seen.2[span].copy_from_slice(px.normal);
            },
        )
        .unwrap();
        assert!(frame.color.is_empty() && frame.depth.is_empty() && frame.normal.is_empty());
        assert_eq!(frame.rays, kept.rays, "{tracer:?}");
        let (color, depth, normal) = seen.into_inner().unwrap();
        assert!(color == kept.color, "{tracer:?}: colour");
        // Depths of misses are +inf; compare the bits.
        let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(bits(&depth) == bits(&kept.depth), "{tracer:?}: depth");
        assert!(normal == kept.normal, "{tracer:?}: normals");
    }
}
