//! Sweeps (issue 28): many independent runs of one scene (a grid over `--set` overrides) or the
//! points of a benchmark's sweep, planned into a task list any scheduler can run, resumed task
//! by task, and collected into one table, plots and a report section.
//!
//! - `cargo xtask plan SWEEP.ron --out DIR` / `plan --bench <crate> --sweep <knob> --out DIR`:
//!   `DIR/tasks.txt` (one self-contained shell command per line), `DIR/sweep.ron` (task →
//!   parameters) and `DIR/sweep.openjd.yaml` (an Open Job Description template) ([`plan`]).
//! - `cargo xtask sweep run DIR/tasks.txt -j N`: on this machine ([`local`]);
//!   `cargo xtask sweep slurm DIR/tasks.txt …`: a Slurm job array and a dependent collect job
//!   ([`slurm`]); `cargo xtask sweep collect DIR`: `DIR/sweep.csv`, plots, report ([`collect`]).
//!
//! A task is finished when its folder holds `summary.json` (written last, atomically) and no
//! `FAILED` ([`task`]); every runner skips finished tasks and clears failed or partial ones.

pub mod collect;
pub mod command;
pub mod file;
pub mod grid;
pub mod local;
pub mod openjd;
pub mod plan;
pub mod plots;
pub mod report;
pub mod slurm;
pub mod task;

#[cfg(test)]
mod tests;
