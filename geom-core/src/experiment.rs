//! What every method crate's experiments share: the run [`Size`], values that depend on it
//! ([`BySize`]), and the typed [`Report`] of figures and paper checks an experiment returns.
//!
//! An experiment is `pub fn run(&Params, Size, &mut dyn Recorder) -> Result<Report>` in
//! `<crate>/src/experiments/<name>.rs`; its `Params` is the scene file's `params` block. The
//! report's figures become `summary.json`, its checks the pass/fail column of the report.
//!
//! ```
//! use geom_core::experiment::{BySize, Report, Size, Target};
//! let frames: BySize<u32> = ron::from_str("(30, 180, 600)").unwrap();
//! assert_eq!(frames.get(Size::Quick), 30);
//! assert_eq!(frames.get(Size::Tiny), 30); // tiny falls back to quick unless given
//! let same: BySize<u32> = ron::from_str("12").unwrap();
//! assert_eq!(same.get(Size::Full), 12);
//!
//! let mut r = Report::default();
//! r.num("max_edge_strain", 0.04).count("nan_steps", 0);
//! r.check("max_edge_strain", Target::AtMost(0.10), "TRACKS §5: inextensible cloth");
//! assert!(r.all_pass());
//! ```

use serde::{Deserialize, Serialize};

/// How big a run is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum Size {
    /// Smaller than quick: the size `cargo test` runs (our crates compile at opt-level 1 there).
    Tiny,
    /// A smoke run (well under a minute).
    Quick,
    /// The default: shows the result within the main job's budget.
    Default,
    /// Paper scale.
    Full,
}

impl Size {
    /// Lower-case name written into summaries (`tiny`, `quick`, `default`, `full`).
    pub fn name(self) -> &'static str {
        match self {
            Size::Tiny => "tiny",
            Size::Quick => "quick",
            Size::Default => "default",
            Size::Full => "full",
        }
    }

    /// Picks one of three values; `Tiny` takes the quick one.
    pub fn pick<T>(self, quick: T, default: T, full: T) -> T {
        match self {
            Size::Tiny | Size::Quick => quick,
            Size::Default => default,
            Size::Full => full,
        }
    }
}

/// A parameter that may differ by run size. In RON: a single value (`12`, the same for every
/// size), a triple `(quick, default, full)`, or a struct `(quick: …, default: …, full: …, tiny:
/// …)` whose `tiny` is optional (it falls back to `quick`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum BySize<T> {
    /// Explicit values per size (tiny optional).
    Named {
        /// `--quick`.
        quick: T,
        /// Default mode.
        default: T,
        /// `--full`.
        full: T,
        /// The test size (defaults to `quick`).
        #[serde(default)]
        tiny: Option<T>,
    },
    /// `(quick, default, full)`.
    Modes(T, T, T),
    /// One value for every size.
    Same(T),
}

impl<T: Clone> BySize<T> {
    /// The value for a run size.
    pub fn get(&self, s: Size) -> T {
        match self {
            BySize::Same(v) => v.clone(),
            BySize::Modes(q, d, f) => s.pick(q, d, f).clone(),
            BySize::Named { quick, default, full, tiny } => match (s, tiny) {
                (Size::Tiny, Some(t)) => t.clone(),
                _ => s.pick(quick, default, full).clone(),
            },
        }
    }
}

/// One figure's value.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Value {
    /// A measured number (NaN is kept: it is written as `null` and fails every check).
    Num(f64),
    /// A count.
    Int(i64),
    /// A yes/no figure.
    Bool(bool),
    /// Text (a configuration name, a unit …).
    Text(String),
}

impl Value {
    /// The value as a number (`true` = 1), or `None` for text.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Num(v) => Some(*v),
            Value::Int(v) => Some(*v as f64),
            Value::Bool(b) => Some(if *b { 1.0 } else { 0.0 }),
            Value::Text(_) => None,
        }
    }
}

/// The target a figure is checked against (the paper's or the issue's number).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub enum Target {
    /// value ≤ x
    AtMost(f64),
    /// value ≥ x
    AtLeast(f64),
    /// value < x
    Below(f64),
    /// value > x
    Above(f64),
    /// lo ≤ value ≤ hi
    Within(f64, f64),
    /// value == x exactly
    Equals(f64),
    /// a `Bool` figure that must be true
    IsTrue,
}

impl Target {
    /// True when `v` meets the target; NaN never does.
    pub fn holds(&self, v: f64) -> bool {
        if v.is_nan() {
            return false;
        }
        match *self {
            Target::AtMost(x) => v <= x,
            Target::AtLeast(x) => v >= x,
            Target::Below(x) => v < x,
            Target::Above(x) => v > x,
            Target::Within(lo, hi) => lo <= v && v <= hi,
            Target::Equals(x) => v == x,
            Target::IsTrue => v == 1.0,
        }
    }

    /// A short human-readable form, e.g. `≤ 0.1`.
    pub fn describe(&self) -> String {
        match *self {
            Target::AtMost(x) => format!("≤ {x}"),
            Target::AtLeast(x) => format!("≥ {x}"),
            Target::Below(x) => format!("< {x}"),
            Target::Above(x) => format!("> {x}"),
            Target::Within(lo, hi) => format!("in [{lo}, {hi}]"),
            Target::Equals(x) => format!("= {x}"),
            Target::IsTrue => "true".into(),
        }
    }
}

/// A paper check: a figure against its target.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Check {
    /// The figure's key.
    pub key: String,
    /// The target.
    pub target: Target,
    /// The figure's value (NaN when the figure is missing or not numeric).
    pub value: f64,
    /// Whether the target holds.
    pub pass: bool,
    /// Where the target comes from (paper section, issue), one line.
    pub source: String,
}

/// What an experiment returns: its figures (the keys of `summary.json`, in insertion order) and
/// its paper checks.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Report {
    /// `(key, value)` pairs; setting a key again replaces its value.
    pub figures: Vec<(String, Value)>,
    /// Checks of figures against targets.
    pub checks: Vec<Check>,
    /// Keys of the figures that measure time or depend on it (wall times, rates, speed-ups,
    /// thread counts): they differ from run to run and are left out of determinism checks.
    pub timing: Vec<String>,
}

impl Report {
    fn set(&mut self, key: &str, v: Value) -> &mut Self {
        match self.figures.iter_mut().find(|(k, _)| k == key) {
            Some(slot) => slot.1 = v,
            None => self.figures.push((key.to_string(), v)),
        }
        self
    }

    /// Sets a measured number.
    pub fn num(&mut self, key: &str, v: f64) -> &mut Self {
        self.set(key, Value::Num(v))
    }

    /// Sets a figure that measures time or derives from it (s, rates, speed-ups, time ratios,
    /// the thread count): excluded from reproducibility comparisons.
    pub fn timing(&mut self, key: &str, v: f64) -> &mut Self {
        if !self.timing.iter().any(|k| k == key) {
            self.timing.push(key.to_string());
        }
        self.set(key, Value::Num(v))
    }

    /// True when `key` was set with [`Report::timing`].
    pub fn is_timing(&self, key: &str) -> bool {
        self.timing.iter().any(|k| k == key)
    }

    /// The figures that do not depend on timing, as `(key, value)`: what must be bitwise
    /// identical across runs and thread counts.
    pub fn reproducible_figures(&self) -> Vec<(String, Value)> {
        self.figures.iter().filter(|(k, _)| !self.is_timing(k)).cloned().collect()
    }

    /// Sets a count.
    pub fn count(&mut self, key: &str, v: u64) -> &mut Self {
        self.set(key, Value::Int(v as i64))
    }

    /// Sets a yes/no figure.
    pub fn flag(&mut self, key: &str, v: bool) -> &mut Self {
        self.set(key, Value::Bool(v))
    }

    /// Sets a text figure.
    pub fn text(&mut self, key: &str, v: &str) -> &mut Self {
        self.set(key, Value::Text(v.to_string()))
    }

    /// A figure's value.
    pub fn get(&self, key: &str) -> Option<&Value> {
        self.figures.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }

    /// A figure as a number (NaN when missing or text).
    pub fn get_f64(&self, key: &str) -> f64 {
        self.get(key).and_then(Value::as_f64).unwrap_or(f64::NAN)
    }

    /// Checks the figure `key` (already set) against `target`; a missing figure fails.
    pub fn check(&mut self, key: &str, target: Target, source: &str) -> &mut Self {
        let value = self.get_f64(key);
        self.checks.push(Check {
            key: key.to_string(),
            target,
            value,
            pass: target.holds(value),
            source: source.into(),
        });
        self
    }

    /// Appends every figure and check of `other`, each key prefixed by `prefix` (e.g. a fabric
    /// name).
    pub fn merge_prefixed(&mut self, prefix: &str, other: &Report) -> &mut Self {
        for (k, v) in &other.figures {
            let key = format!("{prefix}{k}");
            if other.is_timing(k) && !self.is_timing(&key) {
                self.timing.push(key.clone());
            }
            self.set(&key, v.clone());
        }
        for c in &other.checks {
            let mut c = c.clone();
            c.key = format!("{prefix}{}", c.key);
            self.checks.push(c);
        }
        self
    }

    /// True when every check passes (vacuously true without checks).
    pub fn all_pass(&self) -> bool {
        self.checks.iter().all(|c| c.pass)
    }

    /// The checks that fail.
    pub fn failed_checks(&self) -> impl Iterator<Item = &Check> {
        self.checks.iter().filter(|c| !c.pass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_size_forms() {
        let s: BySize<(u32, u32)> = ron::from_str("(160, 120)").unwrap();
        assert_eq!(s.get(Size::Full), (160, 120));
        let m: BySize<(u32, u32)> = ron::from_str("((1, 2), (3, 4), (5, 6))").unwrap();
        assert_eq!(m.get(Size::Default), (3, 4));
        let n: BySize<f64> = ron::from_str("(quick: 1.0, default: 2.5, full: 3.0, tiny: 0.5)").unwrap();
        assert_eq!(n.get(Size::Tiny), 0.5);
        assert_eq!(n.get(Size::Default), 2.5);
        let f: BySize<f64> = ron::from_str("(1, 2, 3)").unwrap();
        assert_eq!(f.get(Size::Full), 3.0);
        assert!(ron::from_str::<BySize<u32>>("(1, 2)").is_err());
    }

    #[test]
    fn checks_fail_on_nan_missing_and_miss() {
        let mut r = Report::default();
        r.num("a", 0.2).num("b", f64::NAN).flag("c", true).count("n", 3);
        r.check("a", Target::AtMost(0.1), "x")
            .check("b", Target::AtMost(1.0), "x")
            .check("missing", Target::AtLeast(0.0), "x")
            .check("c", Target::IsTrue, "x")
            .check("n", Target::Equals(3.0), "x");
        let pass: Vec<bool> = r.checks.iter().map(|c| c.pass).collect();
        assert_eq!(pass, [false, false, false, true, true]);
        assert!(!r.all_pass());
        assert_eq!(r.failed_checks().count(), 3);
        r.num("a", 0.05);
        assert_eq!(r.figures.len(), 4, "setting a key again replaces it");
    }

    #[test]
    fn merge_prefixes_keys() {
        let mut a = Report::default();
        let mut b = Report::default();
        b.num("err", 0.1).check("err", Target::Below(0.2), "x");
        a.merge_prefixed("linen_", &b);
        assert_eq!(a.get_f64("linen_err"), 0.1);
        assert_eq!(a.checks[0].key, "linen_err");
        let mut t = Report::default();
        t.timing("wall_s", 1.0).num("err", 0.5);
        assert!(t.is_timing("wall_s") && !t.is_timing("err"));
        assert_eq!(t.reproducible_figures(), vec![("err".to_string(), Value::Num(0.5))]);
        a.merge_prefixed("x_", &t);
        assert!(a.is_timing("x_wall_s"));
    }
}
