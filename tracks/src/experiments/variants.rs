//! Material and dynamics variants of a tracked scene (Bergou et al. 2007 Fig. 8, 9): the same
//! guide, subdivision, test functions and metric filter L_τ, with only the fine shell's
//! description edited (material, rest shape, wind); every variant runs tracked only. The
//! machinery `tracks/box-variants` and `tracks/bag-variants` share.

use geom_core::experiment::{Report, Size};
use geom_core::record::{Cell, Recorder, Series};
use shells::ShellSceneDesc;

use super::protocol::{bad, run_pair, PairOpts, PairOut, PairParams};
use crate::error::Result;
use crate::metrics::{value_at, window_mean};
use crate::presets::{frames_for, Setup, ShellOptions};

/// An edit of a shell description.
pub type Edit = Box<dyn Fn(&mut ShellSceneDesc) + Send + Sync>;

/// One variant: a name (used in table names and summary keys), its family and how it changes
/// the shell description of the base scene.
pub struct Variant {
    /// Name (`kb_0_1`, `silk` …).
    pub name: String,
    /// Family (`stiffness`, `plastic`, `dynamics`, `bag`).
    pub family: &'static str,
    /// The edit.
    pub edit: Edit,
}

/// Figures of one variant run plus its time series.
pub struct VariantRun {
    /// The variant's name.
    pub name: String,
    /// Its family.
    pub family: &'static str,
    /// Bending stiffness k_B of the variant's material at t = 0 (J).
    pub k_b: f64,
    /// The run.
    pub out: PairOut,
}

impl VariantRun {
    /// Kinetic energy of frames ≥ 1 (J).
    pub fn ke(&self) -> &[f64] {
        self.out.ke_tracked.get(1..).unwrap_or(&[])
    }
    /// Value of a per-frame series (frames ≥ 1) at the frame nearest to `t` (within half a
    /// frame at `fps`), else NaN.
    pub fn at(&self, t: f64, v: &[f64], fps: f64) -> f64 {
        value_at(self.out.t(), v, t, 0.5 / fps)
    }
    /// Mean of a per-frame series (frames ≥ 1) over a − ε ≤ t ≤ b + ε, NaN when none.
    pub fn window_mean(&self, a: f64, b: f64, v: &[f64]) -> f64 {
        window_mean(self.out.t(), v, a, b)
    }
}

/// The variants of this run size: the `quick` names in quick and tiny, the `default` names in
/// default mode when given (else all), all in full (unknown names are an error listing the known
/// ones).
pub fn select(
    all: Vec<Variant>,
    quick: &[String],
    default: Option<&[String]>,
    size: Size,
    scene: &str,
) -> Result<Vec<Variant>> {
    let (names, field) = match (size, default) {
        (Size::Quick | Size::Tiny, _) => (quick, "quick_variants"),
        (Size::Default, Some(d)) => (d, "default_variants"),
        _ => return Ok(all),
    };
    for q in names {
        if !all.iter().any(|v| &v.name == q) {
            let known: Vec<&str> = all.iter().map(|v| v.name.as_str()).collect();
            return Err(bad(scene, format!("{field}: unknown variant `{q}`; known: {}", known.join(", "))));
        }
    }
    Ok(all.into_iter().filter(|v| names.contains(&v.name)).collect())
}

/// Runs `variants` tracked-only with `make_setup(shell options)` as the base scene (tables and
/// sequences tagged `_<variant>`); writes table `series`; returns the runs and the simulated
/// time (s).
pub fn run_variants(
    p: &PairParams,
    size: Size,
    variants: Vec<Variant>,
    intersections: bool,
    make_setup: &dyn Fn(&ShellOptions) -> Result<Setup>,
    rec: &mut dyn Recorder,
) -> Result<(Vec<VariantRun>, f64)> {
    let shell = p.shell(size);
    rec.table(
        "series",
        &["variant", "family", "t", "dc", "a_d_m", "lambda_eff_m", "kinetic_J", "isect_tracked", "isect_guide"],
    )?;
    let mut runs = Vec::new();
    let mut fps = 30.0;
    for v in variants {
        let setup = make_setup(&shell)?.edited(v.edit);
        fps = setup.fps;
        let o = PairOpts {
            frames: frames_for(p.duration.get(size), setup.fps),
            obj_every: p.obj_every,
            untracked: false,
            track: p.track(),
            intersections,
            anchors: None,
            tag: format!("_{}", v.name),
            subsets: Vec::new(),
        };
        let k_b = (setup.desc)().material.bending;
        let out = run_pair(&setup, &o, rec)?;
        let r = VariantRun { name: v.name, family: v.family, k_b, out };
        for i in 0..r.out.t().len() {
            rec.row(
                "series",
                &[
                    Cell::from(r.name.as_str()),
                    Cell::from(r.family),
                    Cell::from(r.out.t()[i]),
                    Cell::from(r.out.dc_tracked[i]),
                    Cell::from(r.out.ad_tracked[i]),
                    Cell::from(r.out.lambda_eff_tracked[i]),
                    Cell::from(r.ke()[i]),
                    Cell::from(r.out.isect_tracked[i + 1]),
                    Cell::from(r.out.isect_guide[i + 1]),
                ],
            )?;
        }
        runs.push(r);
    }
    let duration = frames_for(p.duration.get(size), fps) as f64 / fps;
    Ok((runs, duration))
}

/// Keys both variant scenes share: worst residuals (/L) over the variants and the run settings.
pub fn common_keys(r: &mut Report, runs: &[VariantRun], p: &PairParams, size: Size, duration: f64) {
    let pre: Vec<f64> = runs.iter().map(|v| v.out.r_pre()).collect();
    let post: Vec<f64> = runs.iter().map(|v| v.out.r_post()).collect();
    r.num("max_residual_pre", geom_core::stats::max(&pre));
    r.num("max_residual_post", geom_core::stats::max(&post));
    r.count("variants_run", runs.len() as u64);
    r.count("substeps", p.substeps.get(size) as u64);
    r.count("self_collision", p.self_collision.get(size) as u64);
    r.num("duration_s", duration);
    r.text("mode", size.name());
}

/// A number as a summary-key fragment: `0.1` → `0_1`, `2e-3` → `0_002`, `-0.3` → `m0_3`.
pub fn num_key(x: f64) -> String {
    let s = format!("{}", x.abs()).replace('.', "_");
    if x < 0.0 {
        format!("m{s}")
    } else {
        s
    }
}

/// 1 / 0 for a checked expectation, NaN (JSON null) when the variants it needs did not run.
pub fn flag(v: Option<bool>) -> f64 {
    v.map_or(f64::NAN, |b| if b { 1.0 } else { 0.0 })
}

/// The run named `name`.
pub fn find<'a>(runs: &'a [VariantRun], name: &str) -> Option<&'a VariantRun> {
    runs.iter().find(|r| r.name == name)
}

/// One curve per run of `family` (all runs when `None`) in plot `plot`: a_d(t), or the kinetic
/// energy on a log axis when `log_ke`.
pub fn plot_family(
    runs: &[VariantRun],
    family: Option<&str>,
    plot: &str,
    y: &str,
    log_ke: bool,
    rec: &mut dyn Recorder,
) -> Result<()> {
    for r in runs.iter().filter(|r| family.is_none_or(|f| f == r.family)) {
        let v = if log_ke { r.ke() } else { &r.out.ad_tracked[..] };
        rec.series(&Series {
            plot: plot.into(),
            label: r.name.clone(),
            axes: ("t (s)".into(), y.into()),
            log: (false, log_ke),
            points: r.out.t().iter().copied().zip(v.iter().copied()).collect(),
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn num_key_names() {
        assert_eq!(num_key(0.1), "0_1");
        assert_eq!(num_key(1.0), "1");
        assert_eq!(num_key(2e-3), "0_002");
        assert_eq!(num_key(-0.3), "m0_3");
    }

    /// Unknown names are an error listing the known ones; default size runs the default names when
    /// given, else all; full runs all.
    #[test]
    fn selection() {
        let mk = |n: &str| Variant { name: n.into(), family: "x", edit: Box::new(|_| {}) };
        let all = || vec![mk("a"), mk("b"), mk("c")];
        assert_eq!(select(all(), &["b".into()], None, Size::Quick, "s").unwrap().len(), 1);
        assert_eq!(select(all(), &["b".into()], None, Size::Default, "s").unwrap().len(), 3);
        let d = ["a".to_string(), "c".to_string()];
        let named: Vec<String> =
            select(all(), &["b".into()], Some(&d), Size::Default, "s").unwrap().into_iter().map(|v| v.name).collect();
        assert_eq!(named, ["a", "c"]);
        assert_eq!(select(all(), &["b".into()], Some(&d), Size::Full, "s").unwrap().len(), 3);
        let e = select(all(), &["z".into()], None, Size::Tiny, "s").err().expect("unknown name rejected");
        assert!(e.to_string().contains("`z`") && e.to_string().contains("a, b, c"), "{e}");
        let e = select(all(), &[], Some(&["y".to_string()]), Size::Default, "s").err().expect("unknown default name");
        assert!(e.to_string().contains("default_variants: unknown variant `y`"), "{e}");
    }
}
