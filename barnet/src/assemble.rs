//! Direct assembly of the force-density matrices (spec §3.2):
//! `D = Cᵀ Q C` (n × n, symmetric) and `D_f = Cᵀ Q C_f` (n × n_f), without forming `C`.
//!
//! For bar `(a, b, q)`: both free ⇒ `D_aa += q, D_bb += q, D_ab −= q, D_ba −= q`; `a` free and
//! `b` fixed ⇒ `D_aa += q, (D_f)_ab −= q`; both fixed ⇒ nothing. Rows of `[D | D_f]` sum to 0.
//!
//! The pattern is built once (bars with `q = 0` keep their structural entries, so animating
//! q never changes it); [`Assembly::set_q`] rewrites only the values by scattering each bar's
//! contributions in the same order as the first assembly, so a refreshed matrix is bitwise
//! equal to a fresh one (spec test 7.4 b).

use crate::net::BarNet;
use geom_core::linalg::{Csc, Csr, Triplets};

/// One contribution `sign · q[bar]` to a stored value.
#[derive(Clone, Copy, Debug)]
struct Contrib {
    bar: u32,
    sign: f64,
    /// Position in `d.val` (full D) or in `d_f.val`.
    pos: usize,
    /// Position in `d_lower`'s values, `usize::MAX` for entries above the diagonal or of `D_f`.
    pos_lower: usize,
    /// `true` for a `D_f` entry.
    fixed: bool,
}

/// `D` (full and lower-triangle copies) and `D_f` of a net, with the scatter map that refreshes
/// their values when the force densities change.
#[derive(Clone, Debug)]
pub struct Assembly {
    /// Free nodes `n`.
    pub n: usize,
    /// Fixed nodes `n_f`.
    pub n_fixed: usize,
    /// `D` with both triangles (for products and residuals).
    pub d: Csr,
    /// Lower triangle of `D` (the direct solvers' input).
    pub d_lower: Csc,
    /// `D_f` (n × n_f).
    pub d_f: Csr,
    contribs: Vec<Contrib>,
}

fn csr_pos(m: &Csr, i: usize, j: u32) -> usize {
    let (cols, _) = m.row(i);
    let k = cols.binary_search(&j).expect("entry is in the pattern (pattern built from the same triplets)");
    m.row_ptr[i] + k
}

fn csc_pos(m: &Csc, i: usize, j: usize) -> usize {
    let sym = m.symbolic();
    let start = sym.col_ptr()[j];
    let rows = sym.row_idx_of_col_raw(j);
    start + rows.binary_search(&i).expect("lower entry is in the pattern (converted from the same Csr)")
}

impl Assembly {
    /// Assembles `D` and `D_f` for the net's current force densities. `index` maps a node to its
    /// position among the free or the fixed nodes ([`BarNet::index_maps`]).
    pub fn new(net: &BarNet, n: usize, n_fixed: usize, index: &[u32]) -> Self {
        // (row, col, bar, sign, is_fixed_col)
        let mut keys: Vec<(u32, u32, u32, f64, bool)> = Vec::with_capacity(4 * net.bars.len());
        for (j, bar) in net.bars.iter().enumerate() {
            let (fa, fb) = (net.fixed[bar.a as usize], net.fixed[bar.b as usize]);
            let (ia, ib) = (index[bar.a as usize], index[bar.b as usize]);
            let j = j as u32;
            match (fa, fb) {
                (false, false) => {
                    keys.push((ia, ia, j, 1.0, false));
                    keys.push((ib, ib, j, 1.0, false));
                    keys.push((ia, ib, j, -1.0, false));
                    keys.push((ib, ia, j, -1.0, false));
                }
                (false, true) => {
                    keys.push((ia, ia, j, 1.0, false));
                    keys.push((ia, ib, j, -1.0, true));
                }
                (true, false) => {
                    keys.push((ib, ib, j, 1.0, false));
                    keys.push((ib, ia, j, -1.0, true));
                }
                (true, true) => {}
            }
        }
        let mut td = Triplets::with_capacity(n, n, keys.len());
        let mut tf = Triplets::with_capacity(n, n_fixed, keys.len() / 4);
        for &(i, k, _, _, fixed) in &keys {
            // Structural zeros: values are scattered below.
            if fixed {
                tf.push(i, k, 0.0);
            } else {
                td.push(i, k, 0.0);
            }
        }
        let d = Csr::from_triplets(&td);
        let d_f = Csr::from_triplets(&tf);
        let d_lower = d.to_csc_lower();
        let contribs = keys
            .iter()
            .map(|&(i, k, bar, sign, fixed)| {
                if fixed {
                    Contrib { bar, sign, pos: csr_pos(&d_f, i as usize, k), pos_lower: usize::MAX, fixed }
                } else {
                    let pos_lower = if i >= k { csc_pos(&d_lower, i as usize, k as usize) } else { usize::MAX };
                    Contrib { bar, sign, pos: csr_pos(&d, i as usize, k), pos_lower, fixed }
                }
            })
            .collect();
        let mut a = Self { n, n_fixed, d, d_lower, d_f, contribs };
        a.set_q(&net.q());
        a
    }

    /// Rewrites the values for force densities `q` (one per bar, the net's bar order). The
    /// caller checked the length and finiteness.
    pub fn set_q(&mut self, q: &[f64]) {
        self.d.val.fill(0.0);
        self.d_f.val.fill(0.0);
        let low = self.d_lower.val_mut();
        low.fill(0.0);
        for c in &self.contribs {
            let v = c.sign * q[c.bar as usize];
            if c.fixed {
                self.d_f.val[c.pos] += v;
            } else {
                self.d.val[c.pos] += v;
                if c.pos_lower != usize::MAX {
                    low[c.pos_lower] += v;
                }
            }
        }
    }

    /// `y = D x` for one coordinate.
    pub fn d_mul(&self, x: &[f64], y: &mut [f64]) {
        self.d.mul_vec(x, y);
    }

    /// `y = D_f x_f` for one coordinate.
    pub fn df_mul(&self, x: &[f64], y: &mut [f64]) {
        self.d_f.mul_vec(x, y);
    }
}

/// `D = Cᵀ Q C` and `D_f = Cᵀ Q C_f` by explicit sparse products of the branch–node matrices
/// (spec test 7.2 a compares this with the direct assembly).
pub fn d_from_branch_node(net: &BarNet) -> (Csr, Csr) {
    let (c, cf) = net.branch_node();
    let ct = c.transpose();
    let mut qc = c.clone();
    qc.scale_rows(&net.q());
    let mut qcf = cf.clone();
    qcf.scale_rows(&net.q());
    (ct.matmul(&qc), ct.matmul(&qcf))
}
