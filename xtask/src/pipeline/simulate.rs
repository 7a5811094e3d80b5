//! The simulation stage of `pipeline/character`: the garment on the skinned body (a
//! `shells::DeformingMesh` collider, IPC contact), untracked and tracked (`tracks::Tracker`,
//! the guide being the garment skinned coarsely to the body), with the garment figures of
//! issue 23 measured on every written frame.

use std::sync::Arc;
use std::time::Instant;

use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;
use geom_core::query::{count_self_intersections, tri_tri_intersect};
use geom_core::record::{MeshFrame, Recorder};
use geom_core::spatial::{Aabb, AabbTree};
use shells::metrics::Sanity;
use shells::VertexConstraint;
use shells::{CollisionSettings, DeformingMesh, Effects, IntegratorSettings, Material, ShellSceneDesc, ShellSim};
use tracks::metrics::LowPass;
use tracks::{
    build_test_functions, ClusterOptions, GuideAnimation, TestFunctionSpec, TimeInterp, TrackOptions, Tracker,
};

use crate::error::Result;

/// Everything both runs share.
pub struct SimSetup {
    /// The garment's rest mesh (m).
    pub garment: TriMesh,
    /// Vertices that follow the body (kinematic, on the guide's path).
    pub attached: Vec<u32>,
    /// The garment skinned coarsely to the body, per pose frame (m).
    pub guide: Arc<Vec<Vec<Pt3>>>,
    /// The body as a collider.
    pub body: DeformingMesh,
    /// Pose frames per second (of `guide` and `body`).
    pub fps: f64,
    /// Simulation steps per pose frame.
    pub substeps: u32,
    /// Write a frame every `every` pose frames.
    pub every: usize,
    /// IPC contact distance d̂ (m).
    pub thickness: f64,
    /// Tracking regions.
    pub regions: usize,
}

/// What one run measured.
#[derive(Clone, Debug, Default)]
pub struct SimOut {
    /// Deepest garment vertex inside the body over the written frames (m).
    pub max_body_penetration_m: f64,
    /// Most intersecting triangle pairs (garment self + garment–body) in a written frame.
    pub max_intersections: u64,
    /// Largest ℓ/ℓ̄ − 1 over edges and steps.
    pub max_edge_strain: f64,
    /// Steps that failed with non-finite values.
    pub nan_steps: u64,
    /// Coarse-scale deviation from the guide at the last written frame and its mean.
    pub coarse_deviation: f64,
    /// Mean over the written frames.
    pub coarse_deviation_mean: f64,
    /// Steps taken.
    pub steps: u64,
    /// Wall time (s).
    pub seconds: f64,
    /// The error that stopped the run early (frames written so far are kept).
    pub failure: Option<String>,
}

fn lerp_frames(frames: &[Vec<Pt3>], fps: f64, t: f64, i: usize) -> Pt3 {
    let s = (t * fps).clamp(0.0, (frames.len() - 1) as f64);
    let k = (s.floor() as usize).min(frames.len() - 1);
    let w = s - k as f64;
    if k + 1 >= frames.len() {
        return frames[k][i];
    }
    frames[k][i] + w * (frames[k + 1][i] - frames[k][i])
}

fn desc(s: &SimSetup) -> ShellSceneDesc {
    let guide = s.guide.clone();
    let fps = s.fps;
    ShellSceneDesc {
        rest: s.garment.positions.clone(),
        faces: s.garment.faces.clone(),
        uv: None,
        initial: None,
        initial_velocity: None,
        material: Material::cotton(),
        effects: Effects {
            gravity: Some(geom_core::math::Vec3::new(0.0, -9.81, 0.0)),
            self_collision: true,
            collision: Some(CollisionSettings { thickness: s.thickness, ..Default::default() }),
            ..Default::default()
        },
        constraints: vec![VertexConstraint::Kinematic(
            s.attached.clone(),
            Box::new(move |t: f64, i: u32| lerp_frames(&guide, fps, t, i as usize)),
        )],
        integrator: IntegratorSettings::default(),
        t0: 0.0,
    }
}

/// Garment–body crossings: triangle pairs that intersect.
fn body_crossings(q: &[Pt3], faces: &[[u32; 3]], body: &[Pt3], body_faces: &[[u32; 3]]) -> u64 {
    let boxes: Vec<Aabb> = body_faces.iter().map(|t| Aabb::from_points(&t.map(|i| body[i as usize]))).collect();
    let tree = AabbTree::build(&boxes);
    let mut n = 0u64;
    for f in faces {
        let a = f.map(|i| q[i as usize]);
        tree.query(&Aabb::from_points(&a), |b| {
            n += tri_tri_intersect(&a, &body_faces[b as usize].map(|i| body[i as usize])) as u64;
        });
    }
    n
}

/// One run over `frames` pose frames; frames are recorded as `name` (garment) and
/// `name_body` (garment and body in one mesh).
pub fn run(s: &SimSetup, tracked: bool, frames: usize, name: &str, rec: &mut dyn Recorder) -> Result<SimOut> {
    let t_start = Instant::now();
    let mut sim = ShellSim::new(desc(s))?;
    sim.add_deforming_obstacle(s.body.clone())?;
    let (mut tracker, mut un) = if tracked {
        let g = GuideAnimation::from_frames(s.garment.clone(), s.guide.to_vec(), s.fps, TimeInterp::Linear)?;
        let spec = TestFunctionSpec::Clustered(ClusterOptions { regions: s.regions, ..Default::default() });
        let tf = build_test_functions(&spec, &g, &s.garment, None)?;
        (Some(Tracker::new(sim, g, tf, None, TrackOptions::default())?), None)
    } else {
        (None, Some(sim))
    };
    let lp = LowPass::new(&s.garment, LowPass::tau_for(&s.garment, s.regions))?;
    let scale = s.garment.aabb().size().norm();
    let faces = s.garment.faces.clone();
    let body_faces = s.body.tris().to_vec();
    let nb = s.garment.n_vertices() as u32;
    let both_faces: Vec<[u32; 3]> = faces.iter().copied().chain(body_faces.iter().map(|t| t.map(|i| i + nb))).collect();
    let mut san = Sanity::new(&s.garment.positions, s.garment.topology().edges(), Vec::new(), None);
    let mut out = SimOut::default();
    let mut dcs = Vec::new();
    let h = 1.0 / (s.fps * s.substeps as f64);
    let body_seq = format!("{name}_body");
    for f in 0..frames {
        if f > 0 {
            for _ in 0..s.substeps {
                let r = match (tracker.as_mut(), un.as_mut()) {
                    (Some(tr), _) => track_retry(tr, h),
                    (None, Some(u)) => step_retry(u, h),
                    (None, None) => unreachable!("one of the runs exists"),
                };
                if let Err(e) = r {
                    out.nan_steps += e.contains("non-finite") as u64;
                    out.failure = Some(format!("{name}: step {} (t = {:.4} s): {e}", out.steps, f as f64 / s.fps));
                    break;
                }
                out.steps += 1;
                let st = state(&tracker, &un);
                san.observe(&st.q, st.t, None);
            }
            if out.failure.is_some() {
                break;
            }
        }
        if f % s.every != 0 {
            continue;
        }
        let st = state(&tracker, &un);
        let t = f as f64 / s.fps;
        let q = &st.q;
        let body = s.body.positions(t);
        out.max_body_penetration_m =
            geom_core::stats::nan_max(out.max_body_penetration_m, s.body.max_penetration(t, q)?);
        let isect = count_self_intersections(&faces, q) as u64 + body_crossings(q, &faces, &body, &body_faces);
        out.max_intersections = out.max_intersections.max(isect);
        let d: Vec<_> = q.iter().enumerate().map(|(i, p)| p - s.guide[f.min(s.guide.len() - 1)][i]).collect();
        dcs.push(lp.coarse_deviation(&d, scale)?);
        let both: Vec<Pt3> = q.iter().chain(&body).copied().collect();
        let fi = f / s.every;
        rec.frame(&MeshFrame { sequence: name, index: fi, time: t, positions: q, faces: &faces, attributes: &[] })?;
        rec.frame(&MeshFrame {
            sequence: &body_seq,
            index: fi,
            time: t,
            positions: &both,
            faces: &both_faces,
            attributes: &[],
        })?;
        rec.progress(f as u64, frames as u64);
    }
    out.max_edge_strain = san.max_edge_strain;
    out.coarse_deviation = dcs.last().copied().unwrap_or(f64::NAN);
    out.coarse_deviation_mean = geom_core::stats::mean(&dcs);
    out.seconds = t_start.elapsed().as_secs_f64();
    Ok(out)
}

fn state<'a>(tr: &'a Option<Tracker>, un: &'a Option<ShellSim>) -> &'a shells::ShellState {
    match (tr, un) {
        (Some(t), _) => t.sim.state(),
        (None, Some(u)) => u.state(),
        (None, None) => unreachable!("one of the runs exists"),
    }
}

/// A step, retried as 2, 4, 8 and then 16 substeps (from the saved start state) when a moving body
/// would enter the cloth within it.
fn step_retry(sim: &mut ShellSim, h: f64) -> std::result::Result<(), String> {
    retry(sim, h, |s, h| s.step(h).map(|_| ()).map_err(|e| e.to_string()))
}

/// [`step_retry`] for the tracked run.
fn track_retry(tr: &mut Tracker, h: f64) -> std::result::Result<(), String> {
    let start = tr.sim.state().clone();
    let mut last = String::new();
    for n in [1u32, 2, 4, 8, 16] {
        if n > 1 {
            tr.sim.set_state(start.clone()).map_err(|e| e.to_string())?;
        }
        match (0..n).try_for_each(|_| tr.step(h / n as f64).map(|_| ())) {
            Ok(()) => return Ok(()),
            Err(e) => last = e.to_string(),
        }
        if !last.contains("shorten the step") {
            break;
        }
    }
    Err(last)
}

fn retry(
    sim: &mut ShellSim,
    h: f64,
    step: impl Fn(&mut ShellSim, f64) -> std::result::Result<(), String>,
) -> std::result::Result<(), String> {
    let start = sim.state().clone();
    let mut last = String::new();
    for n in [1u32, 2, 4, 8, 16] {
        if n > 1 {
            sim.set_state(start.clone()).map_err(|e| e.to_string())?;
        }
        match (0..n).try_for_each(|_| step(sim, h / n as f64)) {
            Ok(()) => return Ok(()),
            Err(e) => last = e,
        }
        if !last.contains("shorten the step") {
            break;
        }
    }
    Err(last)
}
