//! Enclosed volume of an open mesh with its holes closed by centroid fans (spec §6.1: "tube
//! closed with caps for the measurement only"). Should move to geom-core
//! (`mesh::signed_volume_capped`, not available when this crate was written).

use crate::error::Result;
use crate::topo::PolyTopo;
use geom_core::math::{AsPt3, Pt3};
use geom_core::mesh::PolyMesh;

/// Precomputed fan triangulation of a polygon mesh and its boundary loops.
#[derive(Clone, Debug)]
pub struct CappedVolume {
    tris: Vec<[u32; 3]>,
    loops: Vec<Vec<u32>>,
}

impl CappedVolume {
    /// Prepares the measurement for meshes with `m`'s faces.
    pub fn new(m: &PolyMesh) -> Result<Self> {
        let t = PolyTopo::new(m)?;
        let loops = t.boundary_loops(m);
        let mut tris = Vec::new();
        for row in m.faces.rows() {
            for i in 1..row.len() - 1 {
                tris.push([row[0], row[i], row[i + 1]]);
            }
        }
        Ok(Self { tris, loops })
    }

    /// Signed volume (divergence theorem, f64 sums) of the capped surface for positions `p`:
    /// positive when the faces are oriented outward. Each boundary loop is closed by a fan
    /// around its centroid, oriented against the loop so that the closed surface is consistent.
    pub fn volume<P: AsPt3>(&self, p: &[P]) -> f64 {
        let tet = |a: &Pt3, b: &Pt3, c: &Pt3| a.coords.dot(&b.coords.cross(&c.coords)) / 6.0;
        let mut v = 0.0;
        for t in &self.tris {
            v += tet(&p[t[0] as usize].pt3(), &p[t[1] as usize].pt3(), &p[t[2] as usize].pt3());
        }
        for lp in &self.loops {
            let c = lp.iter().fold(Pt3::origin(), |acc, &i| acc + p[i as usize].pt3().coords / lp.len() as f64);
            for i in 0..lp.len() {
                let a = p[lp[i] as usize].pt3();
                let b = p[lp[(i + 1) % lp.len()] as usize].pt3();
                v += tet(&c, &b, &a);
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capped_tube_volume_is_the_prism_volume() {
        // A tube of 8 around: cross-section is the regular octagon of circumradius R.
        let (r, l) = (0.045, 0.57);
        let m = crate::arm::open_tube(8, 22, r, l);
        let cv = CappedVolume::new(&m).unwrap();
        let octagon = 0.5 * 8.0 * r * r * (std::f64::consts::TAU / 8.0).sin();
        let v = cv.volume(&m.positions);
        assert!((v.abs() - octagon * l).abs() < 1e-14, "{v} vs {}", octagon * l);
        // Translation invariance (caps close the surface).
        let shifted: Vec<Pt3> = m.positions.iter().map(|p| p + geom_core::math::Vec3::new(1.0, -2.0, 3.0)).collect();
        assert!((cv.volume(&shifted) - v).abs() < 1e-13);
    }
}
