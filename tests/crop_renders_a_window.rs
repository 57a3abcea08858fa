//! Claim: a cropped render (`RenderOptions::crop`, `--crop`, `--tile`) is exactly the window of
//! the whole render: the same colour, depth and normal bits for every pixel, with both tracers,
//! for windows of any shape and place (odd offsets, single pixels, whole bands, the image's last
//! columns and rows), anti-aliased too (a crop traces its filter's halo), and for every
//! `--tile I/N` strip; and the strips of a tiling cover the image once, top to bottom.

mod common;

use common::our_scenes;
use whitted::filter::{Filter, Shape};
use whitted::options::{TILE_ROW_STEP, Window};
use whitted::sampler::{Pattern, Sampler};
use whitted::shade::ShadeOptions;
use whitted::{Frame, RenderOptions, Scene, Tracer, render};

/// `full`'s pixels in `win`, as a frame of its own.
fn cut(full: &Frame, win: Window) -> (Vec<[u32; 3]>, Vec<u32>, Vec<[u32; 3]>) {
    let (mut c, mut d, mut n) = (Vec::new(), Vec::new(), Vec::new());
    for y in win.y0..win.y1 {
        for x in win.x0..win.x1 {
            let i = (y * full.width + x) as usize;
            c.push(full.color[i].to_array().map(f32::to_bits));
            d.push(full.depth[i].to_bits());
            n.push(full.normal[i].to_array().map(f32::to_bits));
        }
    }
    (c, d, n)
}

fn bits(frame: &Frame) -> (Vec<[u32; 3]>, Vec<u32>, Vec<[u32; 3]>) {
    cut(frame, Window::full(frame.width, frame.height))
}

#[test]
fn a_crop_is_the_window_of_the_whole_render_with_both_tracers() {
    crops_are_windows_of_the_whole_render(Sampler::default(), Filter::default());
}

#[test]
fn an_anti_aliased_crop_is_the_window_of_the_whole_render_with_both_tracers() {
    let sampler = Sampler {
        pattern: Pattern::Jittered,
        count: 4,
        seed: 3,
    };
    let filter = Filter {
        shape: Shape::Gaussian,
        size: 1.0,
    };
    crops_are_windows_of_the_whole_render(sampler, filter);
}

fn crops_are_windows_of_the_whole_render(sampler: Sampler, filter: Filter) {
    let (w, h) = (75, 61);
    let windows = [
        Window {
            x0: 0,
            x1: w,
            y0: 0,
            y1: h,
        },
        Window {
            x0: 3,
            x1: 40,
            y0: 5,
            y1: 29,
        },
        Window {
            x0: 37,
            x1: 38,
            y0: 17,
            y1: 18,
        },
        Window {
            x0: 0,
            x1: w,
            y0: 8,
            y1: 24,
        },
        Window {
            x0: 70,
            x1: w,
            y0: 55,
            y1: h,
        },
        Window {
            x0: 1,
            x1: w - 1,
            y0: 1,
            y1: h - 1,
        },
    ];
    for path in our_scenes() {
        let scene = Scene::load(&path).unwrap();
        for tracer in [Tracer::Reference, Tracer::Packet] {
            let opts = RenderOptions {
                width: w,
                height: h,
                tracer,
                sampler,
                filter,
                shade: ShadeOptions {
                    shadows: true,
                    shade_back: true,
                    bounces: 5,
                    transparent_shadows: true,
                    ..ShadeOptions::default()
                },
                ..RenderOptions::default()
            };
            let full = render(&scene, &opts).unwrap();
            for win in windows {
                let crop = render(
                    &scene,
                    &RenderOptions {
                        crop: Some(win),
                        ..opts.clone()
                    },
                )
                .unwrap();
                let what = format!("{} {tracer:?} crop {win}", path.display());
                assert_eq!(
                    (crop.width, crop.height),
                    (win.width(), win.height()),
                    "{what}"
                );
                assert_eq!(crop.window, win, "{what}");
                assert_eq!((crop.image_width, crop.image_height), (w, h), "{what}");
                assert!(bits(&crop) == cut(&full, win), "{what}: pixels differ");
            }
        }
    }
}

#[test]
fn tiles_are_strips_of_whole_bands_covering_the_image_once() {
    for (w, h) in [(1024u32, 768u32), (640, 481), (7, 9), (300, 8)] {
        let runs = h.div_ceil(TILE_ROW_STEP);
        for n in [1, 2, 3, 7, 16, 64].into_iter().filter(|&n| n <= runs) {
            let mut next = 0;
            for i in 0..n {
                let t = Window::tile(i, n, w, h).unwrap();
                assert_eq!((t.x0, t.x1), (0, w));
                assert_eq!(
                    t.y0,
                    next,
                    "{w}x{h} tile {i}/{n} starts where {} ended",
                    i.max(1) - 1
                );
                assert!(t.y1 > t.y0, "{w}x{h} tile {i}/{n} is empty");
                assert!(t.y0 % TILE_ROW_STEP == 0);
                assert!(t.y1 % TILE_ROW_STEP == 0 || t.y1 == h);
                next = t.y1;
            }
            assert_eq!(next, h, "{w}x{h} in {n} tiles ends at the bottom");
        }
    }
    assert_eq!(
        Window::tile(3, 16, 1024, 768).unwrap(),
        Window {
            x0: 0,
            x1: 1024,
            y0: 144,
            y1: 192
        }
    );
    let e = Window::tile(0, 3, 10, 16).unwrap_err().to_string();
    assert_eq!(
        e,
        "option --tile 0/3: a 10x16 image has 2 strips of 8 rows to share, fewer than 3 tiles \
         (see `whitted --help`)"
    );
    let e = Window::tile(4, 4, 10, 64).unwrap_err().to_string();
    assert_eq!(
        e,
        "option --tile 4/4: expected a tile I/N with 0 <= I < N (see `whitted --help`)"
    );
}

#[test]
fn every_tile_of_a_render_is_its_strip_of_the_whole_render() {
    let scene = Scene::load(&our_scenes()[0]).unwrap();
    for tracer in [Tracer::Reference, Tracer::Packet] {
        let opts = RenderOptions {
            width: 64,
            height: 50,
            tracer,
            ..RenderOptions::default()
        };
        let full = render(&scene, &opts).unwrap();
        for i in 0..5 {
            let win = Window::tile(i, 5, 64, 50).unwrap();
            let tile = render(
                &scene,
                &RenderOptions {
                    crop: Some(win),
                    ..opts.clone()
                },
            )
            .unwrap();
            assert!(bits(&tile) == cut(&full, win), "{tracer:?} tile {i}/5");
        }
    }
}

#[test]
fn a_crop_outside_the_image_is_refused() {
    let scene = Scene::load(&our_scenes()[0]).unwrap();
    let opts = RenderOptions {
        width: 40,
        height: 30,
        crop: Some(Window {
            x0: 10,
            x1: 41,
            y0: 0,
            y1: 30,
        }),
        ..RenderOptions::default()
    };
    let e = render(&scene, &opts).unwrap_err().to_string();
    assert_eq!(
        e,
        "option --crop 10 41 0 30: expected a non-empty window of the 40x30 image, \
         0 <= X0 < X1 <= 40 and 0 <= Y0 < Y1 <= 30 (see `whitted --help`)"
    );
    let opts = RenderOptions {
        crop: Some(Window {
            x0: 5,
            x1: 5,
            y0: 0,
            y1: 30,
        }),
        ..opts
    };
    assert!(render(&scene, &opts).is_err());
}
