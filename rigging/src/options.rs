//! Every knob of the method (rigging spec §4) with the paper's values as defaults.

use serde::{Deserialize, Serialize};

/// The penalty weights Γ shipped with the public Pinocchio release (spec §3.7), in the order
/// b1 … b9 (short bones, orientation between joints, symmetric lengths, shared chains, feet,
/// zero-length chains, bone orientation, leaf not at an extremity, far along chains but close
/// in the graph).
pub const GAMMA_PUBLISHED: [f64; 9] = [0.027, 0.023, 0.007, 0.046, 0.014, 0.012, 0.072, 0.005, 0.033];

/// Options of [`crate::autorig`] and its stages. Units: "nu" = normalized units (the
/// character's largest extent is 0.9).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RigOptions {
    /// Distance-field tolerance and medial grid spacing (nu). Paper: 0.003.
    pub tau: f64,
    /// Octree depth cap (levels, ≤ 10).
    pub df_max_depth: u32,
    /// Minimum angle between adjacent distance gradients at a medial point (deg). Paper: 120.
    pub medial_angle_deg: f64,
    /// Medial samples closer than this × τ to the surface are dropped. Paper: 2.
    pub medial_min_depth: f64,
    /// Sphere-packing cap.
    pub max_spheres: usize,
    /// A non-intersecting graph edge must stay this deep (× smaller radius). Paper: ½.
    pub edge_depth_factor: f64,
    /// Samples of the edge depth test.
    pub edge_samples: usize,
    /// Skeleton units → nu.
    pub skeleton_scale: f64,
    /// Largest spheres allowed for fat joints.
    pub fat_candidates: usize,
    /// Play ρ = play · (r_i + r_p).
    pub play_factor: f64,
    /// Penalty weights Γ (b1 … b9).
    pub gamma: [f64; 9],
    /// Single weighted terms or partial lower bounds above this are rejected.
    pub reject_bound: f64,
    /// Best-first queue cap before falling back to a bounded (uncertified) queue.
    pub max_queue: usize,
    /// Partial embeddings the best-first search may expand before it returns the best
    /// embedding found (`certified_optimal = false`); bounds the time of the discrete stage
    /// (about 0.2 ms per expansion on this machine, release build).
    pub max_expansions: usize,
    /// Wall-clock limit (s) of the discrete search, `None` = none (results then depend on the
    /// machine when the limit is hit; the expansion limit does not).
    pub max_search_seconds: Option<f64>,
    /// Outer refinement iterations. Paper: 10.
    pub refine_iters: usize,
    /// Refinement weights (α_S, α_L, α_O, α_A).
    pub refine_alpha: [f64; 4],
    /// Heat constant c in H = k c / d². Paper: 1.
    pub heat_c: f64,
    /// Distance floor in H (nu).
    pub d_floor: f64,
    /// Visibility test (bone point → vertex segment unobstructed).
    pub visibility_test: bool,
    /// Visibility: stop this far (nu) before the vertex.
    pub vis_margin: f64,
    /// Cone test threshold (cosine between bone→vertex and the vertex normal); `None` = off.
    pub cone_cos: Option<f64>,
    /// Weights below this are dropped.
    pub weight_prune: f64,
    /// Per-vertex bone cap (0 = keep all).
    pub max_influences: usize,
    /// Keep the largest component of a multi-component mesh instead of refusing it.
    pub keep_largest_component: bool,
}

impl Default for RigOptions {
    fn default() -> Self {
        Self {
            tau: 0.003,
            df_max_depth: 10,
            medial_angle_deg: 120.0,
            medial_min_depth: 2.0,
            max_spheres: 1000,
            edge_depth_factor: 0.5,
            edge_samples: 101,
            skeleton_scale: 0.35,
            fat_candidates: 50,
            play_factor: 0.7,
            gamma: GAMMA_PUBLISHED,
            reject_bound: 1.0,
            max_queue: 2_000_000,
            max_expansions: 50_000,
            max_search_seconds: None,
            refine_iters: 10,
            refine_alpha: [15000.0, 0.25, 2.0, 1.0],
            heat_c: 1.0,
            d_floor: 1e-4,
            visibility_test: true,
            vis_margin: 0.002,
            cone_cos: Some(0.5),
            weight_prune: 1e-8,
            max_influences: 4,
            keep_largest_component: false,
        }
    }
}

impl RigOptions {
    /// Checks ranges; errors name the bad field.
    pub fn validate(&self) -> crate::Result<()> {
        let bad = |s: &str| Err(crate::RigError::InvalidParameter(s.to_string()));
        if !(self.tau > 0.0 && self.tau < 0.1) {
            return bad("tau must be in (0, 0.1)");
        }
        if !(1..=10).contains(&self.df_max_depth) {
            return bad("df_max_depth must be in 1..=10");
        }
        if self.max_spheres < 1 || self.edge_samples < 2 || self.fat_candidates < 1 {
            return bad("max_spheres, fat_candidates ≥ 1 and edge_samples ≥ 2");
        }
        if !(self.skeleton_scale > 0.0) || !(self.heat_c > 0.0) || !(self.d_floor > 0.0) {
            return bad("skeleton_scale, heat_c and d_floor must be positive");
        }
        if self.max_expansions == 0 || self.max_search_seconds.is_some_and(|s| !(s > 0.0)) {
            return bad("max_expansions must be ≥ 1 and max_search_seconds positive");
        }
        if self.gamma.iter().any(|g| !(*g >= 0.0 && g.is_finite())) {
            return bad("gamma must be finite and non-negative");
        }
        Ok(())
    }
}
