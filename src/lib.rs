//! whitted: a Whitted-style ray tracer for the MIT 6.837 scene format, with a scalar reference
//! tracer that is the specification and an 8-wide SIMD packet tracer held to it.
//!
//! ```text
//! scene file --parse--> Scene { camera, lights, materials, object tree }
//!                          |
//!            render(scene, RenderOptions) -> Frame { colour, depth, normal }
//!                          |  Tracer::Reference: reference.rs, recursive, one ray at a time,
//!                          |      walks the object tree
//!                          |  Tracer::Packet: geometry/ flattens the tree to SoA arrays;
//!                          |      wavefront/ queues rays per bounce, intersects 8 at a time
//!                          |      (packet.rs, simd.rs)
//!                          |  shade.rs and intersect/ hold the maths both tracers share
//!                          v
//!            output.rs: Frame -> PNG / TGA / PPM, written atomically
//!
//! one pixel again --trace_ray_tree--> raytree.rs: RayTree --> JSON
//!                                        '--> witness.rs: witness camera render + overlay -> PNG
//! stats.rs: RayCounts (filled by the tracers) + phase times -> --stats; progress.rs: the bar
//! ```
//!
//! `main.rs` is a thin wrapper around [`cli::run`]; [`bench`] is `whitted bench`, the throughput
//! benchmark shared with the Embree harness.

pub mod bench;
pub mod bvh;
pub mod cli;
pub mod error;
pub mod geometry;
pub mod intersect;
pub mod math;
pub mod output;
pub mod packet;
pub mod progress;
pub mod raytree;
pub mod reference;
pub mod render;
pub mod scene;
pub mod shade;
pub mod simd;
pub mod stats;
pub mod wavefront;
pub mod witness;

pub use error::{Error, Result};
pub use render::{Frame, RenderOptions, Tracer, render};
pub use scene::Scene;

/// True when this CPU has the instruction sets the build was compiled for (AVX2 and FMA).
pub fn cpu_supported() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        true
    }
}
