//! What the plugin's bench binaries (`benches/*.rs`, `harness = false`)
//! share: when to measure, which measurements, the environment's sizes,
//! percentiles and the JSON summary line.
//!
//! A bench measures only when its arguments hold `--bench`, which
//! `cargo bench` passes: `cargo test --all-targets` (as `scripts/test`
//! runs it) builds and runs every bench binary without it, and each then
//! prints one line and exits. Any other argument not starting with `-`
//! selects the measurements whose names contain it (all of them when
//! there is none), as a test filter does.

use std::time::Duration;

/// The measurements a bench run asked for.
pub struct Args {
    filters: Vec<String>,
}

impl Args {
    /// The arguments of this process, or `None` (after a line saying so)
    /// when it was not run as a benchmark.
    pub fn parse(bench: &str) -> Option<Args> {
        let args: Vec<String> = std::env::args().skip(1).collect();
        if !args.iter().any(|a| a == "--bench") {
            println!("{bench}: not run as a benchmark (no --bench argument); skipped");
            return None;
        }
        let filters = args.into_iter().filter(|a| !a.starts_with('-')).collect();
        Some(Args { filters })
    }

    /// Whether the measurement `name` was asked for.
    pub fn wants(&self, name: &str) -> bool {
        self.filters.is_empty() || self.filters.iter().any(|f| name.contains(f.as_str()))
    }
}

/// `name` from the environment, else `default`.
#[allow(dead_code, reason = "not every bench reads sizes from the environment")]
pub fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The `p` quantile of sorted durations, in milliseconds.
#[allow(dead_code, reason = "not every bench measures durations")]
pub fn percentile(sorted: &[Duration], p: f64) -> f64 {
    let k = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[k].as_secs_f64() * 1e3
}

/// CPU time of the whole process so far, every thread.
#[cfg(unix)]
#[allow(dead_code, reason = "not every bench measures CPU time")]
pub fn process_cpu() -> Duration {
    cpu_clock(libc::CLOCK_PROCESS_CPUTIME_ID)
}

/// CPU time of the running thread so far.
#[cfg(unix)]
#[allow(dead_code, reason = "not every bench measures CPU time")]
pub fn thread_cpu() -> Duration {
    cpu_clock(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// CPU time of the whole process: never known here.
#[cfg(not(unix))]
#[allow(dead_code, reason = "not every bench measures CPU time")]
pub fn process_cpu() -> Duration {
    Duration::ZERO
}

/// CPU time of the running thread: never known here.
#[cfg(not(unix))]
#[allow(dead_code, reason = "not every bench measures CPU time")]
pub fn thread_cpu() -> Duration {
    Duration::ZERO
}

/// The CPU time `clock` reads now (0 where it cannot be read).
#[cfg(unix)]
#[allow(dead_code, reason = "not every bench measures CPU time")]
fn cpu_clock(clock: libc::clockid_t) -> Duration {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `clock_gettime` writes one `timespec` through the pointer,
    // which points to a live, writable `timespec` on this stack.
    let status = unsafe { libc::clock_gettime(clock, &raw mut now) };
    match (
        status,
        u64::try_from(now.tv_sec),
        u32::try_from(now.tv_nsec),
    ) {
        (0, Ok(secs), Ok(nanos)) => Duration::new(secs, nanos),
        _ => Duration::ZERO,
    }
}

/// Prints `figures` (a JSON object) as one line, with `"bench":
/// "BENCH::MEASUREMENT"` added: the line a script reads.
pub fn json_line(measurement: &str, figures: serde_json::Value) {
    let mut line = serde_json::Map::new();
    line.insert("bench".into(), measurement.into());
    if let serde_json::Value::Object(figures) = figures {
        line.extend(figures);
    }
    println!("{}", serde_json::Value::Object(line));
}
