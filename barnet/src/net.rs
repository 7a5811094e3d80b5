//! [`BarNet`]: nodes (fixed or free) joined by bars with force densities, its validation
//! (spec §3.3, §8) and the branch–node matrix `C_s = [C | C_f]` (spec §3.1).

use crate::error::{check_finite, BarNetError, Result};
use crate::topo::PolyTopo;
use geom_core::graph::UnionFind;
use geom_core::linalg::{Csr, Triplets};
use geom_core::mesh::PolyMesh;
use geom_core::NONE;
use std::collections::HashMap;

/// One bar: a straight two-node element carrying force `s = q · l` (tension positive).
#[derive(Clone, Debug, PartialEq)]
pub struct Bar {
    /// First end node.
    pub a: u32,
    /// Second end node.
    pub b: u32,
    /// Force density `q = s / l` (force per length; only ratios matter, spec §4).
    pub q: f64,
    /// Optional group, for animated stiffness ([`BarNet::set_group_q`], spec §3.6).
    pub group: Option<u32>,
}

/// A bar network (spec §2.1).
#[derive(Clone, Debug, PartialEq)]
pub struct BarNet {
    /// Number of nodes `N = n + n_f`.
    pub n_nodes: usize,
    /// The bars.
    pub bars: Vec<Bar>,
    /// Per node: fixed (`true`) or free.
    pub fixed: Vec<bool>,
}

/// What [`BarNet::validate`] found (warnings, not errors).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NetReport {
    /// Free nodes `n`.
    pub n_free: usize,
    /// Fixed nodes `n_f`.
    pub n_fixed: usize,
    /// Bars with at least one free end and `q ≠ 0` (the ones that enter `D`).
    pub active_bars: usize,
    /// Pairs of bars joining the same two nodes (their force densities add up in `D`:
    /// "merged by summing q", spec §8), as `(first, duplicate)` bar indices.
    pub duplicates: Vec<(usize, usize)>,
    /// Bars with `q == 0` (ignored by the equilibrium).
    pub zero_q_bars: usize,
    /// Bars with `q < 0` (compression; `D` may be indefinite).
    pub negative_q_bars: usize,
    /// Connected parts of free nodes (each anchored).
    pub free_components: usize,
}

impl BarNet {
    /// A net whose bars are the edges of a polygon mesh (any topology: triangles, quads,
    /// n-gons, holes), nodes = mesh vertices, `free[v]` marks the free nodes (spec §3.4.2).
    /// Only edges with at least one free end become bars (bars between two fixed nodes do not
    /// enter the equilibrium). All bars get force density `q` and no group.
    pub fn from_mesh_edges(mesh: &PolyMesh, free: &[bool], q: f64) -> Result<Self> {
        crate::error::check_len("free-node mask", mesh.positions.len(), free.len())?;
        let topo = PolyTopo::new(mesh)?;
        let bars = topo
            .edges
            .iter()
            .filter(|e| free[e[0] as usize] || free[e[1] as usize])
            .map(|e| Bar { a: e[0], b: e[1], q, group: None })
            .collect();
        Ok(Self { n_nodes: free.len(), bars, fixed: free.iter().map(|f| !f).collect() })
    }

    /// Checks the net (spec §3.3, §8): node indices in range, no self-loop, finite q, and
    /// every part of free nodes joined (through bars with `q ≠ 0`) to at least one fixed node.
    /// Duplicate bars are reported (they are merged by summing q in the assembly).
    ///
    /// Errors: `NodeOutOfRange`, `SelfLoop`, `NonFinite`, `Unanchored { nodes }` (all free nodes
    /// of all unanchored parts), `DimensionMismatch` (the fixed mask).
    pub fn validate(&self) -> Result<NetReport> {
        crate::error::check_len("fixed-node mask", self.n_nodes, self.fixed.len())?;
        let mut rep = NetReport::default();
        let mut seen: HashMap<(u32, u32), usize> = HashMap::new();
        let mut uf = UnionFind::new(self.n_nodes);
        for (j, bar) in self.bars.iter().enumerate() {
            for v in [bar.a, bar.b] {
                if v as usize >= self.n_nodes {
                    return Err(BarNetError::NodeOutOfRange { bar: j, node: v, n_nodes: self.n_nodes });
                }
            }
            if bar.a == bar.b {
                return Err(BarNetError::SelfLoop { bar: j, node: bar.a });
            }
            if !bar.q.is_finite() {
                return Err(BarNetError::NonFinite { what: "bar force density q", index: j });
            }
            let key = (bar.a.min(bar.b), bar.a.max(bar.b));
            if let Some(&first) = seen.get(&key) {
                rep.duplicates.push((first, j));
            } else {
                seen.insert(key, j);
            }
            let touches_free = !self.fixed[bar.a as usize] || !self.fixed[bar.b as usize];
            if bar.q == 0.0 {
                rep.zero_q_bars += 1;
                continue;
            }
            if bar.q < 0.0 {
                rep.negative_q_bars += 1;
            }
            if touches_free {
                rep.active_bars += 1;
            }
            uf.union(bar.a, bar.b);
        }
        let (n_comp, labels) = uf.labels();
        let mut anchored = vec![false; n_comp];
        let mut has_free = vec![false; n_comp];
        for v in 0..self.n_nodes {
            if self.fixed[v] {
                anchored[labels[v] as usize] = true;
            } else {
                has_free[labels[v] as usize] = true;
            }
        }
        let unanchored: Vec<u32> =
            (0..self.n_nodes).filter(|&v| !self.fixed[v] && !anchored[labels[v] as usize]).map(|v| v as u32).collect();
        if !unanchored.is_empty() {
            return Err(BarNetError::Unanchored { nodes: unanchored });
        }
        rep.n_fixed = self.fixed.iter().filter(|&&f| f).count();
        rep.n_free = self.n_nodes - rep.n_fixed;
        rep.free_components = has_free.iter().filter(|&&h| h).count();
        Ok(rep)
    }

    /// `(free_nodes, fixed_nodes, index)`: the node lists in ascending order and, per node, its
    /// position within its own list (column of `C` or `C_f`).
    pub fn index_maps(&self) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
        let mut free = Vec::new();
        let mut fixed = Vec::new();
        let mut index = vec![NONE; self.n_nodes];
        for (v, (idx, &is_fixed)) in index.iter_mut().zip(&self.fixed).enumerate() {
            if is_fixed {
                *idx = fixed.len() as u32;
                fixed.push(v as u32);
            } else {
                *idx = free.len() as u32;
                free.push(v as u32);
            }
        }
        (free, fixed, index)
    }

    /// The branch–node matrix split by node kind (spec §3.1): `C` (m × n) over the free nodes
    /// and `C_f` (m × n_f) over the fixed ones; row `j` has `+1` at bar `j`'s end `a` and `−1`
    /// at its end `b`. Every bar gets a row (bars between two fixed nodes have an empty row of
    /// `C`).
    pub fn branch_node(&self) -> (Csr, Csr) {
        let (free, fixed, index) = self.index_maps();
        let m = self.bars.len();
        let mut c = Triplets::with_capacity(m, free.len(), 2 * m);
        let mut cf = Triplets::with_capacity(m, fixed.len(), 2 * m);
        for (j, bar) in self.bars.iter().enumerate() {
            for (v, s) in [(bar.a, 1.0), (bar.b, -1.0)] {
                let t = if self.fixed[v as usize] { &mut cf } else { &mut c };
                t.push(j as u32, index[v as usize], s);
            }
        }
        (Csr::from_triplets(&c), Csr::from_triplets(&cf))
    }

    /// The force densities of every bar, in bar order.
    pub fn q(&self) -> Vec<f64> {
        self.bars.iter().map(|b| b.q).collect()
    }

    /// Sets `q` of every bar in `group` (spec §3.6). Errors: non-finite `q`.
    pub fn set_group_q(&mut self, group: u32, q: f64) -> Result<()> {
        check_finite("group force density", &[q])?;
        for b in self.bars.iter_mut().filter(|b| b.group == Some(group)) {
            b.q = q;
        }
        Ok(())
    }

    /// Multiplies every `q` by `factor` (spec §3.3: load-induced displacements scale by
    /// `1/factor`). Errors: non-finite `factor`.
    pub fn scale_q(&mut self, factor: f64) -> Result<()> {
        check_finite("q scale factor", &[factor])?;
        for b in &mut self.bars {
            b.q *= factor;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(n_free: usize) -> BarNet {
        let n = n_free + 2;
        let bars = (0..n - 1).map(|i| Bar { a: i as u32, b: i as u32 + 1, q: 1.0, group: None }).collect();
        let mut fixed = vec![false; n];
        fixed[0] = true;
        fixed[n - 1] = true;
        BarNet { n_nodes: n, bars, fixed }
    }

    #[test]
    fn unanchored_part_is_detected_before_factorisation() {
        let mut net = chain(3);
        // Free island {5, 6} joined to nothing fixed.
        net.n_nodes = 7;
        net.fixed.extend([false, false]);
        net.bars.push(Bar { a: 5, b: 6, q: 1.0, group: None });
        match net.validate() {
            Err(BarNetError::Unanchored { nodes }) => assert_eq!(nodes, vec![5, 6]),
            r => panic!("expected Unanchored, got {r:?}"),
        }
    }

    #[test]
    fn zero_q_bar_can_disconnect() {
        let mut net = chain(3);
        net.bars[0].q = 0.0;
        net.bars[3].q = 0.0;
        assert!(matches!(net.validate(), Err(BarNetError::Unanchored { nodes }) if nodes == vec![1, 2, 3]));
    }

    #[test]
    fn self_loop_and_duplicates() {
        let mut net = chain(2);
        net.bars.push(Bar { a: 1, b: 2, q: 0.5, group: None });
        let rep = net.validate().unwrap();
        assert_eq!(rep.duplicates, vec![(1, 3)]);
        net.bars.push(Bar { a: 2, b: 2, q: 1.0, group: None });
        assert!(matches!(net.validate(), Err(BarNetError::SelfLoop { bar: 4, node: 2 })));
    }

    #[test]
    fn branch_node_rows() {
        let net = chain(2);
        let (c, cf) = net.branch_node();
        assert_eq!((c.nrows, c.ncols, cf.ncols), (3, 2, 2));
        // Bar 1 joins free nodes 1 and 2 (free columns 0, 1).
        assert_eq!(c.get(1, 0), 1.0);
        assert_eq!(c.get(1, 1), -1.0);
        assert_eq!(cf.get(0, 0), 1.0);
        assert_eq!(cf.get(2, 1), -1.0);
    }
}
