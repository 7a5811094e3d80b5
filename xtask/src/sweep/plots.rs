//! The plots of a collected sweep: each numeric figure against each varied parameter
//! (`DIR/plots/<figure>--<parameter>.png`), one line per combination of the other parameters.
//! A parameter whose values are not all numbers is plotted against the index of its value (the
//! axis label lists the values). Figures that take fewer than two distinct finite values are not
//! plotted (a flat line says nothing the table does not).

use std::collections::BTreeMap;
use std::path::Path;

use serde_json::Value;

use super::collect::Collected;
use super::plan::Plan;
use crate::error::{io_err, Result};
use crate::plot::{LinePlot, Series};

/// The plots folder of a sweep folder.
pub const PLOTS: &str = "plots";

/// A file-name-safe version of a key.
fn safe(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.' { c } else { '_' }).collect()
}

/// The x coordinate of each distinct value of parameter `p`: the number itself, or its index
/// among the distinct values in task order (then `false`).
fn axis(values: &[String]) -> (BTreeMap<String, f64>, bool) {
    let numeric = values.iter().all(|v| v.parse::<f64>().is_ok_and(f64::is_finite));
    let mut m = BTreeMap::new();
    let mut k = 0.0;
    for v in values {
        if !m.contains_key(v) {
            let x = if numeric { v.parse::<f64>().unwrap_or(f64::NAN) } else { k };
            m.insert(v.clone(), x);
            k += 1.0;
        }
    }
    (m, numeric)
}

/// Writes the plots (the folder is cleared first); returns how many.
pub fn write(dir: &Path, plan: &Plan, c: &Collected) -> Result<usize> {
    let out = dir.join(PLOTS);
    if out.exists() {
        std::fs::remove_dir_all(&out).map_err(io_err(&out))?;
    }
    if c.rows.len() < 2 {
        return Ok(0);
    }
    crate::out::ensure_dir(&out)?;
    let mut n = 0;
    for key in &c.keys {
        let ys: Vec<Option<f64>> = c
            .rows
            .iter()
            .map(|r| match r.figures.get(key) {
                Some(Value::Number(x)) => x.as_f64(),
                Some(Value::Null) => Some(f64::NAN),
                _ => None,
            })
            .collect();
        if ys.iter().any(Option::is_none) {
            continue; // text, flags, or absent in some task
        }
        let mut finite: Vec<f64> = ys.iter().flatten().copied().filter(|y| y.is_finite()).collect();
        finite.sort_by(f64::total_cmp);
        finite.dedup();
        if finite.len() < 2 {
            continue;
        }
        for (p, param) in plan.parameters.iter().enumerate() {
            let col: Vec<String> = c.rows.iter().map(|r| r.values[p].clone()).collect();
            let (xs, numeric) = axis(&col);
            // One line per combination of the other parameters, in task order.
            let mut groups: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
            for (r, y) in c.rows.iter().zip(&ys) {
                let y = y.unwrap_or(f64::NAN);
                if !y.is_finite() {
                    continue;
                }
                let label: Vec<String> = plan
                    .parameters
                    .iter()
                    .enumerate()
                    .filter(|(q, _)| *q != p)
                    .map(|(q, name)| format!("{name}={}", r.values[q]))
                    .collect();
                let label = if label.is_empty() { key.clone() } else { label.join(", ") };
                let pt = (xs[&r.values[p]], y);
                match groups.iter_mut().find(|g| g.0 == label) {
                    Some(g) => g.1.push(pt),
                    None => groups.push((label, vec![pt])),
                }
            }
            let x_label = if numeric {
                param.clone()
            } else {
                format!("{param} ({})", xs.keys().cloned().collect::<Vec<_>>().join(", "))
            };
            let mut plot = LinePlot::new(&format!("{key} vs {param}"), &x_label, key);
            for (label, mut pts) in groups {
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                plot = plot.with(Series::new(label, pts));
            }
            plot.write_png(&out.join(format!("{}--{}.png", safe(key), safe(param))))?;
            n += 1;
        }
    }
    Ok(n)
}
