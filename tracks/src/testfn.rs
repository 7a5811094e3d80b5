//! Test-function designs (spec §3.3, seed §4.1): painted regions, the coarsest subdivision basis,
//! (animation-aware) clustering, pointwise anchors and explicit matrices. Test functions are
//! nodal: φ̄_i = Σ_j S̄_ij ψ̄_j on the guide and φ_i = Σ_l S_il ψ_l on the tracked mesh.

use geom_core::linalg::{Csr, Triplets};
use geom_core::math::Pt3;
use geom_core::mesh::{TriMesh, Uv};

use crate::cluster::{cluster, ClusterOptions};
use crate::error::{Result, TrackError};
use crate::guide::GuideAnimation;

/// A region of a mesh, for painted test functions (spec §3.3a).
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
pub enum RegionSel {
    /// Explicit vertex indices.
    Vertices(Vec<u32>),
    /// Vertices whose rest position lies in the closed box [min, max] (m).
    RestBox {
        /// Lower corner.
        min: (f64, f64, f64),
        /// Upper corner.
        max: (f64, f64, f64),
    },
    /// Vertices whose per-vertex UV (m of material space) lies in u × v (closed intervals).
    Uv {
        /// u interval.
        u: (f64, f64),
        /// v interval.
        v: (f64, f64),
    },
}

impl RegionSel {
    /// The selected vertices of `m`, sorted. Errors: an index out of range, a UV selection on a
    /// mesh without per-vertex UVs.
    pub fn select(&self, m: &TriMesh) -> Result<Vec<u32>> {
        let n = m.n_vertices();
        let mut out: Vec<u32> = match self {
            RegionSel::Vertices(v) => {
                if let Some(&bad) = v.iter().find(|&&i| i as usize >= n) {
                    return Err(TrackError::BadParameter(format!("region vertex {bad} out of range (n = {n})")));
                }
                v.clone()
            }
            RegionSel::RestBox { min, max } => {
                let inside = |p: &Pt3| {
                    p.x >= min.0 && p.x <= max.0 && p.y >= min.1 && p.y <= max.1 && p.z >= min.2 && p.z <= max.2
                };
                (0..n as u32).filter(|&i| inside(&m.positions[i as usize])).collect()
            }
            RegionSel::Uv { u, v } => match &m.uv {
                Some(Uv::PerVertex(uv)) => (0..n as u32)
                    .filter(|&i| {
                        let p = uv[i as usize];
                        p.x >= u.0 && p.x <= u.1 && p.y >= v.0 && p.y <= v.1
                    })
                    .collect(),
                _ => return Err(TrackError::BadParameter("Uv region on a mesh without per-vertex UVs".into())),
            },
        };
        out.sort_unstable();
        out.dedup();
        Ok(out)
    }
}

/// Whether test functions are averaging (weak, mass-weighted) or pointwise anchors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum TestKind {
    /// Weighted averages: C = S𝓜 (eq. 5–7).
    #[default]
    Weak,
    /// Interpolating anchors: C rows are unit vectors (the Fig. 3/4 baseline).
    Pointwise,
}

/// How to build the test functions (spec §2).
#[derive(Clone, Debug)]
pub enum TestFunctionSpec {
    /// Painted regions: `guide[i]` ↔ `tracked[i]` (§3.3a; eq. 8 sets the tracked constant).
    Painted {
        /// Guide regions.
        guide: Vec<RegionSel>,
        /// Tracked regions (same count).
        tracked: Vec<RegionSel>,
    },
    /// Regions painted on the guide only and transferred to the tracked mesh through the
    /// prolongation (S = S̄ Pᵀ, so φ_i equals φ̄_i as a function and g(P q̄) = 0 exactly); for
    /// subdivision-related meshes this avoids the centroid mismatch of painting both meshes
    /// separately (the guide's hat-sum indicator reaches half a coarse cell beyond its region).
    PaintedOnGuide {
        /// Guide regions.
        guide: Vec<RegionSel>,
    },
    /// Coarsest level of the subdivision hierarchy: S̄ = I, S = Pᵀ (§3.3b; needs P).
    SubdivisionBasis,
    /// Clustering of the guide animation (identical guide and tracked meshes, §3.3c).
    Clustered(ClusterOptions),
    /// Clustering with separately clustered refined subsets (Xavier's feet).
    ClusteredWithRefinement {
        /// Options for the complement of all refined subsets.
        base: ClusterOptions,
        /// (subset, regions) pairs clustered on their own.
        refine: Vec<(RegionSel, usize)>,
    },
    /// Pointwise anchors (guide vertex j, tracked vertex l).
    Pointwise {
        /// Anchor pairs.
        pairs: Vec<(u32, u32)>,
    },
    /// Explicit nodal matrices (K × n̄ and K × n).
    Explicit {
        /// S̄.
        s_bar: Csr,
        /// S.
        s: Csr,
    },
}

/// Nodal test functions: S̄ (K × n̄) and S (K × n).
#[derive(Clone, Debug, PartialEq)]
pub struct TestFunctions {
    /// Guide nodal values S̄_ij = φ̄_i(x̄_j).
    pub s_bar: Csr,
    /// Tracked nodal values S_il = φ_i(x_l).
    pub s: Csr,
    /// Weak or pointwise.
    pub kind: TestKind,
}

impl TestFunctions {
    /// Number of (vector) test functions K.
    pub fn len(&self) -> usize {
        self.s.nrows
    }

    /// True for K = 0 (the tracker then takes the untracked path).
    pub fn is_empty(&self) -> bool {
        self.s.nrows == 0
    }

    /// Indicator test functions from vertex labels (`geom_core::NONE` = unassigned), the same on
    /// both meshes (identical guide and tracked meshes).
    pub fn from_labels(labels: &[u32], k: usize) -> Self {
        let n = labels.len();
        let mut t = Triplets::new(k, n);
        for (v, &l) in labels.iter().enumerate() {
            if l != geom_core::NONE {
                t.push(l, v as u32, 1.0);
            }
        }
        let s = Csr::from_triplets(&t);
        Self { s_bar: s.clone(), s, kind: TestKind::Weak }
    }
}

fn indicator_rows(sets: &[Vec<u32>], n: usize) -> Csr {
    // Shared border vertices go to the lower region index (consistent on both meshes).
    let mut owner = vec![u32::MAX; n];
    for (i, s) in sets.iter().enumerate() {
        for &v in s {
            if owner[v as usize] == u32::MAX {
                owner[v as usize] = i as u32;
            }
        }
    }
    let mut t = Triplets::new(sets.len(), n);
    for (i, s) in sets.iter().enumerate() {
        // A region swallowed whole by lower-index regions (a duplicate) keeps its full selection,
        // so the rank check reports it as `RankDeficient` rather than an empty region.
        let swallowed = s.iter().all(|&v| owner[v as usize] != i as u32);
        for &v in s {
            if swallowed || owner[v as usize] == i as u32 {
                t.push(i as u32, v, 1.0);
            }
        }
    }
    Csr::from_triplets(&t)
}

/// Builds the nodal test functions of `spec` (spec §3.3).
///
/// Errors: mismatched region counts, an empty region (`ZeroIntegral`), a missing prolongation
/// for `SubdivisionBasis`, clustering on meshes of different vertex counts, anchors out of range.
pub fn build_test_functions(
    spec: &TestFunctionSpec,
    guide: &GuideAnimation,
    tracked_rest: &TriMesh,
    prolongation: Option<&Csr>,
) -> Result<TestFunctions> {
    let (nb, n) = (guide.n_vertices(), tracked_rest.n_vertices());
    match spec {
        TestFunctionSpec::Painted { guide: g, tracked: t } => {
            if g.len() != t.len() {
                return Err(TrackError::BadParameter(format!(
                    "{} guide regions but {} tracked regions",
                    g.len(),
                    t.len()
                )));
            }
            let gs = g.iter().map(|r| r.select(&guide.rest)).collect::<Result<Vec<_>>>()?;
            let ts = t.iter().map(|r| r.select(tracked_rest)).collect::<Result<Vec<_>>>()?;
            for (i, (a, b)) in gs.iter().zip(&ts).enumerate() {
                if a.is_empty() || b.is_empty() {
                    return Err(TrackError::ZeroIntegral(i));
                }
            }
            Ok(TestFunctions { s_bar: indicator_rows(&gs, nb), s: indicator_rows(&ts, n), kind: TestKind::Weak })
        }
        TestFunctionSpec::PaintedOnGuide { guide: g } => {
            let p = prolongation
                .ok_or_else(|| TrackError::BadParameter("PaintedOnGuide needs the prolongation P".into()))?;
            if p.nrows != n || p.ncols != nb {
                return Err(TrackError::TopologyMismatch {
                    what: "prolongation shape (rows)",
                    expected: n,
                    got: p.nrows,
                });
            }
            let gs = g.iter().map(|r| r.select(&guide.rest)).collect::<Result<Vec<_>>>()?;
            if let Some(i) = gs.iter().position(|s| s.is_empty()) {
                return Err(TrackError::ZeroIntegral(i));
            }
            let s_bar = indicator_rows(&gs, nb);
            let s = s_bar.matmul(&p.transpose());
            Ok(TestFunctions { s_bar, s, kind: TestKind::Weak })
        }
        TestFunctionSpec::SubdivisionBasis => {
            let p = prolongation
                .ok_or_else(|| TrackError::BadParameter("SubdivisionBasis needs the prolongation P".into()))?;
            if p.nrows != n || p.ncols != nb {
                return Err(TrackError::TopologyMismatch {
                    what: "prolongation shape (rows)",
                    expected: n,
                    got: p.nrows,
                });
            }
            Ok(TestFunctions { s_bar: Csr::identity(nb), s: p.transpose(), kind: TestKind::Weak })
        }
        TestFunctionSpec::Clustered(o) => {
            if nb != n {
                return Err(TrackError::TopologyMismatch {
                    what: "clustering needs identical meshes",
                    expected: nb,
                    got: n,
                });
            }
            let c = cluster(guide, o, None)?;
            Ok(TestFunctions::from_labels(&c.vertex_labels, c.regions))
        }
        TestFunctionSpec::ClusteredWithRefinement { base, refine } => {
            if nb != n {
                return Err(TrackError::TopologyMismatch {
                    what: "clustering needs identical meshes",
                    expected: nb,
                    got: n,
                });
            }
            let (labels, k) = clustered_with_refinement(guide, base, refine)?;
            Ok(TestFunctions::from_labels(&labels, k))
        }
        TestFunctionSpec::Pointwise { pairs } => {
            let mut tb = Triplets::new(pairs.len(), nb);
            let mut tt = Triplets::new(pairs.len(), n);
            for (i, &(j, l)) in pairs.iter().enumerate() {
                if j as usize >= nb || l as usize >= n {
                    return Err(TrackError::BadParameter(format!("anchor pair {i} = ({j}, {l}) out of range")));
                }
                tb.push(i as u32, j, 1.0);
                tt.push(i as u32, l, 1.0);
            }
            Ok(TestFunctions { s_bar: Csr::from_triplets(&tb), s: Csr::from_triplets(&tt), kind: TestKind::Pointwise })
        }
        TestFunctionSpec::Explicit { s_bar, s } => {
            if s_bar.nrows != s.nrows || s_bar.ncols != nb || s.ncols != n {
                return Err(TrackError::TopologyMismatch {
                    what: "explicit S̄/S shapes",
                    expected: s_bar.nrows,
                    got: s.nrows,
                });
            }
            Ok(TestFunctions { s_bar: s_bar.clone(), s: s.clone(), kind: TestKind::Weak })
        }
    }
}

/// Clusters each refined subset with its own count and the complement with `base.regions`,
/// concatenating the labels (complement first). Returns vertex labels and K.
fn clustered_with_refinement(
    guide: &GuideAnimation,
    base: &ClusterOptions,
    refine: &[(RegionSel, usize)],
) -> Result<(Vec<u32>, usize)> {
    let nt = guide.rest.n_faces();
    let mut taken = vec![false; guide.n_vertices()];
    let mut subsets: Vec<(Vec<u32>, usize)> = Vec::new();
    for (sel, r) in refine {
        let verts = sel.select(&guide.rest)?;
        let mut in_sel = vec![false; guide.n_vertices()];
        verts.iter().for_each(|&v| in_sel[v as usize] = true);
        // A triangle belongs to the subset when all its vertices do.
        let tris: Vec<u32> = (0..nt as u32)
            .filter(|&f| guide.rest.faces[f as usize].iter().all(|&v| in_sel[v as usize] && !taken[v as usize]))
            .collect();
        for &f in &tris {
            for &v in &guide.rest.faces[f as usize] {
                taken[v as usize] = true;
            }
        }
        subsets.push((tris, *r));
    }
    let mut in_sub = vec![false; nt];
    subsets.iter().for_each(|(t, _)| t.iter().for_each(|&f| in_sub[f as usize] = true));
    let rest_tris: Vec<u32> = (0..nt as u32).filter(|&f| !in_sub[f as usize]).collect();
    let mut tri_labels = vec![geom_core::NONE; nt];
    let mut k = 0usize;
    let mut run = |tris: &[u32], r: usize| -> Result<()> {
        if tris.is_empty() {
            return Ok(());
        }
        let o = ClusterOptions { regions: r.min(tris.len()), ..base.clone() };
        let c = cluster(guide, &o, Some(tris))?;
        for &f in tris {
            tri_labels[f as usize] = c.tri_labels[f as usize] + k as u32;
        }
        k += c.regions_tri;
        Ok(())
    };
    run(&rest_tris, base.regions)?;
    for (tris, r) in &subsets {
        run(tris, *r)?;
    }
    let (labels, k) = crate::cluster::vertex_labels_from_triangles(&guide.rest, &tri_labels, k);
    Ok((labels, k))
}
