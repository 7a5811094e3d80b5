//! S10 (spec §6): the drop-pool geometry run adaptive (coarsest 8) and uniform (coarsest =
//! finest) at the same finest resolutions; particle and wall-time ratios at the largest one, and
//! the cost and particle exponents over the compared resolutions; and the spec's equal-result
//! checks that make the ratios meaningful (issue 26): the potential energy above the rest state's
//! over time and the splash height above the rest surface, adaptive against uniform.
//!
//! ```no_run
//! use flip_tet::experiments::adaptivity_payoff;
//! use geom_core::experiment::Size;
//! let r = adaptivity_payoff::run(&flip_tet::presets::adaptivity_payoff(), Size::Quick, &mut geom_core::record::NullRecorder::default())?;
//! println!("particle ratio {}", r.get_f64("particle_ratio_adaptive_over_uniform"));
//! # Ok::<(), flip_tet::error::SimError>(())
//! ```

use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::record::{Cell, Recorder};
use serde::{Deserialize, Serialize};

use super::{one, plot, simulate, sized_scene, FrameOutput, RunOut};
use crate::error::Result;
use crate::metrics::{interp, profile, rest_potential_energy, splash_height};
use crate::scene::Scene;

/// Parameters (the scene file's `params`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The scene (drop into a pool).
    pub scene: Scene,
    /// Finest resolution per size (overridden per compared size).
    pub finest: BySize<u32>,
    /// Duration per size (s).
    pub duration: BySize<f64>,
    /// Surface OBJ every this many frames (0 = never; sub-runs write none).
    #[serde(default = "one")]
    pub obj_every: u64,
    /// The finest resolutions compared, per size.
    pub sizes: BySize<Vec<u32>>,
}

/// Runs S10.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let base = sized_scene(&p.scene, &p.finest, None, &p.duration, size);
    let list = p.sizes.get(size);
    rec.table("cost_vs_n", &["finest", "variant", "particle_steps", "particles_avg", "wall_s", "steps"])?;
    let mut s = Report::default();
    let mut cost = (Vec::new(), Vec::new());
    let mut parts = (Vec::new(), Vec::new());
    let mut last = (0.0, 0.0, 0.0, 0.0);
    // Per variant of the last compared size: potential energy above the rest state's over time
    // (J) and the splash height above the rest surface (m).
    let mut pe: [Vec<(f64, f64)>; 2] = [Vec::new(), Vec::new()];
    let mut splash = [f64::NAN; 2];
    for &n in &list {
        for adaptive in [true, false] {
            let mut sc = base.clone();
            sc.resolution.finest = n;
            if !adaptive {
                sc.resolution.coarsest = n;
            }
            let name = if adaptive { "adaptive" } else { "uniform" };
            let dir = format!("{name}_{n}/");
            let mut tops = Vec::new();
            let run = simulate(&sc, rec, RunOut::full(&dir, FrameOutput::NONE), &mut |sim, st| {
                tops.push((st.t, crate::metrics::liquid_top(sim.particles())));
                Ok(())
            })?;
            let stats = &run.stats;
            let ps: f64 = stats.iter().map(|x| x.n_particles as f64).sum();
            let avg = ps / stats.len().max(1) as f64;
            rec.row(
                "cost_vs_n",
                &[
                    Cell::Int(i64::from(n)),
                    Cell::Text(name.into()),
                    Cell::Num(ps),
                    Cell::Num(avg),
                    Cell::Num(run.wall),
                    Cell::Int(stats.len() as i64),
                ],
            )?;
            let sim_t = stats.last().map_or(1.0, |x| x.t).max(1e-9);
            let (pe_rest, h_rest) = rest_potential_energy(&sc, run.sim.particles());
            let k = usize::from(!adaptive);
            pe[k] = stats.iter().map(|x| (x.t, x.potential_energy - pe_rest)).collect();
            splash[k] = splash_height(&tops, h_rest);
            if adaptive {
                cost.0.push((f64::from(n), run.wall / sim_t));
                parts.0.push((f64::from(n), avg));
                last.0 = avg;
                last.2 = run.wall;
            } else {
                cost.1.push((f64::from(n), run.wall / sim_t));
                parts.1.push((f64::from(n), avg));
                last.1 = avg;
                last.3 = run.wall;
            }
        }
    }
    s.num("finest_compared", f64::from(*list.last().unwrap_or(&0)));
    s.num("particle_ratio_adaptive_over_uniform", last.0 / last.1.max(1.0));
    s.timing("time_ratio_adaptive_over_uniform", last.2 / last.3.max(1e-12));
    s.text("profile", profile());
    let beta = |v: &Vec<(f64, f64)>| {
        if v.len() >= 2 {
            (v[v.len() - 1].1 / v[0].1).ln() / (v[v.len() - 1].0 / v[0].0).ln()
        } else {
            f64::NAN
        }
    };
    // Equal-result checks (spec §6 S10): relative L2 over time of the potential energy above the
    // rest state's (adaptive read at the uniform run's step times), and the splash heights.
    let num: f64 = pe[1].iter().map(|&(t, e)| (interp(&pe[0], t) - e).powi(2)).sum();
    let den: f64 = pe[1].iter().map(|&(_, e)| e * e).sum();
    s.num("potential_energy_rel_l2_diff", if den > 0.0 { (num / den).sqrt() } else { f64::NAN });
    s.num("splash_height_adaptive_m", splash[0]);
    s.num("splash_height_uniform_m", splash[1]);
    s.num("splash_height_rel_diff", (splash[0] - splash[1]).abs() / splash[1].abs());
    s.check(
        "potential_energy_rel_l2_diff",
        Target::AtMost(0.05),
        "spec §6 S10 / issue 26: equal potential-energy curves",
    );
    s.check("splash_height_rel_diff", Target::AtMost(0.15), "spec §6 S10 / issue 26: equal splash height");
    let ax = ("t (s)", "potential energy above rest (J)");
    plot(rec, "potential_energy", "adaptive", ax, (false, false), pe[0].clone())?;
    plot(rec, "potential_energy", "uniform", ax, (false, false), pe[1].clone())?;
    s.num("beta_particles_adaptive", beta(&parts.0));
    s.num("beta_particles_uniform", beta(&parts.1));
    s.timing("alpha_cost_adaptive", beta(&cost.0));
    s.timing("alpha_cost_uniform", beta(&cost.1));
    s.check(
        "particle_ratio_adaptive_over_uniform",
        Target::AtMost(0.35),
        "spec §6 S10: adaptive ≤ 35 % of uniform particles",
    );
    s.check("time_ratio_adaptive_over_uniform", Target::AtMost(0.5), "spec §6 S10: adaptive ≤ 50 % of uniform time");
    let ax = ("N", "wall s per simulated s");
    plot(rec, "cost_vs_N", "adaptive", ax, (true, true), cost.0)?;
    plot(rec, "cost_vs_N", "uniform", ax, (true, true), cost.1)?;
    let ax = ("N", "particles (avg)");
    plot(rec, "particles_vs_N", "adaptive", ax, (true, true), parts.0)?;
    plot(rec, "particles_vs_N", "uniform", ax, (true, true), parts.1)?;
    Ok(s)
}
