//! The scene files `scenes/flip-tet/*.ron` hold exactly the setups of `flip_tet::presets` (the
//! tests and benches build from the presets, `cargo xtask run` from the files): each file's
//! `params` block parses as its experiment's `Params` and equals the preset.

use serde::de::DeserializeOwned;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File<P> {
    method: String,
    description: String,
    params: P,
}

fn load<P: DeserializeOwned>(name: &str) -> (String, P) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/flip-tet").join(format!("{name}.ron"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let f: File<P> = ron::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(!f.description.trim().is_empty(), "{name}: description");
    (f.method, f.params)
}

fn same<P: DeserializeOwned + PartialEq + std::fmt::Debug>(name: &str, method: &str, want: P) {
    let (m, got) = load::<P>(name);
    assert_eq!(m, method);
    assert!(got == want, "{name}: the scene file differs from the preset:\nfile {got:#?}\npreset {want:#?}");
}

#[test]
fn scene_files_equal_the_presets() {
    use flip_tet::presets as p;
    same("rest-pool", "flip-tet/rest-pool", p::rest_pool());
    same("dam-break", "flip-tet/dam-break", p::dam_break());
    same("standing-wave", "flip-tet/standing-wave", p::standing_wave());
    same("drop-pool", "flip-tet/drop-pool", p::drop_pool());
    same("holes-plate", "flip-tet/holes-plate", p::holes_plate());
    same("adaptivity-payoff", "flip-tet/adaptivity-payoff", p::adaptivity_payoff());
    same("surface-mixed-radii", "flip-tet/surface-mixed-radii", p::surface_mixed_radii());
    same("fvm-vs-nodal", "flip-tet/fvm-vs-nodal", p::fvm_vs_nodal());
    same("open-splash", "flip-tet/open-splash", p::open_splash());
    same("corridor-camera", "flip-tet/corridor-camera", p::corridor_camera());
}

/// The scenes of issue 26 items 4–5 have no preset (only the scene file holds them): each parses
/// as its experiment's `Params`, names its runner, and its scene validates.
#[test]
fn issue_26_scene_files_parse_and_validate() {
    use flip_tet::experiments::{dam_break_gate, inflow, obstacle_force};
    let (m, p) = load::<dam_break_gate::Params>("dam-break-gate");
    assert_eq!(m, "flip-tet/dam-break-gate");
    dam_break_gate::gate_scene(&p.dam.scene, p.gate_thickness, p.gate_speed).unwrap().validate().unwrap();
    let (m, p) = load::<inflow::Params>("inflow");
    assert_eq!(m, "flip-tet/inflow");
    p.scene.validate().unwrap();
    let (m, p) = load::<obstacle_force::Params>("obstacle-force");
    assert_eq!(m, "flip-tet/obstacle-force");
    p.scene.validate().unwrap();
    p.paddle.validate().unwrap();
}

/// A mesh obstacle that is open (a box missing a face) is an error naming the field and the
/// file, not a panic.
#[test]
fn open_mesh_obstacle_is_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("flip-tet-open-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("open.obj");
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\n").unwrap();
    let mut sc = flip_tet::scene::Scene::new(([0.0; 3], [2.0; 3]), (4, 4), vec![]);
    sc.obstacles = vec![flip_tet::scene::Shape::Mesh { path: "open.obj".into() }];
    sc.resolve_paths(&dir);
    let e = flip_tet::obstacle::Obstacles::new(&sc).unwrap_err().to_string();
    assert!(e.contains("obstacles[0]") && e.contains("open.obj") && e.contains("not closed"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
