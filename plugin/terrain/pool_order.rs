//! Carves and debris first on the async compute pool.
//!
//! Bevy's async compute pool runs its tasks in the order they were
//! spawned, on a quarter of the cores (one thread on a machine with up to
//! seven). A streamed world keeps up to
//! [`StreamSettings::max_building`](super::StreamSettings::max_building)
//! chunk builds and as many coarse chunk builds there, each tens of
//! milliseconds, so a crater would wait behind them before its chunk's
//! job ran (the hole showing a frame or two late, exactly while the
//! player runs and shoots), and a piece cut loose across chunk borders
//! would wait behind them twice, for its search and for the job that
//! takes it out, while the player sees it float.
//!
//! The rule: a task spawned with [`PoolOrder::spawn_first`] goes before
//! every build of its world (chunk builds and coarse chunk builds) that
//! has not started yet. First tasks are the carve and undo jobs of the
//! world's chunks, its search for debris across chunk borders and a
//! chunk's job that takes such debris out. Among themselves they keep
//! their order: a carve ranks with the debris work, not after it, since a
//! search follows the carve jobs whose results it reads (it starts once
//! they are applied), and a job that stepped back would lose its place to
//! later ones. Each build begins with [`PoolOrder::after_first`], which,
//! while a first task of its world waits in the pool's queue, puts the
//! build back at the queue's end (behind it); builds already running
//! finish. Other tasks (a chunk's first meshes, border reseals, prop
//! sampling) keep their place. Nothing blocks: a build that steps back is
//! polled again once the first tasks have started.
//!
//! No starvation: a build steps back for at most [`MOST_FIRST_AHEAD`]
//! first tasks spawned after it first came to run (besides those already
//! waiting then); later ones queue behind it. Builds are held back only
//! while first tasks are waiting, so where carves leave the pool any time
//! they still start as before; only a stream of carve jobs that keeps the
//! pool busy by itself meets the bound, and then chunks still stream in.
//!
//! Each world keeps its own count ([`PoolOrder`], held by the world and
//! handed to its builds, its chunks' jobs and its searches): a world's
//! builds step back for its own first tasks only, and only its own count
//! them towards the bound, so a second world (a server's and a client's
//! in one process, or tests side by side) carving every frame neither
//! holds this world's builds back nor wears their bound away. A single
//! terrain's jobs, in no world, jump no builds and spawn plainly. The
//! order of the work changes, not its results: a job, a search and a
//! build compute the same whatever ran before them.

use std::future::Future;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use bevy::tasks::futures_lite::future::yield_now;
use bevy::tasks::{AsyncComputeTaskPool, Task, TaskPool};

/// Most first tasks spawned after a build first came to run that it steps
/// back for; it then keeps its place.
pub(crate) const MOST_FIRST_AHEAD: u64 = 8;

/// One world's order on the async compute pool: its first tasks waiting
/// and spawned (see the module docs). Clones share the counts.
#[derive(Clone, Debug, Default)]
pub(crate) struct PoolOrder(Arc<FirstCounts>);

#[derive(Debug, Default)]
struct FirstCounts {
    /// First tasks spawned that have not started (nor been dropped).
    waiting: AtomicUsize,
    /// First tasks spawned so far.
    spawned: AtomicU64,
}

/// Counts one first task as waiting until it starts or is dropped.
struct Waiting(Arc<FirstCounts>);

impl Waiting {
    fn new(counts: &Arc<FirstCounts>) -> Self {
        counts.spawned.fetch_add(1, Ordering::AcqRel);
        counts.waiting.fetch_add(1, Ordering::AcqRel);
        Self(counts.clone())
    }
}

impl Drop for Waiting {
    fn drop(&mut self) {
        self.0.waiting.fetch_sub(1, Ordering::AcqRel);
    }
}

impl PoolOrder {
    /// Spawns `future` on the async compute pool ahead of this world's
    /// builds that have not started (see the module docs).
    pub(crate) fn spawn_first<T: Send + 'static>(
        &self,
        future: impl Future<Output = T> + Send + 'static,
    ) -> Task<T> {
        self.spawn_first_on(AsyncComputeTaskPool::get(), future)
    }

    /// [`PoolOrder::spawn_first`] on `pool`.
    fn spawn_first_on<T: Send + 'static>(
        &self,
        pool: &TaskPool,
        future: impl Future<Output = T> + Send + 'static,
    ) -> Task<T> {
        let waiting = Waiting::new(&self.0);
        pool.spawn(async move {
            drop(waiting);
            future.await
        })
    }

    /// Whether a first task of this world waits to start.
    pub(crate) fn first_waiting(&self) -> bool {
        self.0.waiting.load(Ordering::Acquire) > 0
    }

    /// Steps back behind this world's first tasks waiting in the pool's
    /// queue, if any, for at most [`MOST_FIRST_AHEAD`] spawned from now:
    /// the start of every chunk build and coarse chunk build.
    pub(crate) async fn after_first(&self) {
        let last = self.0.spawned.load(Ordering::Acquire) + MOST_FIRST_AHEAD;
        while self.first_waiting() && self.0.spawned.load(Ordering::Acquire) <= last {
            yield_now().await;
        }
    }
}

/// Spawns `future` on the async compute pool: ahead of the builds of the
/// world `order` belongs to, or plainly without one (a single terrain).
pub(crate) fn spawn_in_order<T: Send + 'static>(
    order: Option<&PoolOrder>,
    future: impl Future<Output = T> + Send + 'static,
) -> Task<T> {
    match order {
        Some(order) => order.spawn_first(future),
        None => AsyncComputeTaskPool::get().spawn(future),
    }
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc;
    use std::sync::{Arc, Mutex};

    use bevy::tasks::TaskPoolBuilder;
    use bevy::tasks::futures_lite::future::block_on;

    use super::*;

    type Log = Arc<Mutex<Vec<String>>>;

    fn note(log: &Log, what: String) {
        log.lock().expect("log").push(what);
    }

    /// A pool of one thread, held by a task until the sender sends:
    /// everything spawned meanwhile queues in order.
    fn held_pool() -> (Arc<TaskPool>, mpsc::Sender<()>, Task<()>) {
        let pool = Arc::new(TaskPoolBuilder::new().num_threads(1).build());
        let (open, gate) = mpsc::channel::<()>();
        let held = pool.spawn(async move {
            let _ = gate.recv();
        });
        (pool, open, held)
    }

    fn build(pool: &TaskPool, order: &PoolOrder, log: &Log, name: &str) -> Task<()> {
        let (log, name, order) = (log.clone(), name.to_string(), order.clone());
        pool.spawn(async move {
            order.after_first().await;
            note(&log, name);
        })
    }

    fn first(pool: &TaskPool, order: &PoolOrder, log: &Log, name: &str) -> Task<()> {
        let (log, name) = (log.clone(), name.to_string());
        order.spawn_first_on(pool, async move { note(&log, name) })
    }

    /// The world's carves go before its builds that have not started;
    /// another world's carve and a plain task keep their place.
    #[test]
    fn first_tasks_go_before_their_worlds_builds_that_have_not_started() {
        let (pool, open, held) = held_pool();
        let (order, other) = (PoolOrder::default(), PoolOrder::default());
        let log = Log::default();
        let tasks = vec![
            build(&pool, &order, &log, "build 1"),
            build(&pool, &order, &log, "build 2"),
            build(&pool, &other, &log, "other build"),
            first(&pool, &order, &log, "carve 1"),
            first(&pool, &other, &log, "other carve"),
            first(&pool, &order, &log, "carve 2"),
            pool.spawn({
                let log = log.clone();
                async move { note(&log, "plain".into()) }
            }),
        ];
        open.send(()).expect("gate");
        block_on(held);
        for task in tasks {
            block_on(task);
        }
        let order = log.lock().expect("log").clone();
        assert_eq!(
            order,
            [
                "carve 1",
                "other carve",
                "carve 2",
                "plain",
                "build 1",
                "build 2",
                "other build"
            ],
            "first tasks ahead of their world's builds, in their order"
        );
    }

    /// With no first task of its own world waiting, a build keeps its
    /// place before another world's carve.
    #[test]
    fn another_worlds_carves_do_not_hold_a_build_back() {
        let (pool, open, held) = held_pool();
        let (order, other) = (PoolOrder::default(), PoolOrder::default());
        let log = Log::default();
        let tasks = vec![
            build(&pool, &order, &log, "build"),
            first(&pool, &other, &log, "other carve"),
        ];
        open.send(()).expect("gate");
        block_on(held);
        for task in tasks {
            block_on(task);
        }
        assert_eq!(*log.lock().expect("log"), ["build", "other carve"]);
    }

    /// Each first task of a chain spawns the next when it runs, so that
    /// one always waits: the build still runs, after at most
    /// `MOST_FIRST_AHEAD` of them (and the one waiting when it came up),
    /// where it would otherwise wait for the whole chain.
    #[test]
    fn a_build_is_not_starved_by_a_stream_of_first_tasks() {
        const CHAIN: usize = 64;
        fn link(pool: Arc<TaskPool>, order: PoolOrder, log: Log, k: usize) -> Task<()> {
            let (next, next_order) = (pool.clone(), order.clone());
            order.spawn_first_on(&pool, async move {
                note(&log, format!("carve {k}"));
                if k + 1 < CHAIN {
                    link(next, next_order, log, k + 1).detach();
                }
            })
        }
        let (pool, open, held) = held_pool();
        let order = PoolOrder::default();
        let log = Log::default();
        let built = build(&pool, &order, &log, "build");
        link(pool.clone(), order.clone(), log.clone(), 0).detach();
        open.send(()).expect("gate");
        block_on(held);
        block_on(built);
        // The chain ends by itself; wait for its last link.
        while log.lock().expect("log").len() < CHAIN + 1 {
            std::thread::yield_now();
        }
        let order = log.lock().expect("log").clone();
        let at = order.iter().position(|s| s == "build").expect("built");
        assert!(at >= 1, "the build stepped back: {order:?}");
        assert!(
            at <= MOST_FIRST_AHEAD as usize + 2,
            "the build ran after at most {MOST_FIRST_AHEAD} later first tasks: {order:?}"
        );
    }
}
