//! What `whitted bench` prints: per figure a human-readable line and a `CSV,` row in the format
//! of `../shared/bench/SCENES.md` (`CSV,<scene>,<kernel>,<rays>,<hits>,<ms>,<Mrays/s>` and
//! `CSV,<scene>,build_1t_ms,<primitives>,0,<ms>,<Mprims/s>`), plus `#` comment lines. The last
//! step of the benchmark: `mod.rs` hands it the timed figures.

use std::io::Write;
use std::path::Path;

use super::kernels::Tally;
use super::scenes::BenchScene;
use crate::error::{Error, Result};

/// Where the figures go, flushed line by line (a long run shows its progress).
pub struct Report<W: Write> {
    out: W,
}

impl<W: Write> Report<W> {
    /// A report written to `out`.
    pub fn new(out: W) -> Report<W> {
        Report { out }
    }

    /// One line of text (a `#` comment, or anything else that is not a figure).
    pub fn line(&mut self, text: &str) -> Result<()> {
        writeln!(self.out, "{text}")
            .and_then(|()| self.out.flush())
            .map_err(|e| Error::io(Path::new("<stdout>"), "write the report", e))
    }

    /// The run's header: version, image size, repetitions and tracing threads.
    pub fn header(&mut self, width: u32, height: u32, reps: u32, threads: usize) -> Result<()> {
        self.line(&format!(
            "# whitted {} bench: image={width}x{height} reps={reps} threads={threads}",
            env!("CARGO_PKG_VERSION"),
        ))
    }

    /// One traced kernel: `rays` rays, `tally.hits` of them hit, best time `secs`; with
    /// `checksum`, the sum of the hit distances too (human line only).
    pub fn kernel(
        &mut self,
        scene: BenchScene,
        kernel: &str,
        rays: usize,
        tally: Tally,
        secs: f64,
        checksum: bool,
    ) -> Result<()> {
        let hits = tally.hits;
        let rate = if secs > 0.0 {
            rays as f64 / secs * 1e-6
        } else {
            0.0
        };
        let checksum = if checksum {
            format!("  checksum_t={:.6e}", tally.t_sum)
        } else {
            String::new()
        };
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

    /// One BVH build (`build_1t_ms` or `build_mt_ms`) of `prims` primitives into `nodes`
    /// nodes, best time `secs`.
    pub fn build(
        &mut self,
        scene: BenchScene,
        kernel: &str,
        prims: usize,
        nodes: usize,
        secs: f64,
    ) -> Result<()> {
        let rate = prims as f64 / secs * 1e-6;
        self.line(&format!(
            "{:<12} {kernel:<16} prims={prims:>8}  best={:>9.2} ms  {rate:>8.2} Mprims/s  \
             nodes={nodes}",
            scene.name(),
            secs * 1e3
        ))?;
        self.line(&format!(
            "CSV,{},{kernel},{prims},0,{:.4},{rate:.3}",
            scene.name(),
            secs * 1e3
        ))
    }

    /// The number of primary rays where the packet and single-ray paths disagree.
    pub fn disagreement(&mut self, scene: BenchScene, disagree: usize) -> Result<()> {
        self.line(&format!(
            "# {}: primary rays where the packet and scalar paths disagree (hit or t): {disagree}",
            scene.name()
        ))
    }

    /// The process's peak resident memory, `None` where the OS does not say.
    pub fn peak_memory(&mut self, kib: Option<u64>) -> Result<()> {
        self.line(&match kib {
            Some(kb) => format!(
                "# peak memory (VmHWM): {kb} kB = {:.1} MB",
                kb as f64 / 1024.0
            ),
            None => "# peak memory: unavailable (no /proc/self/status)".to_string(),
        })
    }
}
