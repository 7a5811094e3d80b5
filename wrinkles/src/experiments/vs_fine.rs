//! W4 `vs-fine` (spec §6): the paper's central claim — a coarse cloth simulation plus
//! area-conserving wrinkles costs far less than a fine simulation with the same folds. The
//! gathered curtain (loading (a)) is simulated with `shells` at the fine resolutions (stiff
//! membrane) and at the coarse one (soft membrane, same bending); a sinusoid is "designed" from
//! the finest run (its measured wavelength λ̂ and orientation in the region of interest) and put
//! on the coarse cloth (ExactFlatRest; Linearized with the `flat_at_rest` transform as the
//! second variant). Both pipelines are measured in the same run.
//!
//! Per frame (table `metrics`: pipeline, resolution, frame, t, ms_sim, ms_mod, ms_mesh, cpu
//! times, area_ratio, rms_d, orient_deg, lambda_hat): the cost (wall and process CPU), the ROI
//! area ratio (fine triangles / coarse triangles / the displaced level-L mesh) and, after the
//! gather, the fold statistics of the detail height d on a material grid
//! ([`crate::metrics::fold_stats`]: fine `d = (X − X_s)·n_s` with σ = λ̂ of the finest run,
//! iterated from `sigma0`; wrinkles `d = D`).
//!
//! Figures (means over the frames after the gather, `window` in the notes): per fine resolution
//! `fine<q>_{area_ratio, rms_d_m, orient_deg, lambda_hat_m, folds, ms_per_frame, cpu_ms_per_frame}`
//! and its sanity (`fine<q>_max_edge_strain` …); `coarse_area_ratio` (coarse only) and
//! `wrinkled_{area_ratio, area_ratio_err, rms_d_m, orient_deg, lambda_hat_m}` (ExactFlatRest),
//! `linear_{area_ratio, rms_d_m}` (Linearized + flat_at_rest), `rms_ratio_wrinkled_over_fine`,
//! `orientation_error_deg`, `fold_statistics_equal` (the spec's three bands), the cost figures
//! `cost_ratio_fine_over_coarse` (process CPU per frame of the finest run over the coarse
//! pipeline's sim + modulation + level-L mesh), `cost_ratio_wall`, `coarse_{sim,mod,mesh}_cpu_ms`,
//! `design_lambda_m`, `design_angle_deg`, `sigma_m`, `lambda_convergence` (|λ̂ of the two finest
//! runs − 1|), and the coarse cloth's sanity (`coarse_max_edge_strain` …). Frames: `fine<q>`
//! (every fine run) and `wrinkled` (the coarse cloth's level-L displaced mesh).
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! #[derive(serde::Deserialize)]
//! struct File { params: wrinkles::experiments::vs_fine::Params }
//! let opts = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
//! let f: File = opts.from_str(&std::fs::read_to_string("scenes/wrinkles/vs-fine.ron").unwrap()).unwrap();
//! let r = wrinkles::experiments::vs_fine::run(&f.params, Size::Quick, &mut NullRecorder::default()).unwrap();
//! println!("{}", r.get_f64("cost_ratio_fine_over_coarse"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::{Pt2, Pt3};
use geom_core::record::{Cell, MeshFrame, Recorder, SceneItem, Series};
use geom_core::stats::mean;
use serde::Deserialize;

use super::cloth::{Cloth, ClothModel, Curtain};
use crate::animator::{HMax, MapTransform, ModulationOptions, WrinkleAnimator};
use crate::coeffs::{precompute, PrecomputeOptions};
use crate::displaced::Refinement;
use crate::error::{Result, WrinkleError};
use crate::metrics::{
    area_ratio_in, detail_height, fold_stats, locate_uv, orientation_difference_deg, sample_grid_surface, FoldStats,
    MaterialGrid,
};
use crate::modulation::{ModulationMode, StrainMeasure};
use crate::presets::sinusoid;
use crate::smoothing::{Smoothing, VertexWeights};
use geom_core::clock::timed;

/// The scene's `params` block.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The loading.
    pub curtain: Curtain,
    /// Gather duration per run size (s), overriding `curtain.gather_s` (the test run is short).
    #[serde(default)]
    pub gather_s: Option<BySize<f64>>,
    /// Out-of-plane noise of the coarse cloth's initial positions (m), overriding
    /// `curtain.noise_m` for the coarse run only (0: the coarse sheet stays planar and takes the
    /// gather as in-plane compression, which the wrinkles turn back into area).
    #[serde(default)]
    pub coarse_noise_m: Option<f64>,
    /// Fine pipeline (stiff membrane).
    pub fine: ClothModel,
    /// Coarse pipeline (soft membrane, same bending).
    pub coarse: ClothModel,
    /// Fine resolutions (quads per side), ascending; the last is the reference.
    pub fine_quads: BySize<Vec<u32>>,
    /// Coarse resolution (quads per side).
    pub coarse_quads: u32,
    /// Simulated time (s); the statistics window is t ≥ `curtain.gather_s`.
    pub duration: BySize<f64>,
    /// Region of interest in material coordinates, `[lo, hi]` (m).
    pub roi: [[f64; 2]; 2],
    /// Spacing of the material sampling grid (m; the spec asks ≤ λ/8, reported as
    /// `sample_dx_over_lambda`).
    pub sample_dx: f64,
    /// First Gaussian σ of the fine detail height (m), iterated to σ = λ̂ on the finest run.
    pub sigma0: f64,
    /// Rest slope of the designed sinusoid.
    pub slope: f64,
    /// Largest wrinkled slope (h_max `Auto`).
    pub max_slope: f64,
    /// Scale s of the Linearized variant's `flat_at_rest(s)` transform.
    pub flat_at_rest_scale: f64,
    /// Displaced-mesh subdivision level L.
    pub level: u32,
    /// Precomputation tolerance.
    pub tolerance: f64,
    /// Record every n-th frame's meshes (0 = none).
    pub frame_every: usize,
    /// Count exact self-intersections every n-th frame (and on the last; ≥ 1).
    pub intersections_every: usize,
}

/// One frame of one pipeline.
#[derive(Clone, Debug, Default)]
struct FrameRow {
    t: f64,
    wall: [f64; 3],
    cpu: [f64; 3],
    area_ratio: f64,
    stats: Option<FoldStats>,
}

/// What a fine run leaves for the statistics.
struct FineRun {
    quads: u32,
    rows: Vec<FrameRow>,
    window: Vec<Vec<Pt3>>,
    first_window_frame: usize,
}

fn bad(m: String) -> WrinkleError {
    WrinkleError::InvalidOption(m)
}

fn check(p: &Params, c: &Curtain, fine: &[u32], frames: usize) -> Result<()> {
    if fine.is_empty() || fine.windows(2).any(|w| w[0] >= w[1]) {
        return Err(bad(format!("fine_quads must be non-empty and ascending, got {fine:?}")));
    }
    if frames == 0 || c.gather_s * p.fine.integrator.fps >= frames as f64 {
        return Err(bad(format!("duration must extend past the gather ({} s)", c.gather_s)));
    }
    let [lo, hi] = p.roi;
    if !(lo[0] < hi[0] && lo[1] < hi[1] && lo[0] >= 0.0 && lo[1] >= 0.0) || hi[0] > c.width || hi[1] > c.height {
        return Err(bad(format!("roi {:?} must be a non-empty box inside the sheet", p.roi)));
    }
    if !(p.sample_dx > 0.0 && p.sigma0 > 0.0 && p.slope > 0.0 && p.max_slope > 0.0 && p.flat_at_rest_scale > 0.0)
        || p.level == 0
        || p.intersections_every == 0
        || p.fine.integrator.fps != p.coarse.integrator.fps
        || p.coarse_noise_m.is_some_and(|n| n.is_nan() || n < 0.0)
    {
        return Err(bad(
            "sample_dx, sigma0, slope, max_slope, flat_at_rest_scale must be > 0, level and intersections_every ≥ 1, \
             fine and coarse at the same fps"
                .into(),
        ));
    }
    Ok(())
}

fn frame(rec: &mut dyn Recorder, seq: &str, index: usize, time: f64, q: &[Pt3], faces: &[[u32; 3]]) -> Result<()> {
    rec.frame(&MeshFrame { sequence: seq, index, time, positions: q, faces, attributes: &[] })?;
    Ok(())
}

/// Runs the curtain comparison; see the module docs.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let fine_q = p.fine_quads.get(size);
    let mut curtain = p.curtain.clone();
    if let Some(g) = &p.gather_s {
        curtain.gather_s = g.get(size);
    }
    let c = &curtain;
    let frames = (p.duration.get(size) * p.fine.integrator.fps).round() as usize;
    check(p, c, &fine_q, frames)?;
    let (lo, hi) = (Pt2::new(p.roi[0][0], p.roi[0][1]), Pt2::new(p.roi[1][0], p.roi[1][1]));
    let w0 = ((c.gather_s * p.fine.integrator.fps).ceil() as usize).max(1);
    let grid = MaterialGrid::covering(Pt2::new(0.0, 0.0), Pt2::new(c.width, c.height), p.sample_dx);
    let mpts = grid.points();
    rec.scene(&SceneItem::FrameRate { fps: p.fine.integrator.fps })?;
    let total_units = (fine_q.len() + 1) as u64 * frames as u64;
    let mut done = 0u64;

    // Fine runs.
    let mut r = Report::default();
    let mut fines: Vec<FineRun> = Vec::new();
    for &q in &fine_q {
        let mut cl = Cloth::curtain(c, q, &p.fine)?;
        let seq = format!("fine{q}");
        let faces = cl.sim.mesh().tris.clone();
        let uvf = |f: usize, k: usize| cl.rest.uv(f, k);
        let ar = area_ratio_in(&faces, cl.positions(), uvf, lo, hi);
        let mut rows = vec![FrameRow { area_ratio: ar, ..Default::default() }];
        let mut window = Vec::new();
        if p.frame_every > 0 {
            frame(rec, &seq, 0, 0.0, cl.positions(), &faces)?;
        }
        for f in 1..=frames {
            let (wall, cpu) = cl.advance_frame()?;
            let ar = area_ratio_in(&faces, cl.positions(), |f, k| cl.rest.uv(f, k), lo, hi);
            rows.push(FrameRow {
                t: cl.time(),
                wall: [wall, 0.0, 0.0],
                cpu: [cpu, 0.0, 0.0],
                area_ratio: ar,
                stats: None,
            });
            if f >= w0 {
                window.push(cl.positions().to_vec());
            }
            if f % p.intersections_every == 0 || f == frames {
                cl.count_intersections();
            }
            if p.frame_every > 0 && f % p.frame_every == 0 {
                frame(rec, &seq, f / p.frame_every, cl.time(), cl.positions(), &faces)?;
            }
            done += 1;
            rec.progress(done, total_units);
        }
        cl.figures(&mut r, &format!("fine{q}_"));
        fines.push(FineRun { quads: q, rows, window, first_window_frame: w0 });
    }

    // σ = λ̂ of the finest run's last frame (fixed point from sigma0), then the statistics.
    let nx = |q: u32| (q + 1) as usize;
    let sample = |q: u32, x: &[Pt3]| -> Vec<Pt3> {
        mpts.iter().map(|uv| sample_grid_surface(x, nx(q), nx(q), (c.width, c.height), *uv)).collect()
    };
    let finest = fines.last().expect("fine_quads is non-empty");
    let last = sample(finest.quads, finest.window.last().expect("the window holds the last frame"));
    let mut sigma = p.sigma0;
    for _ in 0..4 {
        let s = fold_stats(&detail_height(&last, &grid, sigma), &grid, lo, hi);
        if !(s.lambda_hat.is_finite() && s.lambda_hat > 0.0) {
            return Err(WrinkleError::Driver(format!(
                "the finest fine run shows no folds in the ROI (λ̂ = {}): nothing to design a pattern from",
                s.lambda_hat
            )));
        }
        sigma = s.lambda_hat;
    }
    for fr in &mut fines {
        for (k, x) in fr.window.iter().enumerate() {
            let xs = sample(fr.quads, x);
            fr.rows[fr.first_window_frame + k].stats =
                Some(fold_stats(&detail_height(&xs, &grid, sigma), &grid, lo, hi));
        }
    }
    let wmean = |rows: &[FrameRow], f: &dyn Fn(&FrameRow) -> f64| -> f64 {
        mean(&rows[w0..].iter().map(f).collect::<Vec<_>>())
    };
    let st = |g: fn(&FoldStats) -> f64| move |fr: &FrameRow| fr.stats.as_ref().map_or(f64::NAN, g);
    let mut fine_sum = Vec::new();
    for fr in &fines {
        let k = |s: &str| format!("fine{}_{s}", fr.quads);
        let rms = wmean(&fr.rows, &st(|s| s.rms));
        let lam = wmean(&fr.rows, &st(|s| s.lambda_hat));
        // Orientation: mean of the per-frame angles folded to within 90° of the first.
        let o0 = fr.rows[w0].stats.map_or(f64::NAN, |s| s.orient_deg);
        let orient = wmean(&fr.rows, &|x: &FrameRow| {
            let o = x.stats.map_or(f64::NAN, |s| s.orient_deg);
            o0 + (o - o0 + 90.0).rem_euclid(180.0) - 90.0
        });
        let cpu = 1e3 * mean(&fr.rows[1..].iter().map(|x| x.cpu[0]).collect::<Vec<_>>());
        let wall = 1e3 * mean(&fr.rows[1..].iter().map(|x| x.wall[0]).collect::<Vec<_>>());
        r.num(&k("area_ratio"), wmean(&fr.rows, &|x| x.area_ratio));
        r.num(&k("rms_d_m"), rms);
        r.num(&k("orient_deg"), orient);
        r.num(&k("lambda_hat_m"), lam);
        r.num(&k("folds"), wmean(&fr.rows, &st(|s| s.folds)));
        r.timing(&k("cpu_ms_per_frame"), cpu);
        r.timing(&k("ms_per_frame"), wall);
        fine_sum.push((fr.quads, rms, orient, lam, cpu, wall));
    }
    let &(fq, f_rms, f_orient, f_lambda, f_cpu, f_wall) = fine_sum.last().expect("non-empty");
    r.num("sigma_m", sigma);
    r.num("design_lambda_m", f_lambda);
    r.num("design_angle_deg", f_orient);
    r.num("sample_dx_over_lambda", p.sample_dx / f_lambda);
    if fine_sum.len() >= 2 {
        let a = fine_sum[fine_sum.len() - 2].3;
        r.num("lambda_convergence", (a / f_lambda - 1.0).abs());
    }

    // Coarse + wrinkles.
    let mut cc = c.clone();
    cc.noise_m = p.coarse_noise_m.unwrap_or(c.noise_m);
    let mut cl = Cloth::curtain(&cc, p.coarse_quads, &p.coarse)?;
    let pattern = sinusoid(f_lambda, f_orient, p.slope)?;
    let pre = PrecomputeOptions { tolerance: p.tolerance, ..Default::default() };
    let (rig, pre_wall, pre_cpu) = timed(|| precompute(&cl.rest, std::slice::from_ref(&pattern), &pre));
    let rig = rig?;
    let smoothing = Smoothing::VertexAverage { weights: VertexWeights::Area };
    let h_max = HMax::Auto { max_slope: p.max_slope };
    let mut exact = WrinkleAnimator::new(
        rig.clone(),
        ModulationOptions { mode: ModulationMode::ExactFlatRest, h_max, smoothing, ..Default::default() },
    )?;
    let mut linear = WrinkleAnimator::new(
        rig.clone(),
        ModulationOptions {
            mode: ModulationMode::Linearized { strain: StrainMeasure::Green },
            h_max,
            smoothing,
            transform: MapTransform::flat_at_rest(p.flat_at_rest_scale),
            ..Default::default()
        },
    )?;
    let refine = Refinement::new(cl.rest.positions.len(), &cl.rest.faces, &rig.edges, p.level);
    let located: Vec<Option<(usize, [f64; 3])>> = mpts.iter().map(|uv| locate_uv(&cl.rest, *uv)).collect();
    let cfaces = cl.rest.faces.clone();
    let mut rows = vec![FrameRow::default()];
    let (mut coarse_ar, mut lin_rows) = (vec![f64::NAN], vec![FrameRow::default()]);
    let d_of = |a: &WrinkleAnimator, fm: &crate::animator::FrameModulation| -> Vec<f64> {
        located.iter().map(|l| l.map_or(0.0, |(t, b)| a.displacement(fm, t, b))).collect()
    };
    for f in 1..=frames {
        let (sw, sc) = cl.advance_frame()?;
        let q = cl.positions().to_vec();
        let (fm, mw, mc) = timed(|| exact.frame(&q));
        let fm = fm?;
        let (dm, dw, dc) = timed(|| exact.displaced_on(&refine, &q, &fm));
        let ar = area_ratio_in(&dm.faces, &dm.positions, |f, k| dm.uv.corner(f, &dm.faces[f], k), lo, hi);
        coarse_ar.push(area_ratio_in(&cfaces, &q, |f, k| cl.rest.uv(f, k), lo, hi));
        let stats = (f >= w0).then(|| fold_stats(&d_of(&exact, &fm), &grid, lo, hi));
        rows.push(FrameRow { t: cl.time(), wall: [sw, mw, dw], cpu: [sc, mc, dc], area_ratio: ar, stats });
        let fl = linear.frame(&q)?;
        let dl = linear.displaced_on(&refine, &q, &fl);
        let arl = area_ratio_in(&dl.faces, &dl.positions, |f, k| dl.uv.corner(f, &dl.faces[f], k), lo, hi);
        let sl = (f >= w0).then(|| fold_stats(&d_of(&linear, &fl), &grid, lo, hi));
        lin_rows.push(FrameRow { t: cl.time(), area_ratio: arl, stats: sl, ..Default::default() });
        if f % p.intersections_every == 0 || f == frames {
            cl.count_intersections();
        }
        if p.frame_every > 0 && f % p.frame_every == 0 {
            frame(rec, "wrinkled", f / p.frame_every, cl.time(), &dm.positions, &dm.faces)?;
        }
        done += 1;
        rec.progress(done, total_units);
    }
    cl.figures(&mut r, "coarse_");
    let ms = |i: usize, cpu: bool| {
        1e3 * mean(&rows[1..].iter().map(|x| if cpu { x.cpu[i] } else { x.wall[i] }).collect::<Vec<_>>())
    };
    let (c_cpu, c_wall) = (ms(0, true) + ms(1, true) + ms(2, true), ms(0, false) + ms(1, false) + ms(2, false));
    r.timing("coarse_sim_cpu_ms", ms(0, true));
    r.timing("coarse_mod_cpu_ms", ms(1, true));
    r.timing("coarse_mesh_cpu_ms", ms(2, true));
    r.timing("coarse_pipeline_cpu_ms_per_frame", c_cpu);
    r.timing("coarse_pipeline_ms_per_frame", c_wall);
    r.timing("precompute_cpu_s", pre_cpu);
    r.timing("precompute_s", pre_wall);
    r.timing("threads", rayon::current_num_threads() as f64);
    r.timing("cost_ratio_fine_over_coarse", f_cpu / c_cpu);
    r.timing("cost_ratio_wall", f_wall / c_wall);
    r.count("reference_quads", fq as u64);
    let w_ar = wmean(&rows, &|x| x.area_ratio);
    let w_rms = wmean(&rows, &st(|s| s.rms));
    let w_or = wmean(&rows, &|x: &FrameRow| {
        let o = x.stats.map_or(f64::NAN, |s| s.orient_deg);
        f_orient + (o - f_orient + 90.0).rem_euclid(180.0) - 90.0
    });
    r.num("coarse_area_ratio", mean(&coarse_ar[w0..]));
    r.num("wrinkled_area_ratio", w_ar);
    r.num("wrinkled_area_ratio_err", (w_ar - 1.0).abs());
    r.num("wrinkled_rms_d_m", w_rms);
    r.num("wrinkled_orient_deg", w_or);
    r.num("wrinkled_lambda_hat_m", wmean(&rows, &st(|s| s.lambda_hat)));
    r.num("linear_area_ratio", wmean(&lin_rows, &|x| x.area_ratio));
    r.num("linear_rms_d_m", wmean(&lin_rows, &st(|s| s.rms)));
    let rms_ratio = w_rms / f_rms;
    let o_err = orientation_difference_deg(w_or, f_orient);
    r.num("rms_ratio_wrinkled_over_fine", rms_ratio);
    r.num("orientation_error_deg", o_err);
    let equal = (w_ar - 1.0).abs() <= 0.01 && (0.5..=2.0).contains(&rms_ratio) && o_err <= 15.0;
    r.flag("fold_statistics_equal", equal);

    // Tables and plots.
    rec.table(
        "metrics",
        &[
            "pipeline",
            "resolution",
            "frame",
            "t",
            "ms_sim",
            "ms_mod",
            "ms_mesh",
            "cpu_ms_sim",
            "cpu_ms_mod",
            "cpu_ms_mesh",
            "area_ratio",
            "rms_d",
            "orient_deg",
            "lambda_hat",
        ],
    )?;
    let emit = |pipe: &str, res: u32, rows: &[FrameRow], rec: &mut dyn Recorder| -> Result<()> {
        for (f, x) in rows.iter().enumerate() {
            let s = x.stats.unwrap_or(FoldStats {
                rms: f64::NAN,
                orient_deg: f64::NAN,
                lambda_hat: f64::NAN,
                folds: f64::NAN,
            });
            let mut cells = vec![Cell::from(pipe), Cell::Int(res as i64), Cell::Int(f as i64), Cell::from(x.t)];
            cells.extend(x.wall.iter().chain(&x.cpu).map(|v| Cell::from(1e3 * v)));
            cells.extend([x.area_ratio, s.rms, s.orient_deg, s.lambda_hat].map(Cell::from));
            rec.row("metrics", &cells)?;
        }
        Ok(())
    };
    for fr in &fines {
        emit("fine", fr.quads, &fr.rows, &mut *rec)?;
    }
    emit("coarse+wrinkles", p.coarse_quads, &rows, &mut *rec)?;
    emit("coarse+linear", p.coarse_quads, &lin_rows, &mut *rec)?;
    let curve = |label: String, pts: Vec<(f64, f64)>| Series {
        plot: "area_ratio_vs_time".into(),
        label,
        axes: ("t (s)".into(), "A / A_rest in the ROI".into()),
        log: (false, false),
        points: pts,
    };
    for fr in &fines {
        rec.series(&curve(format!("fine {0}²", fr.quads), fr.rows.iter().map(|x| (x.t, x.area_ratio)).collect()))?;
    }
    rec.series(&curve("coarse only".into(), rows.iter().zip(&coarse_ar).skip(1).map(|(x, a)| (x.t, *a)).collect()))?;
    rec.series(&curve("coarse + wrinkles".into(), rows.iter().skip(1).map(|x| (x.t, x.area_ratio)).collect()))?;
    let mut cost: Vec<(f64, f64)> =
        fines.iter().zip(&fine_sum).map(|(fr, s)| (2.0 * (fr.quads as f64).powi(2), s.4)).collect();
    rec.series(&Series {
        plot: "cost_vs_triangles".into(),
        label: "fine shells".into(),
        axes: ("triangles".into(), "CPU ms per frame".into()),
        log: (true, true),
        points: std::mem::take(&mut cost),
    })?;
    rec.series(&Series {
        plot: "cost_vs_triangles".into(),
        label: "coarse + wrinkles".into(),
        axes: ("triangles".into(), "CPU ms per frame".into()),
        log: (true, true),
        points: vec![(2.0 * (p.coarse_quads as f64).powi(2), c_cpu)],
    })?;
    rec.note(&format!(
        "### wrinkles/vs-fine\n\nCurtain {}×{} m gathered to {} m over {} s; fine {:?}, coarse {}²; statistics over \
         frames {w0}..={frames}. Designed sinusoid λ = {:.4} m at {:.1}°, σ = {:.4} m. Fine {fq}²: RMS(d) {:.2e} m, \
         {:.2} ms CPU per frame; coarse + wrinkles: area ratio {:.4}, RMS(d) {:.2e} m, {:.2} ms CPU per frame \
         (cost ratio {:.1}).\n",
        c.width,
        c.height,
        c.gathered_width,
        c.gather_s,
        fine_q,
        p.coarse_quads,
        f_lambda,
        f_orient,
        sigma,
        f_rms,
        f_cpu,
        w_ar,
        w_rms,
        c_cpu,
        f_cpu / c_cpu
    ))?;
    for fr in &fines {
        let k = format!("fine{}_", fr.quads);
        r.check(&format!("{k}max_intersections"), Target::Equals(0.0), "issue 20 (contact invariants)");
        r.check(&format!("{k}nan_steps"), Target::Equals(0.0), "issue 20 (contact invariants)");
        r.check(&format!("{k}max_edge_strain"), Target::AtMost(0.10), "issue 20 (contact invariants)");
    }
    r.check("coarse_max_intersections", Target::Equals(0.0), "issue 20 (contact invariants)");
    r.check("coarse_nan_steps", Target::Equals(0.0), "issue 20 (contact invariants)");
    r.check("coarse_max_edge_compression", Target::AtMost(0.5), "issue 20 (contact invariants)");
    r.check("wrinkled_area_ratio_err", Target::AtMost(0.01), "spec W4: |area ratio − 1| ≤ 0.01 (ExactFlatRest)");
    r.check("rms_ratio_wrinkled_over_fine", Target::Within(0.5, 2.0), "spec W4: RMS(d) within a factor 2");
    r.check("orientation_error_deg", Target::AtMost(15.0), "spec W4: orientation within 15°");
    r.check("cost_ratio_fine_over_coarse", Target::AtLeast(20.0), "spec W4 / issue 25: ≥ 20× cheaper");
    Ok(r)
}
