//! PC-4 diagnostic (issue 27, README "the semantic miss"): for every true two-beat segment the
//! offline DP misreads at the main cue, compare the chosen chain with the best chain that differs
//! only by putting right-labelled instances on the misread segment and the one after it (same
//! boundaries): is the misread in the control signal (`ΔD`, the control explains the wrong
//! instance better) or in the continuity (`k·ΔC`)? Also the rank of the best right-label instance
//! among all instances by `D` on the misread window.
//!
//! `cargo run --release -p perf-control --example dance_misread` (default size, ≈ 1 min).

use geom_core::experiment::Size;
use perf_control::data::duet::{test_dances, DuetParams};
use perf_control::eval::dance::segment_labels;
use perf_control::experiments::{dance, load_params};
use perf_control::presets::dance_database;
use perf_control::{interpret, score_chain};

fn main() -> perf_control::Result<()> {
    let p: dance::Params = load_params(std::path::Path::new("scenes/perf-control/dance.ron"))?;
    let cue: f64 = std::env::args().nth(1).map_or(p.duet.toggle_cue_m, |s| s.parse().expect("cue (m)"));
    let duet = DuetParams { toggle_cue_m: cue, ..p.duet.clone() };
    let (w, _) = dance_database(&p.database, &duet, p.dp.stretch_limit_s, Size::Default)?;
    let db = &w.db;
    let tests = test_dances(&duet, p.test_seed, None)?;
    println!(
        "cue {cue} m; dance seg true -> out | window | dS dD kdC (right - wrong) | D rank of best right (of {})",
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
            let next = truth.segments.get(i + 1).map(|&(a2, b2, l2)| (cover(0.5 * (a2 + b2)), l2));
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
            // Best substitution of j (and j + 1 when it is misread too) by right-labelled instances.
            let mut best: Option<(f64, f64, f64)> = None;
            let js: Vec<(usize, perf_control::dance::grammar::DanceLabel)> = match next {
                Some((j2, l2)) if j2 == j + 1 && out[i + 1] != Some(l2) => vec![(j, l), (j2, l2)],
                _ => vec![(j, l)],
            };
            let cands: Vec<Vec<u32>> = js.iter().map(|&(_, l)| of(l).collect()).collect();
            let mut idx = vec![0usize; js.len()];
            loop {
                let mut c2 = chain.clone();
                for (q, &(jj, _)) in js.iter().enumerate() {
                    c2[jj].0 = cands[q][idx[q]];
                }
                if let Some(s) = score_chain(db, &x, &c2, &p.dp) {
                    if best.is_none_or(|b| s.score < b.0) {
                        best = Some((s.score, s.d_total, s.c_total));
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
            let (bs, bd, bc) = best.unwrap_or((f64::NAN, f64::NAN, f64::NAN));
            let outl = out[i].map_or("none".to_string(), |o| o.to_string());
            println!(
                "{k} {i:3} {l} -> {outl} | [{s0},{e0}] subst {} | dS {:+.4} dD {:+.4} kdC {:+.4} | rank {:?} (best wrong D {:.4}, best right D {:.4})",
                js.len(),
                bs - wrong.score,
                bd - wrong.d_total,
                p.dp.k * (bc - wrong.c_total),
                rank,
                ds[0].0,
                rank.map_or(f64::NAN, |r| ds[r].0),
            );
        }
    }
    Ok(())
}
