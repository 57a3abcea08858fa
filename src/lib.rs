//! whitted: a Whitted-style ray tracer for the MIT 6.837 scene format, with a scalar reference
//! tracer that is the specification and an 8-wide SIMD packet tracer held to it.
//!
//! ```text
//! scene file --parse--> Scene { camera, lights, materials, object tree }
//!                          |
//!            render(scene, RenderOptions) -> Frame { colour, depth, normal }
//!                          |  Tracer::Reference: reference.rs, recursive, one ray at a time,
//!                          |      walks the object tree
//!                          |  Tracer::Packet: geometry/ flattens the tree to SoA arrays,
//!                          |      bvh/ builds a binned-SAH BVH over them; wavefront/ queues
//!                          |      rays per bounce, intersects 8 at a time (packet.rs, simd.rs)
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
pub mod frame;
pub mod geometry;
pub mod intersect;
pub mod math;
pub mod options;
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
pub use frame::Frame;
pub use options::{RenderOptions, Tracer};
pub use render::render;
pub use scene::Scene;

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
