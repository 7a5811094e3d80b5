//! `rigging/train` (paper §3.12; spec §6.3): max-margin learning of the nine penalty weights Γ
//! on the procedural training characters (seeds 0–61, [`crate::characters::train_params`]).
//!
//! Each round takes the `k_best` embeddings of every character under the current Γ, labels them
//! good or bad against the ground truth ([`character_examples`]), adds them to the training set
//! and re-learns Γ ([`crate::learn::max_margin`]); it stops when Γ changes by less than 1e-3.
//!
//! Outputs: table `gamma_rounds` (Γ, margin and characters embedded correctly per round) and the
//! file `gamma.ron` (the learned Γ).
//!
//! ```no_run
//! use geom_core::experiment::{BySize, Size};
//! use geom_core::record::NullRecorder;
//! use rigging::experiments::train::{run, Params};
//! let p = Params {
//!     characters: BySize::Same(6),
//!     target_vertices: BySize::Same(8000),
//!     tau: 0.004,
//!     k_best: 8,
//!     rounds: BySize::Same(1),
//!     n_starts: BySize::Same(20),
//! };
//! let r = run(&p, Size::Quick, &mut NullRecorder::default()).unwrap();
//! assert!(r.get_f64("margin") > 0.0);
//! ```

use geom_core::collide::MeshQuery;
use geom_core::experiment::{BySize, Report, Size, Target};
use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;
use geom_core::procedural::character::JointSet;
use geom_core::record::{Cell, Recorder};
use geom_core::stats;
use serde::Deserialize;

use crate::characters::train_params;
use crate::embed::{k_best_embeddings, reinsert_joints, Problem};
use crate::error::{Result, RigError};
use crate::eval::score;
use crate::learn::{margin, max_margin, CharacterExamples, LearnOptions};
use crate::presets::humanoid_character;
use crate::{prepare_embedding, Hint, RigOptions, SkeletonTemplate, GAMMA_PUBLISHED};

/// Parameters (the scene file's `params` block).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Training characters (seeds 0, 1, …; at most 62).
    pub characters: BySize<usize>,
    /// Target vertex count per character.
    pub target_vertices: BySize<usize>,
    /// Distance-field tolerance τ (normalized units).
    pub tau: f64,
    /// Embeddings per character and round.
    pub k_best: usize,
    /// Training rounds (at least one).
    pub rounds: BySize<usize>,
    /// Nelder–Mead starts per shrink round.
    pub n_starts: BySize<usize>,
}

/// Features of the `k` best embeddings of one character, labelled by the ground truth (joints
/// after reinsertion, no refinement); a character with no good one gets a good example from a
/// search hinted at its ground-truth reduced joints (spec §3.12). Embeddings not in `seen` are
/// added to it. Returns the examples and whether the best embedding is good.
pub fn character_examples(
    mesh: &TriMesh,
    truth: &JointSet,
    sk: &SkeletonTemplate,
    o: &RigOptions,
    k: usize,
    seen: &mut Vec<Vec<u32>>,
) -> Result<(CharacterExamples, bool)> {
    let rs = sk.reduced();
    let q = MeshQuery::new(mesh)?;
    let (_, e) = prepare_embedding(&mesh.positions, &mesh.faces, sk, &[], o)?;
    let pr = Problem::new(&e.graph, sk, &rs, &e.cand, o);
    let list = k_best_embeddings(&pr, k).unwrap_or_default();
    let mut ex = CharacterExamples::default();
    let mut first_ok = false;
    for (i, d) in list.iter().enumerate() {
        let joints: Vec<Pt3> =
            reinsert_joints(&e.graph, sk, &rs, &d.verts).iter().map(|p| e.sim.inverse_transform_point(p)).collect();
        let good = score(sk, &joints, &truth.rest, &q).ok;
        if i == 0 {
            first_ok = good;
        }
        if !seen.contains(&d.verts) {
            seen.push(d.verts.clone());
        }
        if good {
            ex.good.push(d.features);
        } else {
            ex.bad.push(d.features);
        }
    }
    if ex.good.is_empty() {
        let s = e.sim.scaling();
        let hints: Vec<Hint> = rs
            .full_index
            .iter()
            .map(|&f| Hint::Near {
                joint: sk.joints[f].name.clone(),
                point: truth.rest[f].coords.into(),
                radius: 0.05 / s,
            })
            .collect();
        let (_, eh) = prepare_embedding(&mesh.positions, &mesh.faces, sk, &hints, o)?;
        let prh = Problem::new(&eh.graph, sk, &rs, &eh.cand, o);
        if let Ok(v) = k_best_embeddings(&prh, 1) {
            ex.good.push(v[0].features);
        }
    }
    Ok((ex, first_ok))
}

/// Runs the experiment. Figures: `characters`, `train_ok_published` (best embedding correct
/// under the published Γ, count), `train_ok_last_round`, `margin` (learned, unit Γ),
/// `margin_published`, `gamma_1` … `gamma_9`.
pub fn run(p: &Params, size: Size, rec: &mut dyn Recorder) -> Result<Report> {
    let n = p.characters.get(size).min(62);
    let rounds = p.rounds.get(size);
    let n_starts = p.n_starts.get(size);
    let nv = p.target_vertices.get(size);
    let sk = SkeletonTemplate::human();
    let meshes: Vec<(TriMesh, JointSet)> =
        (0..n as u64).map(|s| humanoid_character(&train_params(s), nv)).collect::<Result<_>>()?;
    let mut gamma = GAMMA_PUBLISHED;
    rec.table("gamma_rounds", &["round", "g1", "g2", "g3", "g4", "g5", "g6", "g7", "g8", "g9", "margin", "train_ok"])?;
    let mut all: Vec<CharacterExamples> = vec![CharacterExamples::default(); n];
    let mut seen: Vec<Vec<Vec<u32>>> = vec![Vec::new(); n];
    let (mut ok_first, mut ok_last) = (0usize, 0usize);
    let mut last_margin = f64::NAN;
    for round in 0..rounds.max(1) {
        rec.progress(round as u64, rounds.max(1) as u64);
        let o = RigOptions { tau: p.tau, gamma, ..Default::default() };
        let mut ok = 0usize;
        for (c, (mesh, truth)) in meshes.iter().enumerate() {
            let (ex, good) = character_examples(mesh, truth, &sk, &o, p.k_best, &mut seen[c])?;
            ok += good as usize;
            all[c].good.extend(ex.good);
            all[c].bad.extend(ex.bad);
        }
        if round == 0 {
            ok_first = ok;
        }
        ok_last = ok;
        let (g, m) = max_margin(&all, &LearnOptions { n_starts, rounds: 6, iters: 300, seed: round as u64 + 1 });
        last_margin = m;
        let mut cells: Vec<Cell> = vec![round.into()];
        cells.extend(g.iter().map(|&x| x.into()));
        cells.extend([m.into(), ok.into()]);
        rec.row("gamma_rounds", &cells)?;
        let change: Vec<f64> = g.iter().zip(&gamma).map(|(a, b)| (a - b).abs()).collect();
        gamma = g;
        if stats::max(&change) < 1e-3 {
            break;
        }
    }
    let text = ron::to_string(&gamma).map_err(|e| RigError::InvalidParameter(format!("gamma.ron: {e}")))?;
    rec.file("gamma.ron", text.as_bytes())?;
    let mut r = Report::default();
    r.count("characters", n as u64)
        .count("train_ok_published", ok_first as u64)
        .count("train_ok_last_round", ok_last as u64)
        .num("margin", last_margin)
        .num("margin_published", margin(&GAMMA_PUBLISHED, &all));
    for (k, g) in gamma.iter().enumerate() {
        r.num(&format!("gamma_{}", k + 1), *g);
    }
    r.check("margin", Target::Above(0.0), "Baran & Popović 2007 §3.12: a positive margin separates good from bad");
    Ok(r)
}
