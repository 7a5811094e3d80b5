//! Test-only tet meshes independent of the octree construction: the Kuhn (Freudenthal)
//! subdivision of a box grid, 6 tets per cube, conforming and positively oriented.

use geom_core::math::Pt3;

use crate::bcc::TetMesh;

/// Kuhn tetrahedralisation of `n[0]×n[1]×n[2]` cubes spanning `[lo, hi]`; fills `nodes`, `tets`,
/// `volume` and `centroid` only.
pub(crate) fn kuhn_box(n: [usize; 3], lo: Pt3, hi: Pt3) -> TetMesh {
    let id = |i: usize, j: usize, k: usize| (i + (n[0] + 1) * (j + (n[1] + 1) * k)) as u32;
    let mut nodes = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let f = |a: usize, m: usize, l: f64, h: f64| l + (h - l) * a as f64 / m as f64;
                nodes.push(Pt3::new(f(i, n[0], lo.x, hi.x), f(j, n[1], lo.y, hi.y), f(k, n[2], lo.z, hi.z)));
            }
        }
    }
    let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let mut tets = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                for p in perms {
                    let mut c = [i, j, k];
                    let mut t = [id(c[0], c[1], c[2]); 4];
                    for (s, &ax) in p.iter().enumerate() {
                        c[ax] += 1;
                        t[s + 1] = id(c[0], c[1], c[2]);
                    }
                    let [a, b, cc, d] = t.map(|v| nodes[v as usize]);
                    if (b - a).cross(&(cc - a)).dot(&(d - a)) < 0.0 {
                        t.swap(2, 3);
                    }
                    tets.push(t);
                }
            }
        }
    }
    let volume = tets
        .iter()
        .map(|t| {
            let [a, b, c, d] = t.map(|v: u32| nodes[v as usize]);
            (b - a).cross(&(c - a)).dot(&(d - a)) / 6.0
        })
        .collect();
    let centroid = tets
        .iter()
        .map(|t: &[u32; 4]| Pt3::from(t.iter().fold(Pt3::origin().coords, |s, &v| s + nodes[v as usize].coords) / 4.0))
        .collect();
    TetMesh { nodes, tets, volume, centroid, ..Default::default() }
}
