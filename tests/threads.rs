//! Claim: the output bytes do not depend on the thread count, for either tracer: every pixel is
//! computed by exactly one worker in a fixed order; with anti-aliasing too, where a pixel's
//! filter reads samples of the neighbouring bands (colour, depth and normal images).

mod common;

use std::path::Path;

use whitted::output::{Format, color_image, encode};
use whitted::shade::ShadeOptions;
use whitted::{RenderOptions, Scene, Tracer};

#[test]
fn the_same_bytes_for_every_thread_count() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in ["showcase.txt", "facing_mirrors.txt", "glass_sphere.txt"] {
        let scene = Scene::load(&scenes.join(name)).unwrap();
        for tracer in [Tracer::Packet, Tracer::Reference] {
            let render = |threads: usize| {
                let opts = RenderOptions {
                    width: 96,
                    height: 70,
                    tracer,
                    threads,
                    shade: ShadeOptions {
                        shadows: true,
                        shade_back: true,
                        transparent_shadows: true,
                        bounces: 6,
                        ..ShadeOptions::default()
                    },
                    ..RenderOptions::default()
                };
                let frame = whitted::render(&scene, &opts).unwrap();
                encode(&color_image(&frame), Format::Png).unwrap()
            };
            let one = render(1);
            for threads in [2, 3, 8] {
                assert!(
                    render(threads) == one,
                    "{name} {tracer:?}: {threads} threads differ from 1"
                );
            }
        }
    }
}

#[test]
fn the_same_bytes_for_every_thread_count_with_a_filter_crossing_bands() {
    use whitted::filter::{Filter, Shape};
    use whitted::output::{depth_image, normal_image};
    use whitted::sampler::{Pattern, Sampler};
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scene = Scene::load(&scenes.join("showcase.txt")).unwrap();
    // Bands are 8 rows: a Gaussian of sigma 2.3 reaches 5 rows into the next band, 1.7 reaches
    // 3; the height leaves a short last band.
    for (sampler, filter) in [
        (
            Pattern::Jittered,
            Filter {
                shape: Shape::Gaussian,
                size: 2.3,
            },
        ),
        (
            Pattern::Random,
            Filter {
                shape: Shape::Tent,
                size: 1.7,
            },
        ),
    ] {
        for tracer in [Tracer::Packet, Tracer::Reference] {
            let render = |threads: usize| {
                let opts = RenderOptions {
                    width: 48,
                    height: 37,
                    tracer,
                    threads,
                    sampler: Sampler {
                        pattern: sampler,
                        count: 4,
                        seed: 11,
                    },
                    filter,
                    shade: ShadeOptions {
                        shadows: true,
                        bounces: 4,
                        ..ShadeOptions::default()
                    },
                    ..RenderOptions::default()
                };
                let frame = whitted::render(&scene, &opts).unwrap();
                [
                    color_image(&frame),
                    depth_image(&frame, 5.0, 20.0),
                    normal_image(&frame),
                ]
                .map(|img| encode(&img, Format::Png).unwrap())
            };
            let one = render(1);
            for threads in [2, 3, 8] {
                assert!(
                    render(threads) == one,
                    "{filter:?} {tracer:?}: {threads} threads differ from 1"
                );
            }
        }
    }
}
