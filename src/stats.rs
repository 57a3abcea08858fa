//! Render statistics for `--stats`: the rays a tracer cast, by kind and by bounce
//! ([`RayCounts`], filled by each tracer and returned in the [`crate::Frame`]), the time of each
//! phase, and the process's peak memory. [`StatsReport`] prints them twice on stderr: a block
//! for people, then one `stats: key=value ...` line for scripts.
//!
//! ```text
//! tracer (per row / per bounce, local counters) --merge--> Frame.rays --+
//! cli/execute.rs phase timers + peak_memory_kib() -----------------------+--> StatsReport -> stderr
//! ```

use std::fmt::Write as _;
use std::time::Duration;

use crate::raytree::SegmentKind;

/// Rays cast by a tracer, by kind and by bounce. Tracers count into a local value per row (or
/// per queue) and [`RayCounts::merge`] the results, so counting never contends between
/// threads. Shadow rays count at the bounce of the surface they leave; a shadow ray counts once
/// even when transparent shadows walk through several occluders.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Rays per kind, indexed by [`SegmentKind::index`].
    pub by_kind: [u64; 4],
    /// Rays per bounce (0 = eye rays and their shadow rays).
    pub by_bounce: Vec<u64>,
}

impl RayCounts {
    /// Counts one ray of `kind` at `bounce`.
    #[inline]
    pub fn count(&mut self, kind: SegmentKind, bounce: u32) {
        self.count_many(kind, bounce, 1);
    }

    /// Counts `n` rays of `kind` at `bounce` (for tracers that count a whole queue at once).
    #[inline]
    pub fn count_many(&mut self, kind: SegmentKind, bounce: u32, n: u64) {
        self.by_kind[kind.index()] += n;
        let b = bounce as usize;
        if self.by_bounce.len() <= b {
            self.by_bounce.resize(b + 1, 0);
        }
        self.by_bounce[b] += n;
    }

    /// Adds `other` into `self`.
    pub fn merge(&mut self, other: &RayCounts) {
        for (a, b) in self.by_kind.iter_mut().zip(other.by_kind) {
            *a += b;
        }
        if self.by_bounce.len() < other.by_bounce.len() {
            self.by_bounce.resize(other.by_bounce.len(), 0);
        }
        for (a, b) in self.by_bounce.iter_mut().zip(&other.by_bounce) {
            *a += b;
        }
    }

    /// The sum of two counts (for parallel reductions).
    pub fn merged(mut self, other: RayCounts) -> RayCounts {
        self.merge(&other);
        self
    }

    /// The number of rays of `kind`.
    pub fn of(&self, kind: SegmentKind) -> u64 {
        self.by_kind[kind.index()]
    }

    /// All rays.
    pub fn total(&self) -> u64 {
        self.by_kind.iter().sum()
    }
}

/// What building the packet tracer's geometry cost.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AccelStats {
    /// Flattening the scene to SoA arrays and building the BVH.
    pub build: Duration,
    /// BVH nodes.
    pub nodes: usize,
    /// Primitives in the BVH (planes stay outside).
    pub bounded: usize,
}

/// The course's grid (`-grid NX NY NZ`): its size, box and occupancy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridStats {
    /// Cells per axis.
    pub cells: [u32; 3],
    /// The grid's box (`None`: the scene has no bounded primitive).
    pub bounds: Option<([f32; 3], [f32; 3])>,
    /// Cells at least one primitive marks.
    pub occupied: u64,
    /// The most primitives marking one cell.
    pub max_count: u32,
    /// Primitive marks summed over all cells.
    pub marks: u64,
    /// Building the grid.
    pub build: Duration,
}

impl GridStats {
    /// All cells.
    pub fn total(&self) -> u64 {
        self.cells.iter().map(|&n| n as u64).product()
    }

    /// The mean number of primitives in an occupied cell (0 when none is).
    pub fn mean_count(&self) -> f64 {
        if self.occupied == 0 {
            0.0
        } else {
            self.marks as f64 / self.occupied as f64
        }
    }
}

/// The process's peak resident memory in KiB (`VmHWM` in `/proc/self/status`), where the
/// system reports it.
pub fn peak_memory_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line["VmHWM:".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Everything `--stats` prints.
#[derive(Clone, Debug, Default)]
pub struct StatsReport {
    /// The scene file as given.
    pub scene: String,
    /// Primitives in the scene (mesh triangles counted one by one).
    pub primitives: usize,
    /// Lights in the scene.
    pub lights: usize,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// `reference` or `packet`.
    pub tracer: &'static str,
    /// Worker threads (resolved, never 0).
    pub threads: usize,
    /// Rays of the main render (the ray tree and witness view are not counted).
    pub rays: RayCounts,
    /// Named phases and their durations, in order (parse, render, write, ...).
    pub phases: Vec<(&'static str, Duration)>,
    /// Images made while the render ran (TGA, PPM and PNG, `output::StreamedImage`): their
    /// conversion, and a PNG's compression, is then part of the render phase, not of the write
    /// phase.
    pub streamed_images: usize,
    /// Peak resident memory, if known.
    pub peak_kib: Option<u64>,
    /// Packet tracer: geometry and BVH build.
    pub accel: Option<AccelStats>,
    /// Packet tracer: time per bounce, summed over worker threads.
    pub bounce_time: Vec<Duration>,
    /// The course's grid, when `-grid` asked for one.
    pub grid: Option<GridStats>,
}

/// `1234567` as `1,234,567`.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

impl StatsReport {
    /// The render phase's duration, if there was one.
    fn render_time(&self) -> Option<Duration> {
        self.phases
            .iter()
            .find(|(name, _)| *name == "render")
            .map(|p| p.1)
    }

    /// Millions of rays per second over the render phase (0 when nothing was rendered).
    pub fn mrays_per_second(&self) -> f64 {
        match self.render_time() {
            Some(t) if t.as_secs_f64() > 0.0 => self.rays.total() as f64 / t.as_secs_f64() / 1e6,
            _ => 0.0,
        }
    }

    /// The block for people.
    pub fn human(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "whitted stats");
        let _ = writeln!(
            s,
            "  scene    {}: {} primitives, {} lights",
            self.scene, self.primitives, self.lights
        );
        let _ = writeln!(
            s,
            "  image    {}x{}, {} tracer, {} threads",
            self.width, self.height, self.tracer, self.threads
        );
        let total: Duration = self.phases.iter().map(|p| p.1).sum();
        let phases: Vec<String> = self
            .phases
            .iter()
            .map(|(name, d)| format!("{name} {:.1} ms", ms(*d)))
            .collect();
        let _ = writeln!(
            s,
            "  time     {}  (total {:.1} ms)",
            phases.join(" | "),
            ms(total)
        );
        if self.streamed_images > 0 {
            let _ = writeln!(
                s,
                "  images   {} written while rendering",
                self.streamed_images
            );
        }
        let _ = writeln!(
            s,
            "  rays     {} in the render, {:.2} Mrays/s",
            grouped(self.rays.total()),
            self.mrays_per_second()
        );
        let kinds: Vec<String> = SegmentKind::ALL
            .iter()
            .map(|k| format!("{} {}", k.name(), grouped(self.rays.of(*k))))
            .collect();
        let _ = writeln!(s, "  by kind  {}", kinds.join(" | "));
        let bounces: Vec<String> = self
            .rays
            .by_bounce
            .iter()
            .enumerate()
            .map(|(b, n)| format!("{b}: {}", grouped(*n)))
            .collect();
        if !bounces.is_empty() {
            let _ = writeln!(s, "  bounce   {}", bounces.join(" | "));
        }
        if let Some(a) = &self.accel {
            let _ = writeln!(
                s,
                "  bvh      {} nodes over {} primitives, built in {:.1} ms",
                grouped(a.nodes as u64),
                grouped(a.bounded as u64),
                ms(a.build)
            );
        }
        if let Some(g) = &self.grid {
            let [nx, ny, nz] = g.cells;
            let bounds = match g.bounds {
                Some((lo, hi)) => format!(
                    "{:.4} {:.4} {:.4} -> {:.4} {:.4} {:.4}",
                    lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
                ),
                None => "NULL (no bounded primitive)".to_string(),
            };
            let _ = writeln!(
                s,
                "  grid     {nx}x{ny}x{nz} = {} cells over {bounds}, built in {:.1} ms",
                grouped(g.total()),
                ms(g.build)
            );
            let _ = writeln!(
                s,
                "           {} occupied ({:.1}%), at most {} and on average {:.2} primitives \
                 per occupied cell",
                grouped(g.occupied),
                100.0 * g.occupied as f64 / g.total().max(1) as f64,
                g.max_count,
                g.mean_count()
            );
        }
        if !self.bounce_time.is_empty() {
            let times: Vec<String> = self
                .bounce_time
                .iter()
                .enumerate()
                .map(|(b, d)| format!("{b}: {:.1} ms", ms(*d)))
                .collect();
            let _ = writeln!(s, "  per bounce (cpu) {}", times.join(" | "));
        }
        match self.peak_kib {
            Some(k) => {
                let _ = writeln!(s, "  memory   peak {:.1} MiB", k as f64 / 1024.0);
            }
            None => {
                let _ = writeln!(s, "  memory   peak unknown (no /proc/self/status)");
            }
        }
        s
    }

    /// The one line for scripts: `stats:` then space-separated `key=value` pairs, no spaces
    /// inside values (the scene path has spaces replaced by `%20`).
    pub fn line(&self) -> String {
        let mut s = String::from("stats:");
        let _ = write!(
            s,
            " scene={} primitives={} lights={} width={} height={} pixels={} tracer={} threads={}",
            self.scene.replace('%', "%25").replace(' ', "%20"),
            self.primitives,
            self.lights,
            self.width,
            self.height,
            self.width as u64 * self.height as u64,
            self.tracer,
            self.threads
        );
        for (name, d) in &self.phases {
            let _ = write!(s, " {name}_ms={:.3}", ms(*d));
        }
        let _ = write!(s, " streamed_images={}", self.streamed_images);
        let _ = write!(s, " rays={}", self.rays.total());
        for k in SegmentKind::ALL {
            let _ = write!(s, " {}_rays={}", k.name(), self.rays.of(k));
        }
        for (b, n) in self.rays.by_bounce.iter().enumerate() {
            let _ = write!(s, " bounce{b}_rays={n}");
        }
        let _ = write!(s, " mrays_per_s={:.3}", self.mrays_per_second());
        if let Some(a) = &self.accel {
            let _ = write!(
                s,
                " bvh_nodes={} bvh_prims={} bvh_build_ms={:.3}",
                a.nodes,
                a.bounded,
                ms(a.build)
            );
        }
        if let Some(g) = &self.grid {
            let _ = write!(
                s,
                " grid={}x{}x{} grid_cells={} grid_occupied={} grid_max_count={} \
                 grid_mean_count={:.3} grid_build_ms={:.3}",
                g.cells[0],
                g.cells[1],
                g.cells[2],
                g.total(),
                g.occupied,
                g.max_count,
                g.mean_count(),
                ms(g.build)
            );
        }
        for (b, d) in self.bounce_time.iter().enumerate() {
            let _ = write!(s, " bounce{b}_cpu_ms={:.3}", ms(*d));
        }
        if let Some(k) = self.peak_kib {
            let _ = write!(s, " peak_kib={k}");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_merge_by_kind_and_bounce() {
        let mut a = RayCounts::default();
        a.count(SegmentKind::Eye, 0);
        a.count(SegmentKind::Shadow, 0);
        let mut b = RayCounts::default();
        b.count(SegmentKind::Reflected, 2);
        let m = a.merged(b);
        assert_eq!(m.total(), 3);
        assert_eq!(m.by_bounce, vec![2, 0, 1]);
        assert_eq!(m.of(SegmentKind::Reflected), 1);
    }

    #[test]
    fn big_numbers_are_grouped_by_thousands() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(1234567), "1,234,567");
    }

    #[test]
    fn the_stats_line_is_key_value_pairs() {
        let mut r = StatsReport {
            scene: "my scene.txt".into(),
            tracer: "reference",
            ..StatsReport::default()
        };
        r.rays.count(SegmentKind::Eye, 0);
        r.phases.push(("render", Duration::from_millis(2)));
        let line = r.line();
        assert!(line.starts_with("stats: scene=my%20scene.txt "));
        for pair in line["stats:".len()..].split_whitespace() {
            assert!(pair.split_once('=').is_some(), "{pair}");
        }
        assert!(line.contains(" eye_rays=1 "));
        assert!(line.contains(" render_ms=2.000 "));
    }
}
