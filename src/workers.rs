//! The worker pools every parallel phase runs on (the scene's loading, the BVH build, the
//! render, the images' encoding): [`pool`] builds a rayon pool of `threads` workers, and when
//! those take every CPU the process may run on, it pins worker `i` to the `i`-th of them. A
//! leaf: the command line and the render's front door call it; it knows nothing of the tracer.
//!
//! Why pin: Linux places a young process's threads by their (still small) load, and on this
//! project's machines (2 vCPUs) it often kept both workers of a new pool on one CPU for the
//! first 10–30 ms of a process — a frame's whole parse and BVH build — before spreading them.
//! In a test of 40 parallel steps of 1 ms, each after 0.3 ms of serial work, 14 to 19 of 20
//! fresh processes ran some of their first 30 steps with both workers on one CPU, taking turns
//! (three batches); pinned, 0 or 1 of 20 (PERF.md, sitting 22). A pool smaller than the
//! machine is left to the scheduler, as is every pool elsewhere than on Linux. Pinning never
//! changes what is computed: the bytes of an image do not depend on which thread traced what.

use rayon::{ThreadPool, ThreadPoolBuildError, ThreadPoolBuilder};

/// A pool of `threads` workers (0: one per CPU) with `stack` bytes of stack each (`None`:
/// rayon's default), pinned one per CPU when they take every CPU the process may use.
pub fn pool(threads: usize, stack: Option<usize>) -> Result<ThreadPool, ThreadPoolBuildError> {
    let mut builder = ThreadPoolBuilder::new().num_threads(threads);
    if let Some(bytes) = stack {
        builder = builder.stack_size(bytes);
    }
    // rayon's own count for 0: RAYON_NUM_THREADS when set, else one per CPU.
    let workers = match threads {
        0 if std::env::var_os("RAYON_NUM_THREADS").is_none() => {
            std::thread::available_parallelism().map_or(0, |n| n.get())
        }
        n => n,
    };
    let cpus = allowed_cpus();
    if cpus.len() > 1 && workers == cpus.len() {
        builder = builder.start_handler(move |i| {
            if let Some(&cpu) = cpus.get(i) {
                pin_to(cpu);
            }
        });
    }
    builder.build()
}

/// The CPUs the process may run on, in increasing order (empty where that is not known).
#[cfg(target_os = "linux")]
fn allowed_cpus() -> Vec<usize> {
    // SAFETY: `set` is a plain bit set that sched_getaffinity fills (for the calling thread,
    // whose mask the pool's threads inherit); on failure it is left empty.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) != 0 {
            return Vec::new();
        }
        (0..libc::CPU_SETSIZE as usize)
            .filter(|&c| libc::CPU_ISSET(c, &set))
            .collect()
    }
}

#[cfg(not(target_os = "linux"))]
fn allowed_cpus() -> Vec<usize> {
    Vec::new()
}

/// Pins the calling thread to `cpu`; a refusal leaves it where the scheduler puts it.
#[cfg(target_os = "linux")]
fn pin_to(cpu: usize) {
    // SAFETY: `set` is a plain bit set naming one CPU, which the process may use.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
}

#[cfg(not(target_os = "linux"))]
fn pin_to(_cpu: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pool_has_the_threads_asked_for_whether_pinned_or_not() {
        let n = allowed_cpus().len().max(1);
        for threads in [1, n, n + 1] {
            let p = pool(threads, None).unwrap();
            assert_eq!(p.current_num_threads(), threads);
            let sum: usize = p.install(|| {
                use rayon::prelude::*;
                (0..1000usize).into_par_iter().sum()
            });
            assert_eq!(sum, 999 * 1000 / 2);
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_pool_that_takes_every_cpu_has_one_worker_on_each() {
        let cpus = allowed_cpus();
        if cpus.len() < 2 {
            return;
        }
        let p = pool(cpus.len(), None).unwrap();
        let mut on: Vec<usize> = p.broadcast(|_| {
            // SAFETY: sched_getcpu only reads the calling thread's CPU.
            unsafe { libc::sched_getcpu() as usize }
        });
        on.sort_unstable();
        assert_eq!(on, cpus);
    }
}
