//! `tracks` scenes (Bergou et al. 2007 §5; spec §6): every scene method is an experiment of
//! `tracks::experiments`, run through [`run_experiment`] (parameters from the scene file,
//! outputs through the file recorder, `summary.json` and `checks.json` from its report).

use tracks::experiments as ex;

use crate::error::{Error, Result};
use crate::record::run_experiment;
use crate::registry::{RunCtx, Runner};

impl From<tracks::TrackError> for Error {
    fn from(e: tracks::TrackError) -> Self {
        Error::Run(format!("tracks: {e}"))
    }
}

/// Adds tracks' scene methods.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "tracks/flag", run: flag });
    v.push(Runner { method: "tracks/box", run: box_twist });
    v.push(Runner { method: "tracks/bag", run: bag });
    v.push(Runner { method: "tracks/xavier", run: xavier });
    v.push(Runner { method: "tracks/fig3-band", run: fig3 });
    v.push(Runner { method: "tracks/fig4-sphere", run: fig4 });
    v.push(Runner { method: "tracks/fig6-partitions", run: fig6 });
    v.push(Runner { method: "tracks/fig7-clustering", run: fig7 });
    v.push(Runner { method: "tracks/table55", run: table55 });
    v.push(Runner { method: "tracks/box-variants", run: box_variants });
    v.push(Runner { method: "tracks/bag-variants", run: bag_variants });
}

fn flag(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::flag::run)
}
fn box_twist(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::box_twist::run)
}
fn bag(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::bag::run)
}
fn xavier(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::xavier::run)
}
fn fig3(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::fig3_band::run)
}
fn fig4(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::fig4_sphere::run)
}
fn fig6(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::fig6_partitions::run)
}
fn fig7(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::fig7_clustering::run)
}
fn table55(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::table55::run)
}
fn box_variants(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::box_variants::run)
}
fn bag_variants(ctx: &RunCtx) -> Result<crate::out::Summary> {
    run_experiment(ctx, ex::bag_variants::run)
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::out::workspace_root;
    use crate::scene;

    /// Every shipped tracks scene file parses into its experiment's parameters (unknown fields
    /// are rejected, naming the field).
    #[test]
    fn scene_files_parse() {
        let dir = workspace_root().join("scenes/tracks");
        let load = |name: &str| dir.join(format!("{name}.ron"));
        for name in ["flag", "box", "bag", "xavier"] {
            scene::load::<tracks::experiments::protocol::PairParams>(&load(name)).expect(name);
        }
        scene::load::<tracks::experiments::anchors::AnchorParams>(&load("fig3-band")).expect("fig3");
        scene::load::<tracks::experiments::anchors::AnchorParams>(&load("fig4-sphere")).expect("fig4");
        scene::load::<tracks::experiments::fig6_partitions::Params>(&load("fig6-partitions")).expect("fig6");
        scene::load::<tracks::experiments::fig7_clustering::Params>(&load("fig7-clustering")).expect("fig7");
        scene::load::<tracks::experiments::table55::Params>(&load("table55")).expect("table55");
        let bx = scene::load::<tracks::experiments::box_variants::Params>(&load("box-variants")).expect("box-v");
        bx.params.validate().expect("valid box variants");
        let bg = scene::load::<tracks::experiments::bag_variants::Params>(&load("bag-variants")).expect("bag-v");
        bg.params.validate().expect("valid bag variants");
        let text = "(method: \"tracks/box\", params: (duration: 1.0, substeps: 4, self_collision: true, \
                    kkt: ConstraintLastLdlt, refine_steps: 0, obj_every: 0, colour: 3))";
        let e = scene::parse::<tracks::experiments::protocol::PairParams>(Path::new("x.ron"), text)
            .expect_err("unknown field rejected");
        assert!(e.to_string().contains("colour") && e.to_string().contains("x.ron"), "{e}");
    }
}
