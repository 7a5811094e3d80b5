//! CPU clocks, reported beside wall-clock times: on a shared machine the wall time of a piece of
//! work includes its waits for a core, its CPU time does not. Linux only (`/proc`); elsewhere the
//! readings are NaN, so a difference of two readings is NaN rather than a wrong number.
//!
//! ```
//! let (x, wall_s, cpu_s) = geom_core::clock::timed(|| (0..200_000).map(|i| (i as f64).sqrt()).sum::<f64>());
//! assert!(x > 0.0 && wall_s >= 0.0);
//! assert!(cpu_s >= 0.0 || cpu_s.is_nan());
//! ```

/// CPU time (s) of the calling thread so far, from `/proc/thread-self/schedstat` (ns
/// resolution); NaN where it cannot be read. The difference over single-threaded work is its
/// time on an idle core.
pub fn thread_cpu_s() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}

#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
mod sys {
    /// `struct timespec` of 64-bit Linux.
    #[repr(C)]
    pub struct Timespec {
        pub tv_sec: i64,
        pub tv_nsec: i64,
    }
    /// `CLOCK_PROCESS_CPUTIME_ID` (linux/time.h).
    pub const CLOCK_PROCESS_CPUTIME_ID: i32 = 2;
    extern "C" {
        pub fn clock_gettime(clk: i32, tp: *mut Timespec) -> i32;
    }
}

/// User + system CPU time (s) of the whole process (every thread) so far:
/// `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)` (ns resolution) on 64-bit Linux, else
/// `/proc/self/stat` (fields 14 and 15, clock ticks of `USER_HZ` = 100 per second: 10 ms
/// resolution); NaN where neither can be read. For parallel work (rayon) the difference is the
/// CPU time summed over threads.
pub fn process_cpu_s() -> f64 {
    #[cfg(all(target_os = "linux", target_pointer_width = "64"))]
    {
        let mut ts = sys::Timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `ts` is a valid, writable timespec (64-bit Linux layout: two i64) that lives
        // across the call; the clock id is a constant the kernel defines.
        let rc = unsafe { sys::clock_gettime(sys::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
        if rc == 0 {
            return ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9;
        }
    }
    let read = || -> Option<f64> {
        let s = std::fs::read_to_string("/proc/self/stat").ok()?;
        // The command name (field 2) is in parentheses and may hold spaces: split after its ')'.
        let rest = &s[s.rfind(')')? + 1..];
        let f: Vec<&str> = rest.split_whitespace().collect();
        // `rest` starts at field 3, so fields 14 and 15 are at 11 and 12.
        let utime: f64 = f.get(11)?.parse().ok()?;
        let stime: f64 = f.get(12)?.parse().ok()?;
        Some((utime + stime) / 100.0)
    };
    read().unwrap_or(f64::NAN)
}

/// Runs `f`; returns its value, the wall seconds and the process CPU seconds it took
/// ([`process_cpu_s`]; NaN where unavailable).
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (c0, t0) = (process_cpu_s(), std::time::Instant::now());
    let out = f();
    (out, t0.elapsed().as_secs_f64(), process_cpu_s() - c0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On Linux both clocks read, advance with work, and the calling thread's CPU time never
    /// exceeds the whole process's.
    #[test]
    fn clocks_advance_with_work() {
        if !cfg!(target_os = "linux") {
            assert!(thread_cpu_s().is_nan() && process_cpu_s().is_nan());
            return;
        }
        let (t0, p0) = (thread_cpu_s(), process_cpu_s());
        assert!(t0.is_finite() && p0.is_finite());
        let mut x = 0.0f64;
        let start = std::time::Instant::now();
        while start.elapsed().as_secs_f64() < 0.05 {
            x += std::hint::black_box(x.sqrt() + 1.0);
        }
        let (t1, p1) = (thread_cpu_s(), process_cpu_s());
        assert!(x > 0.0);
        assert!(t1 > t0, "thread clock did not advance: {t0} → {t1}");
        assert!(p1 >= p0, "process clock went back: {p0} → {p1}");
        // Both are the kernel's accounting of the same run time (ns); 1 ms of slack.
        assert!(t1 - t0 <= p1 - p0 + 1e-3, "thread {} s > process {} s", t1 - t0, p1 - p0);
    }
}
