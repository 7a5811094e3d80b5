//! `tracks` scenes (Bergou et al. 2007 §5; spec §6): every scene method is an experiment of
//! `tracks::experiments`, run through [`run_experiment`] (parameters from the scene file,
//! outputs through the file recorder, `summary.json` and `checks.json` from its report).

use tracks::experiments::{
    bag, bag_variants, box_twist, box_variants, fig3_band, fig4_sphere, fig5_heterogeneous, fig6_partitions,
    fig7_clustering, flag, table55, track, xavier,
};
use tracks::TrackError;

use crate::error::Error;
use crate::record::run_experiment;
use crate::registry::Runner;

impl From<TrackError> for Error {
    fn from(e: TrackError) -> Self {
        match e {
            TrackError::Core(c) => Error::Core(c),
            other => Error::Run(format!("tracks: {other}")),
        }
    }
}

/// Adds tracks' scene methods.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "tracks/flag", run: |c| run_experiment(c, flag::run) });
    v.push(Runner { method: "tracks/box", run: |c| run_experiment(c, box_twist::run) });
    v.push(Runner { method: "tracks/bag", run: |c| run_experiment(c, bag::run) });
    v.push(Runner { method: "tracks/xavier", run: |c| run_experiment(c, xavier::run) });
    v.push(Runner { method: "tracks/fig3-band", run: |c| run_experiment(c, fig3_band::run) });
    v.push(Runner { method: "tracks/fig4-sphere", run: |c| run_experiment(c, fig4_sphere::run) });
    v.push(Runner { method: "tracks/fig5-heterogeneous", run: |c| run_experiment(c, fig5_heterogeneous::run) });
    v.push(Runner { method: "tracks/fig6-partitions", run: |c| run_experiment(c, fig6_partitions::run) });
    v.push(Runner { method: "tracks/fig7-clustering", run: |c| run_experiment(c, fig7_clustering::run) });
    v.push(Runner { method: "tracks/track", run: run_track });
    v.push(Runner { method: "tracks/table55", run: |c| run_experiment(c, table55::run) });
    v.push(Runner { method: "tracks/box-variants", run: |c| run_experiment(c, box_variants::run) });
    v.push(Runner { method: "tracks/bag-variants", run: |c| run_experiment(c, bag_variants::run) });
}

/// A user's own guide: the guide and tracked-mesh paths are relative to the scene file.
fn run_track(ctx: &crate::registry::RunCtx) -> crate::error::Result<crate::out::Summary> {
    run_experiment(ctx, |p: &track::Params, size, rec| {
        let mut p = p.clone();
        p.resolve_paths(&ctx.resolve("."));
        track::run(&p, size, rec)
    })
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
        let f5 =
            scene::load::<tracks::experiments::fig5_heterogeneous::Params>(&load("fig5-heterogeneous")).expect("fig5");
        f5.params.validate().expect("valid fig5");
        scene::load::<tracks::experiments::fig6_partitions::Params>(&load("fig6-partitions")).expect("fig6");
        scene::load::<tracks::experiments::fig7_clustering::Params>(&load("fig7-clustering")).expect("fig7");
        scene::load::<tracks::experiments::table55::Params>(&load("table55")).expect("table55");
        scene::load::<tracks::experiments::track::Params>(&load("own-guide")).expect("own-guide");
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
