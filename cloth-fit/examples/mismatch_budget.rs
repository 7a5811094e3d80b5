//! What the mismatched condition adds to E at the true parameters (waving trial 0, the default
//! scene size: 160 × 120, mesh 8², dt 1/120 s, 20 frames): the truth model alone (res 2×, dt/2,
//! BDF2, supersampling 3), plus image noise, plus the camera error. Diagnoses C3/C5, where
//! E(truth) under mismatch exceeds the fitted E and the cross-comparison's row minima leave the
//! diagonal.
//!
//! `cargo run --release -p cloth-fit --example mismatch_budget`

use cloth_fit::forward::{ShellsForward, SimOptions};
use cloth_fit::noise::NoiseModel;
use cloth_fit::objective::{EvalSetup, Objective};
use cloth_fit::params::{ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, waving_trial, FabricPreset};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let angle = cloth_fit::angle::AngleOptions { grad_threshold: 0.02, ..Default::default() };
    let setup = EvalSetup {
        rig: rig_spec(160, 120).build()?.rig,
        model: SimOptions { res: 8, dt: 1.0 / 120.0, ..fit_model() },
        render: Default::default(),
        angle,
        metric: Default::default(),
    };
    let quiet = NoiseModel {
        sigma: 0.0,
        gain_sigma: 0.0,
        blur_px: 0.0,
        quantize_8bit: false,
        camera_rot_deg: 0.0,
        camera_shift_m: 0.0,
        ..NoiseModel::default()
    };
    let no_camera = NoiseModel { camera_rot_deg: 0.0, camera_shift_m: 0.0, ..NoiseModel::default() };
    for f in FabricPreset::ALL {
        let truth = f.params();
        let e = waving_trial(f, 0, 20);
        let full = SyntheticSource::new(Condition::Mismatched, truth, &setup, NoiseModel::default());
        let cases = [
            ("truth model only", SyntheticSource { noise: Some(quiet), ..full.clone() }),
            ("+ image noise", SyntheticSource { noise: Some(no_camera), ..full.clone() }),
            ("+ camera error (full)", full.clone()),
        ];
        for (name, src) in cases {
            let t = [synthesize(&ShellsForward, &e, &setup.rig, &src, &setup.angle)?.target];
            let sp = ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth)?;
            let obj = Objective::new(&t, &ShellsForward, &sp, &setup)?;
            let r = &obj.eval_params(&[truth])[0];
            println!(
                "{:6} {name:22}: E(truth) = {:8.1}  fold {:8.1}  silh {:6.0} px",
                f.name(),
                r.error,
                r.fold,
                r.silh
            );
        }
    }
    Ok(())
}
