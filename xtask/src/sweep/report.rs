//! The sweep section of the report (`cargo xtask report DIR`, also rebuilt by `sweep collect`):
//! for every collected sweep under the report's root (a folder holding `sweep.ron` and
//! `sweep.csv`), what was swept, the task counts (failed and missing tasks named), the table of
//! `sweep.csv`, links to the plan's files and the plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::collect::{STATUS_JSON, SWEEP_CSV};
use super::plan::{Plan, Source, SWEEP_RON, TASKS_TXT};
use super::plots::PLOTS;
use crate::html::esc;
use crate::report::{anchor, relative};

/// The collected sweeps under `root` (`root` itself included; task folders are not searched),
/// sorted by path.
pub fn find(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        if d.join(SWEEP_RON).is_file() && d.join(SWEEP_CSV).is_file() {
            out.push(d.clone());
        }
        if d.join("summary.json").is_file() {
            continue; // a run folder
        }
        let Ok(rd) = std::fs::read_dir(&d) else { continue };
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name();
            if p.is_dir() && name != "tasks" && name != "report" && name != PLOTS && name != "logs" {
                stack.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The fields of one CSV line (quoted fields with `""` inside, as [`crate::out::CsvWriter`]
/// writes them).
pub fn csv_fields(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            (c, _) => cur.push(c),
        }
    }
    out.push(cur);
    out
}

struct View {
    title: String,
    what: String,
    status: String,
    csv: Vec<Vec<String>>,
    links: Vec<(PathBuf, String)>,
    plots: Vec<PathBuf>,
}

fn view(dir: &Path, root: &Path) -> Option<View> {
    let plan = Plan::read(dir).ok()?;
    let rel = relative(root, dir);
    let title = format!("sweep {}{}", plan.name(), if rel.is_empty() { String::new() } else { format!(" ({rel})") });
    let what = match &plan.source {
        Source::Scene { sweep_file, scene } => format!(
            "{} over {} (sweep file {}), mode {}",
            scene.display(),
            plan.parameters.join(" × "),
            sweep_file.display(),
            plan.mode
        ),
        Source::Bench { krate, sweep } => {
            format!("the points of `bench {krate} --sweep {sweep}`, one task each, mode {}", plan.mode)
        }
    };
    let st: Option<serde_json::Value> =
        std::fs::read_to_string(dir.join(STATUS_JSON)).ok().and_then(|t| serde_json::from_str(&t).ok());
    let list = |k: &str| -> Vec<String> {
        st.as_ref()
            .and_then(|s| s.get(k))
            .and_then(|v| v.as_array())
            .map(|a| a.iter().filter_map(|x| x.as_str().map(str::to_string)).collect())
            .unwrap_or_default()
    };
    let finished = st.as_ref().and_then(|s| s.get("finished")).and_then(|v| v.as_u64()).unwrap_or(0);
    let (failed, missing) = (list("failed"), list("missing"));
    let mut status =
        format!("{} tasks: {finished} finished, {} failed, {} missing", plan.tasks.len(), failed.len(), missing.len());
    if !failed.is_empty() {
        let _ = write!(status, "; failed: {}", failed.join(", "));
    }
    if !missing.is_empty() {
        let _ = write!(status, "; missing: {}", missing.join(", "));
    }
    let csv = std::fs::read_to_string(dir.join(SWEEP_CSV)).unwrap_or_default().lines().map(csv_fields).collect();
    let mut links: Vec<(PathBuf, String)> = [SWEEP_CSV, TASKS_TXT, SWEEP_RON, super::openjd::FILE, STATUS_JSON]
        .iter()
        .map(|n| (dir.join(n), n.to_string()))
        .filter(|(p, _)| p.is_file())
        .collect();
    links.extend(list("tables").into_iter().map(|n| (dir.join(&n), n)));
    let mut plots: Vec<PathBuf> = std::fs::read_dir(dir.join(PLOTS))
        .map(|rd| rd.flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "png")).collect())
        .unwrap_or_default();
    plots.sort();
    Some(View { title, what, status, csv, links, plots })
}

/// The HTML of every sweep under `root`, for the report in `report_dir`.
pub fn html(h: &mut String, report_dir: &Path, root: &Path) {
    for dir in find(root) {
        let Some(v) = view(&dir, root) else { continue };
        let _ = writeln!(h, "<h2 id=\"{}\">{}</h2>", anchor(&v.title), esc(&v.title));
        let _ = writeln!(h, "<p>{}<br><span class=\"mode\">{}</span></p>", esc(&v.what), esc(&v.status));
        h.push_str("<p class=\"files\">");
        for (p, n) in &v.links {
            let _ = write!(h, "<a href=\"{}\">{}</a> ", esc(&relative(report_dir, p)), esc(n));
        }
        h.push_str("</p>\n<details open><summary>sweep.csv</summary><div style=\"overflow:auto\"><table>\n");
        for (k, row) in v.csv.iter().enumerate() {
            let tag = if k == 0 { "th" } else { "td" };
            h.push_str("<tr>");
            for c in row {
                let _ = write!(h, "<{tag}>{}</{tag}>", esc(c));
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</table></div></details>\n");
        if !v.plots.is_empty() {
            let _ =
                writeln!(h, "<details><summary>{} plots: each figure against each parameter</summary>", v.plots.len());
            for p in &v.plots {
                let name = p.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                let rel = relative(report_dir, p);
                let _ = writeln!(
                    h,
                    "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>",
                    esc(&rel),
                    esc(&name)
                );
            }
            h.push_str("</details>\n");
        }
    }
}

/// The Markdown of every sweep under `root`, for the report in `report_dir`.
pub fn markdown(md: &mut String, report_dir: &Path, root: &Path) {
    for dir in find(root) {
        let Some(v) = view(&dir, root) else { continue };
        let _ = writeln!(md, "\n## {}\n\n{}\n\n{}\n", v.title, v.what, v.status);
        let links: Vec<String> = v.links.iter().map(|(p, n)| format!("[{n}]({})", relative(report_dir, p))).collect();
        let _ = writeln!(md, "Files: {}\n", links.join(", "));
        for (k, row) in v.csv.iter().enumerate() {
            let _ = writeln!(md, "| {} |", row.join(" | "));
            if k == 0 {
                let _ = writeln!(md, "|{}", "---|".repeat(row.len()));
            }
        }
        for p in &v.plots {
            let name = p.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let _ = writeln!(md, "\n![{name}]({})", relative(report_dir, p));
        }
    }
}
