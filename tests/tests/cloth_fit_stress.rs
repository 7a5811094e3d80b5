//! The hard cases of cloth-fit spec §8 as a stress suite: typed errors before any evaluation,
//! finite penalties for diverging or extreme simulations, graceful annealing at the box bounds,
//! with a collapsed simplex and at T₀ = 0.

use std::path::PathBuf;

use cloth_fit::anneal::{anneal, initial_temperature, AnnealOptions};
use cloth_fit::dlt::calibrate_dlt;
use cloth_fit::footage::{coverage_warnings, load_corner_tracks, load_png_sequence, silhouettes, SilhouetteSource};
use cloth_fit::forward::{ShellsForward, SimOptions};
use cloth_fit::objective::{EvalSetup, EvalStatus, Objective};
use cloth_fit::params::{ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, static_trial, waving_trial, FabricPreset};
use cloth_fit::render::{render_frame, RenderOptions};
use cloth_fit::rig::{CameraSpec, RigSpec};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};
use cloth_fit::variability::{perturbed, variability, VariabilityOptions};
use cloth_fit::FitError;
use geom_core::image::{write_png_gray16, write_png_gray8, ImageF32};
use geom_core::math::{Pt2, Pt3, Vec3};

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cloth-fit-stress-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn setup() -> EvalSetup {
    EvalSetup {
        rig: rig_spec(64, 48).build().unwrap().rig,
        model: SimOptions { res: 4, dt: 1.0 / 120.0, ..fit_model() },
        render: Default::default(),
        angle: Default::default(),
        metric: Default::default(),
    }
}

/// Extreme parameters at the range limits (stretch 5000 N/m, dt 1/120, β 0.1 s): the
/// simulation succeeds or fails, the objective is finite either way, never NaN.
#[test]
fn extreme_parameters_give_finite_errors() {
    let s = setup();
    let truth = FabricPreset::Satin.params();
    let src = SyntheticSource::new(Condition::Matched, truth, &s, Default::default());
    let t =
        [synthesize(&ShellsForward, &waving_trial(FabricPreset::Satin, 0, 3), &s.rig, &src, &s.angle).unwrap().target];
    let sp = ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth).unwrap();
    let obj = Objective::new(&t, &ShellsForward, &sp, &s).unwrap();
    let corners: Vec<Vec<f64>> = vec![vec![1.0; 9], vec![0.0; 9], (0..9).map(|i| (i % 2) as f64).collect()];
    for r in obj.eval_batch(&corners) {
        assert!(r.error.is_finite(), "{:?}", r.status);
    }
    // Absurd parameters that diverge: a finite penalty, status SimFailed, counted.
    let wild = truth.with(ParamId::Stretch, 1e9).with(ParamId::Bend, 1e-12).with(ParamId::DragN, 1e7);
    let r = obj.eval_params(&[wild]).remove(0);
    assert!(r.error.is_finite());
    if let EvalStatus::SimFailed(m) = &r.status {
        assert!(!m.is_empty());
        assert!(obj.failures() >= 1);
    }
}

/// Zero-valued drag in the variability analysis is perturbed by ±20 % of its range.
#[test]
fn zero_drag_is_perturbed_by_its_range() {
    let s = setup();
    let truth = FabricPreset::Linen.params().with(ParamId::DragN, 0.0);
    let src = SyntheticSource::new(Condition::Matched, truth, &s, Default::default());
    let t =
        [synthesize(&ShellsForward, &waving_trial(FabricPreset::Linen, 0, 3), &s.rig, &src, &s.angle).unwrap().target];
    let sp = ParamSpace::new(default_ranges(), vec![ParamId::DragN], truth).unwrap();
    let obj = Objective::new(&t, &ShellsForward, &sp, &s).unwrap();
    assert_eq!(perturbed(&obj, &truth, ParamId::DragN, -0.2).drag.k_n, 0.8);
    assert_eq!(perturbed(&obj, &truth, ParamId::DragN, 0.1).drag.k_n, 0.4);
    let v = variability(&obj, &truth, &VariabilityOptions { samples: 3, ..Default::default() }, 1.0).unwrap();
    assert_eq!(v.len(), 1);
    assert!(v[0].samples.iter().all(|(_, e)| e.is_finite()));
}

/// Annealing at the bounds, with a collapsed simplex and at T₀ = 0: no point leaves the box,
/// a collapsed simplex is rebuilt at once, T₀ = 0 falls back and runs as Nelder–Mead.
#[test]
fn annealing_edge_cases() {
    let f = |x: &[f64]| x.iter().map(|v| (v - 1.0).powi(2)).sum::<f64>();
    let mut b = |xs: &[Vec<f64>]| xs.iter().map(|x| f(x)).collect::<Vec<_>>();
    let o = AnnealOptions { max_evals: 200, init_step: 0.3, ..Default::default() };
    let r = anneal(&mut b, &[1.0, 1.0, 0.0], None, 0.5, &o);
    assert!(r.history.iter().all(|s| s.x.iter().all(|&v| (0.0..=1.0).contains(&v))));
    let collapsed = AnnealOptions { init_step: 1e-12, max_evals: 50, ..Default::default() };
    let r = anneal(&mut b, &[0.5, 0.5, 0.5], None, 0.5, &collapsed);
    assert!(r.resets.first() == Some(&4), "immediate reset after the initial simplex: {:?}", r.resets);
    let t0 = initial_temperature(&[3.0, 3.0, 3.0, 3.0], &[], 1.0);
    assert!(t0 > 0.0 && t0 < 0.01);
    let r = anneal(&mut b, &[0.2, 0.2, 0.2], None, 0.0, &AnnealOptions { max_evals: 300, ..Default::default() });
    assert!(r.best_y < 1e-3, "Nelder–Mead at T = 0 converges: {}", r.best_y);
}

/// Too few or coplanar markers, in code and in a calibration file: `DegenerateCalibration`.
#[test]
fn degenerate_calibrations() {
    let c = rig_spec(320, 240).build().unwrap().rig.camera;
    let flat: Vec<Pt3> = (0..8).map(|i| Pt3::new(0.1 * (i % 4) as f64, 0.0, 0.1 * (i / 4) as f64)).collect();
    let img: Vec<Pt2> = flat.iter().map(|x| c.project(x).unwrap().0).collect();
    assert!(matches!(calibrate_dlt(&flat, &img, 320, 240), Err(FitError::DegenerateCalibration(_))));
    let mut spec = rig_spec(320, 240);
    spec.camera = CameraSpec::Markers {
        world: flat[..5].to_vec(),
        image: img[..5].to_vec(),
        width: 320,
        height: 240,
        distortion: None,
    };
    let dir = scratch("calib");
    let p = dir.join("rig.ron");
    std::fs::write(&p, ron::ser::to_string(&spec).unwrap()).unwrap();
    match cloth_fit::rig::load_rig(&p) {
        Err(FitError::DegenerateCalibration(m)) => assert!(m.contains("rig.ron"), "{m}"),
        other => panic!("expected DegenerateCalibration, got {other:?}"),
    }
    std::fs::write(&p, "(camera: oops").unwrap();
    assert!(matches!(cloth_fit::rig::load_rig(&p), Err(FitError::Parse { line: 1, .. })));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Stripes below 5 px in the image: `StripesUnderResolved` at setup (override available); a
/// projector beside the camera (baseline parallel to the stripes) gives a warning.
#[test]
fn stripe_checks() {
    let mut spec: RigSpec = rig_spec(320, 240);
    spec.projector.stripe_period_px = 8.0;
    let rig = spec.build().unwrap().rig;
    let (x, n) = (Pt3::new(0.0, 0.0, -0.2), Vec3::y());
    assert!(matches!(rig.check(&x, &n, false), Err(FitError::StripesUnderResolved { .. })));
    assert!(rig.check(&x, &n, true).is_ok());
    let mut side = rig_spec(320, 240);
    side.projector.camera = CameraSpec::LookAt {
        eye: Pt3::new(0.35, -1.1, 0.0),
        target: Pt3::new(0.0, 0.0, -0.2),
        up: Vec3::z(),
        fov_y_deg: 40.0,
        width: 1024,
        height: 768,
    };
    let c = side.build().unwrap().rig.check(&x, &n, true).unwrap();
    assert!(c.warnings.iter().any(|w| w.contains("parallel")), "{:?}", c.warnings);
    let ok = rig_spec(320, 240).build().unwrap().rig.check(&x, &n, false).unwrap();
    assert!(ok.warnings.is_empty() && (ok.stripe_period_img_px - 8.0).abs() < 1.5, "{ok:?}");
}

/// Corrupt, truncated and 16-bit PNGs; frame sizes that differ; corner CSVs that are empty,
/// malformed or shorter than the sequence.
#[test]
fn footage_inputs() {
    let dir = scratch("footage");
    let img = ImageF32::from_data(4, 2, (0..8).map(|i| i as f32 / 7.0).collect()).unwrap();
    write_png_gray16(dir.join("a_0000.png"), &img, 65535.0).unwrap();
    let back = load_png_sequence(&dir.join("a_%04d.png").display().to_string(), 0, 1).unwrap();
    assert!(back[0].data.iter().zip(&img.data).all(|(a, b)| (a - b).abs() < 1e-4), "16-bit decoded");
    write_png_gray8(dir.join("a_0001.png"), &ImageF32::new(5, 2, 0.5)).unwrap();
    assert!(matches!(
        load_png_sequence(&dir.join("a_%04d.png").display().to_string(), 0, 2),
        Err(FitError::ImageSizeMismatch { .. })
    ));
    std::fs::write(dir.join("b_0000.png"), b"not a png at all").unwrap();
    match load_png_sequence(&dir.join("b_%04d.png").display().to_string(), 0, 1) {
        Err(FitError::Io { path, .. }) => assert!(path.ends_with("b_0000.png")),
        other => panic!("{other:?}"),
    }
    assert!(matches!(load_png_sequence(&dir.join("c_%04d.png").display().to_string(), 0, 1), Err(FitError::Io { .. })));
    let csv = dir.join("corners.csv");
    std::fs::write(&csv, "").unwrap();
    assert!(matches!(load_corner_tracks(&csv), Err(FitError::Csv { .. })));
    std::fs::write(&csv, "t,corner,x,y,z\n0.0,0,0,0,0\n0.0,1,1,0,0\n0.1,1,1,x,0\n").unwrap();
    assert!(matches!(load_corner_tracks(&csv), Err(FitError::Csv { line: 4, .. })));
    std::fs::write(&csv, "t,corner,x,y,z\n0.0,0,0,0,0\n0.0,1,1,0,0\n0.1,1,1,0,0\n").unwrap();
    let tr = load_corner_tracks(&csv).unwrap();
    let w = coverage_warnings(&tr, 0.0, 1.0);
    assert_eq!(w.len(), 1, "corner 1 ends early: {w:?}");
    assert_eq!(tr.corners[1].at(5.0), Pt3::new(1.0, 0.0, 0.0), "the last sample is held");
    std::fs::write(&csv, "t,corner,x,y,z\n0.0,0,0,0,0\n").unwrap();
    assert!(matches!(load_corner_tracks(&csv), Err(FitError::Csv { .. })), "corner 1 has no rows");
    let plate = dir.join("plate.png");
    write_png_gray8(&plate, &ImageF32::new(3, 3, 0.0)).unwrap();
    let frames = vec![ImageF32::new(4, 4, 0.5)];
    assert!(matches!(
        silhouettes(&frames, &SilhouetteSource::Background { plate, threshold: 0.1 }),
        Err(FitError::ImageSizeMismatch { .. })
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Unlit or stripe-free regions are invalid (no atan2(0, 0) reaches the metric); geometry
/// behind or through the camera is clipped, not a panic.
#[test]
fn unlit_regions_and_geometry_behind_the_camera() {
    let rig = rig_spec(64, 48).build().unwrap().rig;
    // A sheet through the camera's plane: clipped at the near plane, finite output.
    let p = vec![Pt3::new(-1.0, -2.0, -0.5), Pt3::new(1.0, -2.0, -0.5), Pt3::new(0.0, 0.5, 0.5)];
    let r = render_frame(&p, &[[0, 1, 2]], &rig, &RenderOptions::default());
    assert!(r.intensity.data.iter().all(|v| v.is_finite()));
    // A flat, stripe-free region inside a silhouette: strength 0 → invalid everywhere.
    let img = ImageF32::new(64, 48, 0.3);
    let sil = geom_core::image::Mask::new(64, 48, true);
    let a = cloth_fit::angle::angle_map(&img, &sil, &Default::default());
    assert_eq!(a.valid.count(), 0);
    assert_eq!(a.fold_mask.count(), 0);
    let _ = static_trial(FabricPreset::Linen, 0, 1);
}
