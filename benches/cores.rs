//! Whether the machine's first two CPUs are two cores right now. A loop of multiply-adds that
//! fills one core's floating-point units (eight independent chains of 8-lane multiply-adds)
//! runs on the first CPU alone, on the second alone, then on both at once, round after round,
//! on the render's own workers ([`whitted::render::worker_pool`], which pins them one to a CPU
//! when they take every CPU: unless `RAYON_NUM_THREADS` says otherwise). On two cores each of a
//! pair runs as fast as one alone; on the two hardware threads of one core (where a host may
//! place a virtual machine's two vCPUs) each runs at about half: arithmetic on both CPUs gains
//! nothing while that lasts. PERF.md, sitting 51, measured its machine with it (and found that how
//! often it happened did not predict a run of whole frames).
//!
//! ```text
//! cargo bench --bench cores [-- ROUNDS]      # 40 rounds by default, about half a second each
//! ```
//!
//! Prints each round's four figures (G multiply-adds of 8 lanes a second), then the medians,
//! how many figures of a pair fell below 3/4 of the median alone, and how many pairs ran below
//! 0.6 of it on both CPUs at once (the two CPUs then shared one core).

use std::hint::black_box;
use std::sync::Barrier;
use std::time::Instant;

use whitted::RenderOptions;
use whitted::simd::{F32x8, fused_mul_add};

/// Iterations of the loop per run: about 0.15 s on a 3 GHz core with two multiply-add units.
const ITERATIONS: u64 = 100_000_000;

/// Independent chains: two units with a latency of four cycles need eight in flight.
const CHAINS: usize = 8;

/// G multiply-adds (8-lane vectors) a second of one run of the loop.
fn multiply_adds() -> f64 {
    let (m, c) = black_box((F32x8::splat(0.999_999_9), F32x8::splat(1e-7)));
    let mut a: [F32x8; CHAINS] = std::array::from_fn(|k| F32x8::splat(1.0 + k as f32 * 1e-3));
    let t = Instant::now();
    for _ in 0..ITERATIONS {
        for x in a.iter_mut() {
            *x = fused_mul_add(*x, m, c);
        }
    }
    let s = t.elapsed().as_secs_f64();
    black_box(a);
    (ITERATIONS * CHAINS as u64) as f64 / s / 1e9
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    // `cargo bench` passes `--bench`; the first number given is the round count.
    let rounds = std::env::args()
        .skip(1)
        .find_map(|a| a.parse::<usize>().ok())
        .unwrap_or(40)
        .max(1);
    let opts = RenderOptions {
        threads: 0,
        ..RenderOptions::default()
    };
    let pool = whitted::render::worker_pool(&opts).expect("a worker pool");
    if pool.current_num_threads() < 2 {
        println!("cores: one CPU only; nothing to compare");
        return;
    }
    // Runs the loop on the workers of `on` at once (started together); the others idle.
    let run = |on: &[usize]| -> Vec<f64> {
        let start = Barrier::new(on.len());
        let figures = pool.broadcast(|ctx| {
            on.contains(&ctx.index()).then(|| {
                start.wait();
                multiply_adds()
            })
        });
        figures.into_iter().flatten().collect()
    };
    // `faster`: the faster CPU of each pair; both ran below a share of alone when it did.
    let (mut alone, mut pairs, mut faster) = (Vec::new(), Vec::new(), Vec::new());
    for round in 0..rounds {
        let (a0, a1) = (run(&[0])[0], run(&[1])[0]);
        let pair = run(&[0, 1]);
        println!(
            "round {round:3}: alone {a0:.2} {a1:.2}  both at once {:.2} {:.2}",
            pair[0], pair[1]
        );
        alone.extend([a0, a1]);
        faster.push(pair[0].max(pair[1]));
        pairs.extend(pair);
    }
    let one = median(alone.clone());
    let below = |v: &[f64], share: f64| v.iter().filter(|&&x| x < share * one).count();
    println!(
        "cores, {rounds} rounds: alone median {one:.2}, below 3/4 of it {} of {}; \
         both at once median {:.2}, below 3/4 {} of {}; pairs below 0.6 on both CPUs (one core) \
         {} of {rounds}",
        below(&alone, 0.75),
        alone.len(),
        median(pairs.clone()),
        below(&pairs, 0.75),
        pairs.len(),
        below(&faster, 0.6),
    );
}
