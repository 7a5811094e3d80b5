//! The objective and the search with a cheap stand-in forward model (spec §11: "unit tests use
//! a cheap mass–spring stand-in"): T17 (determinism), T18 (a failed simulation is a finite
//! penalty, status `SimFailed`, and the optimiser continues), and the hard cases of spec §8
//! "every coarse-grid point fails" (`NoValidStart`) and mismatched footage (typed errors before
//! any evaluation).

use std::sync::atomic::{AtomicUsize, Ordering};

use cloth_fit::angle::AngleOptions;
use cloth_fit::coarse::{coarse_search, CoarseSearch};
use cloth_fit::error::SimError;
use cloth_fit::fit::{fit, DynamicInit, FitOptions, TrialPolicy};
use cloth_fit::forward::{ForwardModel, SimOptions, SimTrajectory};
use cloth_fit::objective::{EvalSetup, EvalStatus, Objective, Target};
use cloth_fit::params::{FabricParams, ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, static_trial, FabricPreset};
use cloth_fit::rig::Rig;
use cloth_fit::setup::Experiment;
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};
use cloth_fit::FitError;
use geom_core::math::Pt3;

/// A hanging sheet whose tilt and sag follow bend and stretch analytically; "diverges" when
/// stretch exceeds `fail_above`.
struct Stub {
    fail_above: f64,
    calls: AtomicUsize,
}

impl ForwardModel for Stub {
    fn simulate(
        &self,
        p: &FabricParams,
        e: &Experiment,
        _rig: &Rig,
        o: &SimOptions,
    ) -> Result<SimTrajectory, SimError> {
        self.calls.fetch_add(1, Ordering::Relaxed);
        if p.stretch > self.fail_above {
            return Err(SimError::Diverged { t: 0.5, reason: "stub divergence".into() });
        }
        let n = o.res;
        let tilt = 0.3 * (p.bend / 5e-5).ln().tanh();
        let sag = 0.02 * (1.0 + (p.stretch / 1000.0).ln().tanh());
        let mut q = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let x = -0.2 + 0.4 * u;
                let z = -0.45 * (1.0 - v) - sag * (std::f64::consts::PI * u).sin();
                q.push(Pt3::new(x, tilt * z + 0.05 * (6.0 * u).sin() * (1.0 - v), z));
            }
        }
        Ok(SimTrajectory {
            frames: vec![q; e.frames],
            times: (0..e.frames).map(|k| k as f64 / 30.0).collect(),
            settled: true,
            settle_s: 0.0,
            steps: 0,
        })
    }
    fn faces(&self, o: &SimOptions) -> Vec<[u32; 3]> {
        cloth_fit::forward::swatch_mesh(o.res, 1.0, 1.0).faces
    }
}

fn setup() -> EvalSetup {
    EvalSetup {
        rig: rig_spec(96, 72).build().unwrap().rig,
        model: cloth_fit::forward::SimOptions { res: 6, ..fit_model() },
        render: Default::default(),
        angle: AngleOptions::default(),
        metric: Default::default(),
    }
}

fn target(stub: &Stub, s: &EvalSetup, truth: FabricParams) -> Target {
    let src = SyntheticSource::new(Condition::Matched, truth, s, Default::default());
    synthesize(stub, &static_trial(FabricPreset::Linen, 0, 2), &s.rig, &src, &s.angle).unwrap().target
}

#[test]
fn t17_t18_penalty_determinism_and_the_search_continues() {
    let stub = Stub { fail_above: 3000.0, calls: AtomicUsize::new(0) };
    let s = setup();
    let truth = FabricPreset::Linen.params();
    let t = [target(&stub, &s, truth)];
    let space = ParamSpace::new(default_ranges(), vec![ParamId::Stretch, ParamId::Bend], truth).unwrap();
    let obj = Objective::new(&t, &stub, &space, &s).unwrap();
    // T17: the same x twice → bit-identical E (second one cached), and a fresh objective agrees.
    let x = space.to_unit(&truth.with(ParamId::Bend, 7e-5));
    let (a, b) = (obj.eval(&x), obj.eval(&x));
    assert_eq!(a.error.to_bits(), b.error.to_bits());
    assert!(b.cached && !a.cached);
    let obj2 = Objective::new(&t, &stub, &space, &s).unwrap();
    assert_eq!(obj2.eval(&x).error.to_bits(), a.error.to_bits());
    // T18: a failing point gets a finite penalty 2·max(E seen) and status SimFailed.
    let bad = obj.eval(&space.to_unit(&truth.with(ParamId::Stretch, 4900.0)));
    assert!(matches!(bad.status, EvalStatus::SimFailed(_)));
    assert!(bad.error.is_finite() && bad.error == 2.0 * a.error, "{} vs {}", bad.error, a.error);
    assert_eq!(obj.failures(), 1);
    // The search continues through failures: a fit whose grid straddles the failure threshold
    // (the 3-value stretch grid sits at the cell centres 28, 224 and 1774 N/m; this stub fails
    // above 1000 N/m, so the top row fails).
    let stub = Stub { fail_above: 1000.0, calls: AtomicUsize::new(0) };
    let opts = FitOptions {
        coarse: CoarseSearch::Grid { values_per_param: 3, params: vec![ParamId::Stretch, ParamId::Bend] },
        dynamic_init: DynamicInit::Fixed(0.5),
        anneal: cloth_fit::anneal::AnnealOptions { max_evals: 30, ..Default::default() },
        trials: TrialPolicy::PerTrialThenSelect,
        variability: None,
    };
    let r = fit(&t, &stub, &space, &s, &opts, &mut |_, _| {}).unwrap();
    assert!(r.failures > 0, "the grid's high-stretch row fails");
    assert!(r.error.is_finite());
    assert!(r.trials[0].anneal.evals >= 30);
}

#[test]
fn every_failing_grid_point_is_no_valid_start() {
    let ok = Stub { fail_above: f64::INFINITY, calls: AtomicUsize::new(0) };
    let s = setup();
    let truth = FabricPreset::Linen.params();
    let t = [target(&ok, &s, truth)];
    let space = ParamSpace::new(default_ranges(), vec![ParamId::Stretch, ParamId::Bend], truth).unwrap();
    let failing = Stub { fail_above: 0.0, calls: AtomicUsize::new(0) };
    let obj = Objective::new(&t, &failing, &space, &s).unwrap();
    let c = CoarseSearch::Grid { values_per_param: 2, params: vec![ParamId::Stretch, ParamId::Bend] };
    match coarse_search(&obj, &c, &[0.5, 0.5]) {
        Err(FitError::NoValidStart { count, reasons, .. }) => {
            assert_eq!(count, 4);
            assert!(reasons.iter().all(|r| r.contains("stub divergence")));
        }
        other => panic!("expected NoValidStart, got {other:?}"),
    }
}

#[test]
fn mismatched_footage_is_an_error_before_any_evaluation() {
    let stub = Stub { fail_above: f64::INFINITY, calls: AtomicUsize::new(0) };
    let s = setup();
    let truth = FabricPreset::Linen.params();
    let mut t = target(&stub, &s, truth);
    let space = ParamSpace::new(default_ranges(), vec![ParamId::Bend], truth).unwrap();
    let before = stub.calls.load(Ordering::Relaxed);
    let mut short = t.clone();
    short.frames.pop();
    assert!(matches!(Objective::new(&[short], &stub, &space, &s), Err(FitError::SequenceMismatch { .. })));
    let mut big = setup();
    big.rig = rig_spec(160, 120).build().unwrap().rig;
    assert!(matches!(
        Objective::new(std::slice::from_ref(&t), &stub, &space, &big),
        Err(FitError::ImageSizeMismatch { .. })
    ));
    assert_eq!(stub.calls.load(Ordering::Relaxed), before, "no simulation before the checks");
    t.experiment.frames = 0;
    assert!(Objective::new(&[t], &stub, &space, &s).is_err());
}
