//! Number text for the writers: the shortest decimal that parses back to the same value.
//!
//! Rust's `Display` and `LowerExp` for floats print the shortest digit string that round-trips
//! exactly (Grisu/Ryū-style), so `s.parse::<f64>() == x` bit for bit (also for `-0.0`). `Display`
//! never uses an exponent, which makes `1e-300` three hundred characters long; magnitudes outside
//! `[1e-5, 1e16)` therefore use `LowerExp` (`1e-7`, `1.5e300`), which every OBJ/PLY reader accepts.

use std::fmt::Write as _;

/// Appends the shortest round-trip text of `x` to `out`. Non-finite values print as Rust does
/// (`NaN`, `inf`); the writers refuse them before getting here where the format cannot hold them.
pub(crate) fn push_f64(out: &mut String, x: f64) {
    let a = x.abs();
    // `write!` into a String cannot fail.
    if a == 0.0 || (1e-5..1e16).contains(&a) || !x.is_finite() {
        let _ = write!(out, "{x}");
    } else {
        let _ = write!(out, "{x:e}");
    }
}

/// As [`push_f64`] for `f32` (shortest text that parses back to the same `f32`).
pub(crate) fn push_f32(out: &mut String, x: f32) {
    let a = x.abs();
    if a == 0.0 || (1e-5..1e16).contains(&a) || !x.is_finite() {
        let _ = write!(out, "{x}");
    } else {
        let _ = write!(out, "{x:e}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_awkward_values_bitwise() {
        let xs = [
            0.0,
            -0.0,
            0.1,
            1.0 / 3.0,
            -2.5e-7,
            1e-300,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            123456789.12345679,
            1e16,
            9.999999999999998e15,
        ];
        for &x in &xs {
            let mut s = String::new();
            push_f64(&mut s, x);
            let y: f64 = s.parse().unwrap();
            assert_eq!(x.to_bits(), y.to_bits(), "{x:e} -> {s} -> {y:e}");
            assert!(s.len() <= 24, "{s} too long");
        }
        let fs = [0.1f32, -3.4e38, 1.4e-45, 7.0, 1e-6];
        for &x in &fs {
            let mut s = String::new();
            push_f32(&mut s, x);
            let y: f32 = s.parse().unwrap();
            assert_eq!(x.to_bits(), y.to_bits(), "{x:e} -> {s}");
        }
    }
}
