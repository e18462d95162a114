//! CPU seconds a render's threads spent. Equal-time comparisons divide these, not wall seconds:
//! on a shared machine wall seconds also count whatever else runs there, which would hand one
//! estimator a larger budget than another for reasons that are not its own.

use std::time::Duration;

/// CPU time the calling thread has used so far (POSIX `CLOCK_THREAD_CPUTIME_ID`); zero where the
/// clock is missing, so a caller sees "no measurement" rather than a wrong one.
pub fn thread_cpu_time() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, exclusively borrowed out-parameter for the duration of the call.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0;
    if ok {
        Duration::new(
            ts.tv_sec.max(0) as u64,
            ts.tv_nsec.clamp(0, 999_999_999) as u32,
        )
    } else {
        Duration::ZERO
    }
}

/// CPU time of every worker of `pool` and of the calling thread (which accumulates the passes),
/// summed. Other threads of the process (another render's pool) are not counted.
pub fn pool_cpu_time(pool: &rayon::ThreadPool) -> Duration {
    let workers: Duration = pool.broadcast(|_| thread_cpu_time()).into_iter().sum();
    workers + thread_cpu_time()
}

/// CPU time of every worker of the pool the caller runs in (rayon's global pool outside one),
/// summed: for phases timed from inside a render.
pub fn current_pool_cpu_time() -> Duration {
    rayon::broadcast(|_| thread_cpu_time()).into_iter().sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_pool_accumulates_cpu_time_an_idle_one_does_not() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let t0 = pool_cpu_time(&pool);
        // Each worker spins until its own clock has advanced 30 ms, however loaded the machine.
        let spin = |_: rayon::BroadcastContext<'_>| {
            let start = thread_cpu_time();
            let mut x = 0u64;
            while thread_cpu_time() - start < Duration::from_millis(30) {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
            x
        };
        pool.broadcast(spin);
        let busy = pool_cpu_time(&pool) - t0;
        assert!(busy >= Duration::from_millis(60), "{busy:?}");
        let t1 = pool_cpu_time(&pool);
        std::thread::sleep(Duration::from_millis(100));
        let idle = pool_cpu_time(&pool) - t1;
        assert!(idle < Duration::from_millis(50), "{idle:?}");
    }
}
