//! The figures of a scenario run: as a text report, one JSON line, and
//! per-step CSV.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

/// Per-step latency statistics, milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Latency {
    /// Median step.
    pub median_ms: f64,
    /// 99th percentile (nearest rank).
    pub p99_ms: f64,
    /// Mean of all steps.
    pub mean_ms: f64,
    /// Slowest step.
    pub max_ms: f64,
    /// Mean of the first 100 steps (all steps when fewer).
    pub first100_mean_ms: f64,
    /// Mean of the last 100 steps (all steps when fewer).
    pub last100_mean_ms: f64,
}

impl Latency {
    /// Statistics of per-step durations in seconds.
    #[must_use]
    pub fn of(seconds: &[f64]) -> Self {
        if seconds.is_empty() {
            return Self::default();
        }
        let ms: Vec<f64> = seconds.iter().map(|s| s * 1e3).collect();
        let mut sorted = ms.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        let rank = (0.99 * n as f64).ceil() as usize;
        let mean = |xs: &[f64]| xs.iter().sum::<f64>() / xs.len() as f64;
        let k = n.min(100);
        Self {
            median_ms: median,
            p99_ms: sorted[rank.clamp(1, n) - 1],
            mean_ms: mean(&ms),
            max_ms: sorted[n - 1],
            first100_mean_ms: mean(&ms[..k]),
            last100_mean_ms: mean(&ms[n - k..]),
        }
    }
}

/// Sizes of the final octree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct OctreeFigures {
    /// Leaf cells.
    pub leaves: usize,
    /// Leaf cells holding a BSP.
    pub bsp_leaves: usize,
    /// Deepest leaf.
    pub depth: u8,
    /// Inner BSP nodes over all leaves.
    pub bsp_nodes: usize,
    /// Planes over all leaf palettes.
    pub planes: usize,
    /// Bytes of the BSPs (nodes and planes).
    pub bsp_bytes: usize,
    /// `bsp_bytes / bsp_nodes`.
    pub bytes_per_bsp_node: f64,
}

/// Everything a scenario run reports.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Scenario name (`mill`, `cheese`, `sweep`, `replay`).
    pub scenario: String,
    /// Its parameters (sizes, seed, file).
    pub parameters: serde_json::Value,
    /// Steps applied.
    pub steps: usize,
    /// Worker threads.
    pub threads: usize,
    /// Building the base solid, seconds.
    pub setup_seconds: f64,
    /// All steps, seconds (wall clock).
    pub total_seconds: f64,
    /// All steps, CPU seconds of the thread that ran them (the whole CPU
    /// cost with `--threads 1`; see `cpu_clock`).
    pub total_cpu_seconds: f64,
    /// What one step's latency includes.
    pub per_step: &'static str,
    /// Per-step latency (wall clock).
    #[serde(flatten)]
    pub latency: Latency,
    /// Per-step CPU time of the thread that ran the step, in the same
    /// statistics: unlike wall time, not inflated by other processes on a
    /// loaded machine.
    pub cpu: Latency,
    /// Median time to build the tool (exact hull and its BSP), ms.
    pub hull_median_ms: f64,
    /// Median time to apply it to the octree, ms (the rest of a step is
    /// re-extraction).
    pub apply_median_ms: f64,
    /// Changed cells per step, mean.
    pub changed_cells_mean: f64,
    /// Triangles of the result's surface.
    pub triangles: usize,
    /// Whether that surface is closed (every directed edge matched by as
    /// many opposite edges).
    pub closed: bool,
    /// Whether it is watertight in the strict sense: a closed 2-manifold
    /// (false where the solid touches itself along an edge).
    pub watertight: bool,
    /// Volume of the result, mm³.
    pub volume_mm3: f64,
    /// Octree sizes.
    pub octree: OctreeFigures,
    /// Peak resident memory of the process (VmHWM), MiB.
    pub peak_memory_mib: f64,
    /// Hash of the result mesh (equal for bit-identical results).
    pub mesh_hash: String,
    /// Whether every step passed the `--check` invariants.
    pub checked: bool,
}

impl Report {
    /// One JSON line.
    #[must_use]
    pub fn json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }

    /// A few lines for people.
    #[must_use]
    pub fn text(&self) -> String {
        let l = &self.latency;
        let o = &self.octree;
        let c = &self.cpu;
        let ratio = l.last100_mean_ms / l.first100_mean_ms.max(1e-12);
        let cpu_ratio = c.last100_mean_ms / c.first100_mean_ms.max(1e-12);
        let mut out = String::new();
        let mut line = |name: &str, value: String| out.push_str(&format!("{name:<16}{value}\n"));
        line("scenario", format!("{} {}", self.scenario, self.parameters));
        line(
            "steps",
            format!("{} on {} threads", self.steps, self.threads),
        );
        line(
            "total",
            format!(
                "{:.3} s, {:.3} s CPU (base built in {:.3} s)",
                self.total_seconds, self.total_cpu_seconds, self.setup_seconds
            ),
        );
        line(
            "per step",
            format!(
                "median {:.3} ms, p99 {:.3} ms, mean {:.3} ms, max {:.3} ms",
                l.median_ms, l.p99_ms, l.mean_ms, l.max_ms
            ),
        );
        line(
            "first/last 100",
            format!(
                "{:.3} ms / {:.3} ms (x{ratio:.2})",
                l.first100_mean_ms, l.last100_mean_ms
            ),
        );
        line(
            "per step, CPU",
            format!(
                "median {:.3} ms, p99 {:.3} ms, mean {:.3} ms, first/last 100 {:.3} ms / {:.3} ms (x{cpu_ratio:.2})",
                c.median_ms, c.p99_ms, c.mean_ms, c.first100_mean_ms, c.last100_mean_ms
            ),
        );
        line(
            "step covers",
            format!(
                "{} (medians: hull {:.3} ms, apply {:.3} ms)",
                self.per_step, self.hull_median_ms, self.apply_median_ms
            ),
        );
        line(
            "changed cells",
            format!("{:.1} per step", self.changed_cells_mean),
        );
        line(
            "result",
            format!(
                "{} triangles ({}), volume {:.6} mm³",
                self.triangles,
                match (self.closed, self.watertight) {
                    (true, true) => "watertight",
                    (true, false) => "closed, touching itself along edges",
                    _ => "NOT closed",
                },
                self.volume_mm3
            ),
        );
        line(
            "octree",
            format!(
                "{} leaves ({} with a BSP), depth {}, {} BSP nodes, {} planes",
                o.leaves, o.bsp_leaves, o.depth, o.bsp_nodes, o.planes
            ),
        );
        line(
            "memory",
            format!(
                "{:.2} MiB of BSPs ({:.1} B per BSP node), peak resident {:.1} MiB",
                o.bsp_bytes as f64 / (1024.0 * 1024.0),
                o.bytes_per_bsp_node,
                self.peak_memory_mib
            ),
        );
        line("mesh hash", self.mesh_hash.clone());
        if self.checked {
            line(
                "checked",
                "every step: volume bookkeeping, closed surface".into(),
            );
        }
        out
    }
}

/// One timed step, for the CSV file.
#[derive(Clone, Copy, Debug)]
pub struct StepRecord {
    /// Latency, seconds.
    pub seconds: f64,
    /// CPU time of the thread that ran the step, seconds.
    pub cpu_seconds: f64,
    /// Of which building the tool, seconds.
    pub hull_seconds: f64,
    /// Of which applying it, seconds.
    pub apply_seconds: f64,
    /// Leaf cells reported changed.
    pub changed_cells: usize,
    /// Triangles re-extracted from them.
    pub triangles: usize,
}

/// Writes `step,seconds,cpu_seconds,hull_seconds,apply_seconds,changed_cells,triangles`
/// rows.
///
/// # Errors
/// A message naming the file when it cannot be written.
pub fn write_csv(path: &Path, steps: &[StepRecord]) -> Result<(), String> {
    let fail = |e: std::io::Error| format!("{}: {e}", path.display());
    crate::atomic::write_with(path, |out| {
        writeln!(
            out,
            "step,seconds,cpu_seconds,hull_seconds,apply_seconds,changed_cells,triangles"
        )?;
        for (i, s) in steps.iter().enumerate() {
            writeln!(
                out,
                "{i},{:.9},{:.9},{:.9},{:.9},{},{}",
                s.seconds,
                s.cpu_seconds,
                s.hull_seconds,
                s.apply_seconds,
                s.changed_cells,
                s.triangles
            )?;
        }
        Ok(())
    })
    .map_err(fail)
}

/// Peak resident memory of this process in MiB (`VmHWM`), 0 where the
/// system does not say.
#[must_use]
pub fn peak_memory_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            status
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_statistics() {
        let s: Vec<f64> = (1..=200).map(|i| f64::from(i) * 1e-3).collect();
        let l = Latency::of(&s);
        assert!((l.median_ms - 100.5).abs() < 1e-9);
        assert!((l.p99_ms - 198.0).abs() < 1e-9);
        assert!((l.first100_mean_ms - 50.5).abs() < 1e-9);
        assert!((l.last100_mean_ms - 150.5).abs() < 1e-9);
        assert!((l.max_ms - 200.0).abs() < 1e-9);
        let one = Latency::of(&[0.002]);
        assert!((one.p99_ms - 2.0).abs() < 1e-9 && (one.last100_mean_ms - 2.0).abs() < 1e-9);
        assert_eq!(Latency::of(&[]), Latency::default());
    }

    #[test]
    fn peak_memory_is_read() {
        assert!(peak_memory_mib() > 0.0);
    }
}
