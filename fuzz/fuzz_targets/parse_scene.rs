//! Fuzz target: the scene parser on arbitrary text. Every input must give a `Scene` or an
//! `Error`; a panic, an abort or a stack overflow is a crash. The scene is named as if it sat in
//! `scenes/`, so `TriangleMesh { obj_file torus.obj }` loads a real mesh.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.txt"));
        let _ = whitted::scene::parse::parse_str(text, path);
    }
});
