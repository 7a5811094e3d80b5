//! W3 `sleeve` (spec §6): a garment-like tube simulated by `shells` around a static capsule arm
//! — top ring pinned, the cuff (bottom ring) rising by 30 % of the length, holding, then twisting
//! ±25° — carrying three patterns: `Rings` (axial compression) and `Folds` at ±35° (twist),
//! blended by their modulation factors (spec §3.10), in ExactFlatRest and PrincipalLength.
//!
//! Per frame (table `metrics`): the area ratio A/A_rest of the middle part of the sleeve (ROI)
//! for the coarse cloth alone, with ExactFlatRest wrinkles and with PrincipalLength wrinkles
//! (level-L displaced meshes), and the ROI-mean weight of each pattern. Figures:
//! `hold_area_ratio_{coarse, exact, principal}` (end of the hold), `max_area_ratio_err_exact`
//! (largest |ratio − 1| of ExactFlatRest from the end of the rise on), `hold_weight_rings`,
//! `twist_plus_weight_{p35, m35}` and `twist_minus_weight_{p35, m35}` (at +25° and −25°),
//! `twist_dominant_switches` (1 when the dominant diagonal pattern differs between +25° and
//! −25°), the cloth's sanity figures (`max_edge_strain`, `max_obstacle_penetration_m`,
//! `max_intersections`, `nan_steps` …) and the timings `ms_sim`, `ms_modulation`, `ms_mesh`.
//! Frames: `frames` (the coarse cloth, with the arm as scene context) and `wrinkled`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! #[derive(serde::Deserialize)]
//! struct File { params: wrinkles::experiments::sleeve::Params }
//! let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
//! let f: File = opts.from_str(&std::fs::read_to_string("scenes/wrinkles/sleeve.ron").unwrap()).unwrap();
//! let r = wrinkles::experiments::sleeve::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{}", r.get_f64("hold_area_ratio_exact"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::Pt2;
use geom_core::record::{Cell, MeshFrame, Recorder, SceneItem, Series};
use geom_core::stats::{mean, nan_max};
use serde::Deserialize;

use super::cloth::{Cloth, ClothModel, Sleeve};
use crate::animator::{FrameModulation, HMax, ModulationOptions, WrinkleAnimator};
use crate::blend::BlendOptions;
use crate::coeffs::{precompute, PrecomputeOptions};
use crate::displaced::Refinement;
use crate::error::{Result, WrinkleError};
use crate::metrics::area_ratio_in;
use crate::modulation::ModulationMode;
use crate::pattern::{Normalization, PatternOptions, PatternSource, Procedural, WrinklePattern};
use crate::presets::folds;
use crate::smoothing::{Smoothing, VertexWeights};
use geom_core::clock::timed;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The loading (tube, arm, cuff motion).
    pub sleeve: Sleeve,
    /// Factor on the rise, hold and twist durations per run size (the test run is short).
    #[serde(default)]
    pub time_scale: Option<BySize<f64>>,
    /// The coarse cloth.
    pub cloth: ClothModel,
    /// (vertices per ring, rings) per run size (spec: 16 × 12 quads = (16, 13)).
    pub resolution: BySize<(u32, u32)>,
    /// Rings wavelength (UV m, along the axis).
    pub rings_wavelength: f64,
    /// Diagonal folds wavelength (UV m).
    pub folds_wavelength: f64,
    /// Diagonal folds' wave-vector angles (degrees from the u axis, ± this).
    pub folds_angle_deg: f64,
    /// Rest slope of every pattern.
    pub slope: f64,
    /// Largest wrinkled slope (h_max `Auto`).
    pub max_slope: f64,
    /// Pattern blending.
    pub blend: BlendOptions,
    /// ROI: the band of material v (m along the axis from the cuff).
    pub roi_v: [f64; 2],
    /// Displaced-mesh level L.
    pub level: u32,
    /// Precomputation tolerance.
    pub tolerance: f64,
    /// Record every n-th frame (0 = none).
    pub frame_every: usize,
}

fn rings(lambda: f64, slope: f64) -> Result<WrinklePattern> {
    WrinklePattern::new(
        &PatternSource::Procedural(Procedural::Rings { wavelength_uv: lambda }),
        PatternOptions { normalization: Normalization::TargetRestSlope(slope), ..Default::default() },
    )
}

/// Runs the sleeve; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let mut s = p.sleeve.clone();
    let k = p.time_scale.as_ref().map_or(1.0, |b| b.get(size));
    if k.is_nan() || k <= 0.0 || p.level == 0 || p.roi_v[0].partial_cmp(&p.roi_v[1]) != Some(std::cmp::Ordering::Less) {
        return Err(WrinkleError::InvalidOption(format!(
            "time_scale must be > 0 (got {k}), level ≥ 1, roi_v increasing (got {:?})",
            p.roi_v
        )));
    }
    (s.rise_s, s.hold_s, s.twist_s) = (s.rise_s * k, s.hold_s * k, s.twist_s * k);
    let (around, rings_n) = p.resolution.get(size);
    let mut cl = Cloth::sleeve(&s, around, rings_n, &p.cloth)?;
    let pats = vec![
        rings(p.rings_wavelength, p.slope)?,
        folds(p.folds_wavelength, p.folds_angle_deg, 11, p.slope)?,
        folds(p.folds_wavelength, -p.folds_angle_deg, 12, p.slope)?,
    ];
    let rig = precompute(&cl.rest, &pats, &PrecomputeOptions { tolerance: p.tolerance, ..Default::default() })?;
    let base = ModulationOptions {
        mode: ModulationMode::ExactFlatRest,
        h_max: HMax::Auto { max_slope: p.max_slope },
        smoothing: Smoothing::VertexAverage { weights: VertexWeights::Area },
        blend: p.blend,
        ..Default::default()
    };
    let mut exact = WrinkleAnimator::new(rig.clone(), base.clone())?;
    let mut principal =
        WrinkleAnimator::new(rig.clone(), ModulationOptions { mode: ModulationMode::PrincipalLength, ..base })?;
    let refine = Refinement::new(cl.rest.positions.len(), &cl.rest.faces, &rig.edges, p.level);
    let circ = 2.0 * std::f64::consts::PI * s.radius;
    let (lo, hi) = (Pt2::new(-1.0, p.roi_v[0]), Pt2::new(circ + 1.0, p.roi_v[1]));
    let roi_faces: Vec<usize> = (0..cl.rest.faces.len())
        .filter(|&f| {
            let v = (0..3).map(|k| cl.rest.uv(f, k).y).sum::<f64>() / 3.0;
            v >= lo.y && v <= hi.y
        })
        .collect();
    let t_end = s.rise_s + s.hold_s + s.twist_s;
    let frames = (t_end * cl.fps).round() as usize;
    let fps = cl.fps;
    let at = |t: f64| (t * fps).round() as usize;
    let f_rise = at(s.rise_s);
    let (f_hold, f_plus, f_minus) = (
        at(s.rise_s + s.hold_s),
        at(s.rise_s + s.hold_s + 0.25 * s.twist_s),
        at(s.rise_s + s.hold_s + 0.75 * s.twist_s),
    );
    rec.scene(&SceneItem::FrameRate { fps: cl.fps })?;
    for o in &cl.sim.effects().obstacles {
        if let (shells::ObstacleShape::Capsule { .. }, Some((positions, faces))) =
            (&o.shape, o.shape.surface_mesh().map_err(|e| WrinkleError::Driver(e.to_string()))?)
        {
            rec.scene(&SceneItem::Mesh { name: "arm".into(), positions, faces })?;
        }
    }
    let mut pinned: Vec<u32> = cl.sim.free_dofs().pinned.iter().chain(&cl.sim.free_dofs().kinematic).copied().collect();
    pinned.sort_unstable();
    rec.scene(&SceneItem::Pinned { sequence: "frames".into(), vertices: pinned })?;
    rec.table(
        "metrics",
        &[
            "frame",
            "t",
            "area_ratio_coarse",
            "area_ratio_exact",
            "area_ratio_principal",
            "w_rings",
            "w_p35",
            "w_m35",
            "ms_sim",
            "ms_mod",
            "ms_mesh",
        ],
    )?;
    let faces = cl.rest.faces.clone();
    let weights = |fm: &FrameModulation| -> [f64; 3] {
        let w = |i: usize| mean(&roi_faces.iter().map(|&t| fm.tri_weight[3 * t + i]).collect::<Vec<_>>());
        [w(0), w(1), w(2)]
    };
    let (mut hold, mut plus, mut minus) = ([f64::NAN; 3], [f64::NAN; 3], [f64::NAN; 3]);
    let (mut w_hold, mut w_plus, mut w_minus) = ([f64::NAN; 3], [f64::NAN; 3], [f64::NAN; 3]);
    let mut err_after_rise = 0.0f64;
    let (mut t_sim, mut t_mod, mut t_mesh) = (Vec::new(), Vec::new(), Vec::new());
    let mut series: [Vec<(f64, f64)>; 3] = Default::default();
    for f in 1..=frames {
        let (ws, _) = cl.advance_frame()?;
        let q = cl.positions().to_vec();
        let (fm, wm, _) = timed(|| exact.frame(&q));
        let fm = fm?;
        let (dm, wd, _) = timed(|| exact.displaced_on(&refine, &q, &fm));
        let fp = principal.frame(&q)?;
        let dp = principal.displaced_on(&refine, &q, &fp);
        let ratios = [
            area_ratio_in(&faces, &q, |f, k| cl.rest.uv(f, k), lo, hi),
            area_ratio_in(&dm.faces, &dm.positions, |f, k| dm.uv.corner(f, &dm.faces[f], k), lo, hi),
            area_ratio_in(&dp.faces, &dp.positions, |f, k| dp.uv.corner(f, &dp.faces[f], k), lo, hi),
        ];
        let w = weights(&fm);
        if f >= f_rise {
            err_after_rise = nan_max(err_after_rise, (ratios[1] - 1.0).abs());
        }
        if f == f_hold {
            (hold, w_hold) = (ratios, w);
        }
        if f == f_plus {
            (plus, w_plus) = (ratios, w);
        }
        if f == f_minus {
            (minus, w_minus) = (ratios, w);
        }
        let t = cl.time();
        for (sv, r) in series.iter_mut().zip(ratios) {
            sv.push((t, r));
        }
        if f % 5 == 0 || f == frames {
            cl.count_intersections();
        }
        if p.frame_every > 0 && f % p.frame_every == 0 {
            let i = f / p.frame_every;
            rec.frame(&MeshFrame {
                sequence: "frames",
                index: i,
                time: t,
                positions: &q,
                faces: &faces,
                attributes: &[],
            })?;
            rec.frame(&MeshFrame {
                sequence: "wrinkled",
                index: i,
                time: t,
                positions: &dm.positions,
                faces: &dm.faces,
                attributes: &[],
            })?;
        }
        t_sim.push(ws);
        t_mod.push(wm);
        t_mesh.push(wd);
        let mut cells = vec![Cell::Int(f as i64), Cell::from(t)];
        cells.extend(ratios.iter().chain(&w).map(|v| Cell::from(*v)));
        cells.extend([ws, wm, wd].map(|v| Cell::from(1e3 * v)));
        rec.row("metrics", &cells)?;
        rec.progress(f as u64, frames as u64);
    }
    for (label, pts) in ["coarse only", "ExactFlatRest", "PrincipalLength"].iter().zip(series) {
        rec.series(&Series {
            plot: "area_ratio_vs_time".into(),
            label: (*label).into(),
            axes: ("t (s)".into(), "A / A_rest (middle of the sleeve)".into()),
            log: (false, false),
            points: pts,
        })?;
    }
    let mut r = Report::default();
    cl.figures(&mut r, "");
    r.count("triangles", faces.len() as u64);
    r.num("hold_area_ratio_coarse", hold[0]);
    r.num("hold_area_ratio_exact", hold[1]);
    r.num("hold_area_ratio_principal", hold[2]);
    r.num("twist_plus_area_ratio_exact", plus[1]);
    r.num("twist_minus_area_ratio_exact", minus[1]);
    r.num("max_area_ratio_err_exact", err_after_rise);
    r.num("hold_weight_rings", w_hold[0]);
    r.num("twist_plus_weight_p35", w_plus[1]);
    r.num("twist_plus_weight_m35", w_plus[2]);
    r.num("twist_minus_weight_p35", w_minus[1]);
    r.num("twist_minus_weight_m35", w_minus[2]);
    let switch = (w_plus[1] > w_plus[2]) != (w_minus[1] > w_minus[2]);
    r.count("twist_dominant_switches", switch as u64);
    r.timing("ms_sim", 1e3 * mean(&t_sim));
    r.timing("ms_modulation", 1e3 * mean(&t_mod));
    r.timing("ms_mesh", 1e3 * mean(&t_mesh));
    let src = "issue 20 (contact invariants)";
    r.check("nan_steps", Target::Equals(0.0), src);
    r.check("max_intersections", Target::Equals(0.0), src);
    r.check("max_obstacle_penetration_m", Target::AtMost(1e-4), src);
    r.check("max_edge_compression", Target::AtMost(0.5), src);
    rec.note(&format!(
        "### wrinkles/sleeve\n\n{} triangles, {frames} frames. End of the hold: area ratio {:.4} (coarse), {:.4} \
         (ExactFlatRest), {:.4} (PrincipalLength); rings weight {:.2}. Twist +: weights ±35° {:.2}/{:.2}; twist −: \
         {:.2}/{:.2}.\n",
        faces.len(),
        hold[0],
        hold[1],
        hold[2],
        w_hold[0],
        w_plus[1],
        w_plus[2],
        w_minus[1],
        w_minus[2]
    ))?;
    Ok(r)
}
