//! `whitted bench`: the throughput benchmark of `../shared/bench/SCENES.md`, the contract shared
//! with the Embree 3 harness in `../shared/peer-embree/`. Four procedural scenes (a ground quad
//! plus a grid of analytic spheres or a UV torus mesh), one pinhole camera whose rays come in
//! 4x2 pixel tiles (one tile = one packet), and three secondary queues built from the primary
//! hits (shadow, mirror, diffuse). Every figure is printed as one `CSV,` row.
//!
//! ```text
//! BenchScene --geometry--> Geometry --build_bvh (timed: build_1t_ms)
//! generate_camera_rays --> RayQueue --packets--> PacketQueue
//!     intersect_closest_packet (timed: primary)   intersect_closest (timed: primary_scalar)
//!         '--> generate_secondary_rays --> shadow / mirror / diffuse RayQueues
//!                 intersect_any[_packet] (shadow), intersect_closest[_packet] (mirror, diffuse)
//! ```
//!
//! Everything is computed in `f32` with the same formulas, in the same order, as the C harness,
//! so both programs trace bit-identical primary rays and their hit counts can be compared. The
//! secondary queues are built from the hits of the packet path (the path the renderer uses); the
//! scalar kernels trace the same queues. A timed region holds only the tracing calls: rays are
//! generated and packed, and hit records reset, before it.

use std::f32::consts::PI;
use std::io::Write;
use std::time::Instant;

use rayon::ThreadPool;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::Geometry;
use crate::math::{Ray, Vec3};
use crate::packet::{HitPacket, NO_HIT, RayPacket};
use crate::simd::{F32x8, LANES, Mask, bitmask, from_lanes, lanes, lanes_i32, mask_none};

/// The text of `whitted bench --help`.
pub const HELP: &str = "\
whitted bench: ray throughput on the four procedural scenes of shared/bench/SCENES.md

USAGE:
    whitted bench [--scene NAME|all] [--threads N] [--reps N] [--width W] [--height H]

OPTIONS (defaults in brackets):
    --scene NAME|all    spheres64, spheres4096, torus100k, torus1m or all [all]
    --threads N         worker threads tracing the rays; 0 means all cores [1]
    --reps N            repetitions; each figure is the best of them [3]
    --width W           image width, a multiple of 4 [1024]
    --height H          image height, a multiple of 2 [1024]

Prints `CSV,<scene>,<kernel>,<rays>,<hits>,<ms>,<Mrays/s>` per kernel (primary, shadow, mirror,
diffuse: 8-ray packets; the same with `_scalar`: one ray at a time) and
`CSV,<scene>,build_1t_ms,<primitives>,0,<ms>,<Mprims/s>` for the BVH build on one thread.
";

/// The largest image `whitted bench` accepts (4096 x 4096): its rays alone take ~2 GB.
pub const MAX_BENCH_PIXELS: u64 = 1 << 24;

/// The point light of the shadow rays.
pub const LIGHT: Vec3 = Vec3::new(2.0, 4.0, 1.0);

/// How far secondary rays start off the surface, along the normal facing the incoming ray.
pub const SURFACE_EPSILON: f32 = 1e-4;

/// Packets (or single rays) per rayon task when tracing on several threads.
const CHUNK: usize = 64;

/// One of the four procedural scenes of the contract.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchScene {
    /// 8 x 8 analytic spheres on the ground quad.
    Spheres64,
    /// 64 x 64 analytic spheres on the ground quad.
    Spheres4096,
    /// A 250 x 200 UV torus (100,000 triangles) on the ground quad.
    Torus100k,
    /// A 1000 x 500 UV torus (1,000,000 triangles) on the ground quad.
    Torus1m,
}

impl BenchScene {
    /// Every scene, in the order the Embree harness runs them.
    pub const ALL: [BenchScene; 4] = [
        BenchScene::Spheres64,
        BenchScene::Spheres4096,
        BenchScene::Torus100k,
        BenchScene::Torus1m,
    ];

    /// The scene's name in the CSV rows.
    pub fn name(self) -> &'static str {
        match self {
            BenchScene::Spheres64 => "spheres64",
            BenchScene::Spheres4096 => "spheres4096",
            BenchScene::Torus100k => "torus100k",
            BenchScene::Torus1m => "torus1m",
        }
    }

    /// The scene called `name`.
    pub fn from_name(name: &str) -> Option<BenchScene> {
        BenchScene::ALL.into_iter().find(|s| s.name() == name)
    }

    /// The number of primitives, the 2 ground triangles included.
    pub fn primitive_count(self) -> usize {
        2 + match self.shape() {
            Shape::SphereGrid(g) => g * g,
            Shape::Torus(u, v) => 2 * u * v,
        }
    }

    fn shape(self) -> Shape {
        match self {
            BenchScene::Spheres64 => Shape::SphereGrid(8),
            BenchScene::Spheres4096 => Shape::SphereGrid(64),
            BenchScene::Torus100k => Shape::Torus(250, 200),
            BenchScene::Torus1m => Shape::Torus(1000, 500),
        }
    }

    /// The scene's primitives, without acceleration structure: the ground quad's 2 triangles
    /// first, then the spheres (grid order `i * G + j`) or the torus triangles (quad order).
    pub fn geometry(self) -> Geometry {
        let mut g = Geometry::default();
        push_ground(&mut g);
        match self.shape() {
            Shape::SphereGrid(grid) => push_sphere_grid(&mut g, grid),
            Shape::Torus(u, v) => push_torus(&mut g, u, v),
        }
        g
    }
}

/// What stands on the ground quad.
#[derive(Clone, Copy)]
enum Shape {
    /// G x G spheres.
    SphereGrid(usize),
    /// U segments around the major circle, V around the tube.
    Torus(usize, usize),
}

/// Appends triangle `v` with its unit geometric normal; material 0, scene id = its index.
fn push_triangle(g: &mut Geometry, v: [Vec3; 3]) {
    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    let id = g.triangles.len() as u32;
    g.triangles.push(v, n, 0, id);
}

/// The ground quad at y = 0, x and z in [-2, 2], as triangles (v0, v1, v2) and (v0, v2, v3).
fn push_ground(g: &mut Geometry) {
    let v = [
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, -2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(-2.0, 0.0, 2.0),
    ];
    push_triangle(g, [v[0], v[1], v[2]]);
    push_triangle(g, [v[0], v[2], v[3]]);
}

/// G x G spheres of radius 0.4 s, s = 2 / G, centred at (-1 + s (i + 0.5), r, -1 + s (j + 0.5)).
fn push_sphere_grid(g: &mut Geometry, grid: usize) {
    let s = 2.0 / grid as f32;
    let r = 0.4 * s;
    for i in 0..grid {
        for j in 0..grid {
            let center = Vec3::new(-1.0 + s * (i as f32 + 0.5), r, -1.0 + s * (j as f32 + 0.5));
            let id = g.spheres.len() as u32;
            g.spheres.push(center, r, 0, id);
        }
    }
}

/// The UV torus of major radius 0.7 and minor radius 0.3 resting on the ground: vertex (i, j)
/// at index i V + j; quad (i, j) as triangles (a, b, c) and (b, d, c).
fn push_torus(g: &mut Geometry, u: usize, v: usize) {
    let (major, minor) = (0.7f32, 0.3f32);
    let mut vertices = Vec::with_capacity(u * v);
    for i in 0..u {
        let theta = 2.0 * PI * i as f32 / u as f32;
        for j in 0..v {
            let phi = 2.0 * PI * j as f32 / v as f32;
            vertices.push(Vec3::new(
                (major + minor * phi.cos()) * theta.cos(),
                minor + minor * phi.sin(),
                (major + minor * phi.cos()) * theta.sin(),
            ));
        }
    }
    for i in 0..u {
        for j in 0..v {
            let (i1, j1) = ((i + 1) % u, (j + 1) % v);
            let a = vertices[i * v + j];
            let b = vertices[i1 * v + j];
            let c = vertices[i * v + j1];
            let d = vertices[i1 * v + j1];
            push_triangle(g, [a, b, c]);
            push_triangle(g, [b, d, c]);
        }
    }
}

/// One queued ray; it accepts hits with `0 < t < tmax`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BenchRay {
    pub ray: Ray,
    pub tmax: f32,
}

/// Rays of one kind in queue order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RayQueue {
    pub items: Vec<BenchRay>,
}

impl RayQueue {
    /// The number of rays.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// True when the queue holds no ray.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Appends a ray accepting hits in `(0, tmax)`.
    pub fn push(&mut self, ray: Ray, tmax: f32) {
        self.items.push(BenchRay { ray, tmax });
    }

    /// The queue as packets of 8 consecutive rays; the last packet's missing lanes are inactive.
    pub fn packets(&self) -> PacketQueue {
        let packets = self
            .items
            .chunks(LANES)
            .map(|chunk| {
                let rays: Vec<Ray> = chunk.iter().map(|r| r.ray).collect();
                BenchPacket {
                    rays: RayPacket::from_rays(&rays, 0.0),
                    tmax: from_lanes(std::array::from_fn(|i| {
                        chunk.get(i).map_or(0.0, |r| r.tmax)
                    })),
                }
            })
            .collect();
        PacketQueue {
            packets,
            len: self.len(),
        }
    }
}

/// Eight queued rays and their per-lane `tmax`.
#[derive(Clone, Copy, Debug)]
pub struct BenchPacket {
    pub rays: RayPacket,
    pub tmax: F32x8,
}

/// A [`RayQueue`] loaded as packets.
#[derive(Clone, Debug)]
pub struct PacketQueue {
    pub packets: Vec<BenchPacket>,
    /// The number of rays (active lanes).
    pub len: usize,
}

impl PacketQueue {
    /// Hit records accepting hits up to each ray's `tmax`, one per packet.
    pub fn fresh_hits(&self) -> Vec<HitPacket> {
        self.packets
            .iter()
            .map(|p| HitPacket::with_tmax(p.tmax))
            .collect()
    }

    /// Resets `hits` to [`PacketQueue::fresh_hits`] without allocating.
    pub fn reset_hits(&self, hits: &mut [HitPacket]) {
        for (h, p) in hits.iter_mut().zip(&self.packets) {
            *h = HitPacket::with_tmax(p.tmax);
        }
    }
}

/// Checks an image size for [`generate_camera_rays`]: a width that is a multiple of 4, a
/// height that is a multiple of 2, at most [`MAX_BENCH_PIXELS`] pixels.
pub fn check_size(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 || width % 4 != 0 || height % 2 != 0 {
        return Err(Error::Usage(format!(
            "image size {width}x{height}: the width must be a positive multiple of 4 and the \
             height a positive multiple of 2 (rays come in 4x2 tiles)"
        )));
    }
    let pixels = width as u64 * height as u64;
    if pixels > MAX_BENCH_PIXELS {
        return Err(Error::Limit(format!(
            "image size {width}x{height} is {pixels} pixels, over the benchmark's limit of \
             {MAX_BENCH_PIXELS}"
        )));
    }
    Ok(())
}

/// The camera rays of a `width` x `height` image, in 4x2 tiles: tiles row-major, lanes
/// row-major inside a tile (lane = ty * 4 + tx). Eye (0, 2, 3), look-at (0, 0.25, 0), up +Y,
/// vertical field of view 40 degrees; every ray accepts hits in `(0, inf)`.
pub fn generate_camera_rays(width: u32, height: u32) -> Result<RayQueue> {
    check_size(width, height)?;
    let eye = Vec3::new(0.0, 2.0, 3.0);
    let look_at = Vec3::new(0.0, 0.25, 0.0);
    let f = (look_at - eye).normalize();
    let right = f.cross(Vec3::Y).normalize();
    let up = right.cross(f);
    let th = (0.5 * 40.0 * PI / 180.0f32).tan();
    let aspect = width as f32 / height as f32;
    let (w, h) = (width as f32, height as f32);
    let mut queue = RayQueue {
        items: Vec::with_capacity(width as usize * height as usize),
    };
    for ty in (0..height).step_by(2) {
        for tx in (0..width).step_by(4) {
            for ly in 0..2 {
                for lx in 0..4 {
                    let (px, py) = ((tx + lx) as f32, (ty + ly) as f32);
                    let sx = (2.0 * (px + 0.5) / w - 1.0) * th * aspect;
                    let sy = (1.0 - 2.0 * (py + 0.5) / h) * th;
                    let dir = (f + (right * sx + up * sy)).normalize();
                    queue.push(Ray::new(eye, dir), f32::INFINITY);
                }
            }
        }
    }
    Ok(queue)
}

/// The three secondary queues: one ray of each kind per primary hit, in primary order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SecondaryQueues {
    /// Towards [`LIGHT`], stopping just short of it; any-hit.
    pub shadow: RayQueue,
    /// The mirror reflection; closest hit.
    pub mirror: RayQueue,
    /// Cosine-weighted around the normal (incoherent); closest hit.
    pub diffuse: RayQueue,
}

/// The secondary rays of the primary hits `hits` (one per packet of `primary.packets()`):
/// origin `P = o + t d + 1e-4 N` with `N` the unit geometric normal facing the incoming ray.
pub fn generate_secondary_rays(
    geometry: &Geometry,
    primary: &RayQueue,
    hits: &[HitPacket],
) -> SecondaryQueues {
    let mut q = SecondaryQueues::default();
    for (k, item) in primary.items.iter().enumerate() {
        let Some((t, prim)) = hits[k / LANES].lane(k % LANES) else {
            continue;
        };
        let (o, d) = (item.ray.origin, item.ray.dir);
        let mut n = geometry.surface(prim as u32, &item.ray, t).normal;
        if n.dot(d) > 0.0 {
            n = -n;
        }
        let p = o + d * t + n * SURFACE_EPSILON;
        // shadow: to the light, stopping 1e-4 of the distance short of it
        let to_light = LIGHT - p;
        let dist = to_light.dot(to_light).sqrt();
        let shadow_dir = to_light * (1.0 / dist);
        q.shadow.push(Ray::new(p, shadow_dir), dist * (1.0 - 1e-4));
        // mirror
        let mirror_dir = d - n * (2.0 * d.dot(n));
        q.mirror.push(Ray::new(p, mirror_dir), f32::INFINITY);
        // diffuse: cosine-weighted, seeded by the queue index
        let diffuse_dir = cosine_direction(n, q.diffuse.len() as u32);
        q.diffuse.push(Ray::new(p, diffuse_dir), f32::INFINITY);
    }
    q
}

/// The contract's random numbers: an LCG, each value its top 24 bits over 2^24.
fn lcg_next(state: &mut u32) -> f32 {
    *state = state.wrapping_mul(1664525).wrapping_add(1013904223);
    (*state >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The cosine-weighted direction around unit `n` of queue entry `index`, in the branchless
/// orthonormal basis of Duff et al. 2017.
fn cosine_direction(n: Vec3, index: u32) -> Vec3 {
    let mut state = index.wrapping_mul(2654435769).wrapping_add(1);
    let u1 = lcg_next(&mut state);
    let u2 = lcg_next(&mut state);
    let phi = 2.0 * PI * u1;
    let rr = u2.sqrt();
    let (lx, ly, lz) = (rr * phi.cos(), rr * phi.sin(), (1.0 - u2).max(0.0).sqrt());
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let b1 = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let b2 = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (b1 * lx + b2 * ly + n * lz).normalize()
}

/// Calls `f` on each pair of `input` and `output`, on the calling thread or spread over `pool`.
#[inline(always)]
fn for_each_pair<A: Sync, B: Send>(
    pool: Option<&ThreadPool>,
    input: &[A],
    output: &mut [B],
    f: impl Fn(&A, &mut B) + Sync,
) {
    match pool {
        None => {
            for (a, b) in input.iter().zip(output) {
                f(a, b);
            }
        }
        Some(pool) => pool.install(|| {
            input
                .par_chunks(CHUNK)
                .zip(output.par_chunks_mut(CHUNK))
                .for_each(|(input, output)| {
                    for (a, b) in input.iter().zip(output) {
                        f(a, b);
                    }
                })
        }),
    }
}

/// The closest hit of every ray, one at a time: `hits[i]` is `(t, geometry index)` or `None`.
pub fn intersect_closest(
    geometry: &Geometry,
    queue: &RayQueue,
    hits: &mut [Option<(f32, u32)>],
    pool: Option<&ThreadPool>,
) {
    for_each_pair(pool, &queue.items, hits, |r, hit| {
        *hit = geometry.closest_hit(&r.ray, 0.0, r.tmax);
    });
}

/// The closest hits of every packet into `hits` (reset with [`PacketQueue::reset_hits`]).
pub fn intersect_closest_packet(
    geometry: &Geometry,
    queue: &PacketQueue,
    hits: &mut [HitPacket],
    pool: Option<&ThreadPool>,
) {
    for_each_pair(pool, &queue.packets, hits, |p, hit| {
        geometry.closest_hit_packet(&p.rays, hit);
    });
}

/// Whether anything lies on each ray, one at a time (shadow rays).
pub fn intersect_any(
    geometry: &Geometry,
    queue: &RayQueue,
    occluded: &mut [bool],
    pool: Option<&ThreadPool>,
) {
    for_each_pair(pool, &queue.items, occluded, |r, occ| {
        *occ = geometry.occluded(&r.ray, 0.0, r.tmax);
    });
}

/// The occluded lanes of every packet (shadow rays).
pub fn intersect_any_packet(
    geometry: &Geometry,
    queue: &PacketQueue,
    occluded: &mut [Mask],
    pool: Option<&ThreadPool>,
) {
    for_each_pair(pool, &queue.packets, occluded, |p, occ| {
        *occ = geometry.occluded_packet(&p.rays, p.tmax);
    });
}

/// The number of hits in packet hit records, and the sum of their `t`.
pub fn count_packet_hits(hits: &[HitPacket]) -> (usize, f64) {
    let mut count = 0;
    let mut sum = 0.0;
    for h in hits {
        for (t, prim) in lanes(h.t).into_iter().zip(lanes_i32(h.prim)) {
            if prim != NO_HIT {
                count += 1;
                sum += t as f64;
            }
        }
    }
    (count, sum)
}

/// The number of hits in single-ray hit records, and the sum of their `t`.
pub fn count_hits(hits: &[Option<(f32, u32)>]) -> (usize, f64) {
    hits.iter()
        .flatten()
        .fold((0, 0.0), |(n, s), (t, _)| (n + 1, s + *t as f64))
}

/// The number of occluded lanes in packet results.
pub fn count_occluded_packet(occluded: &[Mask]) -> usize {
    occluded
        .iter()
        .map(|m| bitmask(*m).count_ones() as usize)
        .sum()
}

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

impl BenchOptions {
    /// Parses the arguments after `bench`; `None` asks for the help text.
    pub fn parse(args: &[String]) -> Result<Option<BenchOptions>> {
        let mut opts = BenchOptions::default();
        let mut it = args.iter();
        while let Some(arg) = it.next() {
            let opt = arg.as_str();
            match opt {
                "-h" | "--help" | "-help" => return Ok(None),
                "--scene" => {
                    let v = value(opt, it.next(), "a scene name or `all`")?;
                    opts.scenes = if v == "all" {
                        BenchScene::ALL.to_vec()
                    } else {
                        vec![BenchScene::from_name(v).ok_or_else(|| {
                            Error::Usage(format!(
                                "option --scene: expected one of spheres64, spheres4096, \
                                 torus100k, torus1m or all, found `{v}`"
                            ))
                        })?]
                    };
                }
                "--threads" => opts.threads = number(opt, it.next(), "a thread count")?,
                "--reps" => {
                    opts.reps = number(opt, it.next(), "a repetition count")?;
                    if !(1..=1000).contains(&opts.reps) {
                        return Err(Error::Usage(format!(
                            "option --reps: expected 1 to 1000 repetitions, found {}",
                            opts.reps
                        )));
                    }
                }
                "--width" => opts.width = number(opt, it.next(), "a width in pixels")?,
                "--height" => opts.height = number(opt, it.next(), "a height in pixels")?,
                _ => return Err(Error::Usage(format!("bench: unknown option `{arg}`"))),
            }
        }
        check_size(opts.width, opts.height)?;
        Ok(Some(opts))
    }
}

fn value<'a>(option: &str, value: Option<&'a String>, what: &str) -> Result<&'a str> {
    value
        .map(String::as_str)
        .ok_or_else(|| Error::Usage(format!("option {option}: expected {what}, found nothing")))
}

fn number<T: std::str::FromStr>(option: &str, v: Option<&String>, what: &str) -> Result<T> {
    let v = value(option, v, what)?;
    v.parse::<T>()
        .map_err(|_| Error::Usage(format!("option {option}: expected {what}, found `{v}`")))
}

/// Runs `whitted bench` with the arguments after `bench`, printing to stdout.
pub fn run(args: &[String]) -> Result<()> {
    let Some(opts) = BenchOptions::parse(args)? else {
        print!("{HELP}");
        return Ok(());
    };
    let stdout = std::io::stdout();
    let mut out = Report { out: stdout.lock() };
    run_with(&opts, &mut out)
}

/// Where the figures go: a human-readable line and a `CSV,` row each.
struct Report<W: Write> {
    out: W,
}

impl<W: Write> Report<W> {
    fn line(&mut self, text: &str) -> Result<()> {
        writeln!(self.out, "{text}")
            .and_then(|()| self.out.flush())
            .map_err(|e| Error::io(std::path::Path::new("<stdout>"), "write the report", e))
    }

    /// One traced kernel: `rays` rays, `hits` of them hit, best time `secs`.
    fn kernel(
        &mut self,
        scene: BenchScene,
        kernel: &str,
        rays: usize,
        hits: usize,
        secs: f64,
        checksum: Option<f64>,
    ) -> Result<()> {
        let rate = if secs > 0.0 {
            rays as f64 / secs * 1e-6
        } else {
            0.0
        };
        let checksum = checksum.map_or(String::new(), |c| format!("  checksum_t={c:.6e}"));
        self.line(&format!(
            "{:<12} {kernel:<16} rays={rays:>8} hits={hits:>8}  best={:>9.2} ms  {rate:>8.2} Mrays/s{checksum}",
            scene.name(),
            secs * 1e3
        ))?;
        self.line(&format!(
            "CSV,{},{kernel},{rays},{hits},{:.4},{rate:.3}",
            scene.name(),
            secs * 1e3
        ))
    }
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

fn thread_pool(threads: usize) -> Result<ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Other(format!("cannot start worker threads: {e}")))
}

fn run_with<W: Write>(opts: &BenchOptions, out: &mut Report<W>) -> Result<()> {
    let one_thread = thread_pool(1)?;
    let many = match opts.threads {
        1 => None,
        n => Some(thread_pool(n)?),
    };
    let pool = many.as_ref();
    let threads = pool.map_or(1, ThreadPool::current_num_threads);
    out.line(&format!(
        "# whitted {} bench: image={}x{} reps={} threads={threads}",
        env!("CARGO_PKG_VERSION"),
        opts.width,
        opts.height,
        opts.reps
    ))?;
    let primary = generate_camera_rays(opts.width, opts.height)?;
    for &scene in &opts.scenes {
        let geometry = build_timed(scene, opts.reps, &one_thread, pool, out)?;
        bench_scene(scene, &geometry, &primary, opts.reps, pool, out)?;
    }
    out.line(&match peak_memory_kb() {
        Some(kb) => format!(
            "# peak memory (VmHWM): {kb} kB = {:.1} MB",
            kb as f64 / 1024.0
        ),
        None => "# peak memory: unavailable (no /proc/self/status)".to_string(),
    })
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
    let prims = scene.primitive_count();
    let mut rows = vec![("build_1t_ms", one_thread)];
    rows.extend(pool.map(|p| ("build_mt_ms", p)));
    let mut geometry = None;
    for (kernel, pool) in rows {
        let mut best = f64::INFINITY;
        for _ in 0..reps {
            // one geometry at a time: torus1m's arrays alone are 56 MB
            drop(geometry.take());
            let mut g = scene.geometry();
            let t0 = Instant::now();
            pool.install(|| g.build_bvh());
            best = best.min(t0.elapsed().as_secs_f64());
            geometry = Some(g);
        }
        let rate = prims as f64 / best * 1e-6;
        let nodes = geometry.as_ref().map_or(0, |g| g.bvh().nodes.len());
        out.line(&format!(
            "{:<12} {kernel:<16} prims={prims:>8}  best={:>9.2} ms  {rate:>8.2} Mprims/s  \
             nodes={nodes}",
            scene.name(),
            best * 1e3
        ))?;
        out.line(&format!(
            "CSV,{},{kernel},{prims},0,{:.4},{rate:.3}",
            scene.name(),
            best * 1e3
        ))?;
    }
    geometry.ok_or_else(|| Error::Other("no repetition ran".to_string()))
}

fn bench_scene<W: Write>(
    scene: BenchScene,
    geometry: &Geometry,
    primary: &RayQueue,
    reps: u32,
    pool: Option<&ThreadPool>,
    out: &mut Report<W>,
) -> Result<()> {
    let packets = primary.packets();
    let mut hits = packets.fresh_hits();
    let secs = best_of(
        reps,
        &mut hits[..],
        |h| packets.reset_hits(h),
        |h| intersect_closest_packet(geometry, &packets, h, pool),
    );
    let (n, sum) = count_packet_hits(&hits);
    out.kernel(scene, "primary", primary.len(), n, secs, Some(sum))?;
    drop(packets);

    let mut hits1 = vec![None; primary.len()];
    let secs = best_of(
        reps,
        &mut hits1[..],
        |h| h.fill(None),
        |h| intersect_closest(geometry, primary, h, pool),
    );
    let (n, sum) = count_hits(&hits1);
    out.kernel(scene, "primary_scalar", primary.len(), n, secs, Some(sum))?;
    let disagree = (0..primary.len())
        .filter(|&k| {
            let packet = hits[k / LANES].lane(k % LANES).map(|(t, _)| t.to_bits());
            packet != hits1[k].map(|(t, _)| t.to_bits())
        })
        .count();
    out.line(&format!(
        "# {}: primary rays where the packet and scalar paths disagree (hit or t): {disagree}",
        scene.name()
    ))?;
    drop(hits1);

    let secondary = generate_secondary_rays(geometry, primary, &hits);
    drop(hits);
    trace_any(
        scene,
        "shadow",
        geometry,
        &secondary.shadow,
        reps,
        pool,
        out,
    )?;
    trace_closest(
        scene,
        "mirror",
        geometry,
        &secondary.mirror,
        reps,
        pool,
        out,
    )?;
    trace_closest(
        scene,
        "diffuse",
        geometry,
        &secondary.diffuse,
        reps,
        pool,
        out,
    )
}

/// Times a closest-hit queue on the packet path, then on the single-ray path.
fn trace_closest<W: Write>(
    scene: BenchScene,
    kernel: &str,
    geometry: &Geometry,
    queue: &RayQueue,
    reps: u32,
    pool: Option<&ThreadPool>,
    out: &mut Report<W>,
) -> Result<()> {
    let packets = queue.packets();
    let mut hits = packets.fresh_hits();
    let secs = best_of(
        reps,
        &mut hits[..],
        |h| packets.reset_hits(h),
        |h| intersect_closest_packet(geometry, &packets, h, pool),
    );
    let (n, sum) = count_packet_hits(&hits);
    out.kernel(scene, kernel, queue.len(), n, secs, Some(sum))?;
    drop((packets, hits));

    let mut hits = vec![None; queue.len()];
    let secs = best_of(
        reps,
        &mut hits[..],
        |h| h.fill(None),
        |h| intersect_closest(geometry, queue, h, pool),
    );
    let (n, sum) = count_hits(&hits);
    out.kernel(
        scene,
        &format!("{kernel}_scalar"),
        queue.len(),
        n,
        secs,
        Some(sum),
    )
}

/// Times an any-hit queue on the packet path, then on the single-ray path.
fn trace_any<W: Write>(
    scene: BenchScene,
    kernel: &str,
    geometry: &Geometry,
    queue: &RayQueue,
    reps: u32,
    pool: Option<&ThreadPool>,
    out: &mut Report<W>,
) -> Result<()> {
    let packets = queue.packets();
    let mut occluded = vec![mask_none(); packets.packets.len()];
    let secs = best_of(
        reps,
        &mut occluded[..],
        |o| o.fill(mask_none()),
        |o| intersect_any_packet(geometry, &packets, o, pool),
    );
    let n = count_occluded_packet(&occluded);
    out.kernel(scene, kernel, queue.len(), n, secs, None)?;
    drop((packets, occluded));

    let mut occluded = vec![false; queue.len()];
    let secs = best_of(
        reps,
        &mut occluded[..],
        |o| o.fill(false),
        |o| intersect_any(geometry, queue, o, pool),
    );
    let n = occluded.iter().filter(|&&o| o).count();
    out.kernel(
        scene,
        &format!("{kernel}_scalar"),
        queue.len(),
        n,
        secs,
        None,
    )
}

/// The process's peak resident memory (VmHWM) in kB, where Linux reports it.
pub fn peak_memory_kb() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))?
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_have_the_contract_primitive_counts() {
        for s in BenchScene::ALL {
            let g = s.geometry();
            assert_eq!(g.len(), s.primitive_count(), "{}", s.name());
            assert_eq!(BenchScene::from_name(s.name()), Some(s));
        }
        assert_eq!(BenchScene::Torus100k.primitive_count(), 100_002);
        assert_eq!(BenchScene::Spheres4096.primitive_count(), 4098);
    }

    #[test]
    fn lcg_matches_the_contract() {
        let mut state = 1u32;
        let u = lcg_next(&mut state);
        assert_eq!(state, 1664525 + 1013904223);
        assert_eq!(u, (state >> 8) as f32 / 16_777_216.0);
    }

    #[test]
    fn cosine_directions_are_unit_and_above_the_surface() {
        for (k, n) in [Vec3::Y, -Vec3::Z, Vec3::new(0.6, 0.0, 0.8), Vec3::Z]
            .into_iter()
            .enumerate()
        {
            for i in 0..100 {
                let d = cosine_direction(n, (k * 100 + i) as u32);
                assert!((d.length() - 1.0).abs() < 1e-5);
                assert!(d.dot(n) >= 0.0, "{d} below {n}");
            }
        }
    }

    #[test]
    fn bad_sizes_are_usage_errors() {
        for (w, h) in [(63, 64), (64, 63), (0, 2), (4, 0)] {
            assert!(matches!(check_size(w, h), Err(Error::Usage(_))), "{w}x{h}");
        }
        assert!(matches!(check_size(8192, 8192), Err(Error::Limit(_))));
        assert!(check_size(4, 2).is_ok());
    }

    #[test]
    fn peak_memory_is_read() {
        if std::path::Path::new("/proc/self/status").exists() {
            assert!(peak_memory_kb().is_some_and(|kb| kb > 0));
        }
    }
}
