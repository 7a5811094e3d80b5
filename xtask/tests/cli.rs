//! The command line as a user meets it, through the real binary in a child process: closed pipes,
//! output folders, failed runs, errors that point at the place, paths, `--set`, a copied binary.
//! Every scene run here is a `--quick` `geom-core/render` (well under a second) or a run that
//! fails during validation.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn exe() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_xtask"))
}

fn checkout() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("xtask sits in the workspace").to_path_buf()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("xtask-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn xtask(args: &[&str], cwd: &Path) -> Output {
    Command::new(exe()).args(args).current_dir(cwd).output().expect("xtask runs")
}

fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// `xtask inspect … | head -1`: the reader goes away after one line; no panic, no exit 101.
#[test]
fn a_closed_pipe_is_not_a_panic() {
    let mut child = Command::new(exe())
        .args(["inspect", "assets/mocap/01_01.bvh"])
        .current_dir(checkout())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let mut first = String::new();
    BufReader::new(child.stdout.take().expect("piped")).read_line(&mut first).expect("one line");
    // The read end is dropped here, as `head -1` exits.
    let out = child.wait_with_output().expect("wait");
    assert!(first.contains("01_01.bvh"), "{first}");
    assert_ne!(out.status.code(), Some(101), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!String::from_utf8_lossy(&out.stderr).contains("panicked"));

    // `xtask run … | true`: stdout closed before the first line; the run still finishes.
    let dir = tmp("pipe-run");
    let out_dir = dir.join("render");
    let mut child = Command::new(exe())
        .args(["run", "geom-core/render", "--quick", "--out"])
        .arg(&out_dir)
        .current_dir(checkout())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out_dir.join("summary.json").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn out_folders_are_refused_unless_forced_and_runs_close_with_a_summary_line() {
    let dir = tmp("force");
    std::fs::write(dir.join("stale.txt"), "x").unwrap();
    let d = dir.to_str().unwrap();
    let o = xtask(&["run", "geom-core/render", "--quick", "--out", d], &checkout());
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("--force"), "{}", text(&o));
    assert!(dir.join("stale.txt").exists());
    let o = xtask(
        &["run", "geom-core/render", "--quick", "--out", d, "--force", "--set", "quick_size=(48, 36)"],
        &checkout(),
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(!dir.join("stale.txt").exists(), "cleared by --force");
    let t = text(&o);
    let first = t.lines().next().unwrap_or("");
    assert!(first.starts_with("run geom-core/render (quick) → "), "{t}");
    assert!(t.contains("done geom-core/render (quick) in "), "{t}");
    let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(summary.contains("\"image_width\": 48"), "--set applied: {summary}");
    assert!(dir.join("run.json").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn scene_dir_with(name: &str, scene: &str) -> (PathBuf, PathBuf) {
    let dir = tmp(name);
    let file = dir.join("my.ron");
    std::fs::write(&file, scene).unwrap();
    (dir, file)
}

/// A scene file outside the checkout, run from yet another folder, reading a mesh that sits
/// beside it (issue 23, item 1).
#[test]
fn scene_paths_resolve_against_the_scene_file_and_empty_meshes_are_named() {
    let scene = "(\n    method: \"geom-core/render\",\n    description: \"my mesh\",\n    params: (\n        size: (64, 48),\n        quick_size: (32, 24),\n        supersample: 1,\n        fov_y_deg: 40.0,\n        eye_offset: (0.6, 0.45, 1.0),\n        light: (0.4, 1.0, 0.6),\n        meshes: [(\"mine\", File(\"meshes/mygrid.obj\"))],\n    ),\n)\n";
    let (dir, file) = scene_dir_with("paths", scene);
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(dir.join("meshes/mygrid.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4\nf 1 4 3\n").unwrap();
    let elsewhere = tmp("paths-cwd");
    let out = dir.join("out");
    let o = xtask(&["run", file.to_str().unwrap(), "--quick", "--out", out.to_str().unwrap()], &elsewhere);
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("mine_shaded.png").is_file());
    // The same file, now empty: the error says so and names it.
    std::fs::write(dir.join("meshes/mygrid.obj"), "").unwrap();
    let o = xtask(&["run", file.to_str().unwrap(), "--quick", "--out", out.to_str().unwrap(), "--force"], &elsewhere);
    assert_eq!(o.status.code(), Some(1));
    let t = text(&o);
    assert!(t.contains("empty") && t.contains("mygrid.obj"), "{t}");
    assert!(out.join("FAILED").is_file() && !out.join("summary.json").exists(), "a failed run says so");
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&elsewhere).unwrap();
}

#[test]
fn errors_name_the_file_line_and_field() {
    let drape = std::fs::read_to_string(checkout().join("scenes/shells/drape.ron")).unwrap();
    let line_of = |t: &str, needle: &str| t.lines().position(|l| l.contains(needle)).expect("needle") + 1;
    // A negative density: the crate's validation error is tied to the line of `density`.
    let bad = drape.replace("density: 0.15", "density: -0.15");
    let (dir, file) = scene_dir_with("density", &bad);
    let o = xtask(&["run", file.to_str().unwrap(), "--quick", "--out", dir.join("o").to_str().unwrap()], &dir);
    let t = text(&o);
    let want = format!("my.ron:{}:", line_of(&bad, "density: -0.15"));
    assert!(t.contains(&want) && t.contains("density"), "want {want} in {t}");
    // Substeps 4.5: an integer was expected.
    let bad = drape.replace("substeps: 4,", "substeps: 4.5,");
    std::fs::write(&file, &bad).unwrap();
    let o = xtask(&["run", file.to_str().unwrap(), "--quick", "--out", dir.join("o2").to_str().unwrap()], &dir);
    let t = text(&o);
    assert!(t.contains(&format!("my.ron:{}:", line_of(&bad, "substeps: 4.5"))) && t.contains("integer"), "{t}");
    // The same through --set.
    std::fs::write(&file, &drape).unwrap();
    let o = xtask(
        &[
            "run",
            file.to_str().unwrap(),
            "--quick",
            "--out",
            dir.join("o3").to_str().unwrap(),
            "--set",
            "shell.integrator.substeps=4.5",
        ],
        &dir,
    );
    let t = text(&o);
    assert!(t.contains("integer") && t.contains("--set shell.integrator.substeps=4.5"), "{t}");
    // An unknown method: the line of `method`, never :0:0.
    let bad = drape.replace("method: \"shells/drape\"", "method: \"shells/drap\"");
    std::fs::write(&file, &bad).unwrap();
    let o = xtask(&["run", file.to_str().unwrap(), "--quick", "--out", dir.join("o4").to_str().unwrap()], &dir);
    let t = text(&o);
    assert!(t.contains(&format!("my.ron:{}:", line_of(&bad, "method:"))) && t.contains("unknown method"), "{t}");
    assert!(!t.contains(":0:0"), "{t}");
    // A BVH error names its file.
    std::fs::write(dir.join("broken.bvh"), "HIERARCHY\nROOT Hips\n{\n").unwrap();
    let o = xtask(&["inspect", "broken.bvh"], &dir);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("broken.bvh"), "{}", text(&o));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A copied binary finds its scenes beside it, not in the checkout it was built from.
#[test]
fn a_copied_binary_finds_the_scenes_beside_it() {
    let root = tmp("copied");
    std::fs::create_dir_all(root.join("bin")).unwrap();
    std::fs::create_dir_all(root.join("scenes/geom-core")).unwrap();
    std::fs::create_dir_all(root.join("assets")).unwrap();
    std::fs::copy(checkout().join("scenes/geom-core/render.ron"), root.join("scenes/geom-core/render.ron")).unwrap();
    let copy = root.join("bin/xtask");
    std::fs::copy(exe(), &copy).unwrap();
    let o = Command::new(&copy).arg("list").current_dir("/").output().unwrap();
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("geom-core/render") && !t.contains("shells/drape"), "{t}");
    // --scenes overrides.
    let o = Command::new(&copy)
        .args(["--scenes"])
        .arg(checkout().join("scenes"))
        .arg("list")
        .current_dir("/")
        .output()
        .unwrap();
    assert!(text(&o).contains("shells/drape"), "{}", text(&o));
    std::fs::remove_dir_all(&root).unwrap();
}

#[test]
fn params_prints_an_annotated_template() {
    let o = xtask(&["params", "geom-core/render"], &checkout());
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("// fov_y_deg: Vertical field of view (degrees)"), "{t}");
    assert!(t.contains("fov_y_deg: 40.0"), "{t}");
    let o = xtask(&["params", "nope/x"], &checkout());
    assert_eq!(o.status.code(), Some(1));
}
