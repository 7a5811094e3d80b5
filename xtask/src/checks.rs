//! Reading a run's `checks.json` (the paper checks of its report: figure, target, value,
//! pass/fail, source) back, and formatting figures for people.

use std::path::Path;

use serde::Deserialize;

/// One paper check as written by `record::write_checks`.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckRow {
    /// The figure's key.
    pub key: String,
    /// The target in words (`≤ 0.1`, `in [1, 2]`, `true`).
    pub target: String,
    /// The value (NaN when missing or non-finite).
    pub value: f64,
    /// Whether the target holds.
    pub pass: bool,
    /// Where the target comes from.
    pub source: String,
}

#[derive(Deserialize)]
struct Raw {
    key: String,
    target: serde_json::Value,
    #[serde(default)]
    value: Option<f64>,
    pass: bool,
    #[serde(default)]
    source: String,
}

/// The target of `geom_core::experiment::Target` as serialised (`{"AtMost": 0.1}`, `"IsTrue"`),
/// in words.
fn describe(t: &serde_json::Value) -> String {
    use serde_json::Value as V;
    let num = |v: &V| v.as_f64().map(format_number).unwrap_or_else(|| v.to_string());
    match t {
        V::String(s) if s == "IsTrue" => "true".into(),
        V::Object(m) if m.len() == 1 => {
            let (k, v) = m.iter().next().expect("one entry");
            match (k.as_str(), v) {
                ("AtMost", v) => format!("≤ {}", num(v)),
                ("AtLeast", v) => format!("≥ {}", num(v)),
                ("Below", v) => format!("< {}", num(v)),
                ("Above", v) => format!("> {}", num(v)),
                ("Equals", v) => format!("= {}", num(v)),
                ("Within", V::Array(a)) if a.len() == 2 => format!("in [{}, {}]", num(&a[0]), num(&a[1])),
                (k, v) => format!("{k} {v}"),
            }
        }
        other => other.to_string(),
    }
}

/// The checks of the run in `dir` (`checks.json`); `None` when the run wrote none or the file
/// cannot be read.
pub fn read(dir: &Path) -> Option<Vec<CheckRow>> {
    let text = std::fs::read_to_string(dir.join("checks.json")).ok()?;
    let raw: Vec<Raw> = serde_json::from_str(&text).ok()?;
    Some(
        raw.into_iter()
            .map(|r| CheckRow {
                key: r.key,
                target: describe(&r.target),
                value: r.value.unwrap_or(f64::NAN),
                pass: r.pass,
                source: r.source,
            })
            .collect(),
    )
}

/// A number in at most about six significant digits: `0.0431`, `2.5e-13`, `1.2346e6`, `12`.
pub fn format_number(x: f64) -> String {
    if x.is_nan() {
        return "NaN".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if x == x.trunc() && x.abs() < 1e15 {
        return format!("{x:.0}");
    }
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        return format!("{x:.4e}");
    }
    format!("{x:.6}").trim_end_matches('0').trim_end_matches('.').to_string()
}

/// A summary value for people (numbers through [`format_number`], `null` as non-finite).
pub fn format_value(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) if n.is_f64() => n.as_f64().map(format_number).unwrap_or_else(|| n.to_string()),
        serde_json::Value::Number(n) => n.to_string(),
        serde_json::Value::String(s) => s.clone(),
        serde_json::Value::Null => "null (non-finite)".into(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::experiment::{Report, Target};

    #[test]
    fn reads_what_record_writes() {
        let dir = std::env::temp_dir().join(format!("xtask-checks-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut r = Report::default();
        r.num("strain", 0.04).num("nan", f64::NAN).flag("ok", true).num("w", 1.5);
        r.check("strain", Target::AtMost(0.1), "TRACKS §5")
            .check("nan", Target::AtLeast(0.0), "x")
            .check("ok", Target::IsTrue, "y")
            .check("w", Target::Within(1.0, 2.0), "z");
        crate::record::write_checks(&dir, &r).unwrap();
        let c = read(&dir).unwrap();
        assert_eq!(c.len(), 4);
        assert_eq!((c[0].target.as_str(), c[0].pass, c[0].value), ("≤ 0.1", true, 0.04));
        assert!(c[1].value.is_nan() && !c[1].pass);
        assert_eq!(c[2].target, "true");
        assert_eq!(c[3].target, "in [1, 2]");
        assert_eq!(c[0].source, "TRACKS §5");
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(read(&dir).is_none());
    }

    #[test]
    fn numbers_for_people() {
        assert_eq!(format_number(0.0431), "0.0431");
        assert_eq!(format_number(2.5e-13), "2.5000e-13");
        assert_eq!(format_number(12.0), "12");
        assert_eq!(format_number(f64::NAN), "NaN");
        assert_eq!(format_value(&serde_json::json!(null)), "null (non-finite)");
    }
}
