//! Smoothness across triangles (spec §3.9): the paper's vertex average (reconstructed:
//! rest-area-weighted), and the area-consistent least-squares fit (ours) with its normal matrix
//! factorised once.

use geom_core::linalg::Csr;
use geom_core::linalg::{Ordering, SparseLlt, Triplets};
use serde::{Deserialize, Serialize};

use crate::coeffs::WrinkleRig;
use crate::error::{Result, WrinkleError};

/// Weights of the incident triangles in a vertex average.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum VertexWeights {
    /// Rest area (default).
    #[default]
    Area,
    /// Every incident triangle counts once.
    Uniform,
}

/// Across-triangle smoothing of the per-triangle factors and weights.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Smoothing {
    /// Constant per triangle (comparison only: "patchy").
    PerTriangle,
    /// `y_v = Σ ω_t h_t / Σ ω_t` over incident non-degenerate triangles, then barycentric
    /// interpolation.
    VertexAverage {
        /// Triangle weights.
        weights: VertexWeights,
    },
    /// `min Σ_t C4_t(Σ_k β_tk y_k − h_t)² + μ Σ_edges (y_i − y_j)²`, `β_tk = C4_tk/C4_t`.
    AreaConsistent {
        /// Smoothness weight μ (m², ≥ 0).
        mu: f64,
    },
}

impl Default for Smoothing {
    fn default() -> Self {
        Smoothing::VertexAverage { weights: VertexWeights::Area }
    }
}

/// Vertex average of per-triangle values `tri[t·P + i]` (pattern `i`) into `out[v·P + i]`;
/// vertices touching no non-degenerate triangle take `fallback`.
pub fn vertex_average(rig: &WrinkleRig, w: VertexWeights, tri: &[f64], fallback: f64, out: &mut [f64]) {
    let p = rig.n_patterns();
    for (v, faces) in rig.vertex_faces.iter().enumerate() {
        for i in 0..p {
            let (mut s, mut ws) = (0.0, 0.0);
            for &f in faces {
                let rf = &rig.frames[f as usize];
                if rf.degenerate {
                    continue;
                }
                let om = match w {
                    VertexWeights::Area => rf.area,
                    VertexWeights::Uniform => 1.0,
                };
                s += om * tri[f as usize * p + i];
                ws += om;
            }
            out[v * p + i] = if ws > 0.0 { s / ws } else { fallback };
        }
    }
}

/// The prefactored area-consistent least-squares system, one per pattern.
#[derive(Clone, Debug)]
pub struct AreaConsistentLsq {
    llt: Vec<SparseLlt>,
    /// Number of numeric factorisations performed (for the "factor once" check, T18).
    pub n_factorizations: usize,
}

impl AreaConsistentLsq {
    /// Assembles and factorises `Σ_t c4v c4vᵀ/C4 + μ L` per pattern.
    ///
    /// Errors: [`WrinkleError::InvalidOption`] for μ < 0 or non-finite;
    /// [`WrinkleError::SingularSmoothingSystem`] when a row is empty or the factorisation fails.
    pub fn new(rig: &WrinkleRig, mu: f64) -> Result<Self> {
        if !(mu >= 0.0 && mu.is_finite()) {
            return Err(WrinkleError::InvalidOption(format!("AreaConsistent.mu must be ≥ 0, got {mu}")));
        }
        let nv = rig.mesh.positions.len();
        let p = rig.n_patterns();
        let mut llt = Vec::with_capacity(p);
        let mut n_factorizations = 0;
        for i in 0..p {
            let mut t = Triplets::new(nv, nv);
            let mut diag = vec![0.0; nv];
            for (f, face) in rig.mesh.faces.iter().enumerate() {
                let c = rig.coeff(f, i);
                if !c.status.is_active() {
                    continue;
                }
                for a in 0..3 {
                    for b in 0..3 {
                        let v = c.c4_vertex[a] * c.c4_vertex[b] / c.c4;
                        t.push(face[a], face[b], v);
                    }
                    diag[face[a] as usize] += c.c4_vertex[a] * c.c4_vertex[a] / c.c4;
                }
            }
            if mu > 0.0 {
                for e in &rig.edges {
                    t.push(e[0], e[0], mu);
                    t.push(e[1], e[1], mu);
                    t.push(e[0], e[1], -mu);
                    t.push(e[1], e[0], -mu);
                    diag[e[0] as usize] += mu;
                    diag[e[1] as usize] += mu;
                }
            }
            if let Some(v) = diag.iter().position(|d| d.is_nan() || *d <= 0.0) {
                return Err(WrinkleError::SingularSmoothingSystem { pattern: i, vertex: v });
            }
            let a = Csr::from_triplets(&t).to_csc_lower();
            let mut l = SparseLlt::analyze(&a, Ordering::Amd)
                .map_err(|_| WrinkleError::SingularSmoothingSystem { pattern: i, vertex: usize::MAX })?;
            l.factor(&a).map_err(|_| WrinkleError::SingularSmoothingSystem { pattern: i, vertex: usize::MAX })?;
            n_factorizations += 1;
            llt.push(l);
        }
        Ok(Self { llt, n_factorizations })
    }

    /// Solves for the vertex values of pattern `i` from per-triangle targets `tri[t·P + i]`.
    pub fn solve(&self, rig: &WrinkleRig, i: usize, tri: &[f64], out: &mut [f64]) -> Result<()> {
        let p = rig.n_patterns();
        let nv = rig.mesh.positions.len();
        let mut rhs = vec![0.0; nv];
        for (f, face) in rig.mesh.faces.iter().enumerate() {
            let c = rig.coeff(f, i);
            if !c.status.is_active() {
                continue;
            }
            for k in 0..3 {
                rhs[face[k] as usize] += c.c4_vertex[k] * tri[f * p + i];
            }
        }
        self.llt[i].solve_in_place(&mut rhs)?;
        for v in 0..nv {
            out[v * p + i] = rhs[v];
        }
        Ok(())
    }
}
