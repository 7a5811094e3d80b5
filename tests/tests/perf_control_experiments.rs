//! Every perf-control experiment (the scene files of `scenes/perf-control/`) at `Size::Tiny`
//! through the no-op recorder: the run succeeds, its figures are bitwise identical with 1 and 2
//! rayon threads, and the checks that are meaningful on the tiny databases hold (walk and path
//! tracking, GEMM = push sweep, beam never better than exact).

use std::path::{Path, PathBuf};

use geom_core::experiment::{Report, Size};
use geom_core::record::NullRecorder;
use perf_control::experiments::{dance, dance_timing, load_params, mouse_paths, real_data, walk, walk_timing};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ lives in the workspace").to_path_buf()
}

fn scene(name: &str) -> PathBuf {
    root().join("scenes/perf-control").join(format!("{name}.ron"))
}

fn check(r: &Report, key: &str) -> bool {
    r.checks.iter().find(|c| c.key == key).unwrap_or_else(|| panic!("no check of {key}")).pass
}

#[test]
fn walk_pc1() {
    let p: walk::Params = load_params(&scene("walk")).unwrap();
    let r =
        tests::assert_thread_independent("walk", || walk::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    assert_eq!(r.get_f64("long_inputs"), 1.0);
    assert_eq!(r.get_f64("short_inputs"), 1.0);
    for key in ["long_mid_rms_m", "short_mid_rms_m", "long_heading_rms_deg", "short_heading_rms_deg"] {
        assert!(check(&r, key), "{key} = {}", r.get_f64(key));
    }
    assert!(r.get_f64("db_instances") <= r.get_f64("db_instances_before"));
    // The streaming DP beside the offline one: an agreement in [0, 1], never a better score, a
    // measured latency of at least the lag.
    let agree = r.get_f64("streaming_label_agreement");
    assert!((0.0..=1.0).contains(&agree), "streaming agreement {agree}");
    assert!(r.get_f64("streaming_score_excess_rel") >= -1e-12);
    assert!(r.get_f64("streaming_latency_s") >= r.get_f64("streaming_lag_s") - 1e-12);
}

#[test]
fn walk_timing_pc2() {
    let p: walk_timing::Params = load_params(&scene("walk-timing")).unwrap();
    let r = tests::assert_thread_independent("walk-timing", || {
        walk_timing::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    assert!(r.get_f64("beam_score_excess_rel") >= 0.0, "the beam cannot beat the exact optimum");
    assert!(check(&r, "gemm_score_diff_rel"), "GEMM min-plus = push sweep: {}", r.get_f64("gemm_score_diff_rel"));
    assert_eq!(r.get_f64("gemm_same_chain"), 1.0);
    assert!(r.get_f64("exact_cells_expanded") >= r.get_f64("beam_cells_expanded"));
}

#[test]
fn mouse_paths_pc3() {
    let p: mouse_paths::Params = load_params(&scene("mouse-paths")).unwrap();
    let r = tests::assert_thread_independent("mouse-paths", || {
        mouse_paths::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    assert_eq!(r.get_f64("paths"), 1.0);
    assert!(check(&r, "path_rms_m_worst"), "path RMS {}", r.get_f64("path_rms_m_worst"));
    assert!(r.get_f64("fast_d_per_frame") > r.get_f64("d_per_frame_mean"), "the 6 m/s stroke is explained worse");
}

fn real_data(name: &str) -> Report {
    let mut p: real_data::Params = load_params(&scene(name)).unwrap();
    p.resolve_paths(&root().join("scenes/perf-control"));
    tests::assert_thread_independent(name, || real_data::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap())
}

#[test]
fn real_data_pc6() {
    let r = real_data("real-data");
    assert!(r.get_f64("segments_detected") > 10.0);
    for key in ["mid_rms_m", "phase_agreement", "stride_ratio", "skate_cm_s"] {
        assert!(r.get_f64(key).is_finite(), "{key} = {}", r.get_f64(key));
    }
    // The converter's T-pose (frame 0) is far from the clips' median pose and is dropped.
    for clip in ["01_01", "01_03"] {
        assert!(r.get_f64(&format!("setup_dropped_frames_{clip}")) >= 1.0, "{clip}");
        assert!(r.get_f64(&format!("setup_frame0_pose_dist_m_{clip}")) > 0.3, "{clip}");
    }
}

#[test]
fn real_data_cross_clip_pc6() {
    let r = real_data("real-data-cross-clip");
    assert!(r.get_f64("segments_detected") > 10.0);
    assert!(r.get_f64("setup_dropped_frames_01_03") >= 1.0);
    for key in ["mid_rms_m", "heading_rms_deg", "phase_agreement", "stride_ratio", "skate_cm_s"] {
        assert!(r.get_f64(key).is_finite(), "{key} = {}", r.get_f64(key));
    }
}

#[test]
fn dance_pc4() {
    let p: dance::Params = load_params(&scene("dance")).unwrap();
    let r =
        tests::assert_thread_independent("dance", || dance::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap());
    // One test dance of 2 patterns: 8 two-beat segments, every figure defined.
    assert_eq!(r.get_f64("two_beat_segments"), 8.0);
    assert_eq!(r.get_f64("patterns"), 2.0);
    for key in ["two_beat_error_rate", "closed_rms_m", "open_rms_m", "streaming_label_agreement", "held_gap_cm_ik"] {
        assert!(r.get_f64(key).is_finite(), "{key} = {}", r.get_f64(key));
    }
    assert!(r.get_f64("held_gap_cm_ik") <= r.get_f64("held_gap_cm_post"), "the hand snap closes the gap");
    // The measured latency: at least the lag (the frame at the lag waits that long), at most the
    // lag plus a few segments.
    let (lag, latency) = (r.get_f64("streaming_lag_s"), r.get_f64("streaming_latency_s"));
    assert!(latency >= lag && latency <= lag + 3.0, "latency {latency} s at lag {lag} s");
    for cue in ["cue_30mm_", "cue_60mm_", "cue_120mm_"] {
        assert!(r.get_f64(&format!("{cue}two_beat_error_rate")).is_finite());
    }
}

#[test]
fn dance_timing_pc5() {
    let p: dance_timing::Params = load_params(&scene("dance-timing")).unwrap();
    let r = tests::assert_thread_independent("dance-timing", || {
        dance_timing::run(&p, Size::Tiny, &mut NullRecorder::default()).unwrap()
    });
    assert!(r.get_f64("beam_score_excess_rel") >= 0.0, "the beam cannot beat the exact optimum");
    assert!(r.get_f64("exact_cells_expanded") >= r.get_f64("beam_cells_expanded"));
    assert_eq!(r.get_f64("input_s"), 10.0);
}
