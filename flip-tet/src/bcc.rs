//! Graded BCC tetrahedral mesh (spec §3.2): node/tet arrays and per-tet geometry.

use geom_core::graph::Ragged;
use geom_core::math::{Pt3, Vec3};

/// Integer lattice coordinates of a mesh node in units of `u = h_min / 2` (spec §3.2): nodes are
/// identified exactly by their key, never by comparing float positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LatticeKey(pub [i32; 3]);

/// Tetrahedral mesh with node pressures and per-tet velocities (spec §2, §3.2).
///
/// Tets are positively oriented; `grad_bary[t][a]` is ∇λ_a of vertex `a` of tet `t` (1/m);
/// `face_nbr[t][a]` is the tet across the face opposite vertex `a`, or [`geom_core::NONE`].
#[derive(Clone, Debug, Default)]
pub struct TetMesh {
    /// Node positions (m).
    pub nodes: Vec<Pt3>,
    /// Exact lattice key of each node.
    pub node_key: Vec<LatticeKey>,
    /// Bit `f` set when the node lies on domain box face `f` (order −x, +x, −y, +y, −z, +z).
    pub node_boundary: Vec<u8>,
    /// Vertex ids of each tet, positively oriented.
    pub tets: Vec<[u32; 4]>,
    /// Tet volumes (m³).
    pub volume: Vec<f64>,
    /// Barycentric-coordinate gradients per tet vertex (1/m).
    pub grad_bary: Vec<[Vec3; 4]>,
    /// Tet centroids (m), where the P0 velocity lives.
    pub centroid: Vec<Pt3>,
    /// Octree level of the finer of the two cubes that generated the tet.
    pub tet_level: Vec<u8>,
    /// Face neighbours (opposite vertex a), `NONE` on the domain boundary.
    pub face_nbr: Vec<[u32; 4]>,
    /// Incident tets per node.
    pub node_tets: Ragged<u32>,
    /// Edge neighbours per node (sorted ascending, no duplicates), filled by
    /// [`TetMesh::compute_geometry`]; the same rows as `surface::node_edges`, cached because the
    /// level set and the redistancing need them every step.
    pub node_nbrs: Ragged<u32>,
    /// Local mesh size per node (m): the largest `(12 V)^{1/3}` over the incident tets (the cube
    /// edge of a regular BCC tet), filled by [`TetMesh::compute_geometry`]; equals
    /// `surface::node_sizes` bit for bit.
    pub node_h: Vec<f64>,
    /// Tets having the leaf's centre as a vertex, per octree leaf (point location).
    pub leaf_tets: Ragged<u32>,
    /// Fluid (non-solid) fraction `w_t ∈ [0, 1]` per tet when obstacles exist.
    pub solid_frac: Option<Vec<f64>>,
}

use std::collections::{HashMap, HashSet};

use geom_core::NONE;
use rayon::prelude::*;

use crate::error::MeshError;
use crate::octree::Octree;

/// Relative volume below which a tet is rejected as degenerate (spec §8 H-SLIVER): `V ≤ 1e−14 h³`.
pub const DEGENERATE_REL_VOLUME: f64 = 1e-14;

fn orient_det(a: &[i32; 3], b: &[i32; 3], c: &[i32; 3], d: &[i32; 3]) -> i64 {
    let u = [i64::from(b[0] - a[0]), i64::from(b[1] - a[1]), i64::from(b[2] - a[2])];
    let v = [i64::from(c[0] - a[0]), i64::from(c[1] - a[1]), i64::from(c[2] - a[2])];
    let w = [i64::from(d[0] - a[0]), i64::from(d[1] - a[1]), i64::from(d[2] - a[2])];
    u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])
}

struct Builder {
    key_id: HashMap<[i32; 3], u32>,
    keys: Vec<[i32; 3]>,
    tets: Vec<[u32; 4]>,
    level: Vec<u8>,
}

impl Builder {
    fn node(&mut self, k: [i32; 3]) -> u32 {
        if let Some(&i) = self.key_id.get(&k) {
            return i;
        }
        let i = self.keys.len() as u32;
        self.key_id.insert(k, i);
        self.keys.push(k);
        i
    }
}

/// Graded BCC tetrahedralisation of a strongly 2:1-balanced octree by the double-pyramid
/// construction of spec §3.2: for each leaf `B` and face `F`, the pieces of `F` (the face, or its
/// four quarters when the neighbour is finer) are coned to `c_B` and to the apex on the other side
/// (neighbour centre, small-leaf centre or boundary face centre), fanning over the piece boundary
/// including hanging edge midpoints. Nodes are numbered in order of first use over the sorted
/// leaves (deterministic).
pub fn tetrahedralize(oct: &Octree) -> Result<TetMesh, MeshError> {
    let sp = &oct.spec;
    let ext = sp.extent_units();
    let mut corners: HashSet<[i32; 3]> = HashSet::with_capacity(oct.leaves.len() * 2);
    for lf in &oct.leaves {
        let s = sp.size_units(lf.level);
        let o = lf.origin.0;
        for c in 0..8 {
            corners.insert([o[0] + (c & 1) * s, o[1] + ((c >> 1) & 1) * s, o[2] + ((c >> 2) & 1) * s]);
        }
    }
    let mut b = Builder {
        key_id: HashMap::with_capacity(oct.leaves.len() * 3),
        keys: Vec::new(),
        tets: Vec::with_capacity(oct.leaves.len() * 12),
        level: Vec::with_capacity(oct.leaves.len() * 12),
    };
    // Centres first so that node i < n_leaves is the centre of leaf i.
    for lf in &oct.leaves {
        let h = sp.size_units(lf.level) / 2;
        let o = lf.origin.0;
        b.node([o[0] + h, o[1] + h, o[2] + h]);
    }
    let mut pieces: Vec<([i32; 3], i32, [i32; 3], u8)> = Vec::with_capacity(4);
    for (bi, lf) in oct.leaves.iter().enumerate() {
        let l = lf.level;
        let s = sp.size_units(l);
        let o = lf.origin.0;
        let cb = [o[0] + s / 2, o[1] + s / 2, o[2] + s / 2];
        for d in 0..3 {
            let (d1, d2) = ((d + 1) % 3, (d + 2) % 3);
            for side in [-1i32, 1] {
                pieces.clear();
                let mut f = o;
                if side > 0 {
                    f[d] += s;
                }
                let mut n = o;
                n[d] += side * s;
                if n[d] < 0 || n[d] >= ext[d] {
                    let mut a = f;
                    a[d1] += s / 2;
                    a[d2] += s / 2;
                    pieces.push((f, s, a, l));
                } else if let Some(ni) = oct.leaf_id(l, n) {
                    if (bi as u32) < ni {
                        pieces.push((f, s, [n[0] + s / 2, n[1] + s / 2, n[2] + s / 2], l));
                    }
                } else {
                    // Coarser neighbour: it emits this face. Finer: four quarter pieces.
                    let coarser = (0..l).any(|cl| {
                        let cs = sp.size_units(cl);
                        oct.leaf_id(cl, [floor_to(n[0], cs), floor_to(n[1], cs), floor_to(n[2], cs)]).is_some()
                    });
                    if coarser {
                        continue;
                    }
                    let hs = s / 2;
                    for a1 in 0..2 {
                        for a2 in 0..2 {
                            let mut m = n;
                            if side < 0 {
                                m[d] += hs;
                            }
                            m[d1] += a1 * hs;
                            m[d2] += a2 * hs;
                            if l + 1 >= sp.levels || oct.leaf_id(l + 1, m).is_none() {
                                return Err(MeshError::NonConforming { faces: 1 });
                            }
                            let mut q = f;
                            q[d1] += a1 * hs;
                            q[d2] += a2 * hs;
                            pieces.push((q, hs, [m[0] + hs / 2, m[1] + hs / 2, m[2] + hs / 2], l + 1));
                        }
                    }
                }
                for &(q, t, apex, tl) in &pieces {
                    let mut poly: Vec<[i32; 3]> = Vec::with_capacity(8);
                    let cyc = [(0, 0), (t, 0), (t, t), (0, t)];
                    for k in 0..4 {
                        let (u0, v0) = cyc[k];
                        let (u1, v1) = cyc[(k + 1) % 4];
                        let mut p = q;
                        p[d1] += u0;
                        p[d2] += v0;
                        poly.push(p);
                        if t % 2 == 0 {
                            let mut mid = q;
                            mid[d1] += (u0 + u1) / 2;
                            mid[d2] += (v0 + v1) / 2;
                            if corners.contains(&mid) {
                                poly.push(mid);
                            }
                        }
                    }
                    let ic = b.node(cb);
                    let ia = b.node(apex);
                    for k in 0..poly.len() {
                        let (p0, p1) = (poly[k], poly[(k + 1) % poly.len()]);
                        let det = orient_det(&cb, &apex, &p0, &p1);
                        if det == 0 {
                            return Err(MeshError::DegenerateTet { tet: b.tets.len() as u32, volume: 0.0 });
                        }
                        let (i0, i1) = (b.node(p0), b.node(p1));
                        b.tets.push(if det > 0 { [ic, ia, i0, i1] } else { [ic, ia, i1, i0] });
                        b.level.push(tl);
                    }
                }
            }
        }
    }
    let nodes: Vec<Pt3> = b.keys.iter().map(|k| sp.position(k)).collect();
    let node_boundary: Vec<u8> = b
        .keys
        .iter()
        .map(|k| {
            let mut m = 0u8;
            for a in 0..3 {
                if k[a] == 0 {
                    m |= 1 << (2 * a);
                }
                if k[a] == ext[a] {
                    m |= 1 << (2 * a + 1);
                }
            }
            m
        })
        .collect();
    let mut mesh = TetMesh {
        nodes,
        node_key: b.keys.iter().map(|&k| LatticeKey(k)).collect(),
        node_boundary,
        tets: b.tets,
        tet_level: b.level,
        ..Default::default()
    };
    mesh.compute_geometry(sp.h_root)?;
    mesh.leaf_tets = Ragged::from_rows((0..oct.leaves.len()).map(|i| mesh.node_tets.row(i).to_vec()));
    Ok(mesh)
}

fn floor_to(v: i32, s: i32) -> i32 {
    v.div_euclid(s) * s
}

/// Result of [`TetMesh::quality_report`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QualityReport {
    /// Smallest and largest dihedral angle (degrees).
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle (degrees).
    pub max_dihedral_deg: f64,
    /// Smallest tet volume (m³).
    pub min_volume: f64,
    /// Sum of tet volumes (m³).
    pub total_volume: f64,
    /// Tets per node.
    pub tets_per_node: f64,
    /// Faces without a neighbour that do not lie on the domain boundary (0 for a conforming mesh).
    pub unmatched_interior_faces: usize,
}

/// Dihedral angles (radians) of a tet at its six edges, in the edge order (01, 02, 03, 12, 13, 23).
pub fn dihedral_angles(g: &[Vec3; 4]) -> [f64; 6] {
    // The dihedral angle at edge (i, j) is π minus the angle between the outward normals of the
    // two faces containing the edge, i.e. the faces opposite k and l; ∇λ points inward.
    let pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];
    pairs.map(|(i, j)| {
        let others: Vec<usize> = (0..4).filter(|&k| k != i && k != j).collect();
        let (a, c) = (g[others[0]], g[others[1]]);
        let cosn = a.dot(&c) / (a.norm() * c.norm());
        std::f64::consts::PI - cosn.clamp(-1.0, 1.0).acos()
    })
}

impl TetMesh {
    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Number of tets.
    pub fn n_tets(&self) -> usize {
        self.tets.len()
    }

    /// Whether tet `t` of a mesh built by [`tetrahedralize`] from an octree with resolution `spec`
    /// is a *transition tet* (spec §3.2 table): its two cube-centre vertices (local 0 = `c_B` and
    /// 1 = the apex, the order in which the construction emits them) come from cubes of different
    /// levels, i.e. the apex is neither a boundary face centre nor the centre of an equal cube at
    /// distance `h` of the tet's level. Only these tets can have obtuse dihedral angles and
    /// positive stiffness couplings (T-MESH-GRADED). Used by the mesh tests and the hard cases of
    /// spec §8 (H-GRADED-IFACE, H-SHARP-GRADING). Meaningless for hand-made meshes.
    pub fn is_transition(&self, t: usize, spec: &crate::octree::OctreeSpec) -> bool {
        let (c, a) = (self.tets[t][0] as usize, self.tets[t][1] as usize);
        let (k0, k1) = (self.node_key[c].0, self.node_key[a].0);
        let d2: i64 = (0..3).map(|i| i64::from(k0[i] - k1[i]).pow(2)).sum();
        let h2 = i64::from(spec.size_units(self.tet_level[t])).pow(2);
        self.node_boundary[a] == 0 && d2 != h2 && d2 * 4 != h2
    }

    /// Computes volumes, barycentric gradients, centroids (parallel), face neighbours and
    /// node → tet lists from `nodes` and `tets`. `h_ref` scales the degeneracy test: a tet with
    /// `V ≤ 1e−14 h_ref³` (or negative) is [`MeshError::DegenerateTet`].
    pub fn compute_geometry(&mut self, h_ref: f64) -> Result<(), MeshError> {
        let geo: Vec<(f64, [Vec3; 4], Pt3)> = self
            .tets
            .par_iter()
            .map(|t| {
                let p = t.map(|i| self.nodes[i as usize]);
                let (e1, e2, e3) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
                let det = e1.dot(&e2.cross(&e3));
                let vol = det / 6.0;
                // Rows of the inverse Jacobian give ∇λ1..3; ∇λ0 = −Σ.
                let g1 = e2.cross(&e3) / det;
                let g2 = e3.cross(&e1) / det;
                let g3 = e1.cross(&e2) / det;
                let g0 = -(g1 + g2 + g3);
                let c = Pt3::from((p[0].coords + p[1].coords + p[2].coords + p[3].coords) / 4.0);
                (vol, [g0, g1, g2, g3], c)
            })
            .collect();
        let vmin = DEGENERATE_REL_VOLUME * h_ref.powi(3);
        for (ti, g) in geo.iter().enumerate() {
            if g.0.partial_cmp(&vmin) != Some(std::cmp::Ordering::Greater) {
                return Err(MeshError::DegenerateTet { tet: ti as u32, volume: g.0 });
            }
        }
        self.volume = geo.iter().map(|g| g.0).collect();
        self.grad_bary = geo.iter().map(|g| g.1).collect();
        self.centroid = geo.iter().map(|g| g.2).collect();
        if self.tet_level.len() != self.tets.len() {
            self.tet_level = vec![0; self.tets.len()];
        }
        // Face neighbours through a hash of sorted vertex triples.
        let mut faces: HashMap<[u32; 3], (u32, u8)> = HashMap::with_capacity(self.tets.len() * 2);
        self.face_nbr = vec![[NONE; 4]; self.tets.len()];
        let mut over = 0usize;
        for (ti, t) in self.tets.iter().enumerate() {
            for a in 0..4 {
                let mut f = [t[(a + 1) % 4], t[(a + 2) % 4], t[(a + 3) % 4]];
                f.sort_unstable();
                match faces.remove(&f) {
                    Some((oj, oa)) => {
                        if self.face_nbr[oj as usize][oa as usize] != NONE {
                            over += 1;
                        }
                        self.face_nbr[oj as usize][oa as usize] = ti as u32;
                        self.face_nbr[ti][a] = oj;
                    }
                    None => {
                        faces.insert(f, (ti as u32, a as u8));
                    }
                }
            }
        }
        if over > 0 {
            return Err(MeshError::NonConforming { faces: over });
        }
        let pairs: Vec<(u32, u32)> =
            self.tets.iter().enumerate().flat_map(|(ti, t)| t.map(|i| (i, ti as u32))).collect();
        self.node_tets = Ragged::from_pairs(self.nodes.len(), &pairs);
        let (tets, node_tets, nodes) = (&self.tets, &self.node_tets, &self.nodes);
        let per_node: Vec<(Vec<u32>, f64)> = (0..nodes.len())
            .into_par_iter()
            .map(|i| {
                let mut nb = Vec::with_capacity(16);
                let mut h = 0.0f64;
                for &t in node_tets.row(i) {
                    let tv = tets[t as usize];
                    nb.extend(tv.iter().copied().filter(|&j| j as usize != i));
                    let [a, b, c, d] = tv.map(|v| nodes[v as usize]);
                    h = h.max((12.0 * crate::surface::tet_volume(&a, &b, &c, &d)).cbrt());
                }
                nb.sort_unstable();
                nb.dedup();
                (nb, h)
            })
            .collect();
        self.node_nbrs = Ragged::from_rows(per_node.iter().map(|(nb, _)| nb));
        self.node_h = per_node.iter().map(|(_, h)| *h).collect();
        Ok(())
    }

    /// Barycentric coordinates of `x` in tet `t`.
    pub fn barycentric(&self, t: u32, x: &Pt3) -> [f64; 4] {
        let ti = t as usize;
        let g = &self.grad_bary[ti];
        let c = self.centroid[ti];
        let d = x - c;
        [0.25 + g[0].dot(&d), 0.25 + g[1].dot(&d), 0.25 + g[2].dot(&d), 0.25 + g[3].dot(&d)]
    }

    /// The nodal field `f` interpolated linearly (P1) in tet `t` at `x`.
    pub fn interpolate(&self, t: u32, x: &Pt3, f: &[f64]) -> f64 {
        let l = self.barycentric(t, x);
        let tv = self.tets[t as usize];
        (0..4).map(|a| l[a] * f[tv[a] as usize]).sum()
    }

    /// Gradient of the P1 interpolant of the nodal field `f` in tet `t` (constant per tet).
    pub fn gradient(&self, t: u32, f: &[f64]) -> Vec3 {
        let tv = self.tets[t as usize];
        let g = &self.grad_bary[t as usize];
        (0..4).fold(Vec3::zeros(), |acc, a| acc + g[a] * f[tv[a] as usize])
    }

    /// Point location (spec §3.2): the leaf containing `x`, then the tets around the leaf centre;
    /// the first with all `λ ≥ −1e−12`, else the one with the largest minimum barycentric.
    /// Points outside the box are clamped to it. Returns `None` only for an empty mesh.
    pub fn locate(&self, oct: &Octree, x: &Pt3) -> Option<(u32, [f64; 4])> {
        if self.tets.is_empty() {
            return None;
        }
        let leaf = oct.leaf_at(x);
        let mut best: Option<(u32, [f64; 4], f64)> = None;
        for &t in self.leaf_tets.row(leaf as usize) {
            let l = self.barycentric(t, x);
            let m = l.iter().copied().fold(f64::INFINITY, f64::min);
            if m >= -1e-12 {
                return Some((t, l));
            }
            if best.as_ref().is_none_or(|b| m > b.2) {
                best = Some((t, l, m));
            }
        }
        best.map(|(t, l, _)| (t, l))
    }

    /// Walks from tet `start` towards `x` through face neighbours (across the face with the most
    /// negative barycentric), falling back to [`TetMesh::locate`] after 32 hops or at the boundary.
    pub fn walk(&self, oct: &Octree, start: u32, x: &Pt3) -> Option<(u32, [f64; 4])> {
        if (start as usize) < self.tets.len() {
            let mut t = start;
            for _ in 0..32 {
                let l = self.barycentric(t, x);
                let (mut am, mut m) = (0usize, l[0]);
                for (a, &v) in l.iter().enumerate().skip(1) {
                    if v < m {
                        m = v;
                        am = a;
                    }
                }
                if m >= -1e-12 {
                    return Some((t, l));
                }
                let n = self.face_nbr[t as usize][am];
                if n == NONE {
                    break;
                }
                t = n;
            }
        }
        self.locate(oct, x)
    }

    /// Dihedral extremes, volumes, tets per node and unmatched interior faces (spec §2).
    pub fn quality_report(&self) -> QualityReport {
        let mut q = QualityReport {
            min_dihedral_deg: f64::INFINITY,
            max_dihedral_deg: 0.0,
            min_volume: f64::INFINITY,
            ..Default::default()
        };
        for (ti, g) in self.grad_bary.iter().enumerate() {
            for a in dihedral_angles(g) {
                q.min_dihedral_deg = q.min_dihedral_deg.min(a.to_degrees());
                q.max_dihedral_deg = q.max_dihedral_deg.max(a.to_degrees());
            }
            q.min_volume = q.min_volume.min(self.volume[ti]);
            q.total_volume += self.volume[ti];
            for a in 0..4 {
                if self.face_nbr[ti][a] == NONE {
                    let t = self.tets[ti];
                    let f = [t[(a + 1) % 4], t[(a + 2) % 4], t[(a + 3) % 4]];
                    let common = f.iter().fold(0xffu8, |m, &i| m & self.node_boundary[i as usize]);
                    if common == 0 {
                        q.unmatched_interior_faces += 1;
                    }
                }
            }
        }
        q.tets_per_node = self.tets.len() as f64 / self.nodes.len().max(1) as f64;
        q
    }
}
