//! Enclosed volume of an open mesh with its holes closed by centroid fans (spec §6.1: "tube
//! closed with caps for the measurement only"), by `geom_core::mesh::signed_volume_capped`.

use crate::error::Result;
use crate::topo::PolyTopo;
use geom_core::graph::Ragged;
use geom_core::math::{AsPt3, Pt3};
use geom_core::mesh::{signed_volume_capped, PolyMesh, Topology};

/// Precomputed fan triangulation of a polygon mesh and its geom-core topology.
#[derive(Clone, Debug)]
pub struct CappedVolume {
    tris: Vec<[u32; 3]>,
    topo: Topology,
}

impl CappedVolume {
    /// Prepares the measurement for meshes with `m`'s faces. Errors: a mesh geom-core's
    /// `Topology` rejects (non-manifold, inconsistently oriented).
    pub fn new(m: &PolyMesh) -> Result<Self> {
        let (tris, topo) = PolyTopo::triangle_topology(m)?;
        Ok(Self { tris, topo })
    }

    /// Prepares the measurement for meshes with these polygon faces (positions do not matter
    /// here: only the connectivity is analysed).
    pub fn for_faces(faces: &Ragged<u32>) -> Result<Self> {
        let n = faces.items.iter().map(|&v| v as usize + 1).max().unwrap_or(0);
        Self::new(&PolyMesh { positions: vec![Pt3::origin(); n], faces: faces.clone(), uv: None })
    }

    /// Signed volume (divergence theorem, f64 sums) of the capped surface for positions `p`:
    /// positive when the faces are oriented outward. Each boundary loop is closed by a fan
    /// around its centroid, oriented against the loop so that the closed surface is consistent
    /// (`geom_core::mesh::signed_volume_capped`).
    pub fn volume<P: AsPt3>(&self, p: &[P]) -> f64 {
        signed_volume_capped(&self.topo, &self.tris, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capped_tube_volume_is_the_prism_volume() {
        // A tube of 8 around: cross-section is the regular octagon of circumradius R.
        let (r, l) = (0.045, 0.57);
        let m = crate::arm::open_tube(8, 22, r, l).unwrap();
        let cv = CappedVolume::new(&m).unwrap();
        let octagon = 0.5 * 8.0 * r * r * (std::f64::consts::TAU / 8.0).sin();
        let v = cv.volume(&m.positions);
        assert!((v.abs() - octagon * l).abs() < 1e-14, "{v} vs {}", octagon * l);
        // Translation invariance (caps close the surface).
        let shifted: Vec<geom_core::math::Pt3> =
            m.positions.iter().map(|p| p + geom_core::math::Vec3::new(1.0, -2.0, 3.0)).collect();
        assert!((cv.volume(&shifted) - v).abs() < 1e-13);
    }
}
