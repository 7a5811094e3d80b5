//! `cargo xtask sweep run DIR/tasks.txt -j N`: the tasks of a sweep on this machine, N processes
//! at a time. Finished tasks are skipped (`skipped N finished`), failed or partial ones cleared
//! and run again; each task's output goes to `DIR/logs/<id>.log`.

use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use super::plan::{read_tasks, Plan};
use super::task::{clear_unfinished, state, TaskState};
use crate::error::{io_err, Error, Result};
use crate::out::ensure_dir;

/// The tasks still to run: the number of finished ones skipped, and the indices of the others
/// (whose failed or partial folders are cleared here).
pub fn pending(plan: &Plan) -> Result<(usize, Vec<usize>)> {
    let mut skipped = 0;
    let mut todo = Vec::new();
    for (i, t) in plan.tasks.iter().enumerate() {
        if state(&t.dir) == TaskState::Finished {
            skipped += 1;
        } else {
            clear_unfinished(&t.dir)?;
            todo.push(i);
        }
    }
    Ok((skipped, todo))
}

/// Runs one task line with `sh -c`, output into `log`; true when the task finished.
fn run_line(line: &str, log: &Path, task_dir: &Path) -> Result<bool> {
    let f = std::fs::File::create(log).map_err(io_err(log))?;
    let f2 = f.try_clone().map_err(io_err(log))?;
    let status = Command::new("sh")
        .arg("-c")
        .arg(line)
        .stdin(Stdio::null())
        .stdout(f)
        .stderr(f2)
        .status()
        .map_err(|e| Error::Run(format!("cannot start sh for a task: {e}")))?;
    Ok(status.success() && state(task_dir) == TaskState::Finished)
}

/// `sweep run`: runs the unfinished tasks of `tasks_txt`, `jobs` at a time.
pub fn run(tasks_txt: &Path, jobs: usize) -> Result<()> {
    let (dir, plan, lines) = read_tasks(tasks_txt)?;
    let jobs = jobs.max(1);
    let (skipped, todo) = pending(&plan)?;
    say!(
        "sweep {} ({} tasks): skipped {skipped} finished, {} to run, {jobs} at a time",
        dir.display(),
        plan.tasks.len(),
        todo.len()
    );
    let logs = dir.join("logs");
    ensure_dir(&logs)?;
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let failed: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let errors: Mutex<Vec<Error>> = Mutex::new(Vec::new());
    let t0 = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..jobs.min(todo.len()) {
            s.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&i) = todo.get(k) else { break };
                let t = &plan.tasks[i];
                let log = logs.join(format!("{}.log", t.id));
                let start = Instant::now();
                let ok = match run_line(&lines[i], &log, &t.dir) {
                    Ok(ok) => ok,
                    Err(e) => {
                        errors.lock().unwrap_or_else(|p| p.into_inner()).push(e);
                        false
                    }
                };
                let n = done.fetch_add(1, Ordering::SeqCst) + 1;
                let dt = crate::ui::human_secs(start.elapsed().as_secs_f64());
                if ok {
                    say!("[{n}/{}] task {} ok in {dt}", todo.len(), t.id);
                } else {
                    say!("[{n}/{}] task {} FAILED in {dt}: see {}", todo.len(), t.id, log.display());
                    failed.lock().unwrap_or_else(|p| p.into_inner()).push(t.id.clone());
                }
            });
        }
    });
    if let Some(e) = errors.into_inner().unwrap_or_else(|p| p.into_inner()).into_iter().next() {
        return Err(e);
    }
    let mut failed = failed.into_inner().unwrap_or_else(|p| p.into_inner());
    failed.sort();
    say!(
        "sweep: {} ran in {}, {} failed; collect with: {} sweep collect {}",
        todo.len(),
        crate::ui::human_secs(t0.elapsed().as_secs_f64()),
        failed.len(),
        super::plan::this_binary().map(|p| p.display().to_string()).unwrap_or_else(|_| "xtask".into()),
        dir.display()
    );
    if failed.is_empty() {
        Ok(())
    } else {
        Err(Error::Run(format!("{} of {} tasks failed: {}", failed.len(), todo.len(), failed.join(", "))))
    }
}
