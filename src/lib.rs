//! whitted: a Whitted-style ray tracer for the MIT 6.837 scene format, with a scalar reference
//! tracer that is the specification and an 8-wide SIMD packet tracer held to it.
//!
//! # Example
//!
//! Load a scene, render it with shadows, write a PNG:
//!
//! ```
//! use std::path::Path;
//! use whitted::{RenderOptions, Scene, output};
//!
//! # fn main() -> whitted::Result<()> {
//! let scene = Scene::load(Path::new("scenes/glass_sphere.txt"))?;
//! let mut opts = RenderOptions {
//!     width: 160,
//!     height: 120,
//!     ..RenderOptions::default()
//! };
//! opts.shade.shadows = true;
//! let frame = whitted::render(&scene, &opts)?;
//! let png = std::env::temp_dir().join("whitted-doc-example.png");
//! output::write_image(&output::color_image(&frame), &png)?;
//! assert_eq!(output::read_png(&png)?.width, 160);
//! # Ok(())
//! # }
//! ```
//!
//! A crate that embeds whitted builds it with its own flags: give it
//! `-C target-cpu=x86-64-v3` (AVX2 and FMA) as this crate's `.cargo/config.toml` does, or the
//! packet tracer runs on SSE2 at about half speed.
//!
//! # Data flow
//!
//! ```text
//! scene file --scene::parse--> Scene { camera, lights, materials, object tree }
//!                          |
//!            render::render(scene, RenderOptions) -> Frame { colour, depth, normal }
//!                          |  film/: the image in bands of rows; each band's samples (placed
//!                          |      by sampler.rs) traced by a tracer's closure, then filtered
//!                          |      (filter.rs) into pixels with a halo from the next bands
//!                          |  Tracer::Reference: reference.rs, recursive, one ray at a time,
//!                          |      walks the object tree
//!                          |  Tracer::Packet: geometry/ flattens the tree to SoA arrays,
//!                          |      bvh/ builds a binned-SAH BVH over them; wavefront/ queues
//!                          |      rays per bounce, intersects 8 at a time (packet.rs, simd.rs)
//!                          |  shade.rs and intersect/ hold the maths both tracers share;
//!                          |  grid/ is the course's grid: --stats, and the -visualize_grid
//!                          |      picture both tracers draw with its march
//!                          v
//!            output/: Frame -> PNG / TGA / PPM, EXR / PFM / HDR, written atomically; a
//!                     crop's piece records its place and render (EXR window or sidecar);
//!                     8-bit images made as the film finishes rows (the progress hook
//!                     hands them out): TGA and PPM written in chunks into a file named
//!                     once complete, PNG compressed row by row in order
//!            merge.rs: pieces --checked, assembled--> the full image (`whitted merge`)
//!            sample_images.rs: the samples and the filter drawn (-render_samples/-render_filter)
//!
//! one pixel again --render::trace_ray_tree--> raytree.rs: RayTree --> JSON
//!                                        '--> witness/: witness camera render + overlay -> PNG
//! eye rays again --render::eye_ray_costs--> CostMap (nodes + primitives per pixel)
//!                                        '--> heatmap.rs: colour map + legend -> PNG
//! stats.rs: RayCounts (filled by the tracers) + phase times -> --stats; progress.rs: the bar
//! ```
//!
//! # Dependencies between modules
//!
//! A module imports only from the lines above its own and from names before it on its line,
//! never back up (`tests/module_graph.rs` walks the `crate::` paths of `src/` and fails on any
//! cycle):
//!
//! ```text
//! leaves       error, math, simd (the only file naming `wide`), progress, filter, sampler,
//!              hugepages (the binary's allocator: huge pages for big blocks), fill (big
//!              buffers filled in parallel), workers (thread pools, pinned one per CPU)
//! data         packet (8-ray SoA), scene (parsed tree, cameras, textures)
//! kernels      intersect (Hit and the primitive tests), bvh (knows no primitive)
//! shared       shade, raytree, stats, options, frame, film (samples to pixels),
//!              geometry (SoA arrays + BVH), grid (the course's uniform grid and its picture)
//! tracers      reference (recursive), wavefront (queues and packets)
//! front door   render (threads, picks a tracer), output (files), merge (pieces into one),
//!              witness (ray-tree picture), heatmap (eye-ray cost picture, drawn with witness's
//!              canvas), sample_images (the assignment-7 pictures)
//! commands     bench, cli (main.rs calls cli::run)
//! ```
//!
//! The public API is [`Scene`], [`render()`](render::render), [`RenderOptions`], [`Frame`],
//! [`merge`], [`output`], [`raytree`], [`hugepages`] (the binary's allocator) and [`Error`]. The
//! other modules are public only so that the benchmarks, fuzz targets and tests can reach the
//! kernels; they are hidden from the docs and not a stable interface. `main.rs` is a thin wrapper around `cli::run`.

#[doc(hidden)]
pub mod bench;
#[doc(hidden)]
pub mod bvh;
#[doc(hidden)]
pub mod cli;
pub mod error;
pub(crate) mod fill;
pub mod film;
pub mod filter;
pub mod frame;
#[doc(hidden)]
pub mod geometry;
#[doc(hidden)]
pub mod grid;
pub mod heatmap;
pub mod hugepages;
#[doc(hidden)]
pub mod intersect;
pub mod math;
pub mod merge;
pub mod options;
pub mod output;
#[doc(hidden)]
pub mod packet;
pub(crate) mod progress;
pub mod raytree;
#[doc(hidden)]
pub mod reference;
pub mod render;
pub mod sample_images;
pub mod sampler;
pub mod scene;
#[doc(hidden)]
pub mod shade;
#[doc(hidden)]
pub mod simd;
pub mod stats;
#[cfg(test)]
mod test_rng;
#[doc(hidden)]
pub mod wavefront;
#[doc(hidden)]
pub mod witness;
pub(crate) mod workers;

pub use error::{Error, Result};
pub use frame::{CostMap, Frame};
pub use options::{RenderOptions, Tracer};
pub use render::render;
pub use scene::Scene;
pub use shade::ShadeOptions;

/// True when this CPU (and OS) run what the build was compiled for: x86-64-v3's AVX, AVX2,
/// FMA, BMI1 and BMI2. It asks CPUID itself: `is_x86_feature_detected!` answers "yes" at compile
/// time in a build that enables these features, which is exactly when the question matters.
#[inline(never)]
pub fn cpu_supported() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
        let bit = |word: u32, n: u32| (word >> n) & 1 == 1;
        // Leaf 7 is read only if the CPU reports it.
        if __cpuid(0).eax < 7 {
            return false;
        }
        let leaf1 = __cpuid(1);
        let leaf7 = __cpuid_count(7, 0);
        let (osxsave, avx, fma) = (bit(leaf1.ecx, 27), bit(leaf1.ecx, 28), bit(leaf1.ecx, 12));
        let (avx2, bmi1, bmi2) = (bit(leaf7.ebx, 5), bit(leaf7.ebx, 3), bit(leaf7.ebx, 8));
        // The OS must save the YMM registers (XCR0 bits 1 and 2); XGETBV needs OSXSAVE.
        // SAFETY: XGETBV is only executed when CPUID reports OSXSAVE.
        let ymm_saved = osxsave && unsafe { _xgetbv(0) } & 6 == 6;
        avx && avx2 && fma && bmi1 && bmi2 && ymm_saved
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        true
    }
}
