//! A mixed-polygon control patch with a hole (spec §6.4 `topology`): triangles, quads and
//! pentagons on a shoulder-like spherical cap with a hole at its pole, to show that the bar-net
//! handles arbitrary connectivity (the paper: "the network is capable of handling any
//! connectivity").
//!
//! Decision: the spec suggests a shoulder patch of the geom-core capsule humanoid polygonised at
//! about 300 vertices; that generator was not available this session, so the patch is built
//! procedurally with the same character: `rings + 1` rings of `around` vertices on a sphere
//! cap (radius 0.2 m) between polar radii 0.03 and 0.15 m, no faces inside the first ring (the
//! hole); cells between rings are quads, every cell with `(r + k) % 5 == 0` is split into two
//! triangles, and every ring edge with `(r + 2k) % 7 == 3` gets a midpoint vertex, which turns
//! the two cells sharing it into pentagons.

use geom_core::graph::Ragged;
use geom_core::math::Pt3;
use geom_core::mesh::PolyMesh;
use std::collections::HashMap;
use std::f64::consts::TAU;

/// The patch and its node classes.
#[derive(Clone, Debug)]
pub struct Patch {
    /// The control mesh.
    pub mesh: PolyMesh,
    /// Per vertex: on the hole or the outer boundary (the fixed nodes of the scene).
    pub boundary: Vec<bool>,
}

/// Builds the mixed patch with `rings` cell rings of `around` cells (defaults 12 × 24 give
/// about 330 vertices).
pub fn mixed_patch(rings: usize, around: usize) -> Patch {
    let (rings, around) = (rings.max(3), around.max(6));
    let sphere = 0.2;
    let (rho0, rho1) = (0.03, 0.15);
    let mut positions = Vec::new();
    let mut boundary = Vec::new();
    let at = |rho: f64, th: f64| Pt3::new(rho * th.cos(), rho * th.sin(), (sphere * sphere - rho * rho).sqrt());
    for r in 0..=rings {
        let rho = rho0 + (rho1 - rho0) * r as f64 / rings as f64;
        for k in 0..around {
            positions.push(at(rho, TAU * k as f64 / around as f64));
            boundary.push(r == 0 || r == rings);
        }
    }
    let v = |r: usize, k: usize| (r * around + k % around) as u32;
    // Midpoints on interior ring edges (ring r from 1 to rings-1, edge k→k+1).
    let mut mid: HashMap<(usize, usize), u32> = HashMap::new();
    for r in 1..rings {
        for k in 0..around {
            if (r + 2 * k) % 7 == 3 {
                let rho = rho0 + (rho1 - rho0) * r as f64 / rings as f64;
                mid.insert((r, k), positions.len() as u32);
                positions.push(at(rho, TAU * (k as f64 + 0.5) / around as f64));
                boundary.push(false);
            }
        }
    }
    let mut faces = Ragged::new();
    for r in 0..rings {
        for k in 0..around {
            // Inner ring k → k+1, then the outer ring back (reversed below so that faces are
            // counter-clockwise seen from outside the sphere).
            let mut f = vec![v(r, k), v(r, k + 1)];
            let inner_mid = mid.get(&(r, k)).copied();
            let outer_mid = mid.get(&(r + 1, k)).copied();
            if let Some(m) = inner_mid {
                f.insert(1, m);
            }
            f.push(v(r + 1, k + 1));
            if let Some(m) = outer_mid {
                f.push(m);
            }
            f.push(v(r + 1, k));
            f.reverse();
            if f.len() == 4 && (r + k) % 5 == 0 {
                faces.push_row(&[f[0], f[1], f[2]]);
                faces.push_row(&[f[0], f[2], f[3]]);
            } else {
                faces.push_row(&f);
            }
        }
    }
    Patch { mesh: PolyMesh { positions, faces, uv: None }, boundary }
}

/// Number of faces with 3, 4, 5 and more corners.
pub fn face_histogram(m: &PolyMesh) -> [usize; 4] {
    let mut h = [0; 4];
    for row in m.faces.rows() {
        h[row.len().clamp(3, 6) - 3] += 1;
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topo::PolyTopo;

    #[test]
    fn patch_has_every_face_kind_and_a_hole() {
        let p = mixed_patch(12, 24);
        let h = face_histogram(&p.mesh);
        assert!(h[0] > 0 && h[1] > 0 && h[2] > 0, "{h:?}");
        let n = p.mesh.positions.len();
        assert!((280..=360).contains(&n), "{n} vertices");
        let t = PolyTopo::new(&p.mesh).unwrap();
        // Manifold: every edge has one or two faces; two boundary loops (hole + rim).
        assert!((0..t.edges.len()).all(|e| (1..=2).contains(&t.edge_faces.row(e).len())));
        assert_eq!(t.boundary_loops(&p.mesh).len(), 2);
    }
}
