//! Claim: the output bytes do not depend on the thread count, for either tracer: every pixel is
//! computed by exactly one worker in a fixed order.

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
