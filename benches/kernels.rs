//! Rays per second by kind of ray, packet path against single rays, on the `whitted bench`
//! scenes spheres64 and torus100k at 512 x 512 (the contract's camera and secondary rays, built
//! by `whitted::bench`). Criterion reports Melem/s = Mrays/s. The full-size figures that are
//! compared with Embree come from `whitted bench`; these are for quick A/B while optimising.
//! Not smaller: a 4x2 tile spans more of the scene in a smaller image, so packets lose coherence
//! (torus100k primary packets: 3.2 Mrays/s at 128 x 128 against 8.4 at 1024 x 1024, same run).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use whitted::bench::{
    BenchScene, PacketQueue, RayQueue, generate_camera_rays, generate_secondary_rays,
    intersect_any, intersect_any_packet, intersect_closest, intersect_closest_packet,
};
use whitted::geometry::Geometry;
use whitted::simd::mask_none;

/// The allocator of the `whitted` binary (huge pages for big blocks), so the figures match it.
#[global_allocator]
static ALLOCATOR: whitted::hugepages::HugePages = whitted::hugepages::HugePages;

const WIDTH: u32 = 512;
const HEIGHT: u32 = 512;

/// Closest-hit queue: packets, then single rays.
fn bench_closest(c: &mut Criterion, scene: BenchScene, kind: &str, g: &Geometry, q: &RayQueue) {
    let packets: PacketQueue = q.packets();
    let mut group = c.benchmark_group(format!("kernels/{}/{kind}", scene.name()));
    group.throughput(Throughput::Elements(q.len() as u64));
    group.bench_function("packet", |b| {
        b.iter_batched_ref(
            || packets.fresh_hits(),
            |hits| intersect_closest_packet(g, black_box(&packets), hits, None),
            BatchSize::LargeInput,
        )
    });
    group.bench_function("scalar", |b| {
        b.iter_batched_ref(
            || vec![None; q.len()],
            |hits| intersect_closest(g, black_box(q), hits, None),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

/// Any-hit (shadow) queue: packets, then single rays.
fn bench_any(c: &mut Criterion, scene: BenchScene, kind: &str, g: &Geometry, q: &RayQueue) {
    let packets = q.packets();
    let mut group = c.benchmark_group(format!("kernels/{}/{kind}", scene.name()));
    group.throughput(Throughput::Elements(q.len() as u64));
    group.bench_function("packet", |b| {
        b.iter_batched_ref(
            || vec![mask_none(); packets.packets.len()],
            |occluded| intersect_any_packet(g, black_box(&packets), occluded, None),
            BatchSize::LargeInput,
        )
    });
    group.bench_function("scalar", |b| {
        b.iter_batched_ref(
            || vec![false; q.len()],
            |occluded| intersect_any(g, black_box(q), occluded, None),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

fn kernels(c: &mut Criterion) {
    // the binary's allocator policy (`whitted::hugepages`)
    whitted::hugepages::keep_freed_memory();
    let primary = generate_camera_rays(WIDTH, HEIGHT).expect("valid bench size");
    for scene in [BenchScene::Spheres64, BenchScene::Torus100k] {
        let mut g = scene.geometry();
        g.build_bvh();
        let packets = primary.packets();
        let mut hits = packets.fresh_hits();
        intersect_closest_packet(&g, &packets, &mut hits, None);
        let secondary = generate_secondary_rays(&g, &primary, &hits);
        bench_closest(c, scene, "primary", &g, &primary);
        bench_any(c, scene, "shadow", &g, &secondary.shadow);
        bench_closest(c, scene, "mirror", &g, &secondary.mirror);
        bench_closest(c, scene, "diffuse", &g, &secondary.diffuse);
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = kernels
}
criterion_main!(benches);
