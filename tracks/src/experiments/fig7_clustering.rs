//! `tracks/fig7-clustering` (Bergou et al. 2007 §4.1, Fig. 7): animation-aware variational
//! clustering (μ = 0.98, F = 32 sampled frames) against static L²,¹ VSA of the Xavier animation,
//! r = 200 regions: which regions move rigidly, whether seams fall on joints, how even the region
//! areas are.
//!
//! Keys: `non_rigidity_{animated,static}` (mean over regions of the max over the evaluated frames
//! of the rigid-fit RMS residual / region diameter), `seam_joint_alignment_*`, `area_cv_*`,
//! `iterations_*`, `clustering_s_*`, `mean_position_term`, `mean_normal_term`,
//! `regions_animated`; files `regions_animated.ply`, `regions_static.ply` (vertex colours).
//! The spec's three expectations (§6.8) as claims ([`Claims`]): `animated_less_non_rigid`,
//! `animated_seams_on_joints` (higher seam–joint alignment), `animated_area_cv_below_0_5`;
//! `claims_met` / `claims_total`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/fig7-clustering.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::fig7_clustering::Params }
//! let f: File = ron::from_str(&text).unwrap();
//! let r = tracks::experiments::fig7_clustering::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("non_rigidity_animated"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::io::ply::{to_bytes, Encoding, PlyData};
use geom_core::io::MeshOut;
use geom_core::mesh::TriMesh;
use geom_core::record::Recorder;
use serde::Deserialize;

use super::claims::Claims;
use crate::cluster::{cluster, ClusterMetric, ClusterOptions};
use crate::error::Result;
use crate::metrics::{non_rigidity, region_area_cv, seam_joint_alignment};
use crate::presets::XAVIER_DURATION;
use crate::procedural::{xavier, xavier_guide};

/// Parameters of `tracks/fig7-clustering` (the RON `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Regions r.
    pub regions: usize,
    /// Weight μ of the position term of the animation-aware metric.
    pub mu: f64,
    /// Sampled frames F of the supremum over time.
    pub frames: usize,
    /// Seed of the initial regions and the sampled frames.
    pub seed: u64,
    /// Non-rigidity is evaluated every n-th frame of the 30 fps clip.
    pub eval_every: BySize<usize>,
}

/// Vertex labels as a PLY with per-vertex colours (a hash of the label).
pub fn regions_ply(m: &TriMesh, labels: &[u32]) -> Result<Vec<u8>> {
    let color = |l: u32| -> [u8; 3] {
        let h = (l as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        [(h >> 16) as u8, (h >> 32) as u8, (h >> 48) as u8]
    };
    let rgb: Vec<[u8; 3]> = labels.iter().map(|&l| color(l)).collect();
    Ok(to_bytes(&MeshOut::tri(&m.positions, &m.faces), &[("color", PlyData::Rgb(&rgb))], Encoding::Ascii)?)
}

/// Clusters the Xavier animation both ways and compares them.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let x = xavier()?;
    let guide = xavier_guide(&x, XAVIER_DURATION)?;
    let base =
        ClusterOptions { regions: p.regions, mu: p.mu, frames: p.frames, seed: p.seed, ..ClusterOptions::default() };
    let anim = cluster(&guide, &base, None)?;
    let stat = cluster(&guide, &ClusterOptions { metric: ClusterMetric::StaticVsaL21, ..base.clone() }, None)?;
    let every = p.eval_every.get(size).max(1);
    let times: Vec<f64> = (0..=300).step_by(every).map(|f| f as f64 / 30.0).collect();
    let maxw = x.max_skin_weight();
    rec.file("regions_animated.ply", &regions_ply(&x.mesh, &anim.vertex_labels)?)?;
    rec.file("regions_static.ply", &regions_ply(&x.mesh, &stat.vertex_labels)?)?;
    let mut r = Report::default();
    let nr = (
        non_rigidity(&guide, &anim.vertex_labels, anim.regions, &times),
        non_rigidity(&guide, &stat.vertex_labels, stat.regions, &times),
    );
    let sa = (
        seam_joint_alignment(&x.mesh, &anim.vertex_labels, &maxw),
        seam_joint_alignment(&x.mesh, &stat.vertex_labels, &maxw),
    );
    let cv = (
        region_area_cv(&x.mesh, &anim.tri_labels, anim.regions_tri),
        region_area_cv(&x.mesh, &stat.tri_labels, stat.regions_tri),
    );
    r.num("non_rigidity_animated", nr.0);
    r.num("non_rigidity_static", nr.1);
    r.num("seam_joint_alignment_animated", sa.0);
    r.num("seam_joint_alignment_static", sa.1);
    r.num("area_cv_animated", cv.0);
    r.num("area_cv_static", cv.1);
    r.count("iterations_animated", anim.iterations as u64);
    r.count("iterations_static", stat.iterations as u64);
    r.timing("clustering_s_animated", anim.time_s);
    r.timing("clustering_s_static", stat.time_s);
    r.num("mean_position_term", anim.mean_terms.0);
    r.num("mean_normal_term", anim.mean_terms.1);
    r.count("regions_animated", anim.regions as u64);
    r.text("mode", size.name());
    let src = "Bergou et al. 2007 §4.1, Fig. 7 (spec §6.8): animation-aware regions move rigidly, \
               their seams fall on joints, their areas are even";
    let mut c = Claims::default();
    c.claim(&mut r, "animated_less_non_rigid", nr.0 < nr.1, src);
    c.claim(&mut r, "animated_seams_on_joints", sa.0 > sa.1, src);
    c.claim_target(&mut r, "animated_area_cv_below_0_5", cv.0, Target::Below(0.5), src);
    c.finish(&mut r);
    Ok(r)
}
