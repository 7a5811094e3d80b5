//! The HTML report, `report/index.html`: one self-contained page (inline CSS, no script, no
//! network) over the runs of an output folder; images and raw files are linked relatively, so the
//! folder can be moved or served as it is.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::checks;
use crate::error::{io_err, Result};
use crate::report::{anchor, images, relative, RunInfo};

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// Inline Markdown of a run's notes: `code`, **bold**, escaped text.
fn inline(s: &str) -> String {
    let mut out = String::new();
    let mut code = false;
    for (i, part) in s.split('`').enumerate() {
        if i > 0 {
            out.push_str(if code { "</code>" } else { "<code>" });
            code = !code;
        }
        if code {
            out.push_str(&esc(part));
        } else {
            let mut bold = false;
            for (j, b) in esc(part).split("**").enumerate() {
                if j > 0 {
                    out.push_str(if bold { "</b>" } else { "<b>" });
                    bold = !bold;
                }
                out.push_str(b);
            }
            if bold {
                out.push_str("</b>");
            }
        }
    }
    if code {
        out.push_str("</code>");
    }
    out
}

/// The small Markdown subset the runs' `report.md` notes use: headings, pipe tables, lists and
/// paragraphs (anything else shows as text).
pub fn markdown(md: &str) -> String {
    let mut out = String::new();
    let lines: Vec<&str> = md.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let l = lines[i].trim_end();
        if l.trim().is_empty() {
            i += 1;
        } else if l.trim_start().starts_with('|') {
            out.push_str("<table class=\"notes\">");
            let mut first = true;
            while i < lines.len() && lines[i].trim_start().starts_with('|') {
                let row = lines[i].trim().trim_matches('|');
                let cells: Vec<&str> = row.split('|').map(str::trim).collect();
                let is_rule = cells.iter().all(|c| !c.is_empty() && c.chars().all(|ch| matches!(ch, '-' | ':' | ' ')));
                if !is_rule {
                    let tag = if first { "th" } else { "td" };
                    out.push_str("<tr>");
                    for c in cells {
                        let _ = write!(out, "<{tag}>{}</{tag}>", inline(c));
                    }
                    out.push_str("</tr>");
                    first = false;
                }
                i += 1;
            }
            out.push_str("</table>\n");
        } else if let Some(h) = l.strip_prefix('#') {
            let level = 1 + h.chars().take_while(|&c| c == '#').count();
            let text = h.trim_start_matches('#').trim();
            let lv = (level + 2).min(6);
            let _ = writeln!(out, "<h{lv}>{}</h{lv}>", inline(text));
            i += 1;
        } else if l.trim_start().starts_with("- ") || l.trim_start().starts_with("* ") {
            out.push_str("<ul>");
            while i < lines.len()
                && (lines[i].trim_start().starts_with("- ") || lines[i].trim_start().starts_with("* "))
            {
                let _ = write!(out, "<li>{}</li>", inline(&lines[i].trim_start()[2..]));
                i += 1;
            }
            out.push_str("</ul>\n");
        } else {
            let mut para = Vec::new();
            while i < lines.len() && !lines[i].trim().is_empty() && !lines[i].trim_start().starts_with('|') {
                para.push(lines[i].trim());
                i += 1;
            }
            let _ = writeln!(out, "<p>{}</p>", inline(&para.join(" ")));
        }
    }
    out
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1400px;padding:0 1em;color:#222}\
h1{margin-bottom:.2em}h2{border-top:1px solid #ccc;padding-top:1em;margin-top:2em}\
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ddd;padding:3px 8px;text-align:left;font-size:.92em}\
th{background:#f3f4f6}.ok{color:#137333;font-weight:bold}.fail{color:#b3261e;font-weight:bold}\
.badge{display:inline-block;padding:1px 8px;border-radius:9px;font-size:.8em;margin-left:.5em;vertical-align:middle}\
.badge.ok{background:#e6f4ea}.badge.fail{background:#fce8e6}.mode{color:#555;font-size:.9em}\
img{max-width:100%;border:1px solid #ddd;margin:4px 0}pre{background:#f6f6f6;padding:8px;overflow:auto;white-space:pre-wrap}\
.files a{margin-right:1em;font-size:.9em}details{margin:.5em 0}code{background:#f3f4f6;padding:0 3px}";

/// Files of a run folder to link: top-level files, and each subfolder as one link with its file
/// count.
fn raw_files(dir: &Path) -> Vec<(PathBuf, String)> {
    let Ok(rd) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut v: Vec<(PathBuf, String)> = rd
        .flatten()
        .map(|e| {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                let n = std::fs::read_dir(&p).map(|r| r.count()).unwrap_or(0);
                (p, format!("{name}/ ({n})"))
            } else {
                (p, name)
            }
        })
        .collect();
    v.sort_by(|a, b| a.1.cmp(&b.1));
    v
}

fn run_section(h: &mut String, report_dir: &Path, r: &RunInfo) -> Result<()> {
    let (cls, word) = if r.failed.is_some() { ("fail", "failed") } else { ("ok", "ok") };
    let _ = writeln!(h, "<h2 id=\"{}\">{}<span class=\"badge {cls}\">{word}</span></h2>", anchor(&r.id), esc(&r.id));
    let wall = r.wall_s().map(|w| format!(", {}", crate::ui::human_secs(w))).unwrap_or_default();
    let _ =
        writeln!(h, "<p>{}<br><span class=\"mode\">mode <b>{}</b>{wall}</span></p>", esc(&r.description), esc(&r.mode));
    if let Some(e) = &r.failed {
        let _ = writeln!(h, "<pre class=\"fail\">{}</pre>", esc(e));
    }
    if !r.checks.is_empty() {
        h.push_str("<table><tr><th>figure</th><th>ours</th><th>target</th><th></th><th>source</th></tr>\n");
        for c in &r.checks {
            let (cls, word) = if c.pass { ("ok", "pass") } else { ("fail", "FAIL") };
            let _ = writeln!(
                h,
                "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td class=\"{cls}\">{word}</td><td>{}</td></tr>",
                esc(&c.key),
                esc(&checks::format_number(c.value)),
                esc(&c.target),
                esc(&c.source)
            );
        }
        h.push_str("</table>\n");
    }
    let notes = r.dir.join("report.md");
    if notes.is_file() {
        let text = std::fs::read_to_string(&notes).map_err(io_err(&notes))?;
        h.push_str(&markdown(&text));
    }
    if let Some(s) = &r.summary {
        let n = s.iter().count();
        let _ = writeln!(h, "<details><summary>all {n} figures (summary.json)</summary><table>");
        for (k, v) in s.iter() {
            let _ = writeln!(h, "<tr><td><code>{}</code></td><td>{}</td></tr>", esc(k), esc(&checks::format_value(v)));
        }
        h.push_str("</table></details>\n");
    }
    for img in images(&r.dir) {
        let name = img.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let rel = relative(report_dir, &img);
        let _ = writeln!(
            h,
            "<figure><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>",
            esc(&rel),
            esc(&name)
        );
    }
    h.push_str("<p class=\"files\">files: ");
    for (p, label) in raw_files(&r.dir) {
        let _ = write!(h, "<a href=\"{}\">{}</a> ", esc(&relative(report_dir, &p)), esc(&label));
    }
    h.push_str("</p>\n");
    Ok(())
}

/// Writes `report_dir/index.html` over `runs` found in `root`.
pub fn write(report_dir: &Path, root: &Path, runs: &[RunInfo], wall_s: Option<f64>) -> Result<PathBuf> {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>Reproduction report</title>\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><link rel=\"icon\" href=\"data:,\"><style>{STYLE}</style></head><body>\n"
    );
    let failed = runs.iter().filter(|r| r.failed.is_some()).count();
    let _ = writeln!(h, "<h1>Reproduction report</h1>");
    let _ = writeln!(
        h,
        "<p>{} runs in <code>{}</code>, <span class=\"{}\">{failed} failed</span>{}. Each figure comes from the run it is listed under, in the mode shown there.</p>",
        runs.len(),
        esc(&root.display().to_string()),
        if failed > 0 { "fail" } else { "ok" },
        wall_s.map(|w| format!("; repro wall time {}", crate::ui::human_secs(w))).unwrap_or_default()
    );
    h.push_str("<table><tr><th>run</th><th>status</th><th>mode</th><th>wall time</th><th>checks</th></tr>\n");
    for r in runs {
        let (cls, word) = if r.failed.is_some() { ("fail", "failed") } else { ("ok", "ok") };
        let pass = r.checks.iter().filter(|c| c.pass).count();
        let checks = if r.checks.is_empty() {
            String::new()
        } else {
            format!(
                "<span class=\"{}\">{pass}/{} pass</span>",
                if pass == r.checks.len() { "ok" } else { "fail" },
                r.checks.len()
            )
        };
        let wall = r.wall_s().map(crate::ui::human_secs).unwrap_or_default();
        let _ = writeln!(
            h,
            "<tr><td><a href=\"#{}\">{}</a></td><td class=\"{cls}\">{word}</td><td>{}</td><td>{wall}</td><td>{checks}</td></tr>",
            anchor(&r.id),
            esc(&r.id),
            esc(&r.mode)
        );
    }
    h.push_str("</table>\n");
    crate::sweep::report::html(&mut h, report_dir, root);
    for r in runs {
        run_section(&mut h, report_dir, r)?;
    }
    h.push_str("</body></html>\n");
    let path = report_dir.join("index.html");
    std::fs::write(&path, h).map_err(io_err(&path))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn notes_markdown_becomes_html() {
        let h = markdown(
            "# Title\n\n| a | b |\n|---|---|\n| 1 | `x<y` |\n\nsome **bold** text\nand more\n\n- one\n- two\n",
        );
        assert!(h.contains("<h3>Title</h3>"), "{h}");
        assert!(h.contains("<th>a</th>") && h.contains("<td><code>x&lt;y</code></td>"), "{h}");
        assert!(h.contains("<p>some <b>bold</b> text and more</p>"), "{h}");
        assert!(h.contains("<li>one</li><li>two</li>"), "{h}");
        assert_eq!(esc("<a&\"'>"), "&lt;a&amp;&quot;&#39;&gt;");
    }
}
