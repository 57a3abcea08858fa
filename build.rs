//! Build script: warns when the crate is compiled for x86-64 without AVX2 and FMA. `wide` has no
//! runtime dispatch, so such a build silently falls back to SSE2 and traces at about half
//! speed. This crate's `.cargo/config.toml` enables `target-cpu=x86-64-v3`, but a crate that
//! embeds whitted as a dependency does not read it (README: "Embedding whitted").

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=CARGO_CFG_TARGET_FEATURE");
    let arch = std::env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    if arch != "x86_64" {
        return;
    }
    let features = std::env::var("CARGO_CFG_TARGET_FEATURE").unwrap_or_default();
    let enabled: Vec<&str> = features.split(',').collect();
    let missing: Vec<&str> = ["avx2", "fma"]
        .into_iter()
        .filter(|f| !enabled.contains(f))
        .collect();
    if !missing.is_empty() {
        println!(
            "cargo:warning=whitted is being compiled without {} for x86_64: its SIMD kernels fall \
             back to SSE2 and run at about half speed. Build with RUSTFLAGS=\"-C \
             target-cpu=x86-64-v3\" (or a [target.x86_64-unknown-linux-gnu] rustflags entry in \
             your .cargo/config.toml); see README, \"Embedding whitted\".",
            missing.join(" and ")
        );
    }
}
