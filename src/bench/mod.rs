//! `whitted bench`: the throughput benchmark of `../shared/bench/SCENES.md`, the contract shared
//! with the Embree 3 harness in `../shared/peer-embree/`. Four procedural scenes, one pinhole
//! camera whose rays come in 4x2 pixel tiles (one tile = one packet), and three secondary queues
//! built from the primary hits (shadow, mirror, diffuse). Every figure is printed as one `CSV,`
//! row. The command line (`cli/bench.rs`) parses the options into [`BenchOptions`] and calls [`run`].
//!
//! ```text
//! scenes.rs   BenchScene --geometry--> Geometry --build_bvh (timed: build_1t_ms)
//! rays.rs     generate_camera_rays --> RayQueue (queues.rs) --packets--> PacketQueue
//! kernels.rs      ClosestPacket (timed: primary)   Closest (timed: primary_scalar)
//! rays.rs           '--> generate_secondary_rays --> shadow / mirror / diffuse RayQueues
//! kernels.rs                AnyPacket, Any (shadow); ClosestPacket, Closest (mirror, diffuse)
//! report.rs   a human line and a `CSV,` row per figure; peak memory from stats.rs
//! ```
//!
//! This file is the driver: it times each kernel with `best_of` and hands the figures to the
//! report. The secondary queues are built from the hits of the packet path (the path the
//! renderer uses); the scalar kernels trace the same queues. A timed region holds only the
//! tracing calls: rays are generated and packed, and results reset, before it.

mod kernels;
mod queues;
mod rays;
mod report;
mod scenes;

use std::io::Write;
use std::time::Instant;

use rayon::ThreadPool;

pub use kernels::{
    Any, AnyPacket, Closest, ClosestPacket, Kernel, Tally, count_hits, fresh_results,
    intersect_any, intersect_any_packet, intersect_closest, intersect_closest_packet,
    reset_results, trace,
};
pub use queues::{BenchPacket, BenchRay, PacketQueue, RayQueue};
pub use rays::{
    LIGHT, MAX_BENCH_PIXELS, SURFACE_EPSILON, Secondary, SecondaryQueues, check_size,
    generate_camera_rays, generate_secondary_rays, secondary_rays,
};
use report::Report;
pub use scenes::BenchScene;

use crate::error::{Error, Result};
use crate::geometry::Geometry;
use crate::simd::LANES;
use crate::stats::peak_memory_kib;

/// What `whitted bench` was asked to do.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchOptions {
    pub scenes: Vec<BenchScene>,
    /// Tracing threads; 1 traces on the calling thread, 0 means all cores.
    pub threads: usize,
    pub reps: u32,
    pub width: u32,
    pub height: u32,
}

impl Default for BenchOptions {
    fn default() -> BenchOptions {
        BenchOptions {
            scenes: BenchScene::ALL.to_vec(),
            threads: 1,
            reps: 3,
            width: 1024,
            height: 1024,
        }
    }
}

/// Runs `whitted bench`, printing to stdout.
pub fn run(opts: &BenchOptions) -> Result<()> {
    let stdout = std::io::stdout();
    run_with(opts, &mut Report::new(stdout.lock()))
}

fn run_with<W: Write>(opts: &BenchOptions, out: &mut Report<W>) -> Result<()> {
    let one_thread = thread_pool(1)?;
    let many = match opts.threads {
        1 => None,
        n => Some(thread_pool(n)?),
    };
    let pool = many.as_ref();
    let threads = pool.map_or(1, ThreadPool::current_num_threads);
    out.header(opts.width, opts.height, opts.reps, threads)?;
    let primary = generate_camera_rays(opts.width, opts.height)?;
    for &scene in &opts.scenes {
        let geometry = build_timed(scene, opts.reps, &one_thread, pool, out)?;
        bench_scene(scene, &geometry, &primary, opts.reps, pool, out)?;
    }
    out.peak_memory(peak_memory_kib())
}

fn thread_pool(threads: usize) -> Result<ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Other(format!("cannot start worker threads: {e}")))
}

/// The best wall time of `reps` runs of `timed` on `results`, each preceded by an untimed
/// `reset` of them.
fn best_of<R: ?Sized>(
    reps: u32,
    results: &mut R,
    reset: impl Fn(&mut R),
    timed: impl Fn(&mut R),
) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        reset(results);
        let t0 = Instant::now();
        timed(results);
        best = best.min(t0.elapsed().as_secs_f64());
    }
    best
}

/// Builds the scene's BVH `reps` times on one thread (and on `pool`, if any), reporting the best
/// time of `build_bvh` alone; returns the last built geometry.
fn build_timed<W: Write>(
    scene: BenchScene,
    reps: u32,
    one_thread: &ThreadPool,
    pool: Option<&ThreadPool>,
    out: &mut Report<W>,
) -> Result<Geometry> {
    let mut rows = vec![("build_1t_ms", one_thread)];
    rows.extend(pool.map(|p| ("build_mt_ms", p)));
    let mut geometry = None;
    for (kernel, pool) in rows {
        let mut best = f64::INFINITY;
        for _ in 0..reps {
            // one geometry at a time: torus1m's arrays alone are 56 MB
            drop(geometry.take());
            let mut g = scene.geometry();
            // timed on the pool's thread, as Embree's commit is timed on its caller's: waking
            // the pool's sleeping worker (30-100 us here) is not part of the build
            let elapsed = pool.install(|| {
                let t0 = Instant::now();
                g.build_bvh();
                t0.elapsed()
            });
            best = best.min(elapsed.as_secs_f64());
            geometry = Some(g);
        }
        let nodes = geometry.as_ref().map_or(0, |g| g.bvh().nodes().len());
        out.build(scene, kernel, scene.primitive_count(), nodes, best)?;
    }
    geometry.ok_or_else(|| Error::Other("no repetition ran".to_string()))
}

/// What every timed kernel of one scene shares: the scene, its geometry, the repetitions, the
/// pool and the report.
struct SceneBench<'a, W: Write> {
    scene: BenchScene,
    geometry: &'a Geometry,
    reps: u32,
    pool: Option<&'a ThreadPool>,
    out: &'a mut Report<W>,
}

impl<W: Write> SceneBench<'_, W> {
    /// Times kernel `K` on `items` (`rays` rays), reports its row `{name}{K::SUFFIX}` and
    /// returns its results.
    fn time<K: Kernel>(
        &mut self,
        name: &str,
        items: &[K::Item],
        rays: usize,
    ) -> Result<Vec<K::Result>> {
        let (geometry, pool) = (self.geometry, self.pool);
        let mut results = fresh_results::<K>(items);
        let secs = best_of(
            self.reps,
            &mut results[..],
            |r| reset_results::<K>(items, r),
            |r| trace::<K>(geometry, items, r, pool),
        );
        let tally = count_hits::<K>(&results);
        let kernel = format!("{name}{}", K::SUFFIX);
        self.out
            .kernel(self.scene, &kernel, rays, tally, secs, K::CHECKSUM)?;
        Ok(results)
    }

    /// Times `queue` on the packet path `P`, then on the single-ray path `S`.
    fn time_queue<P, S>(&mut self, name: &str, queue: &RayQueue) -> Result<()>
    where
        P: Kernel<Item = BenchPacket>,
        S: Kernel<Item = BenchRay>,
    {
        let packets = queue.packets();
        drop(self.time::<P>(name, &packets.packets, queue.len())?);
        drop(packets);
        drop(self.time::<S>(name, &queue.items, queue.len())?);
        Ok(())
    }
}

/// The kernels of one scene: primary rays on both paths (and where they disagree), then the
/// secondary queues built from the packet path's hits.
fn bench_scene<W: Write>(
    scene: BenchScene,
    geometry: &Geometry,
    primary: &RayQueue,
    reps: u32,
    pool: Option<&ThreadPool>,
    out: &mut Report<W>,
) -> Result<()> {
    let mut bench = SceneBench {
        scene,
        geometry,
        reps,
        pool,
        out,
    };
    let packets = primary.packets();
    let hits = bench.time::<ClosestPacket>("primary", &packets.packets, primary.len())?;
    drop(packets);
    let hits1 = bench.time::<Closest>("primary", &primary.items, primary.len())?;
    let disagree = (0..primary.len())
        .filter(|&k| {
            let packet = hits[k / LANES].lane(k % LANES).map(|(t, _)| t.to_bits());
            packet != hits1[k].map(|(t, _)| t.to_bits())
        })
        .count();
    bench.out.disagreement(scene, disagree)?;
    drop(hits1);

    // one secondary queue at a time (peak memory: torus1m's queues are 21 MB each)
    let queue = |kind| secondary_rays(geometry, primary, &hits, kind);
    bench.time_queue::<AnyPacket, Any>("shadow", &queue(Secondary::Shadow))?;
    bench.time_queue::<ClosestPacket, Closest>("mirror", &queue(Secondary::Mirror))?;
    bench.time_queue::<ClosestPacket, Closest>("diffuse", &queue(Secondary::Diffuse))
}
