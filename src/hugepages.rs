//! An allocator that asks Linux for transparent huge pages (2 MiB) on big allocations: the
//! system allocator, plus `madvise(MADV_HUGEPAGE)` on every block of at least
//! [`HUGE_MIN_BYTES`] before its pages are first touched. A leaf: it knows nothing of the tracer.
//!
//! Why: a million-triangle scene's BVH nodes and leaf blocks are about 60 MB read in random
//! order; with 4 KiB pages nearly every node fetch also misses the TLB. Many Linux systems
//! (this project's machines among them) set transparent huge pages to `madvise`, so a process
//! gets them only where it asks; Embree asks for its BVH. The `whitted` binary and the
//! benchmarks install it as their global allocator (`#[global_allocator]`); an embedding
//! program may do the same. Where the kernel has no huge pages, or on other systems, the advice
//! is ignored and nothing else changes: the same bytes are allocated and rendered either way.
//!
//! [`keep_freed_memory`] is the other half of the binary's allocator policy: glibc's malloc,
//! left to itself, hands blocks from 128 KiB up to the kernel on every free and takes fresh
//! pages for the next, so a BVH built again (the benchmark's repetitions, an animation) pays a
//! page fault (1.7 us each on this project's VMs) for each 4 KiB it touches again.
//!
//! [`share_one_heap`] is a third, for one-frame processes only (`whitted render`): every
//! thread allocates from one heap, so memory one worker frees (the OBJ reader's chunks) is
//! the next allocation's, whichever worker makes it.

use std::alloc::{GlobalAlloc, Layout, System};

/// Blocks at least this big are advised (a huge page is 2 MiB; smaller blocks cannot hold one).
pub const HUGE_MIN_BYTES: usize = 4 << 20;

/// The system allocator with huge-page advice on big blocks (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct HugePages;

// SAFETY: every call goes to `System` with the caller's arguments unchanged; the advice only
// changes how the kernel backs pages of a block we own, never its contents or layout.
unsafe impl GlobalAlloc for HugePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, passed on unchanged.
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // SAFETY: as for `alloc`.
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System` with this layout (every block here does).
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: as for `dealloc`; the caller upholds `realloc`'s contract.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        advise(p, new_size);
        p
    }
}

/// Blocks below this size come from malloc's heaps rather than a fresh `mmap` each
/// (glibc's largest; bigger blocks are mapped and unmapped as before).
pub const MMAP_THRESHOLD_BYTES: usize = 32 << 20;

/// Free memory at the top of a heap is returned to the kernel only beyond this much.
pub const TRIM_THRESHOLD_BYTES: usize = 256 << 20;

/// Makes glibc's malloc keep freed blocks below [`MMAP_THRESHOLD_BYTES`] for reuse (and return
/// a heap's free top only beyond [`TRIM_THRESHOLD_BYTES`]) instead of unmapping them at each
/// free; the binary and the benchmarks call it first thing. glibc's default raises its
/// thresholds only as it sees blocks freed, so the first builds of a process took 30–70 page
/// faults each (spheres4096, 4098 primitives; measured: PERF.md, sittings 12–15, "Freed memory").
/// Freed memory is reused before a heap grows, so peak memory barely moves (PERF.md). Elsewhere
/// (other C libraries, other systems) it does nothing.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets two of malloc's tuning parameters, under malloc's own locks; a
    // refused setting (it returns 0) leaves glibc's default.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES as libc::c_int);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES as libc::c_int);
    }
}

/// Makes every thread allocate from glibc's main heap (`M_ARENA_MAX` 1) instead of a heap of
/// its own; `whitted render` calls it before it starts its workers. A frame's workers then reuse
/// what any of them frees, and the frame takes fewer fresh pages at either thread count: the
/// course's bunny frame (800x800, 40k triangles) took 952–1,939 page faults at 1 thread and
/// 1,581–1,926 at 2, against 2,689–2,690 and 2,983–3,900 (PERF.md, sitting 53). Not for the
/// benchmark: in a process that builds again and again, the spheres4096 build was slower with it
/// (PERF.md, sittings 34 and 53). Elsewhere (other C libraries, other systems) it does nothing.
pub fn share_one_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets one of malloc's tuning parameters, under malloc's own locks;
    // threads that already have a heap keep it, and a refused setting leaves glibc's default.
    unsafe {
        libc::mallopt(libc::M_ARENA_MAX, 1);
    }
}

/// Advises the whole 4 KiB pages inside `p..p + len` for huge pages, if the block is big.
#[inline]
fn advise(p: *mut u8, len: usize) {
    if p.is_null() || len < HUGE_MIN_BYTES {
        return;
    }
    #[cfg(target_os = "linux")]
    {
        const PAGE: usize = 4096;
        let start = (p as usize).next_multiple_of(PAGE);
        let end = (p as usize + len) & !(PAGE - 1);
        if end > start {
            // SAFETY: the range lies inside a block we just obtained; MADV_HUGEPAGE changes no
            // contents and its failure (EINVAL where THP is off) is harmless, so it is ignored.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn big_and_small_blocks_keep_their_contents_through_growth() {
        for size in [
            16,
            4096,
            HUGE_MIN_BYTES - 1,
            HUGE_MIN_BYTES,
            3 * HUGE_MIN_BYTES + 5,
        ] {
            let layout = Layout::from_size_align(size, 64).unwrap();
            // SAFETY: non-zero size; every pointer is checked and freed with its layout.
            unsafe {
                let p = HugePages.alloc(layout);
                assert!(!p.is_null());
                for i in 0..size {
                    *p.add(i) = (i % 251) as u8;
                }
                let q = HugePages.realloc(p, layout, 2 * size);
                assert!(!q.is_null());
                assert!(
                    (0..size).all(|i| *q.add(i) == (i % 251) as u8),
                    "size {size}"
                );
                HugePages.dealloc(q, Layout::from_size_align(2 * size, 64).unwrap());
                let z = HugePages.alloc_zeroed(layout);
                assert!((0..size).all(|i| *z.add(i) == 0));
                HugePages.dealloc(z, layout);
            }
        }
    }
}
