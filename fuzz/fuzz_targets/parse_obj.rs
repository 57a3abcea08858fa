//! Fuzz target: the OBJ parser on arbitrary text. Every input must give triangles or an `Error`;
//! every triangle it returns must have finite vertices.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(triangles) = whitted::scene::obj::parse_obj(text, std::path::Path::new("fuzz.obj")) {
        assert!(!triangles.is_empty());
        for t in &triangles {
            assert!(
                t.iter().all(|v| v.is_finite()),
                "non-finite vertex in {t:?}"
            );
        }
    }
});
