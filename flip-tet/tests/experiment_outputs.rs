//! What the experiments hand to the recorder (moved from xtask with issue 21): rendered
//! snapshots, particle point sets, high-resolution surface frames; and the S3 / S7 setups'
//! reference geometry.

use flip_tet::experiments::holes_plate::{plate_rims, rim_distance, Rim};
use flip_tet::experiments::{simulate, FrameOutput, RunOut, Snapshots};
use flip_tet::presets;
use flip_tet::reference::WaveTheory;
use flip_tet::scene::{Scene, Shape};
use flip_tet::sim::FlipTetSim;
use geom_core::math::Pt3;
use geom_core::record::MemoryRecorder;

fn pool(duration: f64, fps: f64, top: f64) -> Scene {
    let mut s = Scene::new(([0.0; 3], [0.5; 3]), (4, 8), vec![Shape::Box { min: [0.0; 3], max: [0.5, top, 0.5] }]);
    (s.duration, s.fps) = (duration, fps);
    s
}

/// Linear theory of the S3 scene: `T_th = 1.1818` s at `H = 0.5` m and `1.3976` s at
/// `H = 0.25` m (spec §6 S3; tolerance = the spec's rounding to 0.1 ms).
#[test]
fn wave_theory_matches_the_spec_periods() {
    let sc = presets::standing_wave().scene;
    let th = WaveTheory::of(&sc).expect("cosine surface");
    assert!((th.period - 1.1818).abs() <= 5e-5, "{}", th.period);
    assert_eq!(th.eta(th.x0, 0.0), th.mean + th.amp);
    let shallow = presets::with_depth(&sc, presets::SHALLOW_DEPTH).unwrap();
    assert!((WaveTheory::of(&shallow).unwrap().period - 1.3976).abs() <= 5e-5);
}

/// A short drop into a pool: four frames are chosen, each rendered frame shows liquid (lit
/// pixels) on the black background, and the files reach the recorder.
#[test]
fn snapshots_of_a_short_run() {
    let scene = pool(0.1, 30.0, 0.125);
    let mut rec = MemoryRecorder::default();
    let mut snaps = Snapshots::new(&scene, "").expect("camera");
    assert_eq!(snaps.frames, vec![0, 1, 2, 3]);
    let mut sim = FlipTetSim::new(&scene).expect("sim");
    snaps.frame(&sim, 0, &mut rec).expect("render");
    let mut frame = 0;
    while sim.time() < scene.duration - 1e-9 {
        if sim.step().expect("step").frame_end {
            frame += 1;
            snaps.frame(&sim, frame, &mut rec).expect("render");
        }
    }
    assert_eq!(snaps.images.len(), 4);
    for img in &snaps.images {
        let lit = img.data.iter().filter(|&&v| v > 0.05).count();
        assert!(lit > 1000, "the pool is visible: {lit} lit pixels");
    }
    snaps.finish(&mut rec).expect("strip");
    for f in ["surface_snapshots.png", "snapshots/frame_0003.png"] {
        assert!(rec.files[f].starts_with(b"\x89PNG"), "{f}");
    }
}

/// `ply: 1` hands one point frame per frame with the simulator's particles; `hires: 2` hands the
/// output surface of frames 0 and 2, finer than the simulation surface.
#[test]
fn particle_and_hires_frames_reach_the_recorder() {
    let scene = pool(0.05, 40.0, 0.25);
    let mut rec = MemoryRecorder::default();
    let out = RunOut { frames: FrameOutput { obj: 2, ply: 1, hires: 2 }, ..RunOut::full("", FrameOutput::NONE) };
    let run = simulate(&scene, &mut rec, out, &mut |_, _| Ok(())).expect("short run");
    let pts = &rec.points["particles"];
    assert_eq!(pts.len(), 3);
    assert_eq!(pts[2].2, run.sim.particles().x);
    assert_eq!(rec.frames["frames_hires"].len(), 2);
    assert!(rec.frames["frames_hires"][1].2.len() > rec.frames["frames"][1].2.len());
    assert_eq!(rec.tables["metrics"].rows.len(), run.stats.len());
}

/// The rim distance is zero on the circle, the radial offset in the plane, the vertical offset
/// above the circle; the S7 plate gives 9 holes × 2 faces.
#[test]
fn rims_and_distances() {
    let r = Rim { centre: Pt3::new(0.3, 0.6, 0.3), radius: 0.07 };
    assert!(rim_distance(&Pt3::new(0.37, 0.6, 0.3), &r) < 1e-15);
    assert!((rim_distance(&Pt3::new(0.3, 0.6, 0.4), &r) - 0.03).abs() < 1e-15);
    assert!((rim_distance(&Pt3::new(0.3, 0.65, 0.37), &r) - 0.05).abs() < 1e-15);
    let (rims, bottom) = plate_rims(&presets::holes_plate().scene).expect("S7 plate");
    assert_eq!(rims.len(), 18);
    assert!((bottom - 0.6).abs() < 1e-15);
}
