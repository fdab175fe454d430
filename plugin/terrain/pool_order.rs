//! Debris first on the async compute pool.
//!
//! Bevy's async compute pool runs its tasks in the order they were
//! spawned, on a quarter of the cores (one thread on a machine with up to
//! seven). A streamed world keeps up to
//! [`StreamSettings::max_building`](super::StreamSettings::max_building)
//! chunk builds and as many coarse chunk builds there, so a piece cut
//! loose across chunk borders would wait behind them twice, for its
//! search and for the job that takes it out and builds it, while the
//! player sees it float.
//!
//! The rule: a task spawned with [`spawn_first`] (a world's search for
//! debris across chunk borders, and a chunk's job that takes such debris
//! out) goes before every chunk build and coarse chunk build that has not
//! started yet. Each of those builds begins with [`after_first`], which,
//! while a first task waits in the pool's queue, puts the build back at
//! the queue's end (behind it); builds already running finish. A first
//! task never waits for a build it was spawned after, only for the tasks
//! running when it was spawned and for other tasks (carves, props) ahead
//! of it. Nothing blocks: a build that steps back is polled again once the
//! first tasks have started. The order of the work changes, not its
//! results: a search and a job compute the same whatever ran before them.

use std::future::Future;
use std::sync::atomic::{AtomicUsize, Ordering};

use bevy::tasks::futures_lite::future::yield_now;
use bevy::tasks::{AsyncComputeTaskPool, Task};

/// First tasks spawned that have not started (nor been dropped).
static FIRST_WAITING: AtomicUsize = AtomicUsize::new(0);

/// Counts one first task as waiting until it starts or is dropped.
struct Waiting;

impl Waiting {
    fn new() -> Self {
        FIRST_WAITING.fetch_add(1, Ordering::AcqRel);
        Self
    }
}

impl Drop for Waiting {
    fn drop(&mut self) {
        FIRST_WAITING.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Spawns `future` on the async compute pool ahead of the chunk builds
/// that have not started (see the module docs).
pub(crate) fn spawn_first<T: Send + 'static>(
    future: impl Future<Output = T> + Send + 'static,
) -> Task<T> {
    let waiting = Waiting::new();
    AsyncComputeTaskPool::get().spawn(async move {
        drop(waiting);
        future.await
    })
}

/// Whether a first task waits to start.
pub(crate) fn first_waiting() -> bool {
    FIRST_WAITING.load(Ordering::Acquire) > 0
}

/// Steps back behind the first tasks waiting in the pool's queue, if any:
/// the start of every chunk build and coarse chunk build.
pub(crate) async fn after_first() {
    while first_waiting() {
        yield_now().await;
    }
}
