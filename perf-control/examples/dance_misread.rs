//! PC-4 diagnostic (issue 27, README "the semantic miss"): for every true two-beat segment the
//! offline DP misreads at the main cue (the first of a run of consecutive misreads), compare the
//! chosen chain with the best chain that differs only by putting right-labelled instances on the
//! whole run (up to 4 segments, same boundaries): is the misread in the control signal (`ΔD`, the control explains the wrong
//! instance better) or in the continuity (`k·ΔC`)? Also the rank of the best right-label instance
//! among all instances by `D` on the misread window.
//!
//! `cargo run --release -p perf-control --example dance_misread` (default size, ≈ 1 min).

use geom_core::experiment::Size;
use perf_control::cell::{eval_cell, Column};
use perf_control::data::duet::{test_dances, DuetParams};
use perf_control::eval::dance::segment_labels;
use perf_control::experiments::{dance, load_params};
use perf_control::presets::dance_database;
use perf_control::{interpret, score_chain};

/// A chain as (instance, start, end) per segment.
type Chain = Vec<(u32, i64, i64)>;
/// The best substitution so far: score, `ΣD`, `ΣC`, `C` at the run's junctions, the chain.
type Best = (f64, f64, f64, Vec<f64>, Chain);

fn main() -> perf_control::Result<()> {
    let p: dance::Params = load_params(std::path::Path::new("scenes/perf-control/dance.ron"))?;
    let cue: f64 = std::env::args().nth(1).map_or(p.duet.toggle_cue_m, |s| s.parse().expect("cue (m)"));
    let duet = DuetParams { toggle_cue_m: cue, ..p.duet.clone() };
    let (w, _) = dance_database(&p.database, &duet, p.dp.stretch_limit_s, Size::Default)?;
    let db = &w.db;
    let tests = test_dances(&duet, p.test_seed, None)?;
    println!(
        "cue {cue} m; dance seg true -> out | window | dS dD kdC (right - wrong) | D ranks of the best right instance per window (of {})",
        db.instances.len()
    );
    for (k, (take, truth)) in tests.iter().enumerate() {
        let x = take.control.downsample(p.database.factor);
        let it = interpret(db, &x, &p.dp)?;
        let out = segment_labels(db, &it, truth);
        let chain: Vec<(u32, i64, i64)> = it.segments.iter().map(|s| (s.instance, s.start, s.end)).collect();
        let cover = |secs: f64| {
            let pos = secs * x.rate_hz;
            it.segments.iter().position(|s| (s.start as f64) <= pos && pos <= s.end as f64).expect("covered")
        };
        for (i, &(a, b, l)) in truth.segments.iter().enumerate() {
            if out[i] == Some(l) {
                continue;
            }
            let j = cover(0.5 * (a + b));
            let of = |l| {
                db.instances.iter().enumerate().filter(move |(_, s)| s.label.dance() == Some(l)).map(|(n, _)| n as u32)
            };
            let (s0, e0) = (chain[j].1, chain[j].2);
            // Control only: D of every instance on window j.
            let mut ds: Vec<(f64, u32)> = (0..db.instances.len() as u32)
                .filter_map(|n| score_chain(db, &x, &[(n, s0, e0)], &p.dp).map(|s| (s.d_total, n)))
                .collect();
            ds.sort_by(|a, b| a.0.total_cmp(&b.0));
            let rank = ds.iter().position(|&(_, n)| db.instances[n as usize].label.dance() == Some(l));
            // Best substitution of the run by right-labelled instances.
            let mut best: Option<Best> = None;
            // The whole run of consecutive misread segments from i (each on its own chain segment).
            if i > 0 && out[i - 1] != Some(truth.segments[i - 1].2) {
                continue;
            }
            let mut js: Vec<(usize, perf_control::dance::grammar::DanceLabel)> = vec![(j, l)];
            let mut n = i + 1;
            while let Some(&(a2, b2, l2)) = truth.segments.get(n) {
                let j2 = cover(0.5 * (a2 + b2));
                if out[n] == Some(l2) || j2 != js[js.len() - 1].0 + 1 || js.len() == 4 {
                    break;
                }
                js.push((j2, l2));
                n += 1;
            }
            // D rank of the best right-labelled instance on each window of the run (0 = best).
            let ranks: Vec<Option<usize>> = js
                .iter()
                .map(|&(jj, l)| {
                    let mut d: Vec<(f64, u32)> = (0..db.instances.len() as u32)
                        .filter_map(|n| {
                            score_chain(db, &x, &[(n, chain[jj].1, chain[jj].2)], &p.dp).map(|s| (s.d_total, n))
                        })
                        .collect();
                    d.sort_by(|a, b| a.0.total_cmp(&b.0));
                    d.iter().position(|&(_, n)| db.instances[n as usize].label.dance() == Some(l))
                })
                .collect();
            let cands: Vec<Vec<u32>> = js.iter().map(|&(_, l)| of(l).collect()).collect();
            let mut idx = vec![0usize; js.len()];
            loop {
                let mut c2 = chain.clone();
                for (q, &(jj, _)) in js.iter().enumerate() {
                    c2[jj].0 = cands[q][idx[q]];
                }
                if let Some(s) = score_chain(db, &x, &c2, &p.dp) {
                    if best.as_ref().is_none_or(|b| s.score < b.0) {
                        let (j0, j1) = (js[0].0, (js[js.len() - 1].0 + 1).min(chain.len() - 1));
                        let cs = (j0..=j1).map(|q| s.segments[q].c).collect();
                        best = Some((s.score, s.d_total, s.c_total, cs, c2.clone()));
                    }
                }
                let mut q = 0;
                while q < idx.len() {
                    idx[q] += 1;
                    if idx[q] < cands[q].len() {
                        break;
                    }
                    idx[q] = 0;
                    q += 1;
                }
                if q == idx.len() {
                    break;
                }
            }
            let wrong = score_chain(db, &x, &chain, &p.dp).expect("the DP's chain scores");
            let (bs, bd, bc, bcs, bchain) = best.unwrap_or((f64::NAN, f64::NAN, f64::NAN, vec![], chain.clone()));
            let (j0, j1) = (js[0].0, (js[js.len() - 1].0 + 1).min(chain.len() - 1));
            let wcs: Vec<String> = (j0..=j1).map(|q| format!("{:.3}", wrong.segments[q].c)).collect();
            let rcs: Vec<String> = bcs.iter().map(|c| format!("{c:.3}")).collect();
            let outl = out[i].map_or("none".to_string(), |o| o.to_string());
            println!(
                "{k} {i:3} {l} -> {outl} | [{s0},{e0}] run {} | dS {:+.4} dD {:+.4} kdC {:+.4} | ranks {ranks:?} (window 1: best D {:.4}, best right D {:.4})",
                js.len(),
                bs - wrong.score,
                bd - wrong.d_total,
                p.dp.k * (bc - wrong.c_total),
                ds[0].0,
                rank.map_or(f64::NAN, |r| ds[r].0),
            );
            println!(
                "      C at the run's junctions (entry … exit): wrong [{}] right [{}]",
                wcs.join(" "),
                rcs.join(" ")
            );
            // Per target point (follower left hand, right hand, left ankle, right ankle): the
            // squared gap (m²) at the right chain's costliest junction, and the wrong chain's there.
            if let Some((q, _)) = bcs.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) {
                let jq = j0 + q;
                let gaps = |ch: &[(u32, i64, i64)]| -> Vec<String> {
                    let cell = |c: (u32, i64, i64)| {
                        let col = Column::new(db, c.0, (c.2 - c.1) as usize);
                        eval_cell(&x, &col, c.1, &db.control_weights).expect("in range")
                    };
                    let (a, b) = (cell(ch[jq - 1]), cell(ch[jq]));
                    (0..db.target_points())
                        .map(|p| format!("{:.3}", (a.omega[p] - b.alpha[p]).norm_squared()))
                        .collect()
                };
                println!(
                    "      junction {jq}: per-point gap² wrong [{}] right [{}]",
                    gaps(&chain).join(" "),
                    gaps(&bchain).join(" ")
                );
            }
        }
    }
    Ok(())
}
