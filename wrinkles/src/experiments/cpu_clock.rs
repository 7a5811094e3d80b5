//! CPU time of this process (all threads), the cost measure of the W3/W4 scenes: on a shared
//! machine the wall time also counts other processes, the CPU time of this process does not.
//!
//! ```
//! let t0 = wrinkles::experiments::cpu_clock::process_cpu_seconds();
//! let mut x = 0.0f64;
//! for i in 0..200_000 {
//!     x += (i as f64).sqrt();
//! }
//! assert!(x > 0.0 && wrinkles::experiments::cpu_clock::process_cpu_seconds() >= t0);
//! ```

#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
mod sys {
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

/// CPU seconds (user + system) used so far by every thread of this process:
/// `clock_gettime(CLOCK_PROCESS_CPUTIME_ID)` (ns resolution) on Linux; NaN elsewhere or when
/// the call fails (the figures that use it then read NaN, never a wrong number).
pub fn process_cpu_seconds() -> f64 {
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
    f64::NAN
}

/// Runs `f` and returns its value with the wall and CPU seconds it took.
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (c0, w0) = (process_cpu_seconds(), std::time::Instant::now());
    let out = f();
    (out, w0.elapsed().as_secs_f64(), process_cpu_seconds() - c0)
}
