//! `cargo xtask plan`: a sweep (a sweep file's grid, or the points of a benchmark's sweep) as a
//! task list. Writes into `DIR`:
//! - `tasks.txt`: one complete shell command per task, in task order, with the absolute path of
//!   this binary and absolute paths everywhere (a node sharing the file system runs any line from
//!   any folder); each line is idempotent (`--resume`: a finished task is skipped, a failed or
//!   partial one cleared and run again);
//! - `sweep.ron`: the task → parameters map ([`Plan`]), read by the runners and `collect`;
//! - `sweep.openjd.yaml`: the same tasks as an Open Job Description template ([`super::openjd`]).
//!
//! Task `i` writes into `DIR/tasks/<id>/` (`id` = `i` zero-padded, [`super::grid::task_id`]).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::command;
use super::file::SweepFile;
use super::grid::{expand, task_id};
use crate::error::{io_err, Error, Result};
use crate::out::{ensure_dir, write_atomic};
use crate::scene::Mode;

/// The task list file of a sweep folder.
pub const TASKS_TXT: &str = "tasks.txt";
/// The task → parameters file of a sweep folder.
pub const SWEEP_RON: &str = "sweep.ron";

/// What the tasks run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Source {
    /// `run SCENE --set …` per task.
    Scene {
        /// The sweep file (absolute).
        sweep_file: PathBuf,
        /// The scene file (absolute).
        scene: PathBuf,
    },
    /// `bench CRATE --sweep KNOB --point I` per task.
    Bench {
        /// The crate.
        krate: String,
        /// The sweep of its bench.
        sweep: String,
    },
}

/// One task: its id, its folder and the value of each varied parameter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanTask {
    /// `0000`, `0001`, …
    pub id: String,
    /// Its run folder (absolute).
    pub dir: PathBuf,
    /// The value of each of [`Plan::parameters`] (RON text; a bench point's label).
    pub values: Vec<String>,
}

/// `sweep.ron`: everything the runners and `collect` need to know about a sweep.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// What the tasks run.
    pub source: Source,
    /// `quick`, `default` or `full`.
    pub mode: String,
    /// The varied parameters (scene: `--set` paths; bench: the sweep's knob).
    pub parameters: Vec<String>,
    /// The tasks, in the order of `tasks.txt`.
    pub tasks: Vec<PlanTask>,
}

impl Plan {
    /// The plan of a sweep file's grid, tasks under `dir/tasks/`.
    pub fn from_file(sf: &SweepFile, dir: &Path) -> Plan {
        let combos = expand(&sf.vary.iter().map(|d| d.values.clone()).collect::<Vec<_>>());
        let n = combos.len();
        let tasks = combos
            .into_iter()
            .enumerate()
            .map(|(i, values)| {
                let id = task_id(i, n);
                PlanTask { dir: dir.join("tasks").join(&id), id, values }
            })
            .collect();
        Plan {
            source: Source::Scene { sweep_file: sf.file.clone(), scene: sf.scene.clone() },
            mode: sf.mode.name().into(),
            parameters: sf.vary.iter().map(|d| d.path.clone()).collect(),
            tasks,
        }
    }

    /// The plan of the points of `krate`'s bench sweep `sweep` at `mode`.
    pub fn from_bench(krate: &str, sweep: &str, mode: Mode, dir: &Path) -> Result<Plan> {
        let benches = crate::registry::benches();
        let bench = benches.iter().find(|b| b.crate_name == krate).ok_or_else(|| {
            let known: Vec<&str> = benches.iter().map(|b| b.crate_name).collect();
            Error::Usage(format!("no benchmark for '{krate}'; known: {}", known.join(", ")))
        })?;
        if !bench.sweeps.contains(&sweep) {
            return Err(Error::Usage(format!(
                "no sweep '{sweep}' in the '{krate}' benchmark{}",
                if bench.sweeps.is_empty() { String::new() } else { format!("; known: {}", bench.sweeps.join(", ")) }
            )));
        }
        let labels = crate::bench_points::points(krate, sweep, mode == Mode::Quick).ok_or_else(|| {
            Error::Usage(format!(
                "the '{sweep}' sweep of the '{krate}' benchmark does not split into points (its points share a baseline); \
                 run `cargo xtask bench {krate} --sweep {sweep}` whole"
            ))
        })?;
        let n = labels.len();
        let tasks = labels
            .into_iter()
            .enumerate()
            .map(|(i, l)| {
                let id = task_id(i, n);
                PlanTask { dir: dir.join("tasks").join(&id), id, values: vec![l] }
            })
            .collect();
        Ok(Plan {
            source: Source::Bench { krate: krate.into(), sweep: sweep.into() },
            mode: mode.name().into(),
            parameters: vec![sweep.to_string()],
            tasks,
        })
    }

    /// The run mode.
    pub fn run_mode(&self) -> Mode {
        match self.mode.as_str() {
            "quick" => Mode::Quick,
            "full" => Mode::Full,
            _ => Mode::Default,
        }
    }

    /// One line per task: the command that runs it, with `xtask` the binary's absolute path and
    /// `scenes` the built-in scene folder (absolute) when there is one.
    pub fn command_lines(&self, xtask: &Path, scenes: Option<&Path>) -> Vec<String> {
        let mode = self.run_mode();
        self.tasks
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let words = match &self.source {
                    Source::Scene { scene, .. } => {
                        let sets: Vec<(String, String)> =
                            self.parameters.iter().cloned().zip(t.values.iter().cloned()).collect();
                        command::scene_task(xtask, scenes, scene, mode, &t.dir, &sets)
                    }
                    Source::Bench { krate, sweep } => command::bench_task(xtask, scenes, krate, mode, sweep, i, &t.dir),
                };
                command::join(&words)
            })
            .collect()
    }

    /// A one-line name of the sweep (for reports and job names).
    pub fn name(&self) -> String {
        match &self.source {
            Source::Scene { sweep_file, .. } => {
                sweep_file.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "sweep".into())
            }
            Source::Bench { krate, sweep } => format!("bench-{krate}-{sweep}"),
        }
    }

    /// Reads `dir/sweep.ron`.
    pub fn read(dir: &Path) -> Result<Plan> {
        let path = dir.join(SWEEP_RON);
        let text = std::fs::read_to_string(&path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => Error::Usage(format!(
                "{}: no such file; is {} a folder written by `cargo xtask plan`?",
                path.display(),
                dir.display()
            )),
            _ => Error::Io { path: path.clone(), source: e },
        })?;
        ron::from_str(&text).map_err(|e| crate::scene::spanned(&path, &text, &[], e))
    }
}

/// The absolute path of the running binary (what `tasks.txt` calls).
pub fn this_binary() -> Result<PathBuf> {
    let exe = std::env::current_exe().map_err(|e| Error::Run(format!("cannot find this binary's path: {e}")))?;
    Ok(exe.canonicalize().unwrap_or(exe))
}

/// Writes `tasks.txt`, `sweep.ron` and `sweep.openjd.yaml` into `dir`. A folder holding another
/// sweep's task list is refused (unless `force`, which removes its `tasks/`); planning the same
/// sweep again keeps the finished tasks.
pub fn write(plan: &Plan, dir: &Path, force: bool) -> Result<Vec<String>> {
    let xtask = this_binary()?;
    let scenes =
        crate::paths::scenes_dir().ok().map(|d| d.canonicalize().unwrap_or_else(|_| crate::paths::absolute(&d)));
    let lines = plan.command_lines(&xtask, scenes.as_deref());
    let text = lines.join("\n") + "\n";
    let tasks_txt = dir.join(TASKS_TXT);
    if let Ok(old) = std::fs::read_to_string(&tasks_txt) {
        if old != text {
            if !force {
                return Err(Error::Usage(format!(
                    "{} holds another sweep's task list: choose another --out, or pass --force to replace it (its tasks/ are removed)",
                    dir.display()
                )));
            }
            let t = dir.join("tasks");
            if t.exists() {
                std::fs::remove_dir_all(&t).map_err(io_err(&t))?;
            }
        }
    }
    ensure_dir(dir)?;
    let ron_text = ron::ser::to_string_pretty(plan, ron::ser::PrettyConfig::default())
        .map_err(|e| Error::Run(format!("sweep.ron: {e}")))?;
    write_atomic(&dir.join(SWEEP_RON), (ron_text + "\n").as_bytes())?;
    write_atomic(&dir.join(super::openjd::FILE), super::openjd::template(plan, dir, &xtask).as_bytes())?;
    write_atomic(&tasks_txt, text.as_bytes())?;
    Ok(lines)
}

/// Reads a sweep folder's plan and task lines given its `tasks.txt`; their counts must agree.
pub fn read_tasks(tasks_txt: &Path) -> Result<(PathBuf, Plan, Vec<String>)> {
    let abs = crate::paths::absolute(tasks_txt);
    let dir = abs.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
    let text = std::fs::read_to_string(&abs).map_err(io_err(&abs))?;
    let lines: Vec<String> = text.lines().filter(|l| !l.trim().is_empty()).map(str::to_string).collect();
    let plan = Plan::read(&dir)?;
    if lines.len() != plan.tasks.len() {
        return Err(Error::Usage(format!(
            "{} has {} lines but {} lists {} tasks: plan the sweep again",
            abs.display(),
            lines.len(),
            dir.join(SWEEP_RON).display(),
            plan.tasks.len()
        )));
    }
    Ok((dir, plan, lines))
}
