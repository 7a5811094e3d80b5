//! The sweep as an Open Job Description template (`sweep.openjd.yaml`, specification
//! `jobtemplate-2023-09`): the job format AWS Deadline Cloud and other studio farms accept.
//! Step `tasks` has one task per line of `tasks.txt` (an INT task parameter `Line`, 1 … n), each
//! running that line; step `collect` depends on it and runs `sweep collect`. The template is fixed
//! text, written here without a YAML library; `openjd check` validates it in CI and
//! `openjd run` runs it locally.

use std::path::Path;

use super::plan::{Plan, TASKS_TXT};

/// The template's file name in a sweep folder.
pub const FILE: &str = "sweep.openjd.yaml";

/// `s` as a double-quoted YAML scalar.
pub fn yaml_str(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The template for `plan` in sweep folder `dir` (absolute), calling `xtask`.
pub fn template(plan: &Plan, dir: &Path, xtask: &Path) -> String {
    let tasks = super::command::shell_quote(&dir.join(TASKS_TXT).display().to_string());
    // Runs line {{Task.Param.Line}} of tasks.txt; a missing line is an error, not a silent success.
    let script = format!("line=$(sed -n '{{{{Task.Param.Line}}}}p' {tasks}) && test -n \"$line\" && eval \"$line\"");
    let n = plan.tasks.len().max(1);
    let range = if n == 1 { "1".to_string() } else { format!("1-{n}") };
    format!(
        "# Open Job Description template of the sweep in {dir} (written by `cargo xtask plan`).\n\
         # Each task runs one line of tasks.txt; a finished task is skipped, so the job can be resubmitted.\n\
         specificationVersion: jobtemplate-2023-09\n\
         name: {name}\n\
         steps:\n\
         \x20 - name: tasks\n\
         \x20   parameterSpace:\n\
         \x20     taskParameterDefinitions:\n\
         \x20       - name: Line\n\
         \x20         type: INT\n\
         \x20         range: {range}\n\
         \x20   script:\n\
         \x20     actions:\n\
         \x20       onRun:\n\
         \x20         command: /bin/sh\n\
         \x20         args: [\"-c\", {script}]\n\
         \x20 - name: collect\n\
         \x20   dependencies:\n\
         \x20     - dependsOn: tasks\n\
         \x20   script:\n\
         \x20     actions:\n\
         \x20       onRun:\n\
         \x20         command: {xtask}\n\
         \x20         args: [\"sweep\", \"collect\", {dirq}]\n",
        dir = dir.display(),
        name = yaml_str(&format!("xtask sweep {}", plan.name())),
        range = yaml_str(&range),
        script = yaml_str(&script),
        xtask = yaml_str(&xtask.display().to_string()),
        dirq = yaml_str(&dir.display().to_string()),
    )
}
