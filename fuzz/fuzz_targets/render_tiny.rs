//! Fuzz target: parse arbitrary text as a scene and, when it parses, render it at 8x8 with
//! both tracers, shadows and 3 bounces, once with the course defaults and once with every optional effect
//! (back faces, transparent shadows, Fresnel). A panic, an abort or any NaN or infinite value in
//! a pixel is a crash.

#![no_main]

use libfuzzer_sys::fuzz_target;
use whitted::RenderOptions;
use whitted::options::check_options;
use whitted::reference::render_reference;
use whitted::shade::ShadeOptions;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.txt"));
    let Ok(scene) = whitted::scene::parse::parse_str(text, path) else {
        return;
    };
    let plain = ShadeOptions {
        shadows: true,
        bounces: 3,
        ..ShadeOptions::default()
    };
    let everything = ShadeOptions {
        shade_back: true,
        transparent_shadows: true,
        fresnel: true,
        specular_fix: false,
        ..plain
    };
    for shade in [plain, everything] {
        let opts = RenderOptions {
            width: 8,
            height: 8,
            shade,
            threads: 1,
            ..RenderOptions::default()
        };
        check_options(&opts).expect("valid options");
        // Straight to the tracers: `render` would start a thread pool for every input.
        let geometry = whitted::geometry::Geometry::from_scene(&scene);
        for frame in [
            render_reference(&scene, &opts, &|_| {}).unwrap(),
            whitted::wavefront::render_packet(&scene, &geometry, &opts, &|_| {}).unwrap(),
        ] {
            if let Some((x, y)) = frame.non_finite_pixel() {
                let i = (y * frame.width + x) as usize;
                panic!(
                    "pixel ({x}, {y}) is not finite: colour {} depth {} normal {}",
                    frame.color[i], frame.depth[i], frame.normal[i]
                );
            }
        }
    }
});
