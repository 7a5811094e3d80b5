//! High-resolution output surface (spec §3.11.6): for rendering, a separate octree refined to
//! `finest + output_extra_levels` around the liquid surface and around every particle that can
//! carry it (near-surface and ballistic ones: ballistic spray is part of the rendered liquid even
//! though the simulation level set ignores it), the same hull level set evaluated on its nodes,
//! marching tetrahedra and the simulation's Taubin smoothing.
//!
//! Deviation from the spec's wording ("refined inside a band around **all** particles"): deep
//! interior particles add no demand, so the interior stays at the coarsest level — refining the
//! whole liquid volume one level beyond the simulation's finest would cost 8× the finest node
//! count of the liquid for no triangle (marching tetrahedra only reads signs there). Deep nodes
//! get the sign-only level-set path (`level_set_on_nodes_sign_inside`), which is exact wherever
//! an edge changes sign.

use geom_core::mesh::TriMesh;

use super::{level_set_on_nodes_sign_inside, marching_tets, smooth_surface, SurfaceParams, Walls};
use crate::bcc::tetrahedralize;
use crate::error::{MeshError, Result};
use crate::octree::{build_octree, OctreeSpec, SizeDemand, MAX_LEVELS};
use crate::particles::{ParticleFlags, Particles};

/// The output surface and the size of the mesh it was extracted from.
#[derive(Clone, Debug)]
pub struct OutputSurface {
    /// The smoothed triangle mesh (m); empty when no tet crosses the surface.
    pub mesh: TriMesh,
    /// Nodes of the output tet mesh.
    pub nodes: usize,
    /// Tets of the output tet mesh.
    pub tets: usize,
    /// Output cube edge at the refined level (m).
    pub h_out: f64,
}

/// Builds the output surface of the particle set `parts` in the simulation domain `spec` (its
/// root grid and levels; the output adds `params.output_extra_levels` levels). `walls` mirror
/// particles exactly as for the simulation level set (obstacle nodes are not needed: pass
/// `node_in_solid: None`).
///
/// Demands: every ballistic particle, and every particle whose stored level set `φ_p` is above
/// `−(near_surface_band · r_p + 2 h_out)`, asks for the output's finest level in a ball of radius
/// `2 (h_out + r_p)` (the particle's sphere, the hull facets it spans with its neighbours and
/// the two-cell stencil of marching tetrahedra). Errors: more than `MAX_LEVELS` levels
/// ([`MeshError::TooManyLevels`]), and what tetrahedralisation or extraction report.
pub fn output_surface(
    spec: &OctreeSpec,
    parts: &Particles,
    params: &SurfaceParams,
    walls: &Walls,
) -> Result<OutputSurface> {
    let levels = spec.levels.saturating_add(u8::try_from(params.output_extra_levels).unwrap_or(u8::MAX));
    if levels > MAX_LEVELS {
        return Err(MeshError::TooManyLevels(levels).into());
    }
    let out_spec = OctreeSpec { levels, ..*spec };
    let finest = levels - 1;
    let h_out = out_spec.h(finest);
    // The rendered liquid includes the spray: clear the ballistic flags of a copy so that the
    // level set takes every particle as a source.
    let mut all = parts.clone();
    for f in &mut all.flags {
        f.0 &= !ParticleFlags::BALLISTIC;
    }
    let demands: Vec<SizeDemand> = (0..parts.len())
        .filter(|&i| {
            parts.flags[i].has(ParticleFlags::BALLISTIC)
                // NaN φ (a particle never located) counts as near the surface.
                || parts.phi[i] > -(params.near_surface_band * parts.r[i] + 2.0 * h_out)
                || parts.phi[i].is_nan()
        })
        .map(|i| SizeDemand { center: parts.x[i], pad: 2.0 * (h_out + parts.r[i]), level: finest })
        .collect();
    let oct = build_octree(out_spec, &demands);
    let mesh = tetrahedralize(&oct)?;
    let phi = level_set_on_nodes_sign_inside(&mesh, &all, params, walls);
    let tri = marching_tets(&mesh, &phi)?;
    let tri = if tri.n_faces() > 0 { smooth_surface(&tri, params.smoothing_iterations) } else { tri };
    Ok(OutputSurface { mesh: tri, nodes: mesh.nodes.len(), tets: mesh.tets.len(), h_out })
}
