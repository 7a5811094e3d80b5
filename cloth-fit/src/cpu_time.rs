//! Process CPU time, to report next to wall times on a shared machine (a loaded machine
//! stretches wall times; the CPU time of the work does not stretch with the load).

/// User + system CPU time of this process, all threads (s), from `/proc/self/stat` (fields 14
/// and 15, in clock ticks of `USER_HZ` = 100 per second, fixed by the Linux ABI for `/proc`).
/// `None` where `/proc` is missing or unreadable (not Linux).
pub fn process_cpu_s() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: split after its ')'.
    let rest = &s[s.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3, so fields 14 and 15 are at 11 and 12.
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Wall and CPU seconds of `f` (CPU NaN where the process CPU time cannot be read).
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let c0 = process_cpu_s();
    let t0 = std::time::Instant::now();
    let out = f();
    let wall = t0.elapsed().as_secs_f64();
    let cpu = match (c0, process_cpu_s()) {
        (Some(a), Some(b)) => b - a,
        _ => f64::NAN,
    };
    (out, wall, cpu)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_clock_advances_with_work() {
        if !cfg!(target_os = "linux") {
            return;
        }
        let c0 = process_cpu_s().expect("/proc/self/stat is readable on Linux");
        let t0 = std::time::Instant::now();
        let mut x = 0u64;
        let mut used = 0.0;
        // Spin until 30 ms of CPU were charged (bounded by 20 s of wall on a loaded machine).
        while used < 0.03 && t0.elapsed().as_secs_f64() < 20.0 {
            for _ in 0..100_000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
            used = process_cpu_s().expect("readable") - c0;
        }
        assert!(used >= 0.03, "no CPU time charged after {:.1} s of spinning", t0.elapsed().as_secs_f64());
        let (_, wall, cpu) = timed(|| std::hint::black_box(x));
        assert!(wall >= 0.0 && cpu >= 0.0);
    }
}
