//! `tracks/track`: a user's own guide, the path the artist of the paper takes (Bergou et al.
//! 2007 §5.1: design a coarse animation, then let a fine simulation follow it). The guide is an
//! OBJ sequence (a folder of `NNNN.obj` frames and their frame rate) or a `.usda` file written by
//! this toolkit; the tracked mesh is the guide subdivided `levels` times, or an OBJ whose
//! connectivity is that of the guide subdivided `levels` times (its rest positions may differ:
//! smoothed, crinkled); the test functions are the subdivision basis, an animation-aware
//! clustering (identical meshes) or boxes painted in rest space; material and effects are the
//! `shells` ones. The fine cloth starts on the prolonged first guide frame with the prolonged
//! guide velocity (Catmull–Rom at t = 0) and runs tracked beside
//! its untracked twin (the common keys of [`PairOut::report`](super::protocol::PairOut::report)
//! and issue 20's sanity checks).
//!
//! Paths are relative to the working directory unless [`Params::resolve_paths`] rebases them
//! (the command line resolves them against the scene file's folder).
//!
//! Keys besides the common ones: `guide_vertices`, `guide_frames`, `guide_fps`,
//! `guide_duration_s`, `deviation_ratio_untracked_over_tracked` (mean D_c over frames),
//! `n_vertices`, `duration_s`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! let text = std::fs::read_to_string("scenes/tracks/own-guide.ron").unwrap();
//! #[derive(serde::Deserialize)]
//! struct File { params: tracks::experiments::track::Params }
//! let mut p = ron::from_str::<File>(&text).unwrap().params;
//! p.resolve_paths(std::path::Path::new("scenes/tracks"));
//! let r = tracks::experiments::track::run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("deviation_ratio_untracked_over_tracked"));
//! ```

use std::path::{Path, PathBuf};

use geom_core::experiment::{BySize, Report, Size};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{subdivide_linear, TriMesh};
use geom_core::record::Recorder;
use serde::Deserialize;
use shells::{CollisionSettings, ContactMethod, Effects, Material, Obstacle, ShellSceneDesc, Wind};

use super::protocol::{bad, check_residual, check_sanity, run_standard, PairParams};
use crate::cluster::ClusterOptions;
use crate::error::{Result, TrackError};
use crate::guide::GuideAnimation;
use crate::metrics::guide_on_tracked;
use crate::presets::{ground_at, ground_below, shell_desc, Setup};
use crate::testfn::{build_test_functions, RegionSel, TestFunctionSpec};

const SCENE: &str = "tracks/track";

/// Where the guide comes from.
#[derive(Clone, Debug, Deserialize)]
pub enum GuideSource {
    /// A folder of `NNNN.obj` frames (the first is the rest mesh) played at `fps`.
    ObjSequence {
        /// The folder.
        dir: PathBuf,
        /// Frames per second.
        fps: f64,
    },
    /// A time-sampled `.usda` written by this toolkit (`geom_core::io::usd`).
    Usd {
        /// The file.
        path: PathBuf,
    },
}

/// The tracked (fine) mesh.
#[derive(Clone, Debug, Deserialize)]
pub enum TrackedMesh {
    /// The guide's rest mesh subdivided `levels` times (0 = the guide mesh itself).
    Subdivide {
        /// Levels of linear subdivision.
        levels: u32,
    },
    /// An OBJ with the connectivity of the guide subdivided `levels` times; its positions are
    /// the fine rest shape.
    Obj {
        /// The file.
        path: PathBuf,
        /// Levels of linear subdivision its connectivity matches.
        levels: u32,
    },
}

/// A rest-space box (min corner, max corner) (m).
pub type RestBox = ((f64, f64, f64), (f64, f64, f64));

/// The test-function design (spec §3.3).
#[derive(Clone, Debug, Deserialize)]
pub enum Design {
    /// The guide's hat functions prolonged to the fine mesh (S̄ = I, S = Pᵀ).
    SubdivisionBasis,
    /// Animation-aware clustering of the guide (needs `levels: 0`: identical meshes).
    Clustered {
        /// Regions r.
        regions: usize,
        /// Seed of the initial regions and the sampled frames.
        seed: u64,
    },
    /// Regions painted as rest-space boxes on the guide, transferred to the fine mesh by P.
    Boxes(Vec<RestBox>),
}

/// Effects of the fine cloth.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackEffects {
    /// Gravity (m/s²).
    #[serde(default)]
    pub gravity: Option<Vec3>,
    /// Wind.
    #[serde(default)]
    pub wind: Option<Wind>,
    /// Rigid obstacles.
    #[serde(default)]
    pub obstacles: Vec<Obstacle>,
    /// A ground plane with this friction, just below the guide's lowest point over all frames
    /// (one contact distance + 1 mm, [`ground_below`]).
    #[serde(default)]
    pub ground_friction: Option<f64>,
    /// Cloth–cloth collisions.
    pub self_collision: BySize<bool>,
}

/// Parameters of `tracks/track` (the RON `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The guide.
    pub guide: GuideSource,
    /// The tracked mesh.
    pub tracked: TrackedMesh,
    /// The test functions.
    pub test_functions: Design,
    /// The fine cloth's material (`shells::Material`).
    pub material: Material,
    /// The fine cloth's effects.
    pub effects: TrackEffects,
    /// Run settings (duration, substeps, solver …; `self_collision` here is ignored in favour of
    /// `effects.self_collision`).
    pub run: PairParams,
}

impl Params {
    /// Rebases the relative paths on `base` (the scene file's folder).
    pub fn resolve_paths(&mut self, base: &Path) {
        let fix = |p: &mut PathBuf| {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        };
        match &mut self.guide {
            GuideSource::ObjSequence { dir, .. } => fix(dir),
            GuideSource::Usd { path } => fix(path),
        }
        if let TrackedMesh::Obj { path, .. } = &mut self.tracked {
            fix(path);
        }
    }
}

/// Loads the guide of `src`.
pub fn load_guide(src: &GuideSource) -> Result<GuideAnimation> {
    match src {
        GuideSource::ObjSequence { dir, fps } => {
            if !dir.is_dir() {
                return Err(bad(SCENE, format!("guide folder {} does not exist", dir.display())));
            }
            GuideAnimation::from_obj_sequence(dir, *fps)
        }
        GuideSource::Usd { path } => crate::usd_guide::guide_from_usda(path),
    }
}

/// The tracked rest mesh and the prolongation (guide → tracked).
fn tracked_mesh(guide: &GuideAnimation, t: &TrackedMesh) -> Result<(TriMesh, geom_core::linalg::Csr)> {
    let levels = match t {
        TrackedMesh::Subdivide { levels } | TrackedMesh::Obj { levels, .. } => *levels,
    };
    if levels > 5 {
        return Err(bad(SCENE, format!("tracked levels must be ≤ 5, got {levels}")));
    }
    let (fine, p) = subdivide_linear(&guide.rest, levels);
    match t {
        TrackedMesh::Subdivide { .. } => Ok((fine, p)),
        TrackedMesh::Obj { path, .. } => {
            let m = geom_core::io::obj::read_tri(path)?;
            if m.faces != fine.faces {
                return Err(bad(
                    SCENE,
                    format!(
                        "{}: {} vertices / {} triangles, not the connectivity of the guide subdivided {levels} times \
                         ({} / {})",
                        path.display(),
                        m.n_vertices(),
                        m.faces.len(),
                        fine.n_vertices(),
                        fine.faces.len()
                    ),
                ));
            }
            Ok((m, p))
        }
    }
}

/// Builds the tracking setup of `p` (guide, fine mesh, test functions, fine shell).
pub fn setup(p: &Params, size: Size) -> Result<Setup> {
    p.run.validate(SCENE)?;
    let guide = load_guide(&p.guide)?;
    let (fine, pm) = tracked_mesh(&guide, &p.tracked)?;
    let spec = match &p.test_functions {
        Design::SubdivisionBasis => TestFunctionSpec::SubdivisionBasis,
        Design::Clustered { regions, seed } => {
            if fine.n_vertices() != guide.n_vertices() {
                return Err(bad(SCENE, "Clustered test functions need identical meshes (levels: 0)".into()));
            }
            TestFunctionSpec::Clustered(ClusterOptions {
                regions: *regions,
                seed: *seed,
                frames: 32.min(guide.frames.len()),
                ..ClusterOptions::default()
            })
        }
        Design::Boxes(b) => TestFunctionSpec::PaintedOnGuide {
            guide: b.iter().map(|&(min, max)| RegionSel::RestBox { min, max }).collect(),
        },
    };
    let tf = build_test_functions(&spec, &guide, &fine, Some(&pm))?;
    p.material.validate()?;
    let mut g0 = vec![Pt3::origin(); guide.n_vertices()];
    guide.sample(0.0, &mut g0);
    let initial = guide_on_tracked(Some(&pm), &g0);
    // The guide's velocity at t = 0 (Catmull–Rom), prolonged: both twins start moving with it.
    let mut gv = vec![Vec3::zeros(); guide.n_vertices()];
    guide.sample_velocity(0.0, &mut gv);
    let gv_pts: Vec<Pt3> = gv.iter().map(|v| Pt3::from(*v)).collect();
    let v0: Vec<Vec3> = guide_on_tracked(Some(&pm), &gv_pts).iter().map(|p| p.coords).collect();
    let e = &p.effects;
    let sc = e.self_collision.get(size);
    let mut obstacles = e.obstacles.clone();
    if let Some(mu) = e.ground_friction {
        if !(mu >= 0.0 && mu.is_finite()) {
            return Err(bad(SCENE, format!("ground_friction must be ≥ 0, got {mu}")));
        }
        let low = guide.frames.iter().flatten().map(|q| q.y).fold(f64::INFINITY, f64::min);
        obstacles.push(ground_at(mu, low + ground_below(&fine)));
    }
    let any = sc || !obstacles.is_empty();
    let effects = Effects {
        gravity: e.gravity,
        wind: e.wind.clone(),
        obstacles,
        self_collision: sc,
        collision: any.then(|| CollisionSettings { method: p.run.contact, ..CollisionSettings::default() }),
        ..Effects::default()
    };
    effects.validate()?;
    let (f2, mat) = (fine.clone(), p.material.clone());
    let desc = move || ShellSceneDesc {
        initial: Some(initial.clone()),
        initial_velocity: Some(v0.clone()),
        ..shell_desc(&f2, mat.clone(), effects.clone())
    };
    Ok(Setup {
        fps: guide.fps,
        guide,
        prolongation: Some(pm),
        tracked_rest: fine,
        desc: Box::new(desc),
        tf,
        substeps: p.run.substeps.get(size),
        rest_events: None,
    })
}

/// Runs the user's guide tracked and untracked.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let s = setup(p, size)?;
    if p.run.contact != ContactMethod::Ipc && p.run.contact != ContactMethod::Bridson {
        return Err(TrackError::BadParameter(format!("{SCENE}: unknown contact model")));
    }
    let (nv, nf, fps, dur) = (s.guide.n_vertices(), s.guide.frames.len(), s.fps, s.guide.duration());
    let (out, mut r) = run_standard(&p.run, size, &s, false, rec)?;
    r.count("guide_vertices", nv as u64);
    r.count("guide_frames", nf as u64);
    r.num("guide_fps", fps);
    r.num("guide_duration_s", dur);
    let mean = geom_core::stats::mean;
    r.num("deviation_ratio_untracked_over_tracked", mean(&out.dc_untracked) / mean(&out.dc_tracked));
    check_residual(&mut r, "max_residual_pre");
    check_sanity(&mut r);
    Ok(r)
}
