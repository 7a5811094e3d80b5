//! The whole pipeline ([`autorig`]) and its result ([`Rig`]): preprocessing, distance field,
//! medial sampling, packing, graph, discrete embedding, reinsertion, refinement, bone heat —
//! each stage timed (spec §3.15, Table 1).

use std::time::Instant;

use geom_core::anim::skin::{SkinSkeleton, SkinWeights};
use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;
use nalgebra::Similarity3;

use crate::df::{DfStats, DistanceField};
use crate::embed::{candidates, k_best_embeddings, reinsert_joints, DiscreteEmbedding, Hint, Problem};
use crate::error::{Result, RigError};
use crate::graph::EmbedGraph;
use crate::heat::{bone_heat, HeatReport};
use crate::medial::{pack_spheres, sample_medial};
use crate::options::RigOptions;
use crate::prep::{normalize, prepare, PrepReport};
use crate::refine::{refine, Objective};
use crate::template::SkeletonTemplate;

/// Wall-clock seconds per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimings {
    /// Validation, welding, normalization.
    pub normalize: f64,
    /// Distance field.
    pub distance_field: f64,
    /// Medial sampling.
    pub medial: f64,
    /// Sphere packing.
    pub packing: f64,
    /// Graph and all-pairs shortest paths.
    pub graph: f64,
    /// Discrete search.
    pub discrete: f64,
    /// Reinsertion and refinement.
    pub refine: f64,
    /// Bone heat.
    pub attach: f64,
}

impl StageTimings {
    /// Sum of all stages.
    pub fn total(&self) -> f64 {
        self.normalize
            + self.distance_field
            + self.medial
            + self.packing
            + self.graph
            + self.discrete
            + self.refine
            + self.attach
    }
}

/// Sizes and counts along the pipeline.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RigDiagnostics {
    /// Preprocessing report.
    pub prep: PrepReport,
    /// Distance field statistics.
    pub df: DfStats,
    /// Medial samples.
    pub medial_samples: usize,
    /// Packed spheres (graph vertices).
    pub spheres: usize,
    /// Graph edges.
    pub edges: usize,
    /// Graph components.
    pub graph_components: usize,
    /// Refinement objective before and after.
    pub refine_g: (f64, f64),
    /// Bone-heat diagnostics.
    pub heat: HeatReport,
}

/// A rigged character.
#[derive(Clone, Debug)]
pub struct Rig {
    /// The prepared mesh (welded, oriented) in ORIGINAL coordinates; weights index its vertices.
    pub mesh: TriMesh,
    /// The template that was embedded.
    pub template: SkeletonTemplate,
    /// Embedded joints (template order), ORIGINAL coordinates.
    pub joints: Vec<Pt3>,
    /// Joints after reinsertion, before refinement (original coordinates).
    pub joints_unrefined: Vec<Pt3>,
    /// The discrete embedding.
    pub discrete: DiscreteEmbedding,
    /// Skin weights; joint index `b + 1` = bone `b` of `template.bones()` (index 0 is the
    /// synthetic root of [`Rig::skin_skeleton`], which carries no weight).
    pub weights: SkinWeights,
    /// Stage times.
    pub timings: StageTimings,
    /// Diagnostics.
    pub diagnostics: RigDiagnostics,
    /// Original → normalized similarity.
    pub to_normalized: Similarity3<f64>,
}

/// Intermediate products of the embedding stages (normalized coordinates), exposed for tests,
/// scenes and learning.
pub struct Embedding {
    /// Normalized mesh.
    pub mesh: TriMesh,
    /// Original → normalized.
    pub sim: Similarity3<f64>,
    /// Distance field.
    pub df: DistanceField,
    /// All medial sample points.
    pub medial: Vec<Pt3>,
    /// The graph.
    pub graph: EmbedGraph,
    /// Candidates per reduced joint.
    pub cand: Vec<Vec<u32>>,
    /// Timings so far.
    pub timings: StageTimings,
    /// Diagnostics so far.
    pub diagnostics: RigDiagnostics,
}

/// Stages up to the graph and candidates (everything the discrete search needs).
pub fn prepare_embedding(
    positions: &[Pt3],
    faces: &[[u32; 3]],
    sk: &SkeletonTemplate,
    hints: &[Hint],
    o: &RigOptions,
) -> Result<(TriMesh, Embedding)> {
    o.validate()?;
    sk.validate()?;
    let mut t = StageTimings::default();
    let mut dg = RigDiagnostics::default();
    let t0 = Instant::now();
    let (mesh, prep) = prepare(positions, faces, o.keep_largest_component)?;
    let (nmesh, sim) = normalize(&mesh)?;
    dg.prep = prep;
    t.normalize = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let df = DistanceField::build(&nmesh, o.tau, o.df_max_depth)?;
    dg.df = df.stats();
    t.distance_field = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let samples = sample_medial(&df, o.medial_angle_deg, o.medial_min_depth);
    dg.medial_samples = samples.len();
    t.medial = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let spheres = pack_spheres(&samples, o.max_spheres);
    dg.spheres = spheres.len();
    t.packing = t0.elapsed().as_secs_f64();
    if spheres.is_empty() {
        return Err(RigError::Degenerate(
            "no medial sample deeper than the surface filter (character too thin for tau)".into(),
        ));
    }
    let t0 = Instant::now();
    let graph = EmbedGraph::build(&df, &spheres, o.edge_depth_factor, o.edge_samples);
    dg.edges = graph.adj.iter().map(|a| a.len()).sum::<usize>() / 2;
    dg.graph_components = graph.components;
    let rs = sk.reduced();
    let s = sim.scaling();
    let cand = candidates(&graph, sk, &rs, hints, o, &|p| sim.transform_point(p), s)?;
    t.graph = t0.elapsed().as_secs_f64();
    let medial = samples.iter().map(|x| x.c).collect();
    Ok((mesh, Embedding { mesh: nmesh, sim, df, medial, graph, cand, timings: t, diagnostics: dg }))
}

/// Rigs a character: `positions`/`faces` is the raw input (welded and checked here), `sk` the
/// template, `hints` optional joint constraints (original coordinates).
pub fn autorig(
    positions: &[Pt3],
    faces: &[[u32; 3]],
    sk: &SkeletonTemplate,
    hints: &[Hint],
    o: &RigOptions,
) -> Result<Rig> {
    let (mesh, e) = prepare_embedding(positions, faces, sk, hints, o)?;
    let Embedding { mesh: nmesh, sim, df, medial, graph, cand, mut timings, mut diagnostics } = e;
    let rs = sk.reduced();
    let t0 = Instant::now();
    let pr = Problem::new(&graph, sk, &rs, &cand, o);
    let discrete = match k_best_embeddings(&pr, 1) {
        Ok(mut v) => v.remove(0),
        Err(RigError::NoEmbedding { best_partial, .. }) if graph.components > 1 && best_partial.is_none() => {
            return Err(RigError::GraphDisconnected { components: graph.components })
        }
        Err(e) => return Err(e),
    };
    timings.discrete = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let init = reinsert_joints(&graph, sk, &rs, &discrete.verts);
    let balls = hints
        .iter()
        .filter_map(|h| match h {
            Hint::Near { joint, point, radius } => {
                sk.find(joint).map(|j| (j, sim.transform_point(&Pt3::from(*point)), radius * sim.scaling()))
            }
            Hint::AtGraphVertices { .. } => None,
        })
        .collect();
    let obj = Objective::new(&df, &medial, sk, o).with_constraints(balls);
    let (q, hist) = refine(&obj, &init, o.refine_iters);
    diagnostics.refine_g = (hist[0], *hist.last().expect("history starts with g(init)"));
    timings.refine = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let bones: Vec<[Pt3; 2]> = sk.bones().iter().map(|&(p, c)| [q[p], q[c]]).collect();
    let (w, heat) = bone_heat(&nmesh, &bones, o)?;
    diagnostics.heat = heat;
    // Shift joint indices by one: skinning joint 0 is the synthetic root.
    let weights = SkinWeights { offsets: w.offsets, joint: w.joint.iter().map(|j| j + 1).collect(), w: w.w };
    timings.attach = t0.elapsed().as_secs_f64();
    let back = |p: &Pt3| sim.inverse_transform_point(p);
    Ok(Rig {
        mesh,
        template: sk.clone(),
        joints: q.iter().map(back).collect(),
        joints_unrefined: init.iter().map(back).collect(),
        discrete,
        weights,
        timings,
        diagnostics,
        to_normalized: sim,
    })
}

impl Rig {
    /// The skinning skeleton (spec §3.11.6): a synthetic root at the template root plus one
    /// joint per bone `b = (p, c)`, located at `q_p` with its x axis along the bone, parented to
    /// the joint of the bone ending at `p` (or the synthetic root). Names: the bone's end joint.
    pub fn skin_skeleton(&self) -> Result<SkinSkeleton> {
        let bones = self.template.bones();
        let mut names = vec!["root".to_string()];
        let mut parent = vec![None];
        let mut pos = vec![self.joints[0]];
        for &(p, c) in &bones {
            names.push(self.template.joints[c].name.clone());
            let pb = bones.iter().position(|&(_, c2)| c2 == p).map_or(0, |k| k + 1);
            parent.push(Some(pb));
            pos.push(self.joints[p]);
        }
        // Leaf bones: from_positions orients a joint towards its first child; give each leaf
        // bone its direction through a helper position list (the end joint) by ordering: a
        // bone's children start at its end, so its x axis already points along it.
        Ok(SkinSkeleton::from_positions(names, parent, &pos)?)
    }

    /// The rigged skeleton as an animation skeleton (`anim::Skeleton::from_joint_positions`),
    /// with the template's roles (where a joint has none, the role guessed from its name stays).
    pub fn anim_skeleton(&self) -> Result<geom_core::anim::Skeleton> {
        self.template.anim_skeleton(&self.joints)
    }
}
