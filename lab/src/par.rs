//! One work queue on all cores, for the studies: the kernel methods run single-threaded, so a
//! study renders, scores or compares its methods side by side ([`map`]).

use std::sync::Mutex;

/// `f(0), f(1), ..., f(n - 1)` on up to 16 threads (the machine's cores, never more than
/// `n`), each thread taking the next index from a shared queue; the results in index order.
/// Errors only when a worker panicked while holding the queue or the results.
pub fn map<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Result<Vec<T>, String> {
    let queue = Mutex::new((0..n).rev().collect::<Vec<_>>());
    let results: Mutex<Vec<Option<T>>> = Mutex::new((0..n).map(|_| None).collect());
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get()).clamp(1, 16);
    std::thread::scope(|s| {
        for _ in 0..threads.min(n) {
            s.spawn(|| {
                while let Some(i) = queue.lock().ok().and_then(|mut q| q.pop()) {
                    let r = f(i);
                    if let Ok(mut out) = results.lock() {
                        out[i] = Some(r);
                    }
                }
            });
        }
    });
    results
        .into_inner()
        .map_err(|_| "a worker thread failed".to_string())?
        .into_iter()
        .map(|r| r.ok_or_else(|| "a worker thread failed".to_string()))
        .collect()
}
