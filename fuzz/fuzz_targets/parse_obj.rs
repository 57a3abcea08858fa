//! Fuzz target: the OBJ parser on arbitrary text. Every input must give triangles or an `Error`;
//! every triangle it returns must have finite vertices, and its corner normals (if any) must be
//! finite and of unit length.

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(mesh) = whitted::scene::obj::parse_obj(text, std::path::Path::new("fuzz.obj")) {
        assert!(!mesh.triangles.is_empty());
        for t in &mesh.triangles {
            assert!(
                t.iter().all(|v| v.is_finite()),
                "non-finite vertex in {t:?}"
            );
        }
        assert!(mesh.normals.is_empty() || mesh.normals.len() == mesh.triangles.len());
        for n in mesh.normals.iter().flatten() {
            assert!((n.length() - 1.0).abs() < 1e-5, "normal {n:?} is not unit length");
        }
    }
});
