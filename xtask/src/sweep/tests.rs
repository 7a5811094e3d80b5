//! Unit tests of the planner and the runners' bookkeeping (no Slurm needed): grid expansion,
//! sweep-file errors, command lines, skip logic, CSV merge, Slurm and OpenJD text.

use std::path::{Path, PathBuf};

use super::collect::{collect, gather, write_csv};
use super::command::{join, shell_quote, split};
use super::file::parse;
use super::grid::{expand, task_id};
use super::local::pending;
use super::plan::{Plan, PlanTask, Source};
use super::slurm::{array_spec, parse_job_id, script, SlurmOpts};
use super::task::{state, TaskState};
use crate::out::Summary;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("xtask-sweep-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(v: &[&str]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

#[test]
fn grid_is_the_full_product_first_parameter_outermost() {
    let g = expand(&[s(&["a", "b"]), s(&["1", "2", "3"])]);
    assert_eq!(g.len(), 6);
    assert_eq!(g[0], s(&["a", "1"]));
    assert_eq!(g[2], s(&["a", "3"]));
    assert_eq!(g[3], s(&["b", "1"]));
    assert_eq!(expand(&[]), vec![Vec::<String>::new()]);
    assert!(expand(&[s(&["a"]), vec![]]).is_empty());
    assert_eq!(task_id(7, 16), "0007");
    assert_eq!(task_id(12345, 20000), "12345");
}

#[test]
fn command_lines_quote_what_the_shell_would_break() {
    assert_eq!(shell_quote("/a/b-c.ron"), "/a/b-c.ron");
    assert_eq!(shell_quote("gravity=Some((0.0, -9.81, 0.0))"), "'gravity=Some((0.0, -9.81, 0.0))'");
    assert_eq!(shell_quote("it's"), "'it'\\''s'");
    assert_eq!(shell_quote(""), "''");
    let words = s(&["/x y/xtask", "run", "--set", "name=\"a b\"", "it's", "plain"]);
    assert_eq!(split(&join(&words)).unwrap(), words);
    assert!(split("echo $HOME").is_none());
}

fn drape_sweep(vary: &str) -> String {
    format!("(\n    scene: \"shells/drape\",\n    mode: Quick,\n    vary: [\n{vary}\n    ],\n)\n")
}

#[test]
fn sweep_file_gives_tasks_with_absolute_self_contained_commands() {
    let dir = tmp("plan");
    let text = drape_sweep("        (\"shell.material.density\", [0.1, 0.2]),\n        (\"shell.effects.gravity\", [Some((0.0, -9.81, 0.0)), None]),");
    let file = dir.join("drape-grid.ron");
    let sf = parse(&file, &text).unwrap();
    assert!(sf.scene.is_absolute() && sf.scene.ends_with("scenes/shells/drape.ron"), "{}", sf.scene.display());
    assert_eq!(sf.vary[1].values, s(&["Some((0.0, -9.81, 0.0))", "None"]));
    let plan = Plan::from_file(&sf, &dir.join("out"));
    assert_eq!(plan.tasks.len(), 4);
    assert_eq!(plan.tasks[1].values, s(&["0.1", "None"]));
    let lines = plan.command_lines(Path::new("/opt/tk/bin/xtask"), Some(Path::new("/opt/tk/scenes")));
    let w = split(&lines[2]).unwrap();
    assert_eq!(&w[..4], ["/opt/tk/bin/xtask", "--scenes", "/opt/tk/scenes", "run"]);
    let w = &w[3..];
    assert_eq!(PathBuf::from(&w[1]), sf.scene);
    let out = dir.join("out/tasks/0002");
    let expect = s(&["--quick", "--out", &out.display().to_string(), "--resume"]);
    assert_eq!(&w[2..6], &expect[..]);
    assert_eq!(
        &w[6..],
        &s(&["--set", "shell.material.density=0.2", "--set", "shell.effects.gravity=Some((0.0, -9.81, 0.0))"])[..]
    );
    // The plan round-trips through sweep.ron.
    let text = ron::ser::to_string_pretty(&plan, ron::ser::PrettyConfig::default()).unwrap();
    assert_eq!(ron::from_str::<Plan>(&text).unwrap(), plan);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_sweep_files_name_file_line_and_field() {
    let f = Path::new("/work/my-sweep.ron");
    let err = |text: &str| parse(f, text).unwrap_err().to_string();
    // A path the scene does not have: the line of its first value.
    let e = err(&drape_sweep("        (\"shell.material.densty\", [0.1, 0.2]),"));
    assert!(e.starts_with("/work/my-sweep.ron:5:") && e.contains("`vary.0.0`") && e.contains("densty"), "{e}");
    // No values.
    let e = err(&drape_sweep("        (\"shell.material.density\", []),"));
    assert!(e.starts_with("/work/my-sweep.ron:5:") && e.contains("has no values"), "{e}");
    // Listed twice.
    let e =
        err(&drape_sweep("        (\"shell.material.density\", [0.1]),\n        (\"shell.material.density\", [0.2]),"));
    assert!(e.starts_with("/work/my-sweep.ron:6:") && e.contains("listed twice"), "{e}");
    // An unknown scene: the `scene` line.
    let e = err("(\n    scene: \"shells/nope\",\n    vary: [(\"a\", [1])],\n)\n");
    assert!(e.starts_with("/work/my-sweep.ron:2:") && e.contains("`scene`") && e.contains("no built-in scene"), "{e}");
    // An unknown field and a bad mode: ron's position and the field.
    let e = err("(\n    scene: \"shells/drape\",\n    mode: Fast,\n    vary: [],\n)\n");
    assert!(e.starts_with("/work/my-sweep.ron:3:") && e.contains("Fast"), "{e}");
    let e = err("(\n    scene: \"shells/drape\",\n    vary: [],\n    seed: 3,\n)\n");
    assert!(e.starts_with("/work/my-sweep.ron:4:") && e.contains("seed"), "{e}");
    // No parameter to vary.
    let e = err("(\n    scene: \"shells/drape\",\n    vary: [],\n)\n");
    assert!(e.starts_with("/work/my-sweep.ron:3:") && e.contains("lists no parameter"), "{e}");
    // A relative scene path that does not exist resolves against the sweep file's folder.
    let e = err("(\n    scene: \"mine.ron\",\n    vary: [(\"a\", [1])],\n)\n");
    assert!(e.contains("/work/mine.ron"), "{e}");
}

fn fake_plan(dir: &Path, n: usize) -> Plan {
    Plan {
        source: Source::Bench { krate: "perf-control".into(), sweep: "stretch".into() },
        mode: "quick".into(),
        parameters: s(&["stretch"]),
        tasks: (0..n)
            .map(|i| PlanTask {
                id: task_id(i, n),
                dir: dir.join("tasks").join(task_id(i, n)),
                values: vec![format!("0.{i}")],
            })
            .collect(),
    }
}

fn finish(t: &PlanTask, err: f64, wall: f64) {
    let mut s = Summary::new();
    s.set("err_rms_m", err).set("wall_s", wall).set_str("mode", "quick").set("nan_figure", f64::NAN);
    s.write(&t.dir).unwrap();
    std::fs::write(t.dir.join("timing.json"), "[\"wall_s\"]\n").unwrap();
    std::fs::write(t.dir.join("pc_stretch.csv"), format!("sweep,value,dp_s\nstretch,{},{wall}\n", t.values[0]))
        .unwrap();
}

#[test]
fn finished_tasks_are_skipped_failed_and_partial_ones_cleared() {
    let dir = tmp("skip");
    let plan = fake_plan(&dir, 5);
    finish(&plan.tasks[0], 0.5, 1.0);
    finish(&plan.tasks[3], 0.25, 2.0);
    // 1: failed (FAILED beside a stale summary); 2: partial (killed); 4: never started.
    finish(&plan.tasks[1], 9.0, 1.0);
    std::fs::write(plan.tasks[1].dir.join("FAILED"), "boom\n").unwrap();
    std::fs::create_dir_all(plan.tasks[2].dir.join("frames")).unwrap();
    std::fs::write(plan.tasks[2].dir.join("frames/0000.obj"), "v 0 0 0\n").unwrap();
    let states: Vec<TaskState> = plan.tasks.iter().map(|t| state(&t.dir)).collect();
    use TaskState::*;
    assert_eq!(states, [Finished, Failed, Partial, Finished, Missing]);
    let (skipped, todo) = pending(&plan).unwrap();
    assert_eq!((skipped, todo), (2, vec![1, 2, 4]));
    assert!(!plan.tasks[1].dir.exists() && !plan.tasks[2].dir.exists(), "failed and partial folders cleared");
    assert!(plan.tasks[0].dir.join("summary.json").is_file() && plan.tasks[3].dir.join("pc_stretch.csv").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn collect_merges_summaries_with_parameters_in_task_order() {
    let dir = tmp("collect");
    let plan = fake_plan(&dir, 3);
    finish(&plan.tasks[2], 0.125, 3.0);
    finish(&plan.tasks[0], 0.5, 1.5);
    // Task 1 failed.
    std::fs::create_dir_all(&plan.tasks[1].dir).unwrap();
    std::fs::write(plan.tasks[1].dir.join("FAILED"), "boom\n").unwrap();
    let c = gather(&plan).unwrap();
    assert_eq!(c.failed, ["0001"]);
    assert_eq!(c.timing, ["wall_s"]);
    write_csv(&dir.join("sweep.csv"), &plan, &c).unwrap();
    let text = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    assert_eq!(
        text,
        "task,stretch,err_rms_m,mode,nan_figure,wall_s\n0000,0.0,0.5,quick,NaN,1.5\n0002,0.2,0.125,quick,NaN,3.0\n"
    );
    // The whole collect: status, bench table concatenated in task order, report with the sweep.
    std::fs::write(dir.join("sweep.ron"), ron::ser::to_string_pretty(&plan, Default::default()).unwrap()).unwrap();
    collect(&dir).unwrap();
    let merged = std::fs::read_to_string(dir.join("pc_stretch.csv")).unwrap();
    assert_eq!(merged, "sweep,value,dp_s\nstretch,0.0,1.5\nstretch,0.2,3\n");
    let status: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("sweep-status.json")).unwrap()).unwrap();
    assert_eq!(status["finished"], 2);
    assert_eq!(status["failed"][0], "0001");
    assert!(dir.join("plots/err_rms_m--stretch.png").is_file());
    assert!(!dir.join("plots/mode--stretch.png").exists(), "text figures are not plotted");
    let html = std::fs::read_to_string(dir.join("report/index.html")).unwrap();
    assert!(
        html.contains("sweep bench-perf-control-stretch") && html.contains("failed: 0001"),
        "report shows the sweep"
    );
    assert!(html.contains("<td>0.125</td>"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn slurm_array_lists_only_the_unfinished_lines() {
    assert_eq!(array_spec(&[0, 1, 2, 5, 7, 8]), "0-2,5,7-8");
    assert_eq!(array_spec(&[3]), "3");
    assert_eq!(parse_job_id("1234\n"), Some("1234".into()));
    assert_eq!(parse_job_id("77;cluster\n"), Some("77".into()));
    assert_eq!(parse_job_id("sbatch: error"), None);
    let dir = PathBuf::from("/scratch/sw");
    let plan = fake_plan(&dir, 16);
    let o = SlurmOpts {
        partition: Some("short".into()),
        time: Some("0:10:00".into()),
        mem: Some("2G".into()),
        throttle: Some(4),
    };
    let text = script(&plan, &dir, &[0, 1, 2, 3, 9], &o);
    assert!(text.contains("#SBATCH --array=0-3,9%4\n"), "{text}");
    assert!(text.contains("#SBATCH --partition=short\n#SBATCH --time=0:10:00\n#SBATCH --mem=2G\n"), "{text}");
    assert!(text.contains("#SBATCH --output=/scratch/sw/logs/slurm-%A_%a.out\n"), "{text}");
    assert!(text.contains("sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" /scratch/sw/tasks.txt"), "{text}");
}

#[test]
fn openjd_template_has_one_task_per_line_and_a_collect_step() {
    let dir = PathBuf::from("/scratch/sw");
    let plan = fake_plan(&dir, 16);
    let y = super::openjd::template(&plan, &dir, Path::new("/opt/bin/xtask"));
    assert!(y.contains("specificationVersion: jobtemplate-2023-09\n"), "{y}");
    assert!(y.contains("range: \"1-16\""), "{y}");
    assert!(y.contains("sed -n '{{Task.Param.Line}}p' /scratch/sw/tasks.txt"), "{y}");
    assert!(y.contains("dependsOn: tasks") && y.contains("args: [\"sweep\", \"collect\", \"/scratch/sw\"]"), "{y}");
    assert_eq!(super::openjd::yaml_str("a\"b\\c"), "\"a\\\"b\\\\c\"");
}

#[test]
fn csv_fields_read_quoted_cells() {
    use super::report::csv_fields;
    assert_eq!(csv_fields("a,\"b,c\",\"x\"\"y\","), s(&["a", "b,c", "x\"y", ""]));
}

#[test]
fn bench_points_are_checked_before_anything_runs() {
    use crate::run::{run_bench, DirPolicy, RunOptions};
    use crate::scene::Mode;
    let dir = tmp("points");
    let o = RunOptions {
        mode: Mode::Quick,
        out_dir: dir.join("run"),
        policy: DirPolicy::Explicit { force: false },
        overrides: Vec::new(),
        previews: false,
        label: "t".into(),
    };
    let e = run_bench("flip-tet", Some("resolution"), Some(2), &o).unwrap_err().to_string();
    assert!(e.contains("has 2 points"), "{e}");
    let e = run_bench("flip-tet", Some("solver"), Some(0), &o).unwrap_err().to_string();
    assert!(e.contains("does not split"), "{e}");
    let e = run_bench("flip-tet", Some("all"), Some(0), &o).unwrap_err().to_string();
    assert!(e.contains("needs --sweep"), "{e}");
    assert!(!o.out_dir.exists(), "nothing ran");
    let e = Plan::from_bench("perf-control", "beam", Mode::Quick, &dir).unwrap_err().to_string();
    assert!(e.contains("does not split"), "{e}");
    let e = Plan::from_bench("flip-tet", "nope", Mode::Quick, &dir).unwrap_err().to_string();
    assert!(e.contains("no sweep 'nope'") && e.contains("resolution"), "{e}");
    let p = Plan::from_bench("flip-tet", "resolution", Mode::Full, &dir).unwrap();
    assert_eq!(p.tasks.iter().map(|t| t.values[0].as_str()).collect::<Vec<_>>(), ["16", "32", "64"]);
    let lines = p.command_lines(Path::new("/b/xtask"), None);
    let w = split(&lines[1]).unwrap();
    let out = dir.join("tasks/0001").display().to_string();
    assert_eq!(
        w,
        s(&[
            "/b/xtask",
            "bench",
            "flip-tet",
            "--full",
            "--sweep",
            "resolution",
            "--point",
            "1",
            "--out",
            &out,
            "--resume"
        ])
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
