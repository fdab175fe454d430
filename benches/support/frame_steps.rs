//! Where a frame's time goes, step by step: a `tracing` layer that times
//! every span the plugin opens around a step of its systems
//! (`chisel::stream::release`, `chisel::upload::upload_meshes`, ...), in
//! wall time and in the running thread's CPU time, summed per frame.
//!
//! CPU time comes from the thread's CPU clock (`CLOCK_THREAD_CPUTIME_ID`,
//! exact to the nanosecond on Linux) and the time the thread waited,
//! runnable, for a core from `/proc/thread-self/schedstat` (whose CPU
//! figure only moves at scheduler ticks, too coarse for sub-millisecond
//! steps), with the times the thread was put on a core (so its wake-ups);
//! elsewhere these read 0. The file is opened once per thread and read
//! again in place: opening it inside every timed step cost several
//! microseconds a step. On a loaded machine a slow frame can be one whose
//! main thread simply was not running, and the two tell that apart from
//! one that had work to do; a frame whose wall time is neither CPU nor
//! runqueue wait is one whose thread slept, waiting on other threads.

use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use bevy::log::tracing::span::{Attributes, Id};
use bevy::log::tracing::{Subscriber, subscriber};
use bevy::log::tracing_subscriber::layer::{Context, Layer, SubscriberExt};
use bevy::log::tracing_subscriber::registry::{LookupSpan, Registry};

/// Wall, CPU and runnable-but-waiting time of one thread over an interval,
/// how many times it was put on a core, and how many times the step ran.
#[derive(Clone, Copy, Debug, Default)]
pub struct Times {
    /// Wall-clock time.
    pub wall: Duration,
    /// Time the thread ran on a core.
    pub cpu: Duration,
    /// Time the thread was runnable but waited for a core.
    pub wait: Duration,
    /// Times the thread was put on a core (once, plus once per wake-up
    /// after it slept or was preempted).
    pub slices: u64,
    /// Runs of the step.
    pub runs: u32,
}

impl Times {
    fn add(&mut self, other: Times) {
        self.wall += other.wall;
        self.cpu += other.cpu;
        self.wait += other.wait;
        self.slices += other.slices;
        self.runs += other.runs;
    }
}

/// The running thread's CPU time so far, and from its scheduler
/// statistics its runqueue wait and the times it was put on a core.
#[must_use]
pub fn thread_clock() -> (Duration, Duration, u64) {
    let (wait, slices) = schedstat();
    (super::support::thread_cpu(), wait, slices)
}

std::thread_local! {
    /// This thread's `/proc/thread-self/schedstat`, opened once: reading
    /// it again at offset 0 costs a fraction of opening it (the path walk
    /// through /proc), which would otherwise sit inside every timed step.
    static SCHEDSTAT: Option<std::fs::File> =
        std::fs::File::open("/proc/thread-self/schedstat").ok();
}

/// The running thread's runqueue wait and times put on a core so far
/// (0 where there are no scheduler statistics).
#[cfg(unix)]
fn schedstat() -> (Duration, u64) {
    use std::os::unix::fs::FileExt;
    SCHEDSTAT.with(|file| {
        let mut buf = [0u8; 96];
        let Some(n) = file.as_ref().and_then(|f| f.read_at(&mut buf, 0).ok()) else {
            return (Duration::ZERO, 0);
        };
        let text = std::str::from_utf8(&buf[..n]).unwrap_or_default();
        let mut fields = text
            .split_whitespace()
            .map(|f| f.parse::<u64>().unwrap_or(0));
        let _cpu = fields.next();
        let wait = fields.next().unwrap_or(0);
        let slices = fields.next().unwrap_or(0);
        (Duration::from_nanos(wait), slices)
    })
}

/// The running thread's runqueue wait and times put on a core: never
/// known here.
#[cfg(not(unix))]
fn schedstat() -> (Duration, u64) {
    (Duration::ZERO, 0)
}

/// A point in time on the running thread, to time an interval with
/// [`Mark::since`].
#[derive(Clone, Copy)]
pub struct Mark {
    at: Instant,
    cpu: Duration,
    wait: Duration,
    slices: u64,
}

impl Mark {
    /// Now, on this thread.
    #[must_use]
    pub fn now() -> Self {
        let (cpu, wait, slices) = thread_clock();
        Self {
            at: Instant::now(),
            cpu,
            wait,
            slices,
        }
    }

    /// The interval from this mark to now (on the same thread).
    #[must_use]
    pub fn since(&self) -> Times {
        let (cpu, wait, slices) = thread_clock();
        Times {
            wall: self.at.elapsed(),
            cpu: cpu.saturating_sub(self.cpu),
            wait: wait.saturating_sub(self.wait),
            slices: slices.saturating_sub(self.slices),
            runs: 1,
        }
    }
}

/// CPU, runqueue wait and times put on a core of each of the process's
/// threads so far, by
/// thread id, with the thread's group: `main` (the process's first thread),
/// `compute` (Bevy's compute pool: the frame's systems), `async` (Bevy's
/// async compute pool: chunk builds), `workers` (the terrain's carve and
/// mesh threads), `io`, `other`.
#[must_use]
pub fn threads() -> BTreeMap<u32, (&'static str, Duration, Duration, u64)> {
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
        let (cpu, wait, slices) = (
            it.next().unwrap_or(0),
            it.next().unwrap_or(0),
            it.next().unwrap_or(0),
        );
        out.insert(
            tid,
            (
                group,
                Duration::from_nanos(cpu),
                Duration::from_nanos(wait),
                slices,
            ),
        );
    }
    out
}

/// CPU and wait per thread group between two [`threads`] readings, as
/// steps named `threads::GROUP`.
pub fn thread_steps(
    before: &BTreeMap<u32, (&'static str, Duration, Duration, u64)>,
    after: &BTreeMap<u32, (&'static str, Duration, Duration, u64)>,
) -> BTreeMap<&'static str, Times> {
    let mut out: BTreeMap<&'static str, Times> = BTreeMap::new();
    for (tid, &(group, cpu, wait, slices)) in after {
        let (cpu0, wait0, slices0) = before
            .get(tid)
            .map_or((Duration::ZERO, Duration::ZERO, 0), |b| (b.1, b.2, b.3));
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
            slices: slices.saturating_sub(slices0),
            runs: 1,
        });
    }
    out
}

/// The steps timed since the last [`take_frame`], by span name.
static FRAME: Mutex<BTreeMap<&'static str, Times>> = Mutex::new(BTreeMap::new());

/// The steps timed on the main thread since the last [`take_main_frame`],
/// by span name.
static MAIN_FRAME: Mutex<BTreeMap<&'static str, Times>> = Mutex::new(BTreeMap::new());

/// Whether the running thread is the process's main thread.
fn on_main_thread() -> bool {
    std::thread::current().name() == Some("main")
}

/// Adds `times` to the step `name` of this frame (and of this frame's
/// main-thread steps when the running thread is the main one).
fn record(name: &'static str, times: Times) {
    if let Ok(mut frame) = FRAME.lock() {
        frame.entry(name).or_default().add(times);
    }
    if on_main_thread()
        && let Ok(mut frame) = MAIN_FRAME.lock()
    {
        frame.entry(name).or_default().add(times);
    }
}

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
        record(span.metadata().name(), mark.since());
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

/// The steps timed on the main thread since the last call, by span name
/// (the schedules of [`time_schedules`] among them).
pub fn take_main_frame() -> BTreeMap<&'static str, Times> {
    MAIN_FRAME
        .lock()
        .map(|mut f| std::mem::take(&mut *f))
        .unwrap_or_default()
}

/// The main schedule order [`time_schedules`] runs in its one schedule.
#[derive(bevy::ecs::resource::Resource)]
struct TimedOrder(Vec<bevy::ecs::schedule::InternedScheduleLabel>);

/// The one schedule [`time_schedules`] leaves in the main schedule order.
#[derive(bevy::ecs::schedule::ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
struct TimedMain;

/// Times each schedule of `app`'s main order (`First`, `PreUpdate`, ...,
/// `Last`) as a step named `schedule::LABEL`, on the main thread that runs
/// them, by running them in that order from one exclusive system in their
/// stead. `App::update` runs the same schedules in the same order.
pub fn time_schedules(app: &mut bevy::app::App) {
    use bevy::app::MainScheduleOrder;
    use bevy::ecs::schedule::{
        InternedScheduleLabel, Schedule, ScheduleLabel, SingleThreadedExecutor,
    };
    use bevy::ecs::world::World;
    let labels = std::mem::take(&mut app.world_mut().resource_mut::<MainScheduleOrder>().labels);
    app.insert_resource(TimedOrder(labels.clone()));
    let named: Vec<(InternedScheduleLabel, &'static str)> = labels
        .iter()
        .map(|&label| {
            let name: &'static str = Box::leak(format!("schedule::{label:?}").into_boxed_str());
            (label, name)
        })
        .collect();
    let mut schedule = Schedule::new(TimedMain);
    schedule.set_executor(SingleThreadedExecutor::new());
    schedule.add_systems(move |world: &mut World| {
        for &(label, name) in &named {
            let mark = Mark::now();
            // A schedule not (yet) in the world is skipped, as `Main` does.
            let _ = world.try_run_schedule(label);
            record(name, mark.since());
        }
    });
    app.add_schedule(schedule);
    app.world_mut()
        .resource_mut::<MainScheduleOrder>()
        .labels
        .push(TimedMain.intern());
}

/// Prints, per schedule of `app`'s main order (once they have run), its
/// systems and those of them that run on the main thread under the
/// multi-threaded executor: exclusive systems, command sync points
/// (`apply_deferred`) and systems that are not `Send`. Each hands the
/// frame from a pool thread to the main thread and back.
pub fn print_main_thread_systems(app: &bevy::app::App) {
    use bevy::app::MainScheduleOrder;
    use bevy::ecs::schedule::Schedules;
    let labels = app.world().get_resource::<TimedOrder>().map_or_else(
        || app.world().resource::<MainScheduleOrder>().labels.clone(),
        |order| order.0.clone(),
    );
    let schedules = app.world().resource::<Schedules>();
    for label in labels {
        let Some(schedule) = schedules.get(label) else {
            continue;
        };
        let Ok(systems) = schedule.systems() else {
            println!("    {label:?}: not run yet");
            continue;
        };
        let (mut all, mut sync_points) = (0usize, 0usize);
        let mut on_main = Vec::new();
        for (_, system) in systems {
            all += 1;
            if system.system_type() == std::any::TypeId::of::<bevy::ecs::schedule::ApplyDeferred>()
            {
                sync_points += 1;
            } else if system.is_exclusive() || !system.is_send() {
                // Names need Bevy's `debug` feature; without it, the kind.
                let name = system.name().to_string();
                on_main.push(if name.starts_with('<') {
                    if system.is_exclusive() {
                        "(an exclusive system)".to_string()
                    } else {
                        "(a system that is not Send)".to_string()
                    }
                } else {
                    name
                });
            }
        }
        println!(
            "    {label:?}: {all} systems, {sync_points} command sync points, {} other on the \
             main thread: {}",
            on_main.len(),
            on_main.join(", ")
        );
    }
}

/// Per step, the median and the mean over `frames` of its wall and CPU
/// time per frame (0 in a frame where it did not run), printed slowest
/// first by mean wall time; a step is kept when its mean wall or CPU time
/// reaches `floor`.
pub fn print_medians(label: &str, frames: &[BTreeMap<&'static str, Times>], floor: Duration) {
    let mut names: Vec<&'static str> = frames.iter().flat_map(|f| f.keys().copied()).collect();
    names.sort_unstable();
    names.dedup();
    let n = frames.len().max(1);
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let median = |mut v: Vec<Duration>| {
        v.sort_unstable();
        v.get(v.len() / 2).copied().unwrap_or_default()
    };
    let mut rows: Vec<(
        &'static str,
        Duration,
        Duration,
        Duration,
        Duration,
        f64,
        f64,
    )> = names
        .into_iter()
        .map(|name| {
            let get = |f: &BTreeMap<&'static str, Times>| f.get(name).copied().unwrap_or_default();
            let walls: Vec<Duration> = frames.iter().map(|f| get(f).wall).collect();
            let cpus: Vec<Duration> = frames.iter().map(|f| get(f).cpu).collect();
            let runs: u32 = frames.iter().map(|f| get(f).runs).sum();
            let slices: u64 = frames.iter().map(|f| get(f).slices).sum();
            let mean = |v: &[Duration]| v.iter().sum::<Duration>() / n as u32;
            (
                name,
                median(walls.clone()),
                mean(&walls),
                median(cpus.clone()),
                mean(&cpus),
                f64::from(runs) / n as f64,
                slices as f64 / n as f64,
            )
        })
        .filter(|r| r.2 >= floor || r.4 >= floor)
        .collect();
    rows.sort_by_key(|r| std::cmp::Reverse(r.2));
    println!(
        "{label} ({} frames), per frame: wall median / mean, CPU median / mean, times put on a \
         core (mean), runs (mean)",
        frames.len()
    );
    for (name, wall_median, wall_mean, cpu_median, cpu_mean, runs, slices) in rows {
        println!(
            "    {name:34} wall {:6.3} / {:6.3} ms, CPU {:6.3} / {:6.3} ms, on a core {slices:5.1}, \
             runs {runs:.2}",
            ms(wall_median),
            ms(wall_mean),
            ms(cpu_median),
            ms(cpu_mean)
        );
    }
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
