//! Big buffers made in parallel: [`filled`] is `vec![value; n]` with the filling shared out
//! over the current rayon pool, [`try_filled`] the same without aborting when memory runs out.
//! A leaf: the film (its output image), the 8-bit encoders and the input reader use it.
//!
//! Why: `vec![0.0; n]` on a worker thread whose malloc arena has served earlier phases (the
//! command line loads, builds, renders and encodes on one pool) is cleared by that one thread
//! (calloc clears reused memory itself), first-touching every page of it: for the 7.7 MB film of
//! an 800x800 frame, about a millisecond of huge-page zeroing at the start of every render on
//! one thread while the other waited (`perf`, PERF.md sitting 22).

use rayon::prelude::*;

/// Buffers of fewer elements than this are filled on the calling thread.
const PARALLEL_MIN: usize = 1 << 16;

/// `vec![value; n]`, filled in parallel on the current rayon pool when `n` is large.
pub fn filled<T: Copy + Send + Sync>(n: usize, value: T) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    fill(&mut v, n, value);
    v
}

/// [`filled`], or `None` when the memory cannot be had (no abort: a huge input file is an
/// error, not a crash).
pub fn try_filled<T: Copy + Send + Sync>(n: usize, value: T) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok()?;
    fill(&mut v, n, value);
    Some(v)
}

/// Appends `n` copies of `value` to `v`, whose capacity already holds them: in parallel when
/// `n` is large.
fn fill<T: Copy + Send + Sync>(v: &mut Vec<T>, n: usize, value: T) {
    if n < PARALLEL_MIN {
        v.extend(std::iter::repeat_n(value, n));
    } else {
        v.par_extend(rayon::iter::repeat_n(value, n));
    }
}

#[cfg(test)]
mod tests {
    use super::{PARALLEL_MIN, filled, try_filled};

    #[test]
    fn a_filled_buffer_is_the_value_n_times_below_and_above_the_parallel_size() {
        for n in [
            0,
            1,
            1000,
            PARALLEL_MIN - 1,
            PARALLEL_MIN,
            3 * PARALLEL_MIN + 7,
        ] {
            for v in [filled(n, 7u16), try_filled(n, 7u16).unwrap()] {
                assert_eq!(v.len(), n);
                assert!(v.iter().all(|&x| x == 7));
            }
        }
    }
}
