//! CPU time of the calling thread, for per-step figures that a loaded
//! machine does not inflate: a step's wall time there includes the time
//! other processes held the core, its thread CPU time does not.
//!
//! With `--threads 1` every step runs on the one worker thread that times
//! it, so its thread CPU time is the step's whole CPU cost; with more
//! threads the other workers' share is not counted.

/// Seconds of CPU the calling thread has used (`CLOCK_THREAD_CPUTIME_ID`),
/// or `None` where the system has no such clock.
#[cfg(unix)]
#[must_use]
pub fn thread_cpu_seconds() -> Option<f64> {
    let mut now = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `clock_gettime` writes one `timespec` through the pointer,
    // which points to a live, writable `timespec` on this stack.
    let status = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &raw mut now) };
    (status == 0).then_some(now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9)
}

/// Seconds of CPU the calling thread has used; never known here.
#[cfg(not(unix))]
#[must_use]
pub fn thread_cpu_seconds() -> Option<f64> {
    None
}

/// A thread CPU stopwatch: started on the thread that reads it.
#[derive(Clone, Copy, Debug)]
pub struct CpuStopwatch {
    start: Option<f64>,
}

impl CpuStopwatch {
    /// Starts at the calling thread's CPU time now.
    #[must_use]
    pub fn start() -> Self {
        Self {
            start: thread_cpu_seconds(),
        }
    }

    /// CPU seconds the calling thread used since [`CpuStopwatch::start`]
    /// (0 where the clock is unknown). Read it on the thread that started it.
    #[must_use]
    pub fn elapsed(&self) -> f64 {
        match (self.start, thread_cpu_seconds()) {
            (Some(start), Some(now)) => (now - start).max(0.0),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg(unix)]
    fn counts_work_not_sleep() {
        let watch = CpuStopwatch::start();
        std::thread::sleep(std::time::Duration::from_millis(30));
        let slept = watch.elapsed();
        assert!(slept < 0.015, "sleeping used {slept} s of CPU");
        let watch = CpuStopwatch::start();
        let wall = std::time::Instant::now();
        let mut x: u64 = 1;
        while wall.elapsed().as_secs_f64() < 0.03 {
            for _ in 0..1000 {
                x = std::hint::black_box(x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1));
            }
        }
        let busy = watch.elapsed();
        assert!(
            busy > 0.0 && busy <= wall.elapsed().as_secs_f64() + 1e-3,
            "busy {busy} s"
        );
    }
}
