//! The objective E(p) of the search (spec §3.7): simulate every target experiment with the
//! candidate parameters, render it with the rig, compute angle maps, and sum the paper's frame
//! errors (eqs. 5–9) over frames and targets.
//!
//! A failed simulation is not an error here: it gets the finite penalty E_fail = 2·max(E seen
//! so far), status `SimFailed`, and the search continues (spec §3.7, §8). Results are cached by
//! the bit pattern of the parameters, so repeated points cost nothing. Batches of independent
//! points run in parallel with rayon, frames within an evaluation too; every value, penalty and
//! record index is assigned in input order, so results are bitwise identical for any thread
//! count.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::Instant;

use geom_core::math::Pt3;
use rayon::prelude::*;

use crate::angle::{angle_map, AngleFrame, AngleOptions};
use crate::error::{FitError, Result, SimError};
use crate::fold_error::{frame_error, MetricOptions};
use crate::forward::{ForwardModel, SimOptions};
use crate::params::{FabricParams, ParamSpace};
use crate::render::{render_intensity, RenderOptions};
use crate::rig::Rig;
use crate::setup::Experiment;

/// Preprocessed footage of one experiment (spec §2 `Target`).
#[derive(Clone, Debug)]
pub struct Target {
    /// The experiment it shows.
    pub experiment: Experiment,
    /// Its angle frames (computed once, the paper "preprocess[es] the input video").
    pub frames: Vec<AngleFrame>,
}

/// How candidates are simulated, rendered and compared (the fit side of a scene).
#[derive(Clone, Debug)]
pub struct EvalSetup {
    /// Camera, projector, fps, gravity.
    pub rig: Rig,
    /// The fitting model.
    pub model: SimOptions,
    /// Rendering of simulated frames.
    pub render: RenderOptions,
    /// Angle maps.
    pub angle: AngleOptions,
    /// Frame error.
    pub metric: MetricOptions,
}

/// Whether an evaluation simulated.
#[derive(Clone, Debug, PartialEq)]
pub enum EvalStatus {
    /// Simulated, rendered and compared.
    Ok,
    /// The forward simulation failed (reason); the error is the penalty.
    SimFailed(String),
}

/// One evaluation (spec §3.8 "History").
#[derive(Clone, Debug, PartialEq)]
pub struct EvalRecord {
    /// Call order (0-based) over the objective's lifetime.
    pub index: usize,
    /// Unit-cube point (empty for direct parameter evaluations).
    pub x: Vec<f64>,
    /// The parameters.
    pub params: FabricParams,
    /// E (eq. 9 summed over targets), or the failure penalty.
    pub error: f64,
    /// Σ E_fold.
    pub fold: f64,
    /// Σ E_silh.
    pub silh: f64,
    /// E per target.
    pub per_target: Vec<f64>,
    /// Ok or SimFailed.
    pub status: EvalStatus,
    /// True when the value came from the cache.
    pub cached: bool,
    /// Wall time of the evaluation (s; 0 when cached).
    pub wall_s: f64,
    /// Time in the simulation (s).
    pub sim_s: f64,
    /// Time rendering (summed over frames, s).
    pub render_s: f64,
    /// Time computing angle maps (summed over frames, s).
    pub filter_s: f64,
    /// Time in the frame errors (summed over frames, s).
    pub metric_s: f64,
    /// Time since the objective was created when this record was logged (s): the anytime
    /// curve's clock.
    pub t_s: f64,
}

/// What one simulation + comparison produced.
#[derive(Clone, Debug)]
enum Outcome {
    Ok { error: f64, fold: f64, silh: f64, per_target: Vec<f64>, t: [f64; 5] },
    Failed { reason: String, t: [f64; 5] },
}

#[derive(Default)]
struct State {
    cache: HashMap<[u64; 9], Outcome>,
    log: Vec<EvalRecord>,
    max_seen: Option<f64>,
    failures: usize,
}

/// E(p) over a set of targets (spec §2 `Objective`).
pub struct Objective<'a> {
    targets: &'a [Target],
    forward: &'a dyn ForwardModel,
    space: &'a ParamSpace,
    setup: &'a EvalSetup,
    faces: Vec<[u32; 3]>,
    bound: f64,
    state: Mutex<State>,
    created: Instant,
}

fn key(p: &FabricParams) -> [u64; 9] {
    crate::params::ParamId::ALL.map(|id| p.get(id).to_bits())
}

impl<'a> Objective<'a> {
    /// The objective over `targets`. Checks before any evaluation that every target's frame
    /// count matches its experiment (`SequenceMismatch`) and that every frame has the camera's
    /// size (`ImageSizeMismatch`), and validates the settings.
    pub fn new(
        targets: &'a [Target],
        forward: &'a dyn ForwardModel,
        space: &'a ParamSpace,
        setup: &'a EvalSetup,
    ) -> Result<Self> {
        space.validate()?;
        setup.model.validate()?;
        setup.angle.validate()?;
        if targets.is_empty() {
            return Err(FitError::BadParameter("objective without targets".into()));
        }
        let (w, h) = (setup.rig.camera.width, setup.rig.camera.height);
        let mut bound = 0.0;
        for (ti, t) in targets.iter().enumerate() {
            t.experiment.validate()?;
            if t.frames.len() != t.experiment.frames {
                return Err(FitError::SequenceMismatch {
                    what: format!("target {ti}: footage frames vs experiment frames"),
                    expected: t.experiment.frames,
                    got: t.frames.len(),
                });
            }
            for (k, f) in t.frames.iter().enumerate() {
                if (f.theta.width, f.theta.height) != (w, h) {
                    return Err(FitError::ImageSizeMismatch {
                        what: format!("target {ti} frame {k}"),
                        expected: (w, h),
                        got: (f.theta.width, f.theta.height),
                    });
                }
            }
            bound += t.frames.len() as f64
                * (w as f64 * h as f64)
                * (std::f64::consts::FRAC_PI_2.powi(2) + setup.metric.alpha);
        }
        Ok(Self {
            targets,
            forward,
            space,
            setup,
            faces: forward.faces(&setup.model),
            bound,
            state: Mutex::new(State::default()),
            created: Instant::now(),
        })
    }

    /// The search space.
    pub fn space(&self) -> &ParamSpace {
        self.space
    }

    /// The targets.
    pub fn targets(&self) -> &[Target] {
        self.targets
    }

    /// The evaluation settings.
    pub fn setup(&self) -> &EvalSetup {
        self.setup
    }

    /// E at one unit-cube point.
    pub fn eval(&self, x: &[f64]) -> EvalRecord {
        self.eval_batch(&[x.to_vec()]).remove(0)
    }

    /// E at several unit-cube points, evaluated in parallel; records in input order.
    pub fn eval_batch(&self, xs: &[Vec<f64>]) -> Vec<EvalRecord> {
        let pts: Vec<(Vec<f64>, FabricParams)> = xs.iter().map(|x| (x.clone(), self.space.from_unit(x))).collect();
        self.run(pts)
    }

    /// E at physical parameters (e.g. the truth), bypassing the unit cube (logged, cached).
    pub fn eval_params(&self, ps: &[FabricParams]) -> Vec<EvalRecord> {
        self.run(ps.iter().map(|p| (Vec::new(), *p)).collect())
    }

    /// Every evaluation so far, in call order.
    pub fn history(&self) -> Vec<EvalRecord> {
        self.state.lock().expect("objective state poisoned").log.clone()
    }

    /// Number of evaluations whose simulation failed (cached repeats not counted).
    pub fn failures(&self) -> usize {
        self.state.lock().expect("objective state poisoned").failures
    }

    /// The finite upper bound of E used as the penalty before any success: every pixel of
    /// every frame at the largest angle difference and silhouette mismatch.
    pub fn error_bound(&self) -> f64 {
        self.bound
    }

    fn run(&self, pts: Vec<(Vec<f64>, FabricParams)>) -> Vec<EvalRecord> {
        let keys: Vec<[u64; 9]> = pts.iter().map(|(_, p)| key(p)).collect();
        // Unique uncached points, first occurrence order.
        let todo: Vec<usize> = {
            let st = self.state.lock().expect("objective state poisoned");
            let mut seen = std::collections::HashSet::new();
            (0..pts.len()).filter(|&i| !st.cache.contains_key(&keys[i]) && seen.insert(keys[i])).collect()
        };
        let fresh: Vec<(usize, Outcome, f64)> = todo
            .par_iter()
            .map(|&i| {
                let t0 = Instant::now();
                let o = self.compute(&pts[i].1);
                (i, o, t0.elapsed().as_secs_f64())
            })
            .collect();
        let mut st = self.state.lock().expect("objective state poisoned");
        let mut walls = HashMap::new();
        for (i, o, wall) in fresh {
            if let Outcome::Ok { error, .. } = &o {
                st.max_seen = Some(st.max_seen.map_or(*error, |m: f64| m.max(*error)));
            } else {
                st.failures += 1;
            }
            walls.insert(i, wall);
            st.cache.insert(keys[i], o);
        }
        let penalty = st.max_seen.map_or(self.bound, |m| 2.0 * m);
        let t_s = self.created.elapsed().as_secs_f64();
        let mut out = Vec::with_capacity(pts.len());
        for (i, (x, p)) in pts.into_iter().enumerate() {
            let o = st.cache[&keys[i]].clone();
            let cached = !walls.contains_key(&i);
            let wall_s = walls.get(&i).copied().unwrap_or(0.0);
            let index = st.log.len();
            let rec = match o {
                Outcome::Ok { error, fold, silh, per_target, t } => EvalRecord {
                    index,
                    x,
                    params: p,
                    error,
                    fold,
                    silh,
                    per_target,
                    status: EvalStatus::Ok,
                    cached,
                    wall_s,
                    sim_s: t[0],
                    render_s: t[1],
                    filter_s: t[2],
                    metric_s: t[3],
                    t_s,
                },
                Outcome::Failed { reason, t } => EvalRecord {
                    index,
                    x,
                    params: p,
                    error: penalty,
                    fold: f64::NAN,
                    silh: f64::NAN,
                    per_target: vec![penalty / self.targets.len() as f64; self.targets.len()],
                    status: EvalStatus::SimFailed(reason),
                    cached,
                    wall_s,
                    sim_s: t[0],
                    render_s: 0.0,
                    filter_s: 0.0,
                    metric_s: 0.0,
                    t_s,
                },
            };
            st.log.push(rec.clone());
            out.push(rec);
        }
        out
    }

    fn compute(&self, p: &FabricParams) -> Outcome {
        let mut t = [0.0; 5];
        let mut per_target = Vec::with_capacity(self.targets.len());
        let (mut fold, mut silh) = (0.0, 0.0);
        for target in self.targets {
            let ts = Instant::now();
            let sim = self.forward.simulate(p, &target.experiment, &self.setup.rig, &self.setup.model);
            t[0] += ts.elapsed().as_secs_f64();
            let sim = match sim {
                Ok(s) => s,
                Err(e) => return Outcome::Failed { reason: e.to_string(), t },
            };
            let frames = match compare_frames(&sim.frames, &self.faces, target, self.setup) {
                Ok(f) => f,
                Err(e) => return Outcome::Failed { reason: e.to_string(), t },
            };
            let mut e_t = 0.0;
            for f in &frames {
                e_t += f.0.total;
                fold += f.0.fold;
                silh += f.0.silh;
                t[1] += f.1[0];
                t[2] += f.1[1];
                t[3] += f.1[2];
            }
            per_target.push(e_t);
        }
        Outcome::Ok { error: per_target.iter().sum(), fold, silh, per_target, t }
    }
}

/// Renders, filters and compares simulated frames against a target, in parallel over frames;
/// per frame the error and the (render, filter, metric) times. A frame whose positions are
/// bitwise those of the previous frame (the static test's settled frames) reuses that frame's
/// angle map: the render and filter run once per distinct frame, and the times are counted where
/// they were spent.
pub fn compare_frames(
    frames: &[Vec<Pt3>],
    faces: &[[u32; 3]],
    target: &Target,
    setup: &EvalSetup,
) -> Result<Vec<(crate::fold_error::FrameError, [f64; 3])>, SimError> {
    if frames.len() != target.frames.len() {
        return Err(SimError::Setup(format!(
            "simulation produced {} frames for {} target frames",
            frames.len(),
            target.frames.len()
        )));
    }
    // Index of the angle map each frame uses (the first of a run of identical frames).
    let mut source = Vec::with_capacity(frames.len());
    for (k, q) in frames.iter().enumerate() {
        let s = match source.last() {
            Some(&j) if frames[j] == *q => j,
            _ => k,
        };
        source.push(s);
    }
    let maps: Vec<Option<(AngleFrame, [f64; 2])>> = frames
        .par_iter()
        .enumerate()
        .map(|(k, q)| {
            (source[k] == k).then(|| {
                let t0 = Instant::now();
                let (img, sil) = render_intensity(q, faces, &setup.rig, &setup.render);
                let t1 = Instant::now();
                let sim = angle_map(&img, &sil, &setup.angle);
                (sim, [(t1 - t0).as_secs_f64(), t1.elapsed().as_secs_f64()])
            })
        })
        .collect();
    target
        .frames
        .par_iter()
        .enumerate()
        .map(|(k, real)| {
            let (sim, [tr, tf]) = maps[source[k]].as_ref().expect("every source frame was rendered");
            let (tr, tf) = if source[k] == k { (*tr, *tf) } else { (0.0, 0.0) };
            let t2 = Instant::now();
            let e = frame_error(real, sim, &setup.metric).map_err(|e| SimError::Setup(e.to_string()))?;
            Ok((e, [tr, tf, t2.elapsed().as_secs_f64()]))
        })
        .collect()
}
