//! Where a frame's time goes, step by step: a `tracing` layer that times
//! every span the plugin opens around a step of its systems
//! (`chisel::stream::release`, `chisel::upload::upload_meshes`, ...), in
//! wall time and in the running thread's CPU time, summed per frame.
//!
//! CPU time comes from the thread's CPU clock (`CLOCK_THREAD_CPUTIME_ID`,
//! exact to the nanosecond on Linux) and the time the thread waited,
//! runnable, for a core from `/proc/thread-self/schedstat` (whose CPU
//! figure only moves at scheduler ticks, too coarse for sub-millisecond
//! steps); elsewhere both read 0. On a loaded machine a slow frame can be
//! one whose main thread simply was not running, and the two tell that
//! apart from one that had work to do.

use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use bevy::log::tracing::span::{Attributes, Id};
use bevy::log::tracing::{Subscriber, subscriber};
use bevy::log::tracing_subscriber::layer::{Context, Layer, SubscriberExt};
use bevy::log::tracing_subscriber::registry::{LookupSpan, Registry};

/// Wall, CPU and runnable-but-waiting time of one thread over an interval,
/// and how many times the step ran.
#[derive(Clone, Copy, Debug, Default)]
pub struct Times {
    /// Wall-clock time.
    pub wall: Duration,
    /// Time the thread ran on a core.
    pub cpu: Duration,
    /// Time the thread was runnable but waited for a core.
    pub wait: Duration,
    /// Runs of the step.
    pub runs: u32,
}

impl Times {
    fn add(&mut self, other: Times) {
        self.wall += other.wall;
        self.cpu += other.cpu;
        self.wait += other.wait;
        self.runs += other.runs;
    }
}

/// The running thread's CPU time and runqueue wait so far.
#[must_use]
pub fn thread_clock() -> (Duration, Duration) {
    let wait = || -> Option<u64> {
        let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
        text.split_whitespace().nth(1)?.parse().ok()
    };
    (thread_cpu(), Duration::from_nanos(wait().unwrap_or(0)))
}

/// The running thread's CPU time so far (0 where there is no such clock).
#[cfg(unix)]
fn thread_cpu() -> Duration {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `clock_gettime` writes one `timespec` through the pointer,
    // which points to a live, writable `timespec` on this stack.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &raw mut now) };
    match (
        status,
        u64::try_from(now.tv_sec),
        u32::try_from(now.tv_nsec),
    ) {
        (0, Ok(secs), Ok(nanos)) => Duration::new(secs, nanos),
        _ => Duration::ZERO,
    }
}

/// The running thread's CPU time so far: never known here.
#[cfg(not(unix))]
fn thread_cpu() -> Duration {
    Duration::ZERO
}

/// A point in time on the running thread, to time an interval with
/// [`Mark::since`].
#[derive(Clone, Copy)]
pub struct Mark {
    at: Instant,
    cpu: Duration,
    wait: Duration,
}

impl Mark {
    /// Now, on this thread.
    #[must_use]
    pub fn now() -> Self {
        let (cpu, wait) = thread_clock();
        Self {
            at: Instant::now(),
            cpu,
            wait,
        }
    }

    /// The interval from this mark to now (on the same thread).
    #[must_use]
    pub fn since(&self) -> Times {
        let (cpu, wait) = thread_clock();
        Times {
            wall: self.at.elapsed(),
            cpu: cpu.saturating_sub(self.cpu),
            wait: wait.saturating_sub(self.wait),
            runs: 1,
        }
    }
}

/// CPU and runqueue wait of each of the process's threads so far, by
/// thread id, with the thread's group: `main` (the process's first thread),
/// `compute` (Bevy's compute pool: the frame's systems), `async` (Bevy's
/// async compute pool: chunk builds), `workers` (the terrain's carve and
/// mesh threads), `io`, `other`.
#[must_use]
pub fn threads() -> BTreeMap<u32, (&'static str, Duration, Duration)> {
    let mut out = BTreeMap::new();
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return out;
    };
    let pid = std::process::id();
    for entry in dir.flatten() {
        let Some(tid) = entry
            .file_name()
            .to_str()
            .and_then(|s| s.parse::<u32>().ok())
        else {
            continue;
        };
        let path = entry.path();
        let comm = std::fs::read_to_string(path.join("comm")).unwrap_or_default();
        let group = if tid == pid {
            "main"
        } else if comm.starts_with("Compute") {
            "compute"
        } else if comm.starts_with("Async") {
            "async"
        } else if comm.starts_with("chisel-terrain") {
            "workers"
        } else if comm.starts_with("IO") {
            "io"
        } else {
            "other"
        };
        let stat = std::fs::read_to_string(path.join("schedstat")).unwrap_or_default();
        let mut it = stat
            .split_whitespace()
            .map(|n| n.parse::<u64>().unwrap_or(0));
        let (cpu, wait) = (it.next().unwrap_or(0), it.next().unwrap_or(0));
        out.insert(
            tid,
            (group, Duration::from_nanos(cpu), Duration::from_nanos(wait)),
        );
    }
    out
}

/// CPU and wait per thread group between two [`threads`] readings, as
/// steps named `threads::GROUP`.
pub fn thread_steps(
    before: &BTreeMap<u32, (&'static str, Duration, Duration)>,
    after: &BTreeMap<u32, (&'static str, Duration, Duration)>,
) -> BTreeMap<&'static str, Times> {
    let mut out: BTreeMap<&'static str, Times> = BTreeMap::new();
    for (tid, &(group, cpu, wait)) in after {
        let (cpu0, wait0) = before
            .get(tid)
            .map_or((Duration::ZERO, Duration::ZERO), |b| (b.1, b.2));
        let name = match group {
            "main" => "threads::main",
            "compute" => "threads::compute",
            "async" => "threads::async",
            "workers" => "threads::workers",
            "io" => "threads::io",
            _ => "threads::other",
        };
        out.entry(name).or_default().add(Times {
            wall: Duration::ZERO,
            cpu: cpu.saturating_sub(cpu0),
            wait: wait.saturating_sub(wait0),
            runs: 1,
        });
    }
    out
}

/// The steps timed since the last [`take_frame`], by span name.
static FRAME: Mutex<BTreeMap<&'static str, Times>> = Mutex::new(BTreeMap::new());

struct StepLayer;

impl<S: Subscriber + for<'a> LookupSpan<'a>> Layer<S> for StepLayer {
    fn on_new_span(&self, _attrs: &Attributes<'_>, _id: &Id, _ctx: Context<'_, S>) {}

    fn on_enter(&self, id: &Id, ctx: Context<'_, S>) {
        if let Some(span) = ctx.span(id) {
            span.extensions_mut().replace(Mark::now());
        }
    }

    fn on_exit(&self, id: &Id, ctx: Context<'_, S>) {
        let Some(span) = ctx.span(id) else {
            return;
        };
        let Some(mark) = span.extensions_mut().remove::<Mark>() else {
            return;
        };
        let times = mark.since();
        let name = span.metadata().name();
        if let Ok(mut frame) = FRAME.lock() {
            frame.entry(name).or_default().add(times);
        }
    }
}

/// Installs the layer as the process's subscriber; false when one was
/// already set (then nothing is timed).
pub fn install() -> bool {
    subscriber::set_global_default(Registry::default().with(StepLayer)).is_ok()
}

/// The steps timed since the last call, by span name.
pub fn take_frame() -> BTreeMap<&'static str, Times> {
    FRAME
        .lock()
        .map(|mut f| std::mem::take(&mut *f))
        .unwrap_or_default()
}

/// One frame's record: the whole update on the main thread and its steps.
pub struct FrameRecord {
    /// `App::update` on the main thread.
    pub update: Times,
    /// The plugin's steps (on whichever thread ran them).
    pub steps: BTreeMap<&'static str, Times>,
}

/// Prints, for the slowest `share` of `frames` by wall time, the mean per
/// slow frame of the update's wall, CPU and wait time and of each step,
/// then the `worst` slowest frames one by one.
pub fn report(frames: &[FrameRecord], share: f64, worst: usize) {
    let mut order: Vec<usize> = (0..frames.len()).collect();
    order.sort_by(|&a, &b| frames[b].update.wall.cmp(&frames[a].update.wall));
    let slow = ((frames.len() as f64 * share).ceil() as usize).clamp(1, frames.len().max(1));
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let summarise = |picked: &[usize], label: &str| {
        let n = picked.len().max(1) as f64;
        let mut update = Times::default();
        let mut steps: BTreeMap<&'static str, Times> = BTreeMap::new();
        for &i in picked {
            update.add(frames[i].update);
            for (name, t) in &frames[i].steps {
                steps.entry(name).or_default().add(*t);
            }
        }
        println!(
            "{label} ({} frames), mean per frame: update wall {:.2} ms = main-thread CPU {:.2} + \
             waiting for a core {:.2} + other {:.2}",
            picked.len(),
            ms(update.wall) / n,
            ms(update.cpu) / n,
            ms(update.wait) / n,
            (ms(update.wall) - ms(update.cpu) - ms(update.wait)) / n
        );
        for (name, t) in &steps {
            println!(
                "    {name:34} wall {:7.2} ms, CPU {:7.2} ms, wait {:7.2} ms, runs {:.2}",
                ms(t.wall) / n,
                ms(t.cpu) / n,
                ms(t.wait) / n,
                f64::from(t.runs) / n
            );
        }
    };
    if frames.is_empty() {
        return;
    }
    summarise(&order[..slow], &format!("slowest {:.1} %", share * 100.0));
    summarise(&order[slow..], "the other frames");
    for &i in order.iter().take(worst) {
        let f = &frames[i];
        let steps: Vec<String> = f
            .steps
            .iter()
            .filter(|(_, t)| {
                t.wall >= Duration::from_micros(500) || t.cpu + t.wait >= Duration::from_micros(500)
            })
            .map(|(name, t)| {
                format!(
                    "{} {:.1}/{:.1}/{:.1}",
                    name.trim_start_matches("chisel::"),
                    ms(t.wall),
                    ms(t.cpu),
                    ms(t.wait)
                )
            })
            .collect();
        println!(
            "  frame {i}: wall {:.1} ms, CPU {:.1}, wait {:.1}; steps (wall/CPU/wait ms): {}",
            ms(f.update.wall),
            ms(f.update.cpu),
            ms(f.update.wait),
            steps.join(", ")
        );
    }
}
