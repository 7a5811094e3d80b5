//! `shells/plastic-crease` (shells.md §6 scene 5; TRACKS §4.4 bending plasticity): a foil strip
//! clamped at its left end; the half x ≥ `kinematic_from_x` is folded by `peak_deg` about the
//! strip's middle line and back ([`presets::fold_path`]), then released to settle. A table over
//! yield Δκ_max × hardening η, and a step-size study of the crease under the return map and the
//! seed-literal rule.
//!
//! Figures: `elastic_final_max_angle` (rad; the elastic strip must return flat),
//! `plastic_crease_spread` ((max − min)/mean over substeps of the geometric fold angle after
//! settling, return map), `plastic_crease_spread_max_hinge` (the same for the per-hinge crease
//! max|θ̄ − θ̄₀|), `seed_literal_crease_spread`, `seed_literal_crease_spread_max_hinge`,
//! `diverged_runs`, and the sanity figures over every step of every run
//! ([`super::contact::sanity_figures`]: `max_edge_strain`, `max_edge_compression`,
//! `max_obstacle_penetration_m`, `max_intersections` (counted once per frame time), `nan_steps`
//! (failed steps of diverged runs), …) with the timing `s_per_step`. A diverged run is a table row, and makes its spread NaN. Table `crease`.
//!
//! ```no_run
//! use geom_core::experiment::Size;
//! use geom_core::record::NullRecorder;
//! #[derive(serde::Deserialize)]
//! struct File { params: shells::experiments::plastic_crease::Params }
//! let f: File = ron::from_str(&std::fs::read_to_string("scenes/shells/plastic-crease.ron").unwrap()).unwrap();
//! let r = shells::experiments::plastic_crease::run(&f.params, Size::Tiny, &mut NullRecorder::default()).unwrap();
//! println!("{:?}", r.get("plastic_crease_spread"));
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, NullRecorder, Recorder};
use serde::Deserialize;

use super::protocol::{self, RunPlan, RunStats};
use crate::error::{Error, Result};
use crate::material::{PlasticRule, Plasticity};
use crate::metrics::{self, Sanity};
use crate::presets;
use crate::scene::ShellScene;
use crate::sim::{ShellSim, VertexConstraint};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The strip (a Grid mesh; its material's plasticity is replaced per run).
    pub shell: ShellScene,
    /// Grid (nx, ny) vertices per run size; `None` keeps the scene's mesh.
    #[serde(default)]
    pub resolution: Option<BySize<(u32, u32)>>,
    /// Steps per frame of the parameter table, per run size; `None` keeps the scene's.
    #[serde(default)]
    pub substeps: Option<BySize<u32>>,
    /// Kinematic half: vertices with x ≥ this (m) rotate about the strip's middle line x = 0
    /// (along y, in the sheet plane), folding toward +z.
    pub kinematic_from_x: f64,
    /// Peak rotation (degrees) reached at half of `motion_time`.
    pub peak_deg: f64,
    /// Duration of the there-and-back rotation (s).
    pub motion_time: f64,
    /// Settling time after release (s).
    pub settle_time: f64,
    /// Yield values Δκ_max (1/m; ≥ 1e299 means elastic).
    pub yields: Vec<f64>,
    /// Hardening values η (m).
    pub hardenings: Vec<f64>,
    /// Substeps of the step-size study, per run size.
    pub substeps_study: BySize<Vec<u32>>,
    /// Yield used in the step-size study (1/m).
    pub study_yield: f64,
}

/// What one fold-and-release run measured.
#[derive(Clone, Copy, Debug)]
pub struct CreaseOut {
    /// Geometric fold angle after settling (rad): angle between the clamp's first segment and
    /// the free end's last segment (middle row) — the integrated crease, insensitive to how the
    /// plastic rotation is spread over neighbouring hinges.
    pub fold: f64,
    /// max|θ̄ − θ̄₀| (rad): the largest rest-angle change of one hinge.
    pub crease: f64,
    /// The hinge stiffness ratio k/k₀ farthest from 1 (hardening).
    pub k_ratio: f64,
    /// max|θ| after settling (rad).
    pub final_max_angle: f64,
}

const NAN_OUT: CreaseOut = CreaseOut { fold: f64::NAN, crease: f64::NAN, k_ratio: f64::NAN, final_max_angle: f64::NAN };

/// The sanity watch shared by every run of the scene (one strip mesh): the invariants of
/// [`Sanity`] and the summed run statistics.
pub struct Watch {
    /// Edge strain and compression over every step of every run (no obstacle, no energy).
    pub sanity: Sanity,
    /// Every run's statistics merged.
    pub stats: RunStats,
}

impl Watch {
    /// A watch of the scene's strip.
    pub fn new(shell: &ShellScene) -> Result<Self> {
        let b = shell.build(std::path::Path::new("."))?;
        let sim = ShellSim::new(b.desc)?;
        let sanity = Sanity::new(&sim.mesh().rest, &sim.mesh().edges, Vec::new(), None);
        let mut stats = RunStats::default();
        stats.totals.contact.min_gap = f64::INFINITY;
        Ok(Self { sanity, stats })
    }

    /// Steps `sim` for `steps` steps of `h` through [`protocol::run`] (self-intersections
    /// counted every `count_every` steps); a failed step is an error.
    fn run(&mut self, sim: &mut ShellSim, steps: usize, h: f64, count_every: usize) -> Result<()> {
        let plan = RunPlan {
            frames: steps,
            substeps: 1,
            h,
            frame_every: count_every.max(1),
            sequence: "crease".into(),
            count_intersections: true,
            track_energy: false,
            tables: false,
        };
        let rs = protocol::run(sim, &plan, &mut self.sanity, &mut NullRecorder::default(), |_, _| {})?;
        self.stats.merge(&rs);
        match rs.error {
            Some(message) => Err(Error::RunFailed { scene: "plastic-crease".into(), steps: rs.steps, message }),
            None => Ok(()),
        }
    }
}

/// One run: fold the kinematic half there and back over `motion_time`, release it, let it
/// settle for `settle_time`, measure; every step is watched by `watch`.
pub fn crease_run(
    p: &Params,
    shell: &ShellScene,
    plasticity: Option<Plasticity>,
    substeps: u32,
    watch: &mut Watch,
) -> Result<CreaseOut> {
    let mut sh = shell.clone();
    sh.material.plasticity = plasticity;
    sh.integrator.substeps = substeps;
    let base = std::path::Path::new(".");
    let b = sh.build(base)?;
    let rest = b.desc.rest.clone();
    let kin: Vec<u32> = (0..rest.len() as u32).filter(|&i| rest[i as usize].x >= p.kinematic_from_x).collect();
    let path = presets::fold_path(rest.clone(), p.peak_deg.to_radians(), p.motion_time);
    let mut desc = b.desc;
    desc.constraints.push(VertexConstraint::Kinematic(kin, Box::new(path)));
    let h = sh.integrator.h();
    let mut sim = ShellSim::new(desc)?;
    let theta0 = sim.rest_angles();
    let k0 = sim.hinge_stiffness();
    let n1 = (p.motion_time / h).round() as usize;
    watch.run(&mut sim, n1, h, substeps as usize)?;
    // Release the kinematic half and let it settle.
    let b2 = sh.build(base)?;
    let grid = b2.grid;
    let mut d2 = b2.desc;
    d2.initial = Some(sim.state().q.clone());
    d2.initial_velocity = Some(sim.state().v.clone());
    let theta_bar = sim.rest_angles();
    let kk = sim.hinge_stiffness();
    let mut sim2 = ShellSim::new(d2)?;
    sim2.set_rest_angles(&theta_bar)?;
    sim2.set_hinge_stiffness(&kk)?;
    let n2 = (p.settle_time / h).round() as usize;
    watch.run(&mut sim2, n2, h, substeps as usize)?;
    let crease = metrics::max_abs_change(&sim2.rest_angles(), &theta0);
    let k_ratio = metrics::extreme_ratio(&sim2.hinge_stiffness(), &k0);
    let final_max_angle = metrics::max_abs(&sim2.hinge_angles(&sim2.state().q));
    let (nx, ny) = grid.ok_or_else(|| Error::BadParameter("plastic-crease needs a Grid mesh".into()))?;
    let row = (ny / 2) * nx;
    let q = &sim2.state().q;
    let d0 = q[row as usize + 1] - q[row as usize];
    let d1 = q[(row + nx - 1) as usize] - q[(row + nx - 2) as usize];
    Ok(CreaseOut { fold: metrics::segment_angle(&d0, &d1), crease, k_ratio, final_max_angle })
}

fn row(rec: &mut dyn Recorder, md: &mut String, rule: &str, y: f64, eta: f64, sub: u32, c: &CreaseOut) -> Result<()> {
    rec.row(
        "crease",
        &[
            Cell::Text(rule.into()),
            Cell::Num(y),
            Cell::Num(eta),
            Cell::Int(sub as i64),
            Cell::Num(c.fold),
            Cell::Num(c.crease),
            Cell::Num(c.k_ratio),
            Cell::Num(c.final_max_angle),
        ],
    )?;
    *md += &format!(
        "| {rule} | {y} | {eta} | {sub} | {:.4} | {:.4} | {:.3} | {:.4} |\n",
        c.fold, c.crease, c.k_ratio, c.final_max_angle
    );
    Ok(())
}

/// Runs the parameter table and the step-size study.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let mut shell = protocol::sized(&p.shell, p.resolution.as_ref(), None, size);
    if let Some(s) = &p.substeps {
        shell.integrator.substeps = s.get(size);
    }
    let study = p.substeps_study.get(size);
    let base_sub = shell.integrator.substeps;
    // Runs are deterministic: the table's (study yield, η = 0, base substeps) run is reused by the
    // step-size study instead of being simulated twice.
    let mut memo: Vec<((PlasticRule, u64, u64, u32), CreaseOut)> = Vec::new();
    rec.table(
        "crease",
        &[
            "rule",
            "yield_per_m",
            "hardening_m",
            "substeps",
            "fold_angle_rad",
            "crease_angle_rad",
            "stiffness_ratio",
            "final_max_angle_rad",
        ],
    )?;
    let mut md = String::new();
    let mut watch = Watch::new(&shell)?;
    let mut elastic_angle = f64::NAN;
    let mut diverged = 0u64;
    for &y in &p.yields {
        let etas: Vec<f64> = if y >= 1e299 { vec![0.0] } else { p.hardenings.clone() };
        for &eta in &etas {
            let pl = (y < 1e299).then_some(Plasticity {
                max_curvature_dev: y,
                hardening: eta,
                rule: PlasticRule::ReturnMapping,
            });
            match crease_run(p, &shell, pl, base_sub, &mut watch) {
                Ok(c) => {
                    if let Some(pl) = pl {
                        memo.push(((pl.rule, y.to_bits(), eta.to_bits(), base_sub), c));
                    } else {
                        elastic_angle = c.final_max_angle;
                    }
                    row(rec, &mut md, "ReturnMapping", y, eta, base_sub, &c)?;
                }
                // A diverging combination is reported in the table, not fatal for the scene.
                Err(e) => {
                    diverged += 1;
                    let rule = format!("ReturnMapping (diverged: {e})").replace(',', ";");
                    row(rec, &mut md, &rule, y, eta, base_sub, &NAN_OUT)?;
                }
            }
        }
    }
    // Step-size study: spread (max − min)/mean over substeps of the geometric fold angle after
    // settling (the integrated crease: `plastic_crease_spread`) and of the largest rest-angle
    // change max|θ̄ − θ̄₀| (spec §6.5's per-hinge crease angle: `…_max_hinge`); a diverged run
    // makes the spread NaN (reported, not hidden).
    let mut spreads = Vec::new();
    for rule in [PlasticRule::ReturnMapping, PlasticRule::SeedLiteral] {
        let (mut folds, mut creases) = (Vec::new(), Vec::new());
        for &sub in &study {
            let pl = Plasticity { max_curvature_dev: p.study_yield, hardening: 0.0, rule };
            let key = (rule, p.study_yield.to_bits(), 0f64.to_bits(), sub);
            let res = match memo.iter().find(|(k, _)| *k == key) {
                Some((_, c)) => Ok(*c),
                None => crease_run(p, &shell, Some(pl), sub, &mut watch),
            };
            let c = match res {
                Ok(c) => {
                    row(rec, &mut md, &format!("{rule:?}"), p.study_yield, 0.0, sub, &c)?;
                    c
                }
                Err(e) => {
                    diverged += 1;
                    let name = format!("{rule:?} (diverged: {e})").replace(',', ";");
                    row(rec, &mut md, &name, p.study_yield, 0.0, sub, &NAN_OUT)?;
                    NAN_OUT
                }
            };
            folds.push(c.fold);
            creases.push(c.crease);
        }
        spreads.push((metrics::relative_spread(&folds), metrics::relative_spread(&creases)));
    }
    rec.note(&format!(
        "### shells/plastic-crease\n\nFoil strip, one end pinned, the other half rotated by {}° and back, then released.\n\n\
         | rule | Δκ_max (1/m) | η (m) | substeps | fold angle (rad) | max|θ̄−θ̄₀| (rad) | k/k₀ | final max|θ| (rad) |\n\
         |---|---|---|---|---|---|---|---|\n{md}\nStep-size spread of the fold angle after settling: return map {:.4}, \
         seed-literal {:.4}; of the largest rest-angle change max|θ̄−θ̄₀|: {:.4} and {:.4}.\n",
        p.peak_deg, spreads[0].0, spreads[1].0, spreads[0].1, spreads[1].1
    ))?;
    let mut r = Report::default();
    r.num("elastic_final_max_angle", elastic_angle);
    r.num("plastic_crease_spread", spreads[0].0);
    r.num("plastic_crease_spread_max_hinge", spreads[0].1);
    r.num("seed_literal_crease_spread", spreads[1].0);
    r.num("seed_literal_crease_spread_max_hinge", spreads[1].1);
    r.count("diverged_runs", diverged);
    super::contact::sanity_figures(&mut r, "", &watch.sanity, &watch.stats);
    r.timing("s_per_step", watch.stats.s_per_step());
    let src = "shells.md §6.5 (elastic returns flat; return-map crease step-size independent)";
    r.check("elastic_final_max_angle", Target::Below(0.02), src);
    r.check("plastic_crease_spread", Target::Below(0.05), src);
    Ok(r)
}
