//! Liquid volume of a piecewise-linear level set on a tet mesh (spec §3.11.5).

use geom_core::math::Pt3;

use crate::bcc::TetMesh;

/// Unsigned volume of the tetrahedron `(a, b, c, d)` (m³).
pub(crate) fn tet_volume(a: &Pt3, b: &Pt3, c: &Pt3, d: &Pt3) -> f64 {
    ((b - a).cross(&(c - a))).dot(&(d - a)).abs() / 6.0
}

/// Point where the linear interpolant crosses zero on the edge `(pa, va) – (pb, vb)`
/// (`va`, `vb` of opposite signs).
fn crossing(pa: &Pt3, pb: &Pt3, va: f64, vb: f64) -> Pt3 {
    pa + (pb - pa) * (va / (va - vb))
}

/// Volume of `{φ < 0}` inside one tet for the linear interpolant of the vertex values `v` (m³).
///
/// One negative vertex `a`: `V Π_{b≠a} φ_a/(φ_a − φ_b)`; three negative: `V` minus the
/// one-positive formula; two negative: the wedge split into three tets (spec §3.11.5). Exact up
/// to rounding. A value of exactly 0 counts as outside.
pub fn tet_liquid_volume(p: &[Pt3; 4], v: &[f64; 4]) -> f64 {
    let neg: Vec<usize> = (0..4).filter(|&i| v[i] < 0.0).collect();
    let vol = tet_volume(&p[0], &p[1], &p[2], &p[3]);
    let corner = |a: usize| -> f64 { (0..4).filter(|&b| b != a).map(|b| v[a] / (v[a] - v[b])).product::<f64>() * vol };
    match neg.len() {
        0 => 0.0,
        4 => vol,
        1 => corner(neg[0]),
        3 => {
            let pos = (0..4).find(|i| !neg.contains(i)).expect("exactly one non-negative vertex");
            vol - corner(pos)
        }
        _ => {
            let (a, b) = (neg[0], neg[1]);
            let pos: Vec<usize> = (0..4).filter(|i| !neg.contains(i)).collect();
            let (c, d) = (pos[0], pos[1]);
            let pac = crossing(&p[a], &p[c], v[a], v[c]);
            let pad = crossing(&p[a], &p[d], v[a], v[d]);
            let pbc = crossing(&p[b], &p[c], v[b], v[c]);
            let pbd = crossing(&p[b], &p[d], v[b], v[d]);
            // Prism (a, pac, pad) / (b, pbc, pbd), lateral edges a–b, pac–pbc, pad–pbd.
            tet_volume(&p[a], &pac, &pad, &pbd)
                + tet_volume(&p[a], &pac, &pbc, &pbd)
                + tet_volume(&p[a], &p[b], &pbc, &pbd)
        }
    }
}

/// `vol_levelset`: total volume of `{φ < 0}` over the mesh for the piecewise-linear `phi` (one
/// value per node), exact for piecewise-linear fields (spec §3.11.5), in m³. Tet volumes are
/// recomputed from the node positions, so only `mesh.nodes` and `mesh.tets` are read.
///
/// Panics if `phi.len() != mesh.nodes.len()` (a caller bug: the field belongs to another mesh).
pub fn liquid_volume(mesh: &TetMesh, phi: &[f64]) -> f64 {
    assert_eq!(phi.len(), mesh.nodes.len(), "liquid_volume: one value per node expected");
    mesh.tets
        .iter()
        .map(|t| {
            let p = t.map(|i| mesh.nodes[i as usize]);
            let v = t.map(|i| phi[i as usize]);
            tet_liquid_volume(&p, &v)
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::test_mesh::kuhn_box;
    use geom_core::rng::Rng;

    #[test]
    fn planar_field_gives_exact_prism_volume() {
        // Box [0,1]×[0,0.5]×[0,0.25], plane y = H tilted slightly (still within the box).
        let mesh = kuhn_box([6, 3, 2], Pt3::origin(), Pt3::new(1.0, 0.5, 0.25));
        for h in [0.1, 0.2371, 0.3333] {
            let phi: Vec<f64> = mesh.nodes.iter().map(|p| p.y - h).collect();
            let v = liquid_volume(&mesh, &phi);
            let exact = 1.0 * 0.25 * h;
            assert!((v - exact).abs() <= 1e-12 * exact, "{v} vs {exact}");
            // Tilted plane y = h + 0.05 (x − 0.5): same volume (antisymmetric tilt).
            let phi: Vec<f64> = mesh.nodes.iter().map(|p| p.y - h - 0.05 * (p.x - 0.5)).collect();
            let v = liquid_volume(&mesh, &phi);
            assert!((v - exact).abs() <= 1e-12 * exact, "{v} vs {exact}");
        }
    }

    #[test]
    fn single_tet_cases_are_complementary() {
        let p = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0), Pt3::new(0.0, 0.0, 1.0)];
        let full = tet_volume(&p[0], &p[1], &p[2], &p[3]);
        let mut rng = Rng::new(3);
        for _ in 0..200 {
            let v = [0, 1, 2, 3].map(|_| rng.range(-1.0, 1.0));
            let neg = tet_liquid_volume(&p, &v);
            let pos = tet_liquid_volume(&p, &v.map(|x| -x));
            // {φ<0} and {−φ<0} partition the tet (1e-14 relative: a few roundings).
            assert!((neg + pos - full).abs() <= 1e-14, "{neg} + {pos} != {full}");
            assert!(neg >= 0.0 && neg <= full + 1e-15);
        }
        // One negative vertex at the origin with φ = x + y + z − 1/2: corner tet of edge 1/2.
        let v = [-0.5, 0.5, 0.5, 0.5];
        assert!((tet_liquid_volume(&p, &v) - full / 8.0).abs() <= 1e-16);
    }
}
