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
