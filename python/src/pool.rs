//! The worlds' thread pool: many worlds' work at once, each world on one thread, alone.
//!
//! A call is often one action's 20 steps per world, ~0.4 ms: starting threads for it cost a fifth
//! of that, and waking sleeping ones nearly as much (two worlds on 2 cores ran 1.63× one world in
//! 20-step calls, 1.94× in long ones). So the calling thread does the first share of the worlds
//! itself, and a pool of the others, kept between calls and kept awake a moment after each, does
//! the rest; at the end the calling thread waits awake for the pool's shares instead of sleeping
//! (two worlds' 20-step calls: 1.72–1.79× one world sleeping, 1.83–1.89× spinning;
//! docs/python.md), yielding its core at each look so that a busy machine's other work — or the
//! pool's own thread — can have it.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// The machine's cores, the default number of threads: read once, since the standard library
/// reads it afresh from the cgroup files each time (a dozen system calls, ~65 µs a call on a VM,
/// a tenth of a 20-step action).
pub(crate) fn cores() -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |c| c.get()))
}

/// Does `work` on every item, on up to `threads` threads (the calling thread one of them). Each
/// item is worked on by one thread, alone, so the results do not depend on the threads.
pub(crate) fn for_each<T: Send>(items: &mut [T], threads: usize, work: impl Fn(&mut T) + Sync) {
    let run = |share: &mut [T]| share.iter_mut().for_each(&work);
    let threads = threads.clamp(1, items.len().max(1));
    if threads == 1 {
        run(items);
        return;
    }
    let mut shares = items.chunks_mut(items.len().div_ceil(threads));
    let first = shares.next().expect("more than one item");
    let pool = pool(threads - 1);
    let spawned = shares.len();
    let done = AtomicUsize::new(0);
    let call = pool.in_place_scope(|scope| {
        for share in shares {
            let done = &done;
            scope.spawn(move |_| {
                // counted even if the work panics (the scope then re-raises it)
                let _counted = Counted(done);
                run(share)
            });
        }
        // only now do the threads kept awake by the last call stop spinning: their next job
        // is already queued, so none goes to sleep looking for it
        let call = CALLS.fetch_add(1, Ordering::Relaxed) + 1;
        run(first);
        // the pool's shares end within microseconds of this one's: wait for them awake rather
        // than sleep on the scope's lock, whose wake-up on a VM costs tens of microseconds —
        // yielding the core at each look, not spinning on it: where other work holds the other
        // cores, the pool's thread may be waiting for this very core (a pure spin then burnt
        // the whole 2 ms a call: two worlds ran 0.19× one world beside another job)
        let started = Instant::now();
        while done.load(Ordering::Acquire) < spawned && started.elapsed() < WAIT_SPINNING {
            std::thread::yield_now();
        }
        call
    });
    keep_awake(&pool, threads - 1, call);
}

/// Keeps the pool's threads awake for the next call: between two actions Python reads the
/// results and picks the next actions, long enough for an idle thread to sleep, and waking it
/// took as long as the gap. Each spins until the next call or [`KEEP_AWAKE`].
fn keep_awake(pool: &rayon::ThreadPool, threads: usize, call: u64) {
    for _ in 0..threads {
        pool.spawn(move || {
            let started = Instant::now();
            while CALLS.load(Ordering::Relaxed) == call && started.elapsed() < KEEP_AWAKE {
                // awake, but giving the core to whatever else wants it
                std::thread::yield_now();
            }
        });
    }
}

/// Counts one finished share when dropped, so a share that panics is counted too.
struct Counted<'a>(&'a AtomicUsize);

impl Drop for Counted<'_> {
    fn drop(&mut self) {
        self.0.fetch_add(1, Ordering::Release);
    }
}

/// How long the calling thread spins for the pool's shares after its own before it sleeps: a
/// world's 20-step action takes ~0.3 ms, and two worlds' differ by a fraction of that.
const WAIT_SPINNING: Duration = Duration::from_millis(2);

/// Calls of [`for_each`] on a pool so far: a thread kept awake stops when it changes.
static CALLS: AtomicU64 = AtomicU64::new(0);

/// How long a pool thread stays awake after a call, waiting for the next (longer than a
/// Gymnasium step's Python work, short enough to cost nothing when no call follows).
const KEEP_AWAKE: Duration = Duration::from_micros(500);

/// The thread pool of `threads` threads, made on first use and kept.
fn pool(threads: usize) -> Arc<rayon::ThreadPool> {
    static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());
    let mut pools = POOLS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, pool)) = pools.iter().find(|(n, _)| *n == threads) {
        return pool.clone();
    }
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("hexsim-world-{i}"))
            .build()
            .expect("a thread pool of a few threads starts"),
    );
    pools.push((threads, pool.clone()));
    pool
}
