//! The points of the benchmarks' sweeps that split into independent runs (issue 28): one list per
//! sweep, read both by the bench's own loop and by `cargo xtask plan --bench <crate> --sweep
//! <knob>`, so that `bench <crate> --sweep <knob> --point I` runs exactly the `I`-th point of the
//! loop `bench <crate> --sweep <knob>` runs, and nothing else.
//!
//! A sweep is splittable when its points do not depend on each other (no shared baseline run, no
//! cross-point figure). flip-tet: `resolution`, `levels`, `tol`, `bc`, `remesh`, `cfl`;
//! perf-control: `rate`, `stretch`, `k`. The others run whole.

use crate::registry::BenchCtx;

/// The points of `all` this run computes: every one, or only the `--point I`-th
/// ([`BenchCtx::point`]).
pub fn pts<T>(ctx: &BenchCtx, all: Vec<T>) -> Vec<T> {
    all.into_iter().enumerate().filter(|(i, _)| ctx.point.is_none_or(|p| p == *i)).map(|(_, v)| v).collect()
}

/// flip-tet `resolution`: finest level n of the dam break.
pub fn flip_tet_resolution(quick: bool) -> Vec<u32> {
    if quick {
        vec![16, 32]
    } else {
        vec![16, 32, 64]
    }
}

/// flip-tet `levels`: (coarsest, finest) of the dam break.
pub fn flip_tet_levels(quick: bool) -> Vec<(u32, u32)> {
    let finest = if quick { 32 } else { 64 };
    [finest, finest / 2, 8].into_iter().map(|c| (c, finest)).collect()
}

/// flip-tet `tol`: the MIC(0)-PCG tolerances after the direct solve.
pub fn flip_tet_tols(quick: bool) -> Vec<f64> {
    if quick {
        vec![1e-2, 1e-6]
    } else {
        vec![1e-2, 1e-3, 1e-4, 1e-6, 1e-8]
    }
}

/// flip-tet `tol`: the point names (`direct`, then `mic_pcg_<tol>`).
pub fn flip_tet_tol_names(quick: bool) -> Vec<String> {
    let mut v = vec!["direct".to_string()];
    v.extend(flip_tet_tols(quick).iter().map(|t| format!("mic_pcg_{t:e}")));
    v
}

/// flip-tet `bc`: second-order, then first-order free-surface boundary.
pub const FLIP_TET_BC: [(bool, &str); 2] = [(true, "second"), (false, "first")];

/// flip-tet `remesh`: remesh interval (steps).
pub fn flip_tet_remesh(quick: bool) -> Vec<u32> {
    if quick {
        vec![1, 10]
    } else {
        vec![1, 5, 10, 20]
    }
}

/// flip-tet `cfl`: CFL number.
pub fn flip_tet_cfl(quick: bool) -> Vec<f64> {
    if quick {
        vec![0.5, 2.0]
    } else {
        vec![0.5, 1.0, 2.0, 4.0]
    }
}

/// perf-control `rate`: (working rate Hz, factor); the 30 Hz point is left out of quick sweeps.
pub fn perf_control_rate(quick: bool) -> Vec<(f64, usize)> {
    [(5.0, 6usize), (7.5, 4), (10.0, 3), (15.0, 2), (30.0, 1)]
        .into_iter()
        .filter(|&(_, f)| !(quick && f == 1))
        .collect()
}

/// perf-control `stretch`: stretch limit (s).
pub const PERF_CONTROL_STRETCH: [f64; 5] = [0.0, 0.1, 0.15, 0.2, 0.3];

/// perf-control `k`: continuity constant.
pub const PERF_CONTROL_K: [f64; 6] = [0.0, 1.0, 3.0, 10.0, 30.0, 100.0];

/// The point labels of `crate_name`'s sweep `sweep` (the `value` the bench writes for each), or
/// `None` when that sweep does not split into points.
pub fn points(crate_name: &str, sweep: &str, quick: bool) -> Option<Vec<String>> {
    let s = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>();
    Some(match (crate_name, sweep) {
        ("flip-tet", "resolution") => flip_tet_resolution(quick).iter().map(u32::to_string).collect(),
        ("flip-tet", "levels") => flip_tet_levels(quick).iter().map(|(c, f)| format!("{c}-{f}")).collect(),
        ("flip-tet", "tol") => flip_tet_tol_names(quick),
        ("flip-tet", "bc") => FLIP_TET_BC.iter().map(|b| b.1.to_string()).collect(),
        ("flip-tet", "remesh") => flip_tet_remesh(quick).iter().map(u32::to_string).collect(),
        ("flip-tet", "cfl") => s(&flip_tet_cfl(quick)),
        ("perf-control", "rate") => s(&perf_control_rate(quick).iter().map(|r| r.0).collect::<Vec<_>>()),
        ("perf-control", "stretch") => s(&PERF_CONTROL_STRETCH),
        ("perf-control", "k") => s(&PERF_CONTROL_K),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splittable_sweeps_name_their_points() {
        assert_eq!(points("flip-tet", "resolution", true).unwrap(), ["16", "32"]);
        assert_eq!(points("flip-tet", "levels", false).unwrap(), ["64-64", "32-64", "8-64"]);
        assert_eq!(points("flip-tet", "tol", true).unwrap(), ["direct", "mic_pcg_1e-2", "mic_pcg_1e-6"]);
        assert_eq!(points("perf-control", "rate", true).unwrap().len(), 4);
        assert_eq!(points("perf-control", "stretch", true).unwrap(), ["0", "0.1", "0.15", "0.2", "0.3"]);
        assert!(points("flip-tet", "solver", true).is_none());
        assert!(points("perf-control", "beam", true).is_none());
        assert!(points("shells", "resolution", true).is_none());
    }
}
