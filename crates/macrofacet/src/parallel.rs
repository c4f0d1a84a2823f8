//! Work spread over scoped threads (`std::thread::scope`), for the parts of building a surface
//! that are one independent computation per item (a mesh's triangles, edges, grid blocks): the
//! host says how many threads a construction may use. The results come back in item order, the
//! same whatever the thread count; a worker's panic resumes in the caller, where the C ABI's
//! boundary catches it. No thread outlives the call that started it.

use std::sync::atomic::{AtomicUsize, Ordering};

/// Fewest items per thread: starting one costs about as much as building a triangle's face
/// region (~30 µs), and the items here cost at least that.
const MIN_ITEMS_PER_THREAD: usize = 16;
/// Chunks per thread: threads take chunks in turn, so that uneven items (a grid's blocks far
/// from the surface cost almost nothing) still keep every thread busy to the end.
const CHUNKS_PER_THREAD: usize = 32;

/// `f(scratch, i)` for every `i` in `0..n`, in order, on up to `threads` threads (the calling
/// one among them; 0 counts as 1). Each thread has its own working space from `scratch()`.
pub fn map<T: Send, S>(n: usize, threads: usize, scratch: impl Fn() -> S + Sync, f: impl Fn(&mut S, usize) -> T + Sync) -> Vec<T> {
    let threads = threads.clamp(1, (n / MIN_ITEMS_PER_THREAD).max(1));
    if threads == 1 {
        let mut s = scratch();
        return (0..n).map(|i| f(&mut s, i)).collect();
    }
    let chunk = n.div_ceil(threads * CHUNKS_PER_THREAD);
    let next = AtomicUsize::new(0);
    let work = || {
        let mut s = scratch();
        let mut done = Vec::new();
        loop {
            let c = next.fetch_add(1, Ordering::Relaxed);
            let start = c * chunk;
            if start >= n {
                return done;
            }
            done.push((c, (start..(start + chunk).min(n)).map(|i| f(&mut s, i)).collect::<Vec<T>>()));
        }
    };
    let mut chunks = std::thread::scope(|scope| {
        let others: Vec<_> = (1..threads).map(|_| scope.spawn(work)).collect();
        let mut all = work();
        for other in others {
            match other.join() {
                Ok(done) => all.extend(done),
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
        all
    });
    chunks.sort_unstable_by_key(|(c, _)| *c);
    chunks.into_iter().flat_map(|(_, items)| items).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same results in the same order for every thread count, with per-thread scratch.
    #[test]
    fn map_gives_the_same_results_in_order_for_any_thread_count() {
        for n in [0, 1, 15, 16, 33, 1000, 4097] {
            let serial: Vec<u64> = (0..n as u64).map(|i| i * i + 7).collect();
            for threads in [0, 1, 2, 3, 8, 64] {
                let got = map(n, threads, Vec::<u64>::new, |scratch, i| {
                    scratch.push(i as u64); // (each thread's own: never shared)
                    (i as u64) * (i as u64) + 7
                });
                assert_eq!(got, serial, "n = {n}, threads = {threads}");
            }
        }
    }

    /// A worker's panic reaches the caller with its message.
    #[test]
    fn a_workers_panic_resumes_in_the_caller() {
        let caught = std::panic::catch_unwind(|| map(10_000, 4, || (), |_, i| if i == 9_000 { panic!("item {i}") } else { i }));
        let message = caught.expect_err("the panic must propagate");
        let text = message.downcast_ref::<String>().cloned().unwrap_or_default();
        assert_eq!(text, "item 9000");
    }
}
