//! Material and dynamics variants of two tracks scenes (spec §6.2, §6.3): the same guide
//! animation tracked by differently parameterised fine shells, the "post facto" material axes of
//! the seed's Fig. 8 (box) and Fig. 9 (bag). Every variant runs tracked only (no untracked twin);
//! the guide, the subdivision, the test functions and the metric filter L_τ are those of
//! `tracks/box` and `tracks/bag` (built by [`box_setup`] / [`bag_setup`]), only the shell
//! description (material, rest shape, wind) changes.
//!
//! - `tracks/box-variants` (§6.2, Fig. 8): families `stiffness` (k_B and Yt scaled), `plastic`
//!   (yield Δκ_max × hardening η) and `dynamics` (Rayleigh β × areal density ρ_s) of the rubber box.
//! - `tracks/bag-variants` (§6.3, Fig. 9): `vinyl`, `silk`, `accordion`, `ribbon`, `cellophane`,
//!   `wind`, plus `cellophane_vinyl` (ours: the cellophane rest shape in vinyl, to time the rough
//!   rest shape alone).
//!
//! Outputs per variant `<v>`: `steps_<v>.csv`, `frames_<v>.csv` (written by [`run_pair`]); for the
//! scene `series.csv` (variant, t, D_c, a_d, λ_eff, kinetic energy), `variants.csv` (one row of
//! figures per variant) and PNG plots of a_d (and, for the box, kinetic energy) against time.

use std::path::Path;

use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::{vertex_normals, NormalWeight};
use geom_core::rng::Rng;
use serde::Deserialize;
use shells::{Damping, Material, MembraneLaw, PlasticRule, Plasticity, ShellSceneDesc, Wind};

use super::tracks::{
    bag_setup, box_setup, frames_for, iso_material, pick3, rubber, run_pair, track_opts, vinyl, PairOpts, PairOut,
    PairParams, Setup,
};
use crate::error::{Error, Result};
use crate::out::{Cell, CsvWriter, Summary};
use crate::plot::{LinePlot, Series};
use crate::registry::{RunCtx, Runner};
use crate::scene::{self, Mode};

/// Adds the variant runners.
pub fn register(v: &mut Vec<Runner>) {
    v.push(Runner { method: "tracks/box-variants", run: run_box_variants });
    v.push(Runner { method: "tracks/bag-variants", run: run_bag_variants });
}

// ---------------------------------------------------------------------------------------------
// shared: run settings, one variant, the per-variant loop

/// Checks the shared run settings (`tracks/box`'s and `tracks/bag`'s parameter block).
fn validate_run(p: &PairParams, scene: &str) -> Result<()> {
    let d = [p.duration.0, p.duration.1, p.duration.2];
    if d.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return Err(bad(scene, format!("run.duration must be finite and > 0 s, got {d:?}")));
    }
    let s = [p.substeps.0, p.substeps.1, p.substeps.2];
    if s.contains(&0) {
        return Err(bad(scene, format!("run.substeps must be ≥ 1, got {s:?}")));
    }
    Ok(())
}

fn bad(scene: &str, msg: String) -> Error {
    Error::Run(format!("{scene}: invalid parameter: {msg}"))
}

/// One variant: a name (used in file names and summary keys), its family and how it changes
/// the shell description of the base scene.
struct Variant {
    name: String,
    family: &'static str,
    edit: Box<dyn Fn(&mut ShellSceneDesc)>,
}

/// Figures of one variant run plus its time series (frames ≥ 1).
struct VariantRun {
    name: String,
    family: &'static str,
    /// Bending stiffness k_B of the variant's material at t = 0 (J).
    k_b: f64,
    out: PairOut,
}

impl VariantRun {
    /// Times of frames ≥ 1 (aligned with `dc_tracked`, `ad_tracked`, `lambda_eff_tracked`).
    fn t(&self) -> &[f64] {
        &self.out.times[1..]
    }
    /// Kinetic energy of frames ≥ 1 (J).
    fn ke(&self) -> &[f64] {
        &self.out.ke_tracked[1..]
    }
    /// Value of a per-frame series at the frame nearest to `t` (within half a frame), else NaN.
    fn at(&self, t: f64, v: &[f64], fps: f64) -> f64 {
        self.t().iter().zip(v).find(|(x, _)| (**x - t).abs() < 0.5 / fps).map_or(f64::NAN, |(_, y)| *y)
    }
    /// Mean of a per-frame series over frames with a − ε ≤ t ≤ b + ε, NaN when none.
    fn window_mean(&self, a: f64, b: f64, v: &[f64]) -> f64 {
        let sel: Vec<f64> =
            self.t().iter().zip(v).filter(|(x, _)| **x >= a - 1e-9 && **x <= b + 1e-9).map(|(_, y)| *y).collect();
        if sel.is_empty() {
            f64::NAN
        } else {
            sel.iter().sum::<f64>() / sel.len() as f64
        }
    }
    fn r_pre(&self) -> f64 {
        self.out.max_r_pre / self.out.scale
    }
    fn r_post(&self) -> f64 {
        self.out.max_r_post / self.out.scale
    }
}

/// Frame rate of the box and bag guides (`box_setup` / `bag_setup`).
const FPS: f64 = 30.0;

/// Replaces the shell description of `s` by `edit` applied to it.
fn edited(s: Setup, edit: Box<dyn Fn(&mut ShellSceneDesc)>) -> Setup {
    let Setup { guide, prolongation, tracked_rest, desc, tf, fps, substeps, rest_events } = s;
    Setup {
        desc: Box::new(move || {
            let mut d = desc();
            edit(&mut d);
            d
        }),
        guide,
        prolongation,
        tracked_rest,
        tf,
        fps,
        substeps,
        rest_events,
    }
}

/// The variants of this mode: all in default / full, the named ones in quick (unknown names are
/// an error listing the known ones).
fn select(all: Vec<Variant>, quick: &[String], mode: Mode, scene: &str) -> Result<Vec<Variant>> {
    if mode != Mode::Quick {
        return Ok(all);
    }
    for q in quick {
        if !all.iter().any(|v| &v.name == q) {
            let known: Vec<&str> = all.iter().map(|v| v.name.as_str()).collect();
            return Err(bad(scene, format!("quick_variants: unknown variant `{q}`; known: {}", known.join(", "))));
        }
    }
    Ok(all.into_iter().filter(|v| quick.contains(&v.name)).collect())
}

/// Runs the variants of this mode (see [`select`]) tracked-only with `make_setup()` as the base
/// scene; writes `series.csv`; returns the runs and the simulated time (s).
fn run_variants(
    ctx: &RunCtx,
    p: &PairParams,
    all: Vec<Variant>,
    quick: &[String],
    scene: &str,
    intersections: bool,
    make_setup: &dyn Fn(u32, bool) -> Result<Setup>,
) -> Result<(Vec<VariantRun>, f64)> {
    let m = ctx.mode;
    let variants = select(all, quick, m, scene)?;
    let substeps = pick3(m, p.substeps);
    let sc = pick3(m, p.self_collision);
    let mut series = CsvWriter::create(
        &ctx.out_dir.join("series.csv"),
        &["variant", "family", "t", "dc", "a_d_m", "lambda_eff_m", "kinetic_J", "isect_tracked", "isect_guide"],
    )?;
    let mut runs = Vec::new();
    for v in variants {
        let setup = edited(make_setup(substeps, sc)?, v.edit);
        let o = PairOpts {
            frames: frames_for(pick3(m, p.duration), setup.fps),
            obj_every: p.obj_every,
            untracked: false,
            track: track_opts(p.kkt, p.refine_steps),
            intersections,
            anchors: None,
            tag: format!("_{}", v.name),
        };
        let k_b = (setup.desc)().material.bending;
        let out = run_pair(&setup, &o, &ctx.out_dir)?;
        let r = VariantRun { name: v.name, family: v.family, k_b, out };
        for i in 0..r.t().len() {
            series.row(&[
                Cell::Text(r.name.clone()),
                Cell::Text(r.family.to_string()),
                Cell::Num(r.t()[i]),
                Cell::Num(r.out.dc_tracked[i]),
                Cell::Num(r.out.ad_tracked[i]),
                Cell::Num(r.out.lambda_eff_tracked[i]),
                Cell::Num(r.ke()[i]),
                Cell::Int(r.out.isect_tracked[i + 1] as i64),
                Cell::Int(r.out.isect_guide[i + 1] as i64),
            ])?;
        }
        runs.push(r);
    }
    let duration = frames_for(pick3(m, p.duration), FPS) as f64 / FPS;
    Ok((runs, duration))
}

/// Keys both scenes share: worst residuals (/L) over the variants and the run settings.
fn common_keys(s: &mut Summary, runs: &[VariantRun], p: &PairParams, m: Mode, duration: f64) {
    s.set("max_residual_pre", runs.iter().map(VariantRun::r_pre).fold(0.0, f64::max));
    s.set("max_residual_post", runs.iter().map(VariantRun::r_post).fold(0.0, f64::max));
    s.set_count("variants_run", runs.len() as u64);
    s.set_count("substeps", pick3(m, p.substeps) as u64);
    s.set_count("self_collision", pick3(m, p.self_collision) as u64);
    s.set("duration_s", duration);
    s.set_str("mode", m.name());
}

/// A number as a summary-key fragment: `0.1` → `0_1`, `2e-3` → `0_002`, `-0.3` → `m0_3`.
fn num_key(x: f64) -> String {
    let s = format!("{}", x.abs()).replace('.', "_");
    if x < 0.0 {
        format!("m{s}")
    } else {
        s
    }
}

/// 1 / 0 for a checked expectation, NaN (JSON null) when the variants it needs did not run.
fn flag(v: Option<bool>) -> f64 {
    v.map_or(f64::NAN, |b| if b { 1.0 } else { 0.0 })
}

fn find<'a>(runs: &'a [VariantRun], name: &str) -> Option<&'a VariantRun> {
    runs.iter().find(|r| r.name == name)
}

/// One a_d(t) plot per family (or one for all when `family` is None).
fn plot_family(
    runs: &[VariantRun],
    family: Option<&str>,
    title: &str,
    y: &str,
    log_y: bool,
    path: &Path,
) -> Result<()> {
    let mut plot = LinePlot::new(title, "t (s)", y).log(false, log_y);
    for r in runs.iter().filter(|r| family.is_none_or(|f| f == r.family)) {
        let v = if log_y { r.ke() } else { &r.out.ad_tracked[..] };
        plot = plot.with(Series::new(r.name.clone(), r.t().iter().copied().zip(v.iter().copied()).collect()));
    }
    plot.write_png(path)?;
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// box variants (§6.2, Fig. 8)

/// Guide times of the box clip (spec §6.2): fully twisted and held at 2.5 s, the detail is
/// compared at 4.4 s (untwisted, before the abrupt stop at 4.5 s).
const T_TWISTED: f64 = 2.5;
const T_UNTWISTED: f64 = 4.4;
const T_STOP: f64 = 4.5;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxVariantsParams {
    /// Run settings, as in `tracks/box`.
    run: PairParams,
    /// The variants run with `--quick` (names as in the summary keys); default and full run all.
    quick_variants: Vec<String>,
    /// `stiffness` family: bending k_B scales (at Yt × 1); the k_B × 1 run is the elastic base.
    kb_scale: Vec<f64>,
    /// `stiffness` family: membrane Yt scales (at k_B × 1); a scale of 1 is the `kb_1` run.
    yt_scale: Vec<f64>,
    /// `plastic` family: finite yields Δκ_max (1/m); Δκ_max = ∞ never yields, whatever η, so
    /// the ∞ row of Fig. 8 is the elastic `kb_1` run.
    plastic_yield_per_m: Vec<f64>,
    /// `plastic` family: hardening η (m), k ← k·exp(η x) (shells spec §3.6).
    plastic_hardening_m: Vec<f64>,
    /// `dynamics` family: Rayleigh stiffness damping β (s).
    dynamics_beta_s: Vec<f64>,
    /// `dynamics` family: areal density ρ_s (kg/m²).
    dynamics_density_kg_m2: Vec<f64>,
}

impl BoxVariantsParams {
    fn validate(&self) -> Result<()> {
        const S: &str = "tracks/box-variants";
        validate_run(&self.run, S)?;
        let pos = |name: &str, v: &[f64]| -> Result<()> {
            if v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
                return Err(bad(S, format!("{name} entries must be finite and > 0, got {v:?}")));
            }
            Ok(())
        };
        pos("kb_scale", &self.kb_scale)?;
        pos("yt_scale", &self.yt_scale)?;
        pos("plastic_yield_per_m", &self.plastic_yield_per_m)?;
        pos("dynamics_density_kg_m2", &self.dynamics_density_kg_m2)?;
        if self.plastic_hardening_m.iter().any(|x| !x.is_finite()) {
            return Err(bad(S, format!("plastic_hardening_m must be finite, got {:?}", self.plastic_hardening_m)));
        }
        if self.dynamics_beta_s.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(bad(S, format!("dynamics_beta_s must be finite and ≥ 0, got {:?}", self.dynamics_beta_s)));
        }
        if !self.kb_scale.contains(&1.0) {
            return Err(bad(S, format!("kb_scale must contain 1 (the elastic base run), got {:?}", self.kb_scale)));
        }
        Ok(())
    }
}

fn scale_yt(m: &mut Material, s: f64) {
    if let MembraneLaw::Isotropic { young_thickness, .. } = &mut m.membrane {
        *young_thickness *= s;
    }
}

/// The Fig. 8 variants of the rubber box.
fn box_variants(p: &BoxVariantsParams) -> Vec<Variant> {
    let mut v = Vec::new();
    for &kb in &p.kb_scale {
        v.push(Variant {
            name: format!("kb_{}", num_key(kb)),
            family: "stiffness",
            edit: Box::new(move |d| d.material.bending *= kb),
        });
    }
    for &yt in p.yt_scale.iter().filter(|&&s| s != 1.0) {
        v.push(Variant {
            name: format!("yt_{}", num_key(yt)),
            family: "stiffness",
            edit: Box::new(move |d| scale_yt(&mut d.material, yt)),
        });
    }
    for &y in &p.plastic_yield_per_m {
        for &eta in &p.plastic_hardening_m {
            let sign = if eta > 0.0 { "p" } else { "" };
            v.push(Variant {
                name: format!("plastic_{}_eta_{sign}{}", num_key(y), num_key(eta)),
                family: "plastic",
                edit: Box::new(move |d| {
                    d.material.plasticity =
                        Some(Plasticity { max_curvature_dev: y, hardening: eta, rule: PlasticRule::ReturnMapping })
                }),
            });
        }
    }
    for &beta in &p.dynamics_beta_s {
        for &rho in &p.dynamics_density_kg_m2 {
            v.push(Variant {
                name: format!("beta_{}_rho_{}", num_key(beta), num_key(rho)),
                family: "dynamics",
                edit: Box::new(move |d| {
                    d.material.damping = Damping::Rayleigh { alpha: 0.0, beta };
                    d.material.density = rho;
                }),
            });
        }
    }
    v
}

fn run_box_variants(ctx: &RunCtx) -> Result<Summary> {
    let p: BoxVariantsParams = scene::load(&ctx.scene_file)?.params;
    p.validate()?;
    let m = ctx.mode;
    let q = &p.quick_variants;
    let (runs, duration) =
        run_variants(ctx, &p.run, box_variants(&p), q, "tracks/box-variants", false, &|n, sc| box_setup(n, sc))?;
    let fps = FPS;
    let mut s = Summary::new();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("variants.csv"),
        &[
            "variant",
            "family",
            "a_d_2_5s_m",
            "lambda_eff_2_5s_m",
            "a_d_4_4s_m",
            "ad_ratio_4_4_over_2_5",
            "ke_after_stop_J",
            "ke_end_window_J",
            "ke_decay_rate_per_s",
            "bend_2_5s_J",
            "bend_over_kb_2_5s",
            "max_residual_pre",
            "max_residual_post",
            "s_per_frame",
        ],
    )?;
    // KE windows after the abrupt stop: [4.5, 5.0] s and the last 0.5 s of the run; the decay
    // rate is ln(E_early / E_late) over the distance of the window centres.
    let late = (duration - 0.5, duration);
    let has_late = duration >= T_STOP + 1.0 - 1e-9;
    let mut decay = Vec::new();
    for r in &runs {
        let ad25 = r.at(T_TWISTED, &r.out.ad_tracked, fps);
        let l25 = r.at(T_TWISTED, &r.out.lambda_eff_tracked, fps);
        let ad44 = r.at(T_UNTWISTED, &r.out.ad_tracked, fps);
        let ke_early = r.window_mean(T_STOP, T_STOP + 0.5, r.ke());
        let ke_late = if has_late { r.window_mean(late.0, late.1, r.ke()) } else { f64::NAN };
        let rate = (ke_early / ke_late).ln() / (late.0 - T_STOP);
        // Supplementary wrinkle indicator (not a spec metric): hinge bending energy at 2.5 s
        // (frame-0 aligned series) and the same divided by the variant's initial k_B, i.e. the
        // geometric Σ ω Δθ² of the shells hinge model (for plastic runs k and θ̄ evolve).
        let bend = r.out.times.iter().zip(&r.out.bend_tracked).find(|(t, _)| (**t - T_TWISTED).abs() < 0.5 / fps);
        let bend = bend.map_or(f64::NAN, |(_, e)| *e);
        let bend_geo = bend / r.k_b;
        decay.push(rate);
        let n = &r.name;
        s.set(&format!("ad_2_5s_{n}"), ad25);
        s.set(&format!("lambda_eff_2_5s_{n}"), l25);
        s.set(&format!("ad_ratio_4_4_over_2_5_{n}"), ad44 / ad25);
        s.set(&format!("ke_after_stop_J_{n}"), ke_early);
        s.set(&format!("ke_decay_rate_per_s_{n}"), rate);
        s.set(&format!("s_per_frame_{n}"), r.out.s_per_frame_tracked());
        s.set(&format!("bend_over_kb_2_5s_{n}"), bend_geo);
        csv.row(&[
            Cell::Text(n.clone()),
            Cell::Text(r.family.to_string()),
            Cell::Num(ad25),
            Cell::Num(l25),
            Cell::Num(ad44),
            Cell::Num(ad44 / ad25),
            Cell::Num(ke_early),
            Cell::Num(ke_late),
            Cell::Num(rate),
            Cell::Num(bend),
            Cell::Num(bend_geo),
            Cell::Num(r.r_pre()),
            Cell::Num(r.r_post()),
            Cell::Num(r.out.s_per_frame_tracked()),
        ])?;
    }
    // λ_eff(2.5 s) strictly increasing with k_B over the kb_* runs (sorted by scale).
    let mut kb = p.kb_scale.clone();
    kb.sort_by(f64::total_cmp);
    let lam: Option<Vec<f64>> = kb
        .iter()
        .map(|&k| find(&runs, &format!("kb_{}", num_key(k))).map(|r| r.at(T_TWISTED, &r.out.lambda_eff_tracked, fps)))
        .collect();
    let mono = lam.filter(|l| l.len() >= 2).map(|l| l.windows(2).all(|w| w[1] > w[0]));
    s.set("lambda_monotone_in_kb", flag(mono));
    let ratio = |name: &str| {
        find(&runs, name)
            .map_or(f64::NAN, |r| r.at(T_UNTWISTED, &r.out.ad_tracked, fps) / r.at(T_TWISTED, &r.out.ad_tracked, fps))
    };
    s.set("ad_ratio_4_4_over_2_5_elastic", ratio("kb_1"));
    // The first finite yield with η = 0 is "the" plastic run of the spec's expectation.
    let plastic = p.plastic_yield_per_m.first().map(|&y| format!("plastic_{}_eta_0", num_key(y)));
    s.set("ad_ratio_4_4_over_2_5_plastic", plastic.as_deref().map_or(f64::NAN, ratio));
    // Larger β ⇒ faster KE decay, per density: every (β_lo, β_hi) pair at equal ρ_s.
    // A rate that could not be measured (run too short) leaves the check undecided (null).
    let mut pairs: Vec<Option<bool>> = Vec::new();
    for &rho in &p.dynamics_density_kg_m2 {
        let rates: Vec<(f64, f64)> = p
            .dynamics_beta_s
            .iter()
            .filter_map(|&b| {
                let name = format!("beta_{}_rho_{}", num_key(b), num_key(rho));
                runs.iter().position(|r| r.name == name).map(|i| (b, decay[i]))
            })
            .collect();
        for a in &rates {
            for b in rates.iter().filter(|b| b.0 > a.0) {
                pairs.push((a.1.is_finite() && b.1.is_finite()).then_some(b.1 > a.1));
            }
        }
    }
    let faster = (!pairs.is_empty() && !pairs.contains(&None)).then(|| pairs.iter().all(|&x| x == Some(true)));
    s.set("ke_decay_faster_with_beta", flag(faster));
    let ke_pos = runs.iter().map(|r| r.window_mean(T_STOP, T_STOP + 0.5, r.ke())).collect::<Vec<_>>();
    s.set("ke_positive_after_stop", flag((!ke_pos.is_empty()).then(|| ke_pos.iter().all(|&e| e > 0.0))));
    s.set("ke_after_stop_min_J", ke_pos.iter().copied().fold(f64::NAN, f64::min));
    s.set("guide_motion_after_stop_m", guide_motion_after(T_STOP, duration)?);
    common_keys(&mut s, &runs, &p.run, m, duration);
    for f in ["stiffness", "plastic", "dynamics"] {
        if runs.iter().any(|r| r.family == f) {
            let title = format!("box {f} variants: detail amplitude a_d");
            plot_family(&runs, Some(f), &title, "a_d (m)", false, &ctx.out_dir.join(format!("ad_{f}.png")))?;
        }
    }
    if runs.iter().any(|r| r.family == "dynamics") {
        let path = ctx.out_dir.join("ke_dynamics.png");
        plot_family(&runs, Some("dynamics"), "box dynamics variants: tracked kinetic energy", "KE (J)", true, &path)?;
    }
    Ok(s)
}

/// Largest displacement (m) of any guide vertex between `t0` and any frame up to `t1` (the guide's
/// kinetic energy after the stop is zero iff this is zero).
fn guide_motion_after(t0: f64, t1: f64) -> Result<f64> {
    let g = super::tracks::tk(tracks::procedural::box_guide(6.0))?;
    let mut a = vec![Pt3::origin(); g.n_vertices()];
    let mut b = a.clone();
    g.sample(t0, &mut a);
    let mut worst = 0.0f64;
    let mut t = t0;
    while t <= t1 + 1e-9 {
        g.sample(t, &mut b);
        worst = a.iter().zip(&b).map(|(x, y)| (x - y).norm()).fold(worst, f64::max);
        t += 1.0 / 30.0;
    }
    Ok(worst)
}

// ---------------------------------------------------------------------------------------------
// bag variants (§6.3, Fig. 9)

/// Guide time after which the silk and vinyl bags are compared (the landing is at 1.4 s).
const T_AFTER_LANDING: f64 = 1.5;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BagVariantsParams {
    /// Run settings, as in `tracks/bag`.
    run: PairParams,
    /// The variants run with `--quick` (names as in the summary keys); default and full run all.
    quick_variants: Vec<String>,
    /// `accordion`: relative amplitude and wavelength (m) of r ← r(1 + a sin(2πy/λ)).
    accordion: (f64, f64),
    /// `ribbon`: relative amplitude and lobe count of r ← r(1 + a|sin(nφ)|).
    ribbon: (f64, u32),
    /// `cellophane`: half-width (m) of the uniform rest offset along the normals and its seed.
    cellophane_noise: (f64, u64),
    /// `wind`: speed (m/s, along +x), turbulence amplitude and gust seed.
    wind: (f64, f64, u64),
}

impl BagVariantsParams {
    fn validate(&self) -> Result<()> {
        const S: &str = "tracks/bag-variants";
        validate_run(&self.run, S)?;
        let (a, l) = self.accordion;
        if !(a.is_finite() && (0.0..1.0).contains(&a) && l.is_finite() && l > 0.0) {
            return Err(bad(S, format!("accordion needs 0 ≤ amplitude < 1 and wavelength > 0 m, got ({a}, {l})")));
        }
        if !(self.ribbon.0.is_finite() && (0.0..1.0).contains(&self.ribbon.0)) {
            return Err(bad(S, format!("ribbon amplitude must be in [0, 1), got {}", self.ribbon.0)));
        }
        if !(self.cellophane_noise.0.is_finite() && (0.0..0.05).contains(&self.cellophane_noise.0)) {
            return Err(bad(S, format!("cellophane_noise must be in [0, 0.05) m, got {}", self.cellophane_noise.0)));
        }
        let (w, turb, _) = self.wind;
        if !(w.is_finite() && turb.is_finite() && (0.0..=1.0).contains(&turb)) {
            return Err(bad(S, format!("wind needs a finite speed and turbulence in [0, 1], got ({w}, {turb})")));
        }
        Ok(())
    }
}

/// Silk (undamped, flowy): the shells spec §4 preset table (ρ_s 0.08 kg/m², Yt 800 N/m, ν 0.3,
/// k_B 1e-6 J, α = β = 0); shells has no `Material::silk()` constructor.
fn silk() -> Material {
    iso_material(0.08, 800.0, 0.3, 1e-6, 0.0)
}

/// Side vertices of the bag's fine rest mesh: the ones `bag_setup` projected onto the cylinder
/// of radius 0.2 m (same test).
fn on_side(q: &Pt3) -> bool {
    q.y > 1e-9 || (q.x * q.x + q.z * q.z).sqrt() > 0.19
}

/// Scales the radius of every side vertex by `f(q)`; the bottom disc is unchanged. The initial
/// state is the new rest shape (the bag starts at rest).
fn radial(rest: &[Pt3], f: impl Fn(&Pt3) -> f64) -> Vec<Pt3> {
    rest.iter().map(|q| if on_side(q) { Pt3::new(q.x * f(q), q.y, q.z * f(q)) } else { *q }).collect()
}

/// The six Fig. 9 variants (spec §6.3) and `cellophane_vinyl` (ours).
fn bag_variants(p: &BagVariantsParams, smooth: &[Pt3], faces: &[[u32; 3]]) -> Vec<Variant> {
    let set_rest = |rest: Vec<Pt3>| -> Box<dyn Fn(&mut ShellSceneDesc)> {
        // The bag stands on the ground plane y = 0: the initial state is the rest shape lifted
        // to y ≥ 0 (offsets below the ground would start in contact).
        let init: Vec<Pt3> = rest.iter().map(|q| Pt3::new(q.x, q.y.max(0.0), q.z)).collect();
        Box::new(move |d: &mut ShellSceneDesc| {
            d.rest = rest.clone();
            d.initial = Some(init.clone());
        })
    };
    let (aa, al) = p.accordion;
    let accordion = radial(smooth, |q| 1.0 + aa * (std::f64::consts::TAU * q.y / al).sin());
    let (ra, rn) = p.ribbon;
    let ribbon = radial(smooth, |q| 1.0 + ra * (rn as f64 * q.z.atan2(q.x)).sin().abs());
    let (noise, seed) = p.cellophane_noise;
    let normals = vertex_normals(faces, smooth, NormalWeight::Area);
    let mut rng = Rng::new(seed);
    let cellophane: Vec<Pt3> = smooth.iter().zip(&normals).map(|(q, n)| q + *n * rng.range(-noise, noise)).collect();
    let cello_rest = set_rest(cellophane.clone());
    let (ws, wt, wseed) = p.wind;
    let mut wind = Wind::steady(Vec3::new(ws, 0.0, 0.0));
    wind.turbulence = wt;
    wind.seed = wseed;
    vec![
        Variant { name: "vinyl".into(), family: "bag", edit: Box::new(|d| d.material = vinyl()) },
        Variant { name: "silk".into(), family: "bag", edit: Box::new(|d| d.material = silk()) },
        Variant { name: "accordion".into(), family: "bag", edit: set_rest(accordion) },
        Variant { name: "ribbon".into(), family: "bag", edit: set_rest(ribbon) },
        Variant {
            name: "cellophane".into(),
            family: "bag",
            edit: Box::new(move |d| {
                cello_rest(d);
                d.material = rubber();
            }),
        },
        Variant { name: "wind".into(), family: "bag", edit: Box::new(move |d| d.effects.wind = Some(wind.clone())) },
        // Ours (not in the spec's list): the cellophane rest shape with the vinyl material, so the
        // runtime effect of the rough rest shape alone is measured against `vinyl`.
        Variant { name: "cellophane_vinyl".into(), family: "bag", edit: set_rest(cellophane) },
    ]
}

fn run_bag_variants(ctx: &RunCtx) -> Result<Summary> {
    let p: BagVariantsParams = scene::load(&ctx.scene_file)?.params;
    p.validate()?;
    let m = ctx.mode;
    let base = bag_setup(1, false)?;
    let all = bag_variants(&p, &base.tracked_rest.positions, &base.tracked_rest.faces);
    let q = &p.quick_variants;
    let (runs, duration) = run_variants(ctx, &p.run, all, q, "tracks/bag-variants", true, &|n, sc| bag_setup(n, sc))?;
    let mut s = Summary::new();
    let mut csv = CsvWriter::create(
        &ctx.out_dir.join("variants.csv"),
        &[
            "variant",
            "tracked_intersections_max",
            "guide_intersections_max",
            "max_residual_pre",
            "max_residual_post",
            "dc_mean",
            "dc_end",
            "a_d_mean_after_1_5s_m",
            "lambda_eff_mean_after_1_5s_m",
            "s_per_frame",
        ],
    )?;
    let after = |r: &VariantRun, v: &[f64]| r.window_mean(T_AFTER_LANDING, f64::INFINITY, v);
    for r in &runs {
        let n = &r.name;
        let it = r.out.isect_tracked.iter().copied().max().unwrap_or(0);
        let ig = r.out.isect_guide.iter().copied().max().unwrap_or(0);
        let dc_mean = r.window_mean(0.0, f64::INFINITY, &r.out.dc_tracked);
        let dc_end = r.out.dc_tracked.last().copied().unwrap_or(f64::NAN);
        let ad = after(r, &r.out.ad_tracked);
        let lam = after(r, &r.out.lambda_eff_tracked);
        s.set_count(&format!("tracked_intersections_max_{n}"), it as u64);
        s.set(&format!("max_residual_pre_{n}"), r.r_pre());
        s.set(&format!("max_residual_post_{n}"), r.r_post());
        s.set(&format!("dc_mean_{n}"), dc_mean);
        s.set(&format!("ad_mean_after_1_5s_{n}"), ad);
        s.set(&format!("lambda_eff_mean_after_1_5s_{n}"), lam);
        s.set(&format!("s_per_frame_{n}"), r.out.s_per_frame_tracked());
        csv.row(&[
            Cell::Text(n.clone()),
            Cell::Int(it as i64),
            Cell::Int(ig as i64),
            Cell::Num(r.r_pre()),
            Cell::Num(r.r_post()),
            Cell::Num(dc_mean),
            Cell::Num(dc_end),
            Cell::Num(ad),
            Cell::Num(lam),
            Cell::Num(r.out.s_per_frame_tracked()),
        ])?;
    }
    let max_of = |f: &dyn Fn(&VariantRun) -> usize| runs.iter().map(f).max().unwrap_or(0) as u64;
    s.set_count("tracked_intersections_max", max_of(&|r| r.out.isect_tracked.iter().copied().max().unwrap_or(0)));
    s.set_count(
        "tracked_intersecting_frames",
        runs.iter().map(|r| r.out.isect_tracked.iter().filter(|&&x| x > 0).count() as u64).sum(),
    );
    s.set_count("guide_intersections_max", max_of(&|r| r.out.isect_guide.iter().copied().max().unwrap_or(0)));
    s.set_count(
        "guide_self_intersecting_frames",
        runs.first().map_or(0, |r| r.out.isect_guide.iter().filter(|&&x| x > 0).count() as u64),
    );
    let (silk, vin) = (find(&runs, "silk"), find(&runs, "vinyl"));
    let (ratio, frac) = match (silk, vin) {
        (Some(a), Some(b)) => {
            let sel: Vec<(f64, f64)> = a
                .t()
                .iter()
                .zip(a.out.ad_tracked.iter().zip(&b.out.ad_tracked))
                .filter(|(t, _)| **t > T_AFTER_LANDING)
                .map(|(_, (x, y))| (*x, *y))
                .collect();
            let frac = sel.iter().filter(|(x, y)| x > y).count() as f64 / sel.len().max(1) as f64;
            let ratio = after(a, &a.out.ad_tracked) / after(b, &b.out.ad_tracked);
            if sel.is_empty() {
                (f64::NAN, f64::NAN)
            } else {
                (ratio, frac)
            }
        }
        _ => (f64::NAN, f64::NAN),
    };
    s.set("ad_silk_over_vinyl_after_1_5s", ratio);
    s.set("ad_silk_gt_vinyl_frame_fraction_after_1_5s", frac);
    let cello = find(&runs, "cellophane").map(|r| r.out.s_per_frame_tracked());
    let vinyl_spf = vin.map(|r| r.out.s_per_frame_tracked());
    let over_vinyl = |x: Option<f64>| match (x, vinyl_spf) {
        (Some(c), Some(v)) => c / v,
        _ => f64::NAN,
    };
    s.set("s_per_frame_cellophane_over_vinyl", over_vinyl(cello));
    let cv = find(&runs, "cellophane_vinyl").map(|r| r.out.s_per_frame_tracked());
    s.set("s_per_frame_cellophane_vinyl_over_vinyl", over_vinyl(cv));
    common_keys(&mut s, &runs, &p.run, m, duration);
    plot_family(&runs, None, "bag variants: detail amplitude a_d", "a_d (m)", false, &ctx.out_dir.join("ad_vs_t.png"))?;
    let mut dc = LinePlot::new("bag variants: coarse deviation D_c", "t (s)", "D_c (1/L)");
    for r in &runs {
        dc =
            dc.with(Series::new(r.name.clone(), r.t().iter().copied().zip(r.out.dc_tracked.iter().copied()).collect()));
    }
    dc.write_png(&ctx.out_dir.join("dc_vs_t.png"))?;
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::out::workspace_root;

    fn box_params() -> BoxVariantsParams {
        scene::load(&workspace_root().join("scenes/tracks/box-variants.ron")).expect("box-variants.ron parses").params
    }

    #[test]
    fn num_key_names() {
        assert_eq!(num_key(0.1), "0_1");
        assert_eq!(num_key(1.0), "1");
        assert_eq!(num_key(2e-3), "0_002");
        assert_eq!(num_key(-0.3), "m0_3");
    }

    /// The shipped box file validates, names the spec's 12 distinct runs (Yt × 1 and Δκ_max = ∞
    /// are the `kb_1` run) and its quick list selects existing variants.
    #[test]
    fn box_file_variants() {
        let p = box_params();
        p.validate().expect("valid");
        let names: Vec<String> = box_variants(&p).into_iter().map(|v| v.name).collect();
        assert_eq!(names.len(), 12, "{names:?}");
        for n in ["kb_0_1", "kb_10", "yt_0_3", "plastic_3_eta_p0_3", "plastic_3_eta_m0_3", "beta_0_002_rho_2"] {
            assert!(names.iter().any(|x| x == n), "{n} missing from {names:?}");
        }
        let quick = select(box_variants(&p), &p.quick_variants, Mode::Quick, "t").expect("quick names exist");
        assert_eq!(quick.len(), p.quick_variants.len());
    }

    /// Bad parameters are typed errors naming the parameter (no panic, no silent run).
    #[test]
    fn bad_parameters_are_clear_errors() {
        let mut p = box_params();
        p.kb_scale = vec![1.0, -2.0];
        assert!(p.validate().unwrap_err().to_string().contains("kb_scale"));
        let mut p = box_params();
        p.run.substeps = (0, 4, 4);
        assert!(p.validate().unwrap_err().to_string().contains("substeps"));
        let mut p = box_params();
        p.quick_variants = vec!["kb_7".into()];
        let e = select(box_variants(&p), &p.quick_variants, Mode::Quick, "t").err().expect("unknown name rejected");
        assert!(e.to_string().contains("kb_7"), "{e}");
        let bag: BagVariantsParams =
            scene::load(&workspace_root().join("scenes/tracks/bag-variants.ron")).expect("bag file parses").params;
        bag.validate().expect("shipped bag file is valid");
        let bad = BagVariantsParams { accordion: (1.5, 0.06), ..bag };
        assert!(bad.validate().unwrap_err().to_string().contains("accordion"));
        let text = "(method: \"tracks/bag-variants\", params: (run: (duration: (1.0, 1.0, 1.0), substeps: (1, 1, 1), \
                    self_collision: (true, true, true), kkt: ConstraintLastLdlt, refine_steps: 0, obj_every: 0), \
                    quick_variants: [], accordion: (0.06, 0.06), ribbon: (0.03, 24), cellophane_noise: (0.003, 1), \
                    wind: (12.0, 0.6, 7), colour: 3))";
        let e = scene::parse::<BagVariantsParams>(Path::new("x.ron"), text).expect_err("unknown field rejected");
        assert!(e.to_string().contains("colour"), "{e}");
    }
}
