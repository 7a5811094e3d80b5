//! CPU time of the calling thread, reported beside wall-clock times: the DP, the refinement and
//! the post-processing run on one thread, so on a shared machine the CPU time is their time on an
//! idle core (the wall time includes the waits for a core).

/// CPU time (s) of the calling thread so far, from `/proc/thread-self/schedstat` (Linux; NaN
/// elsewhere, so a difference of two readings is NaN rather than a wrong number).
pub fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}
