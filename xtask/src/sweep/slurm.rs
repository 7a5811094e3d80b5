//! `cargo xtask sweep slurm DIR/tasks.txt [--partition P --time T --mem M --throttle K]`: the
//! unfinished tasks as one Slurm job array (`DIR/sweep.sbatch`, element i runs line i + 1 of
//! `tasks.txt`; `%K` runs at most K at once), and a job that collects the results once the array
//! ends (`--dependency=afterany:<array id>`, so a partly failed or cancelled sweep is still
//! collected). Finished tasks are left out of the array (`skipped N finished`); failed or partial
//! ones are cleared first. Submitted with `sbatch --parsable`; logs in `DIR/logs/`.

use std::path::Path;
use std::process::Command;

use super::command::{join, shell_quote};
use super::plan::{read_tasks, Plan, TASKS_TXT};
use crate::error::{Error, Result};
use crate::out::{ensure_dir, write_atomic};

/// The script's file name in a sweep folder.
pub const FILE: &str = "sweep.sbatch";

/// Resources of the array's elements and the collect job (Slurm's syntax, passed through).
#[derive(Clone, Debug, Default)]
pub struct SlurmOpts {
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` (e.g. `0:30:00`).
    pub time: Option<String>,
    /// `--mem` (e.g. `4G`).
    pub mem: Option<String>,
    /// The array throttle `%K`: at most K elements at once.
    pub throttle: Option<usize>,
}

impl SlurmOpts {
    fn flags(&self) -> Vec<String> {
        let mut v = Vec::new();
        for (k, x) in [("partition", &self.partition), ("time", &self.time), ("mem", &self.mem)] {
            if let Some(x) = x {
                v.push(format!("--{k}={x}"));
            }
        }
        v
    }
}

/// Slurm's array syntax for sorted indices: runs of consecutive indices as `a-b`
/// (`[0, 1, 2, 5, 7, 8]` → `0-2,5,7-8`).
pub fn array_spec(indices: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut k = 0;
    while k < indices.len() {
        let start = indices[k];
        let mut end = start;
        while k + 1 < indices.len() && indices[k + 1] == end + 1 {
            k += 1;
            end = indices[k];
        }
        parts.push(if start == end { start.to_string() } else { format!("{start}-{end}") });
        k += 1;
    }
    parts.join(",")
}

/// The job-array script running `indices` (0-based lines of `tasks.txt`) of the sweep in `dir`.
pub fn script(plan: &Plan, dir: &Path, indices: &[usize], o: &SlurmOpts) -> String {
    let mut s = format!(
        "#!/bin/bash\n\
         # Slurm job array of the sweep in {d} (written by `cargo xtask sweep slurm`):\n\
         # element i runs line i + 1 of tasks.txt; finished tasks are not in the array.\n\
         #SBATCH --job-name=xtask-{name}\n\
         #SBATCH --array={spec}{throttle}\n\
         #SBATCH --output={d}/logs/slurm-%A_%a.out\n",
        d = dir.display(),
        name = plan.name(),
        spec = array_spec(indices),
        throttle = o.throttle.map(|k| format!("%{k}")).unwrap_or_default(),
    );
    for f in o.flags() {
        s.push_str(&format!("#SBATCH {f}\n"));
    }
    s.push_str(&format!(
        "set -eu\nline=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" {tasks})\ntest -n \"$line\"\neval \"$line\"\n",
        tasks = shell_quote(&dir.join(TASKS_TXT).display().to_string())
    ));
    s
}

/// The job id in `sbatch --parsable` output (`123` or `123;cluster`).
pub fn parse_job_id(out: &str) -> Option<String> {
    let id = out.trim().split(';').next()?.trim();
    (!id.is_empty() && id.chars().all(|c| c.is_ascii_digit())).then(|| id.to_string())
}

fn sbatch(args: &[String]) -> Result<String> {
    let out = Command::new("sbatch")
        .args(args)
        .output()
        .map_err(|e| Error::Run(format!("cannot run sbatch ({e}): is Slurm installed and on PATH?")))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(Error::Run(format!(
            "sbatch {} failed: {}{}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim(),
            stdout.trim()
        )));
    }
    parse_job_id(&stdout).ok_or_else(|| Error::Run(format!("sbatch printed no job id: {stdout}")))
}

/// `sweep slurm`: writes `DIR/sweep.sbatch` for the unfinished tasks and submits it and the
/// collect job (unless `submit` is false).
pub fn submit(tasks_txt: &Path, o: &SlurmOpts, submit: bool) -> Result<()> {
    let (dir, plan, _lines) = read_tasks(tasks_txt)?;
    let (skipped, todo) = super::local::pending(&plan)?;
    say!("sweep {} ({} tasks): skipped {skipped} finished, {} to submit", dir.display(), plan.tasks.len(), todo.len());
    let xtask = super::plan::this_binary()?;
    let collect = join(&[xtask.display().to_string(), "sweep".into(), "collect".into(), dir.display().to_string()]);
    if todo.is_empty() {
        say!("nothing to submit; collecting here");
        return super::collect::collect(&dir).map(|_| ());
    }
    ensure_dir(&dir.join("logs"))?;
    let path = dir.join(FILE);
    write_atomic(&path, script(&plan, &dir, &todo, o).as_bytes())?;
    if !submit {
        say!("wrote {} (not submitted)", path.display());
        return Ok(());
    }
    let array = sbatch(&["--parsable".into(), path.display().to_string()])?;
    let mut args = vec![
        "--parsable".to_string(),
        format!("--dependency=afterany:{array}"),
        format!("--job-name=xtask-{}-collect", plan.name()),
        format!("--output={}/logs/slurm-collect-%j.out", dir.display()),
    ];
    args.extend(o.flags());
    args.extend(["--wrap".into(), collect]);
    let collect_id = sbatch(&args)?;
    say!(
        "array job: {array} ({} tasks{})",
        todo.len(),
        o.throttle.map(|k| format!(", at most {k} at once")).unwrap_or_default()
    );
    say!("collect job: {collect_id} (after the array ends; writes {})", dir.join("sweep.csv").display());
    Ok(())
}
