//! Claim: the fuzz targets in `fuzz/` build. Running them needs cargo-fuzz and the sanitizer
//! flags of a nightly compiler (see `fuzz/README.md`) and stays manual; building them with the
//! plain toolchain is part of `cargo test`, so a change to the library that breaks a target is
//! caught in CI.
//!
//! The fuzz crate is a workspace of its own (normal builds never compile it) and builds into
//! its own target folder under this one, so it neither waits for nor disturbs the build that
//! runs this test. What belongs here: this check only; crashes the fuzzers found are regression
//! tests in `fuzz_regressions.rs`.

use std::path::Path;
use std::process::Command;

#[test]
fn fuzz_targets_build() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let target_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-build");
    let out = Command::new(cargo)
        .args(["build", "--bins", "--manifest-path"])
        .arg(root.join("fuzz/Cargo.toml"))
        .arg("--target-dir")
        .arg(&target_dir)
        .current_dir(root)
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "building the fuzz targets failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for target in ["parse_scene", "parse_obj", "render_tiny"] {
        assert!(
            target_dir.join("debug").join(target).is_file(),
            "fuzz target {target} was not built"
        );
    }
}
