//! `cargo xtask inspect <file>`: what a mesh (OBJ/PLY/OFF) or motion (BVH) file holds, or why it
//! cannot be read. Unlike `TriMesh::new`, which stops at the first problem, this reports every
//! problem it finds, so a user can see how broken a file is before choosing to repair it.

use std::collections::HashMap;
use std::path::Path;

use geom_core::graph::UnionFind;
use geom_core::math::Pt3;
use geom_core::mesh::PolyMesh;

use crate::error::{io_err, Result};

/// Prints the file's contents; an unreadable file is an error (non-zero exit).
pub fn inspect(path: &Path) -> Result<()> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase()).unwrap_or_default();
    if ext == "bvh" {
        return inspect_bvh(path);
    }
    let mesh = geom_core::io::read_any(path)?;
    let d = diagnose(&mesh);
    say!("{}", path.display());
    say!("{}", d.render().trim_end());
    Ok(())
}

fn inspect_bvh(path: &Path) -> Result<()> {
    let text = std::fs::read_to_string(path).map_err(io_err(path))?;
    let info = geom_core::anim::bvh::inspect(&text)
        .map_err(|e| geom_core::Error::InFile { path: path.to_path_buf(), source: Box::new(e) })?;
    say!("{}", path.display());
    say!("{}", info.to_string().trim_end());
    Ok(())
}

/// Everything `inspect` reports about a polygon mesh.
#[derive(Debug, Default, PartialEq)]
pub struct MeshDiagnosis {
    /// Vertex count.
    pub vertices: usize,
    /// Polygon count.
    pub polygons: usize,
    /// Triangles after fan triangulation.
    pub triangles: usize,
    /// Axis-aligned bounds (None when there are no vertices).
    pub bounds: Option<(Pt3, Pt3)>,
    /// Vertices with a NaN/infinite coordinate.
    pub non_finite_vertices: Vec<u32>,
    /// Vertices used by no face.
    pub unreferenced_vertices: usize,
    /// Connected components (of faces sharing vertices), isolated vertices not counted.
    pub components: usize,
    /// Boundary loops (closed chains of edges with one incident face).
    pub boundary_loops: usize,
    /// Boundary edges.
    pub boundary_edges: usize,
    /// Edges with more than two incident faces, as (a, b, face count).
    pub non_manifold_edges: Vec<(u32, u32, usize)>,
    /// Vertices whose incident faces form more than one fan.
    pub non_manifold_vertices: Vec<u32>,
    /// Pairs of faces traversing a shared edge in the same direction.
    pub inconsistent_edges: usize,
    /// Triangles (after fan triangulation) with area below 1e-14·(bbox diagonal)².
    pub degenerate_faces: Vec<u32>,
}

/// Analyses a polygon mesh without failing on any defect.
pub fn diagnose(m: &PolyMesh) -> MeshDiagnosis {
    let n = m.positions.len();
    let mut d = MeshDiagnosis { vertices: n, polygons: m.faces.len(), ..Default::default() };
    let mut lo = Pt3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let mut hi = -lo;
    for (i, p) in m.positions.iter().enumerate() {
        if p.iter().all(|c| c.is_finite()) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        } else {
            d.non_finite_vertices.push(i as u32);
        }
    }
    if lo.x.is_finite() {
        d.bounds = Some((lo, hi));
    }
    let diag2 = if lo.x.is_finite() { (hi - lo).norm_squared() } else { 0.0 };
    // Fan triangles over valid indices only; faces with bad indices were refused by the reader.
    let mut tris: Vec<[u32; 3]> = Vec::new();
    for f in m.faces.rows() {
        for k in 1..f.len().saturating_sub(1) {
            tris.push([f[0], f[k], f[k + 1]]);
        }
    }
    d.triangles = tris.len();
    let valid = |v: u32| (v as usize) < n;
    let mut used = vec![false; n];
    let mut directed: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (fi, t) in tris.iter().enumerate() {
        if !t.iter().all(|&v| valid(v)) {
            continue;
        }
        for &v in t {
            used[v as usize] = true;
        }
        let [a, b, c] = t.map(|v| m.positions[v as usize]);
        let area = 0.5 * (b - a).cross(&(c - a)).norm();
        if area.is_nan() || area <= 1e-14 * diag2 {
            d.degenerate_faces.push(fi as u32);
        }
        for k in 0..3 {
            directed.entry((t[k], t[(k + 1) % 3])).or_default().push(fi as u32);
        }
    }
    d.unreferenced_vertices = used.iter().filter(|u| !**u).count();
    // Undirected edges: incident faces and orientation consistency.
    let mut undirected: HashMap<(u32, u32), (usize, usize)> = HashMap::new(); // (a→b count, b→a count)
    for (&(a, b), fs) in &directed {
        let key = (a.min(b), a.max(b));
        let e = undirected.entry(key).or_default();
        if a < b {
            e.0 += fs.len();
        } else {
            e.1 += fs.len();
        }
    }
    let mut boundary: Vec<(u32, u32)> = Vec::new();
    let mut edges: Vec<_> = undirected.into_iter().collect();
    edges.sort_unstable();
    for ((a, b), (ab, ba)) in &edges {
        let total = ab + ba;
        if total == 1 {
            d.boundary_edges += 1;
            boundary.push((*a, *b));
        } else if total > 2 {
            d.non_manifold_edges.push((*a, *b, total));
        } else if *ab == 2 || *ba == 2 {
            d.inconsistent_edges += 1;
        }
    }
    // Components over faces sharing a vertex.
    let mut uf = UnionFind::new(n);
    for t in tris.iter().filter(|t| t.iter().all(|&v| valid(v))) {
        uf.union(t[0], t[1]);
        uf.union(t[1], t[2]);
    }
    let mut roots: Vec<u32> = (0..n as u32).filter(|&v| used[v as usize]).map(|v| uf.find(v)).collect();
    roots.sort_unstable();
    roots.dedup();
    d.components = roots.len();
    // Boundary loops: components of the boundary-edge graph.
    let mut buf = UnionFind::new(n);
    let mut on_boundary = vec![false; n];
    for &(a, b) in &boundary {
        buf.union(a, b);
        on_boundary[a as usize] = true;
        on_boundary[b as usize] = true;
    }
    let mut broots: Vec<u32> = (0..n as u32).filter(|&v| on_boundary[v as usize]).map(|v| buf.find(v)).collect();
    broots.sort_unstable();
    broots.dedup();
    d.boundary_loops = broots.len();
    // Non-manifold vertices: the faces around a vertex, linked through shared manifold edges,
    // must form one fan.
    let mut vertex_tris: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (fi, t) in tris.iter().enumerate() {
        if t.iter().all(|&v| valid(v)) {
            for &v in t {
                vertex_tris[v as usize].push(fi as u32);
            }
        }
    }
    for (v, fs) in vertex_tris.iter().enumerate() {
        if fs.len() < 2 {
            continue;
        }
        let mut local = UnionFind::new(fs.len());
        for i in 0..fs.len() {
            for j in i + 1..fs.len() {
                let (ti, tj) = (tris[fs[i] as usize], tris[fs[j] as usize]);
                let shared = ti.iter().filter(|&&x| x != v as u32 && tj.contains(&x)).count();
                if shared > 0 {
                    local.union(i as u32, j as u32);
                }
            }
        }
        if local.labels().0 > 1 {
            d.non_manifold_vertices.push(v as u32);
        }
    }
    d
}

impl MeshDiagnosis {
    /// Human-readable multi-line report.
    pub fn render(&self) -> String {
        use std::fmt::Write as _;
        let list = |v: &[u32]| {
            let shown: Vec<String> = v.iter().take(10).map(|x| x.to_string()).collect();
            format!(
                "{}{}",
                shown.join(", "),
                if v.len() > 10 { format!(", … ({} in all)", v.len()) } else { String::new() }
            )
        };
        let mut s = String::new();
        let _ = writeln!(s, "  vertices            {}", self.vertices);
        let _ = writeln!(s, "  polygons            {} ({} triangles)", self.polygons, self.triangles);
        match self.bounds {
            Some((lo, hi)) => {
                let _ =
                    writeln!(
                    s,
                    "  bounds              [{:.6}, {:.6}, {:.6}] – [{:.6}, {:.6}, {:.6}] (size {:.6} × {:.6} × {:.6})",
                    lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, hi.x - lo.x, hi.y - lo.y, hi.z - lo.z
                );
            }
            None => {
                let _ = writeln!(s, "  bounds              (no vertices)");
            }
        }
        let _ = writeln!(s, "  components          {}", self.components);
        let _ = writeln!(s, "  boundary loops      {} ({} boundary edges)", self.boundary_loops, self.boundary_edges);
        let _ = writeln!(s, "  unreferenced verts  {}", self.unreferenced_vertices);
        let _ = writeln!(s, "  non-finite verts    {}", self.non_finite_vertices.len());
        if !self.non_finite_vertices.is_empty() {
            let _ = writeln!(s, "      {}", list(&self.non_finite_vertices));
        }
        let _ = writeln!(s, "  non-manifold edges  {}", self.non_manifold_edges.len());
        for (a, b, k) in self.non_manifold_edges.iter().take(10) {
            let _ = writeln!(s, "      ({a}, {b}) shared by {k} faces");
        }
        let _ = writeln!(s, "  non-manifold verts  {}", self.non_manifold_vertices.len());
        if !self.non_manifold_vertices.is_empty() {
            let _ = writeln!(s, "      {}", list(&self.non_manifold_vertices));
        }
        let _ = writeln!(
            s,
            "  inconsistent edges  {} (neighbouring faces with opposite orientation)",
            self.inconsistent_edges
        );
        let _ = writeln!(s, "  degenerate faces    {}", self.degenerate_faces.len());
        if !self.degenerate_faces.is_empty() {
            let _ = writeln!(s, "      triangles {}", list(&self.degenerate_faces));
        }
        let closed = self.boundary_edges == 0 && self.non_manifold_edges.is_empty() && self.triangles > 0;
        let _ = writeln!(
            s,
            "  closed manifold     {}",
            if closed && self.non_manifold_vertices.is_empty() { "yes" } else { "no" }
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::graph::Ragged;

    fn poly(p: &[[f64; 3]], f: &[&[u32]]) -> PolyMesh {
        PolyMesh {
            positions: p.iter().map(|q| Pt3::new(q[0], q[1], q[2])).collect(),
            faces: Ragged::from_rows(f.iter().map(|r| r.to_vec())),
            uv: None,
        }
    }

    const TET: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    #[test]
    fn closed_tetrahedron_is_clean() {
        let d = diagnose(&poly(&TET, &[&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[0, 3, 2]]));
        assert_eq!((d.components, d.boundary_loops, d.boundary_edges, d.inconsistent_edges), (1, 0, 0, 0));
        assert!(d.non_manifold_edges.is_empty() && d.non_manifold_vertices.is_empty() && d.degenerate_faces.is_empty());
        assert!(d.render().contains("closed manifold     yes"));
    }

    #[test]
    fn finds_every_defect() {
        // Three triangles on edge (0,1) (non-manifold edge), a flipped face, a degenerate face,
        // two fans meeting at vertex 6 (bow tie), an unreferenced vertex.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.5, 0.0, 1.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [4.0, 1.0, 0.0],
            [4.0, -1.0, 0.0],
            [2.0, 1.0, 0.0],
            [2.0, -1.0, 0.0],
            [9.0, 9.0, 9.0],
            [5.0, 5.0, 5.0],
        ];
        let f: &[&[u32]] = &[&[0, 1, 2], &[1, 0, 3], &[0, 1, 4], &[6, 7, 8], &[6, 9, 10], &[5, 5, 6]];
        let d = diagnose(&poly(&p, f));
        assert_eq!(d.non_manifold_edges, vec![(0, 1, 3)]);
        assert!(d.non_manifold_vertices.contains(&6));
        assert_eq!(d.degenerate_faces, vec![5]);
        assert_eq!(d.unreferenced_vertices, 2);
    }

    #[test]
    fn flipped_neighbour_is_counted() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let d = diagnose(&poly(&p, &[&[0, 1, 2], &[1, 2, 3]]));
        assert_eq!(d.inconsistent_edges, 1);
        assert_eq!(d.boundary_loops, 1);
    }
}
