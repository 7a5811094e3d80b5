//! Element evaluation and fixed-pattern sparse assembly of the implicit system (shells.md §3.7,
//! §3.8).
//!
//! Every element (triangle, hinge) writes its energy, local forces and local system matrix
//! (h_eff²K_e + h_eff K_d,e − h_eff J_v,e) into its own slot of flat buffers, in parallel. Then
//! (a) each vertex sums its element forces in a fixed order and (b) each stored matrix entry sums
//! its contributions in a fixed order ([`FixedPattern`]). Both reductions are independent of the
//! thread count, so the whole assembly is bitwise deterministic. The pattern never changes, so
//! the symbolic Cholesky analysis is computed once.

use crate::integrator::DofMap;
use crate::kernels::bending::{bending_eval, wrap_angle};
use crate::kernels::hinge::{hinge_is_collapsed, HingeFrame};
use crate::kernels::membrane::{membrane_eval, Membrane};
use crate::kernels::psd::HessianMode;
use crate::mesh::ShellMesh;
use crate::wind::WindField;
use geom_core::linalg::{Csc, FixedPattern};
use geom_core::math::{Mat3, Pt3, Vec3};
use geom_core::NONE;
use rayon::prelude::*;

const TRI_VALS: usize = 81;
const HINGE_VALS: usize = 144;
const DIAG_VALS: usize = 9;
/// Values per extra (contact-coupling) pair: blocks (i, j) and (j, i) stacked as the rows of a
/// 6 × 3 column-major matrix with column stride 9, the stride of the triangles' local matrices,
/// so every off-diagonal block offset is addressed alike (`vals[off + 9c + r]`).
const EXTRA_VALS: usize = 27;

/// Inputs of one element pass.
pub(crate) struct EvalInput<'a> {
    pub q: &'a [Pt3],
    pub v: &'a [Vec3],
    pub h_eff: f64,
    pub mode: HessianMode,
    pub law: &'a Membrane,
    /// (α, β_stretch, β_shear, β_bend).
    pub damping: (f64, f64, f64, f64),
    pub wind: Option<(&'a WindField, f64)>,
    /// Extra diagonal shift τ (times the mass) for the regularised retry.
    pub shift: f64,
}

/// Element pass results that are not stored in the matrix.
#[derive(Clone, Debug, Default)]
pub(crate) struct EvalOutput {
    pub skipped_hinges: u32,
    pub collapsed_triangles: u32,
}

/// Buffers, gather lists, the fixed pattern.
///
/// Element matrices are stored column-major in `vals` (triangles, then hinges, then the diagonal
/// mass blocks). Every stored entry `e` of the lower-triangular CSC matrix is the sum of
/// `vals[gather[k]]` for k in `gather_ptr[e]..gather_ptr[e + 1]`, in the fixed contribution
/// order of [`FixedPattern`] (precomputed once: no hashing, sorting or intermediate buffer per
/// step), so the sums are bitwise independent of the thread count.
pub(crate) struct Assembler {
    pub dofs: DofMap,
    mat: Csc,
    gather_ptr: Vec<u32>,
    gather: Vec<u32>,
    vals: Vec<f64>,
    off_hinge: usize,
    off_diag: usize,
    elem_force: Vec<Vec3>,
    tri_energy: Vec<f64>,
    hinge_energy: Vec<f64>,
    hinge_skipped: Vec<bool>,
    tri_collapsed: Vec<bool>,
    force_ptr: Vec<u32>,
    force_idx: Vec<u32>,
    /// Custom diagonal Jacobian blocks (−h J_v − h² J_x) per free vertex, added to the diagonal.
    pub custom_diag: Vec<Mat3>,
    /// Custom off-diagonal blocks: (offset of the block in a triangle's local matrix, block).
    pub custom_offdiag: Vec<(usize, Mat3)>,
    /// Contact Hessian blocks (h² times the barrier and friction Hessians) per free vertex.
    pub contact_diag: Vec<Mat3>,
    /// Contact off-diagonal blocks inside the pattern: (offset in a triangle's local matrix, block).
    pub contact_offdiag: Vec<(usize, Mat3)>,
    /// Offset in the element buffers of block (i, j): in the local matrix of the first triangle
    /// holding both vertices, or in the contact-coupling region for an [`Assembler::extra`] pair.
    pub(crate) block_offset: std::collections::HashMap<(u32, u32), usize>,
    /// Vertex pairs (i < j, both free, sharing no triangle) whose 3×3 coupling blocks the pattern
    /// also holds (contact pairs of IPC, [`Assembler::with_extra`]); sorted.
    pub(crate) extra: Vec<(u32, u32)>,
    off_extra: usize,
}

impl Assembler {
    pub(crate) fn new(mesh: &ShellMesh, dofs: DofMap) -> Self {
        Self::with_extra(mesh, dofs, Vec::new())
    }

    /// The assembler of the mesh's pattern plus the coupling blocks of the vertex pairs `extra`
    /// (pairs already in the mesh's pattern, with a constrained vertex, or i = j are dropped).
    /// Each extra pair owns [`EXTRA_VALS`] values after the diagonal blocks (blocks (i, j) and
    /// (j, i)); only their lower-triangle entries enter the matrix (as for elements).
    pub(crate) fn with_extra(mesh: &ShellMesh, dofs: DofMap, mut extra: Vec<(u32, u32)>) -> Self {
        let nt = mesh.tris.len();
        let nh = mesh.hinges.len();
        let nf = dofs.n_free();
        let off_hinge = nt * TRI_VALS;
        let off_diag = off_hinge + nh * HINGE_VALS;
        let off_extra = off_diag + nf * DIAG_VALS;
        let mut block_offset = std::collections::HashMap::new();
        for (t, tri) in mesh.tris.iter().enumerate() {
            for a in 0..3 {
                for b in 0..3 {
                    if a != b {
                        block_offset.entry((tri[a], tri[b])).or_insert(t * TRI_VALS + 3 * b * 9 + 3 * a);
                    }
                }
            }
        }
        for p in extra.iter_mut() {
            *p = (p.0.min(p.1), p.0.max(p.1));
        }
        extra.sort_unstable();
        extra.dedup();
        extra.retain(|&(i, j)| {
            i != j
                && dofs.free_index[i as usize] != NONE
                && dofs.free_index[j as usize] != NONE
                && !block_offset.contains_key(&(i, j))
        });
        let mut keys: Vec<(u32, u32)> = Vec::new();
        let mut src: Vec<u32> = Vec::new();
        let fi = &dofs.free_index;
        let mut push_elem = |verts: &[u32], base: usize, nloc: usize| {
            for (a, &va) in verts.iter().enumerate() {
                let fa = fi[va as usize];
                if fa == NONE {
                    continue;
                }
                for (b, &vb) in verts.iter().enumerate() {
                    let fb = fi[vb as usize];
                    if fb == NONE {
                        continue;
                    }
                    for r in 0..3 {
                        for c in 0..3 {
                            let (row, col) = (3 * fa + r, 3 * fb + c);
                            if row >= col {
                                keys.push((row, col));
                                // Column-major local storage: entry (3a + r, 3b + c).
                                src.push((base + (3 * b + c as usize) * nloc + 3 * a + r as usize) as u32);
                            }
                        }
                    }
                }
            }
        };
        for (t, tri) in mesh.tris.iter().enumerate() {
            push_elem(tri, t * TRI_VALS, 9);
        }
        for (h, hg) in mesh.hinges.iter().enumerate() {
            push_elem(&hg.v, off_hinge + h * HINGE_VALS, 12);
        }
        for f in 0..nf as u32 {
            for r in 0..3u32 {
                for c in 0..=r {
                    keys.push((3 * f + r, 3 * f + c));
                    src.push((off_diag + f as usize * DIAG_VALS + (3 * r + c) as usize) as u32);
                }
            }
        }
        for (k, &(i, j)) in extra.iter().enumerate() {
            let base = off_extra + EXTRA_VALS * k;
            for (blk, (a, b)) in [(i, j), (j, i)].into_iter().enumerate() {
                let (fa, fb) = (fi[a as usize], fi[b as usize]);
                if fa < fb {
                    continue; // strictly upper block: its transpose carries the entries
                }
                for r in 0..3u32 {
                    for c in 0..3u32 {
                        keys.push((3 * fa + r, 3 * fb + c));
                        src.push((base + 3 * blk + (9 * c + r) as usize) as u32);
                    }
                }
            }
            block_offset.insert((i, j), base);
            block_offset.insert((j, i), base + 3);
        }
        let pattern = FixedPattern::new(3 * nf, 3 * nf, &keys, true);
        // Per stored entry, the `vals` indices of its contributions in increasing key order (the
        // order FixedPattern sums in).
        let nnz = pattern.nnz();
        let mut count = vec![0u32; nnz + 1];
        for k in 0..keys.len() {
            if let Some(e) = pattern.slot(k) {
                count[e + 1] += 1;
            }
        }
        for e in 0..nnz {
            count[e + 1] += count[e];
        }
        let gather_ptr = count.clone();
        let mut gather = vec![0u32; count[nnz] as usize];
        for (k, &sk) in src.iter().enumerate() {
            if let Some(e) = pattern.slot(k) {
                gather[count[e] as usize] = sk;
                count[e] += 1;
            }
        }
        let mat = pattern.csc().clone();
        // Per-vertex force gather in element order (triangles first, then hinges).
        let n = mesh.n_vertices();
        let mut count = vec![0u32; n + 1];
        for tri in &mesh.tris {
            for &v in tri {
                count[v as usize + 1] += 1;
            }
        }
        for hg in &mesh.hinges {
            for &v in &hg.v {
                count[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let force_ptr = count.clone();
        let mut fill = count;
        let mut force_idx = vec![0u32; *force_ptr.last().unwrap_or(&0) as usize];
        for (t, tri) in mesh.tris.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                force_idx[fill[v as usize] as usize] = (3 * t + k) as u32;
                fill[v as usize] += 1;
            }
        }
        for (h, hg) in mesh.hinges.iter().enumerate() {
            for (k, &v) in hg.v.iter().enumerate() {
                force_idx[fill[v as usize] as usize] = (3 * nt + 4 * h + k) as u32;
                fill[v as usize] += 1;
            }
        }
        Self {
            mat,
            gather_ptr,
            gather,
            vals: vec![0.0; off_extra + EXTRA_VALS * extra.len()],
            off_hinge,
            off_diag,
            elem_force: vec![Vec3::zeros(); 3 * nt + 4 * nh],
            tri_energy: vec![0.0; nt],
            hinge_energy: vec![0.0; nh],
            hinge_skipped: vec![false; nh],
            tri_collapsed: vec![false; nt],
            force_ptr,
            force_idx,
            custom_diag: vec![Mat3::zeros(); nf],
            custom_offdiag: Vec::new(),
            contact_diag: vec![Mat3::zeros(); nf],
            contact_offdiag: Vec::new(),
            block_offset,
            extra,
            off_extra,
            dofs,
        }
    }

    /// Where the contact-coupling blocks of the extra pairs start in the element buffers.
    pub(crate) fn off_extra(&self) -> usize {
        self.off_extra
    }

    /// Offset of the (i, j) block (i ≠ j sharing a triangle, or an extra pair) in the buffers.
    pub(crate) fn block_offset(&self, i: u32, j: u32) -> Option<usize> {
        self.block_offset.get(&(i, j)).copied()
    }

    /// The assembled matrix (lower triangle) as of the last [`Assembler::assemble`].
    pub(crate) fn matrix(&self) -> &Csc {
        &self.mat
    }

    /// Sums the element buffers into the matrix (fixed order per entry, parallel over entries).
    fn gather_matrix(&mut self) {
        let (ptr, idx, vals) = (&self.gather_ptr, &self.gather, &self.vals);
        self.mat.val_mut().par_iter_mut().with_min_len(4096).enumerate().for_each(|(e, out)| {
            let mut s = 0.0;
            for &k in &idx[ptr[e] as usize..ptr[e + 1] as usize] {
                s += vals[k as usize];
            }
            *out = s;
        });
    }

    /// Evaluates all elements at `inp.q`/`inp.v`, writes element forces (elastic + damping +
    /// wind) into `force` (one per vertex, overwritten), and assembles the system matrix.
    pub(crate) fn assemble(&mut self, mesh: &ShellMesh, inp: &EvalInput, force: &mut [Vec3]) -> EvalOutput {
        let (alpha, bs, bsh, bb) = inp.damping;
        let h = inp.h_eff;
        let h2 = h * h;
        let damp_mem = (bs > 0.0 || bsh > 0.0).then_some((bs, bsh));
        let nt = mesh.tris.len();
        let (tri_vals, rest) = self.vals.split_at_mut(self.off_hinge);
        let (hinge_vals, diag_vals) = rest.split_at_mut(self.off_diag - self.off_hinge);
        let (tri_force, hinge_force) = self.elem_force.split_at_mut(3 * nt);
        // Triangles: membrane (+ damping, + wind).
        tri_vals
            .par_chunks_mut(TRI_VALS)
            .zip(tri_force.par_chunks_mut(3))
            .zip(self.tri_energy.par_iter_mut())
            .zip(self.tri_collapsed.par_iter_mut())
            .enumerate()
            .for_each(|(t, (((m, f), e), col))| {
                let tri = mesh.tris[t];
                let x = tri.map(|v| inp.q[v as usize]);
                let vl = tri.map(|v| inp.v[v as usize]);
                let o = membrane_eval(&mesh.tri_rest[t], inp.law, &x, inp.mode, damp_mem);
                *e = o.energy;
                *col = o.collapsed;
                let mut mat = h2 * o.hess;
                for a in 0..3 {
                    f[a] = -o.grad.fixed_rows::<3>(3 * a).into_owned();
                }
                if let Some(d) = &o.damp {
                    mat += h * d;
                    for a in 0..3 {
                        for b in 0..3 {
                            f[a] -= d.fixed_view::<3, 3>(3 * a, 3 * b) * vl[b];
                        }
                    }
                }
                if let Some((wf, t_wind)) = inp.wind {
                    let (fw, jv) = wf.triangle(&x, &vl, t_wind);
                    for a in 0..3 {
                        f[a] += fw;
                        for b in 0..3 {
                            let mut blk = mat.fixed_view_mut::<3, 3>(3 * a, 3 * b);
                            blk -= h * jv;
                        }
                    }
                }
                m.copy_from_slice(mat.as_slice()); // column-major
            });
        // Hinges: bending (+ damping).
        hinge_vals
            .par_chunks_mut(HINGE_VALS)
            .zip(hinge_force.par_chunks_mut(4))
            .zip(self.hinge_energy.par_iter_mut())
            .zip(self.hinge_skipped.par_iter_mut())
            .enumerate()
            .for_each(|(i, (((m, f), e), sk))| {
                let hg = &mesh.hinges[i];
                let x = hg.v.map(|v| inp.q[v as usize]);
                if inp.mode == HessianMode::ProjectedCheap {
                    // Gauss–Newton only: the matrix (h² + hβ_bend)·2kω∇θ∇θᵀ is rank one, and so
                    // is its damping force −β_bend·2kω∇θ(∇θ·v); no 12×12 products.
                    *sk = hinge_is_collapsed(&x);
                    if *sk {
                        *e = 0.0;
                        m.fill(0.0);
                        f.fill(Vec3::zeros());
                        return;
                    }
                    let fr = HingeFrame::new(&x);
                    let d = wrap_angle(fr.angle() - hg.rest_theta);
                    let kw = hg.stiffness * hg.weight;
                    let g = fr.grad();
                    *e = kw * d * d;
                    let gv: f64 = if bb > 0.0 { (0..4).map(|a| g[a].dot(&inp.v[hg.v[a] as usize])).sum() } else { 0.0 };
                    let fs = -2.0 * kw * (d + bb * gv);
                    for a in 0..4 {
                        f[a] = fs * g[a];
                    }
                    let c = 2.0 * kw * (h2 + h * bb);
                    let gl: [f64; 12] = std::array::from_fn(|k| g[k / 3][k % 3]);
                    for (col, chunk) in m.chunks_exact_mut(12).enumerate() {
                        let cg = c * gl[col];
                        for (r, out) in chunk.iter_mut().enumerate() {
                            *out = cg * gl[r];
                        }
                    }
                    return;
                }
                let o = bending_eval(hg, &x, inp.mode, bb > 0.0);
                *e = o.energy;
                *sk = o.skipped;
                let mut mat = h2 * o.hess;
                for a in 0..4 {
                    f[a] = -o.grad.fixed_rows::<3>(3 * a).into_owned();
                }
                if let Some(gn) = &o.gauss_newton {
                    mat += (h * bb) * gn;
                    let vl = hg.v.map(|v| inp.v[v as usize]);
                    for a in 0..4 {
                        for b in 0..4 {
                            f[a] -= bb * (gn.fixed_view::<3, 3>(3 * a, 3 * b) * vl[b]);
                        }
                    }
                }
                m.copy_from_slice(mat.as_slice());
            });
        // Diagonal mass blocks (1 + hα + τ)m I + custom Jacobian blocks.
        let dofs = &self.dofs;
        let (custom, contact) = (&self.custom_diag, &self.contact_diag);
        diag_vals[..dofs.n_free() * DIAG_VALS].par_chunks_mut(DIAG_VALS).enumerate().for_each(|(fidx, d)| {
            let v = dofs.free_vertices[fidx] as usize;
            let m = mesh.mass[v] * (1.0 + h * alpha + inp.shift);
            let blk = Mat3::from_diagonal_element(m) + custom[fidx] + contact[fidx];
            d.copy_from_slice(blk.as_slice());
        });
        // Custom and contact off-diagonal blocks, in the order given (deterministic), onto the
        // element buffers and the (zeroed) contact-coupling region.
        self.vals[self.off_extra..].fill(0.0);
        for &(off, m) in self.custom_offdiag.iter().chain(&self.contact_offdiag) {
            for r in 0..3 {
                for c in 0..3 {
                    self.vals[off + c * 9 + r] += m[(r, c)];
                }
            }
        }
        // Per-vertex force sums in fixed element order.
        let (ptr, idx, ef) = (&self.force_ptr, &self.force_idx, &self.elem_force);
        force.par_iter_mut().enumerate().for_each(|(v, out)| {
            let mut s = Vec3::zeros();
            for &k in &idx[ptr[v] as usize..ptr[v + 1] as usize] {
                s += ef[k as usize];
            }
            *out = s;
        });
        // Matrix: fixed-order sums straight from the element buffers.
        self.gather_matrix();
        EvalOutput {
            skipped_hinges: self.hinge_skipped.iter().filter(|&&s| s).count() as u32,
            collapsed_triangles: self.tri_collapsed.iter().filter(|&&s| s).count() as u32,
        }
    }

    /// Re-assembles only the diagonal blocks with a new shift τ (regularised retry, §3.8).
    pub(crate) fn reshift(&mut self, mesh: &ShellMesh, h_eff: f64, alpha: f64, shift: f64) {
        for fidx in 0..self.dofs.n_free() {
            let v = self.dofs.free_vertices[fidx] as usize;
            let m = mesh.mass[v] * (1.0 + h_eff * alpha + shift);
            let blk = Mat3::from_diagonal_element(m) + self.custom_diag[fidx] + self.contact_diag[fidx];
            let o = self.off_diag + fidx * DIAG_VALS;
            self.vals[o..o + DIAG_VALS].copy_from_slice(blk.as_slice());
        }
        self.gather_matrix();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;

    /// Two triangles and a far vertex pair (0, 4) that shares no triangle; vertex 5 is pinned.
    fn setup(extra: Vec<(u32, u32)>) -> (ShellMesh, Assembler) {
        let p = vec![
            Pt3::new(0.0, 0.0, 0.0),
            Pt3::new(1.0, 0.0, 0.0),
            Pt3::new(1.0, 1.0, 0.1),
            Pt3::new(0.0, 1.0, 0.0),
            Pt3::new(3.0, 0.0, 0.0),
            Pt3::new(3.0, 1.0, 0.0),
            Pt3::new(4.0, 0.5, 0.0),
        ];
        let f = [[0, 1, 2], [0, 2, 3], [4, 6, 5]];
        let mesh = ShellMesh::new(p, &f, None, &Material::cotton()).unwrap();
        let mut dofs = DofMap { free_index: vec![NONE; 7], ..Default::default() };
        for i in [0u32, 1, 2, 3, 4, 6] {
            dofs.free_index[i as usize] = dofs.free_vertices.len() as u32;
            dofs.free_vertices.push(i);
        }
        dofs.pinned.push(5);
        let asm = Assembler::with_extra(&mesh, dofs, extra);
        (mesh, asm)
    }

    fn product(asm: &Assembler, u: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; u.len()];
        geom_core::linalg::sym_mul_vec(asm.matrix(), u, &mut y);
        y
    }

    /// Contact-coupling blocks of extra pairs land in the matrix exactly where they belong:
    /// A·u = A₀·u + C·u, with C the blocks handed in (both orientations), for a pair in the
    /// mesh pattern and for an extra pair; pairs with a pinned vertex or already in the
    /// pattern are not added as extra.
    #[test]
    fn extra_pairs_hold_their_coupling_blocks() {
        let (mesh, mut asm) = setup(vec![(4, 0), (2, 0), (0, 5), (2, 2), (1, 3)]);
        assert_eq!(asm.extra, vec![(0, 4), (1, 3)], "(0, 2) shares a triangle, 5 is pinned, (2, 2) is a diagonal");
        let law = Membrane::isotropic(2000.0, 0.3);
        let q = mesh.rest.iter().map(|p| p + Vec3::new(0.01 * p.y, -0.02 * p.x, 0.03)).collect::<Vec<_>>();
        let v = vec![Vec3::zeros(); 7];
        let inp = EvalInput {
            q: &q,
            v: &v,
            h_eff: 0.01,
            mode: HessianMode::ProjectedCheap,
            law: &law,
            damping: (0.0, 0.0, 0.0, 0.0),
            wind: None,
            shift: 0.0,
        };
        let mut force = vec![Vec3::zeros(); 7];
        asm.assemble(&mesh, &inp, &mut force);
        let u: Vec<f64> = (0..18).map(|k| ((k * 7919) % 13) as f64 - 6.0).collect();
        let y0 = product(&asm, &u);
        let b = Mat3::new(1.0, 2.0, 3.0, -4.0, 5.0, 6.0, 7.0, -8.0, 9.5);
        let c = Mat3::new(0.5, -1.0, 0.25, 2.0, 1.5, -3.0, 0.0, 4.0, 1.0);
        for (i, j, m) in [(0u32, 4u32, b), (1, 2, c)] {
            asm.contact_offdiag.push((asm.block_offset(i, j).unwrap(), m));
            asm.contact_offdiag.push((asm.block_offset(j, i).unwrap(), m.transpose()));
        }
        asm.assemble(&mesh, &inp, &mut force);
        let y1 = product(&asm, &u);
        let fi = &asm.dofs.free_index;
        let mut yc = [0.0; 18];
        for (i, j, m) in [(0u32, 4u32, b), (1, 2, c)] {
            let (fi_, fj_) = (fi[i as usize] as usize, fi[j as usize] as usize);
            let (ui, uj) =
                (Vec3::from_column_slice(&u[3 * fi_..3 * fi_ + 3]), Vec3::from_column_slice(&u[3 * fj_..3 * fj_ + 3]));
            let (ri, rj) = (m * uj, m.transpose() * ui);
            for k in 0..3 {
                yc[3 * fi_ + k] += ri[k];
                yc[3 * fj_ + k] += rj[k];
            }
        }
        for k in 0..18 {
            assert!((y1[k] - y0[k] - yc[k]).abs() < 1e-12, "row {k}: {} vs {}", y1[k] - y0[k], yc[k]);
        }
        // The region is cleared by every assembly: without the blocks, A₀ again.
        asm.contact_offdiag.clear();
        asm.assemble(&mesh, &inp, &mut force);
        assert_eq!(product(&asm, &u), y0);
    }
}
