//! Study of the MG-1 problems the search does not solve: what the guided beam alone reaches at
//! several widths (best body errors of the beam's paths, per problem), and the problems'
//! geometry (chord speeds and turns). `cargo run --release -p motion-graph --example mg_study --
//! [problems,comma,separated] [widths,comma,separated] [runs]`.

use std::time::Instant;

use geom_core::anim::synth::{library, Preset};
use motion_graph::{
    random_mg1, Database, DbParams, GraphParams, GuidedParams, MotionGraph, Search, SearchParams, Weights,
};

fn list(i: usize, default: &str) -> Vec<usize> {
    std::env::args().nth(i).unwrap_or_else(|| default.to_string()).split(',').filter_map(|s| s.parse().ok()).collect()
}

fn main() -> motion_graph::Result<()> {
    if std::env::var("MG_TWO").is_ok() {
        return two_characters();
    }
    let which = list(1, "0,3,4,8,11,13,14");
    let widths = list(2, "24,96");
    let runs: u64 = std::env::args().nth(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let db = Database::from_motions(
        library(Preset::Football, 80, (150, 300), 30.0, 7),
        &DbParams { rate_hz: 30.0, max_clip_frames: 300, ..Default::default() },
    )?;
    let g = MotionGraph::build(
        db,
        &GraphParams { target_edges_per_frame: 30.0, min_self_gap: 15, k_max: 16, ..Default::default() },
    )?;
    let problems = random_mg1(20, 300, 30.0, (1, 3), 4.0, (0.3, 0.8), 1.0, 11, Weights::default());
    for &k in &which {
        let pb = &problems[k];
        let seg: Vec<String> = pb
            .body
            .windows(2)
            .map(|w| {
                let (dx, dz) = (w[1].x - w[0].x, w[1].z - w[0].z);
                let dt = (w[1].time - w[0].time) as f64 / 30.0;
                format!(
                    "t{}→{} {:.1}m/s dir {:.0}°",
                    w[0].time,
                    w[1].time,
                    dx.hypot(dz) / dt,
                    dx.atan2(dz).to_degrees()
                )
            })
            .collect();
        println!(
            "problem {k}: {} | end yaw {:.0}°",
            seg.join(", "),
            pb.body.last().and_then(|c| c.yaw).map_or(f64::NAN, f64::to_degrees)
        );
        if std::env::var("MG_EXACT").is_ok() {
            // Exhaustive 0- and 1-cut paths (leaf edges) to the first constraint alone.
            let b1 = &pb.body[1];
            let t1 = b1.time;
            let start = motion_graph::Rigid2::from(geom_core::math::Planar::new(0.0, 0.0, 0.0));
            let err = |w: &motion_graph::Rigid2| (w.x - b1.x).hypot(w.z - b1.z);
            let mut best0 = f64::INFINITY;
            for c in 0..g.db.clips.len() as u32 {
                let len = g.clip_len(c);
                for s0 in 0..len.saturating_sub(t1) {
                    let w0 = start.compose(&g.torso_r(c, s0).inverse());
                    best0 = best0.min(err(&w0.compose(&g.torso_r(c, s0 + t1))));
                }
            }
            let mut best1 = (f64::INFINITY, 0.0);
            let mut under = 0usize;
            for (e, n) in g.edges.iter().enumerate() {
                if !n.is_leaf() {
                    continue;
                }
                let (i, j) = (n.from.frame, n.to.frame);
                let lo = i.saturating_sub(t1 - 1);
                for s0 in lo..=i.saturating_sub(5) {
                    if i + 1 - s0 < 6 {
                        break;
                    }
                    let t_in = i - s0 + 1;
                    if t_in > t1 {
                        continue;
                    }
                    let f = j + (t1 - t_in);
                    if f >= g.clip_len(n.to.clip) {
                        continue;
                    }
                    let w0 = start.compose(&g.torso_r(n.from.clip, s0).inverse());
                    let w1 = w0.compose(&g.delta[e]);
                    let wt = w1.compose(&g.torso_r(n.to.clip, f));
                    let d = err(&wt);
                    if d < 0.3 {
                        under += 1;
                    }
                    if d < best1.0 {
                        best1 = (d, wt.yaw.to_degrees());
                    }
                }
            }
            println!(
                "  exact first constraint (t {t1}): 0 cuts {best0:.2} m; 1 leaf cut {:.2} m (yaw there {:.0}°), {under} one-cut paths within 0.3 m",
                best1.0, best1.1
            );
            continue;
        }
        if std::env::var("MG_PREFIX").is_ok() {
            // Truncated problems: the first j constraints only (reachability of each prefix).
            for j in 1..pb.body.len() {
                let mut q = pb.clone();
                q.body.truncate(j + 1);
                q.length = Some(q.body[j].time + 1);
                let tol = motion_graph::Tolerance::default();
                let sp = SearchParams {
                    seeds: 20,
                    keep_best: 2,
                    population_cap: 32,
                    max_mutations: 300,
                    rng_seed: 5,
                    guided: GuidedParams { width: 96, every: 4, one_cut_draws: 300, ..Default::default() },
                    ..Default::default()
                };
                let t = Instant::now();
                let beam_only = std::env::var("MG_BEAM").ok().and_then(|v| v.parse::<usize>().ok());
                let sp = match beam_only {
                    Some(w) => SearchParams {
                        seeds: 1,
                        guided: GuidedParams {
                            width: w,
                            one_cut_draws: 300,
                            projection_share: std::env::var("MG_PS").ok().and_then(|v| v.parse().ok()).unwrap_or(0.5),
                            aimed_starts: std::env::var("MG_AS").ok().and_then(|v| v.parse().ok()).unwrap_or(0.5),
                            ..Default::default()
                        },
                        ..sp
                    },
                    None => sp,
                };
                let mut s = Search::new(&g, q, sp)?;
                if beam_only.is_none() {
                    s.run_until(&tol, std::time::Duration::from_secs_f64(4.0), 100_000);
                }
                let b = s.best().expect("Search::new seeds a non-empty population or errors");
                let e: Vec<String> = b.errors.body_pos.iter().skip(1).map(|x| format!("{x:.2}")).collect();
                println!(
                    "  prefix {j}: {:.2} s, {} it, err [{}], yaw {:.1}°",
                    t.elapsed().as_secs_f64(),
                    s.iterations(),
                    e.join(" "),
                    b.errors.body_yaw_deg.last().copied().unwrap_or(f64::NAN)
                );
            }
            continue;
        }
        for &w in &widths {
            for r in 0..runs {
                let t = Instant::now();
                let sp = SearchParams {
                    seeds: 1,
                    rng_seed: 100 + r,
                    guided: GuidedParams {
                        width: w,
                        one_cut_draws: 300,
                        projection_share: std::env::var("MG_PS").ok().and_then(|v| v.parse().ok()).unwrap_or(0.5),
                        ..Default::default()
                    },
                    ..Default::default()
                };
                let s = Search::new(&g, pb.clone(), sp)?;
                let b = s.best().expect("Search::new seeds a non-empty population or errors");
                let e: Vec<String> = b.errors.body_pos.iter().skip(1).map(|x| format!("{x:.2}")).collect();
                println!(
                    "  width {w:4} run {r}: {:.3} s, score {:.2}, err [{}], yaw {:.1}°, pop {}",
                    t.elapsed().as_secs_f64(),
                    b.score,
                    e.join(" "),
                    b.errors.body_yaw_deg.last().copied().unwrap_or(f64::NAN),
                    s.population().len()
                );
            }
        }
    }
    Ok(())
}

/// MG-5 (`two-characters`, default mode: 80 `Mixed` clips, seed 5, 10 edges per frame):
/// exhaustive 0- and 1-leaf-cut paths that play a `wave` frame at frame 150, with the error to
/// each character's body constraint there (position and heading).
fn two_characters() -> motion_graph::Result<()> {
    use geom_core::math::{wrap_angle, Planar};
    use motion_graph::Rigid2;
    let db = Database::from_motions(
        library(Preset::Mixed, 80, (150, 300), 30.0, 5),
        &DbParams { rate_hz: 30.0, max_clip_frames: 300, ..Default::default() },
    )?;
    let g = MotionGraph::build(db, &GraphParams::default())?;
    let bit = g.db.label_bit("wave").expect("the Mixed database has wave frames");
    let wave = |c: u32, f: u32| g.db.clips[c as usize].labels.bits.get(f as usize).is_some_and(|b| b & bit != 0);
    let t = 150u32;
    // (start x, z, yaw) and (target x, z, yaw) of the two characters (scene file, degrees → rad).
    let chars = [((-3.0, -2.0, 45.0f64), (-0.75, 0.0, 90.0f64)), ((3.0, 2.0, -135.0), (0.75, 0.0, -90.0))];
    for (k, (st, tg)) in chars.iter().enumerate() {
        let start = Rigid2::from(Planar::new(st.0, st.1, st.2.to_radians()));
        let err = |w: &Rigid2| {
            let e = (w.x - tg.0).hypot(w.z - tg.1);
            let dy = wrap_angle(w.yaw - tg.2.to_radians()).abs().to_degrees();
            (e, dy)
        };
        let mut best0 = (f64::INFINITY, 0.0);
        for c in 0..g.db.clips.len() as u32 {
            for f in t..g.clip_len(c) {
                if wave(c, f) {
                    let w0 = start.compose(&g.torso_r(c, f - t).inverse());
                    let e = err(&w0.compose(&g.torso_r(c, f)));
                    if e.0 < best0.0 {
                        best0 = e;
                    }
                }
            }
        }
        let (mut best1, mut under, mut paths) = ((f64::INFINITY, 0.0), 0usize, 0usize);
        // Smallest heading error among the paths within 0.3 m.
        let mut yaw_at_pos = f64::INFINITY;
        for (e, n) in g.edges.iter().enumerate() {
            if !n.is_leaf() {
                continue;
            }
            let (i, j) = (n.from.frame, n.to.frame);
            for s0 in i.saturating_sub(t - 1)..=i.saturating_sub(5) {
                let t_in = i - s0 + 1;
                if t_in > t || t_in < 6 {
                    continue;
                }
                let f = j + (t - t_in);
                if f >= g.clip_len(n.to.clip) || !wave(n.to.clip, f) {
                    continue;
                }
                paths += 1;
                let w1 = start.compose(&g.torso_r(n.from.clip, s0).inverse()).compose(&g.delta[e]);
                let d = err(&w1.compose(&g.torso_r(n.to.clip, f)));
                if d.0 < 0.3 && d.1 < 10.0 {
                    under += 1;
                }
                if d.0 < 0.3 {
                    yaw_at_pos = yaw_at_pos.min(d.1);
                }
                if d.0 + d.1 / 10.0 * 0.3 < best1.0 + best1.1 / 10.0 * 0.3 {
                    best1 = d;
                }
            }
        }
        println!(
            "character {k}: wave at {t}: 0 cuts best {:.2} m / {:.0}°; 1 leaf cut best {:.2} m / {:.0}° of {paths} paths, {under} within 0.3 m and 10°; smallest heading error within 0.3 m: {yaw_at_pos:.0}°",
            best0.0, best0.1, best1.0, best1.1
        );
    }
    Ok(())
}
