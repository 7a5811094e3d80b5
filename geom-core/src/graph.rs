//! Index lists and connectivity: [`Ragged`] (compressed rows of indices), [`UnionFind`] and
//! [`components`].

use serde::{Deserialize, Serialize};

/// Compressed ragged array: row `i` is `items[offsets[i]..offsets[i + 1]]`.
///
/// Used for polygon faces, vertex→face incidence, one-rings, skin weights: anything that is "a
/// short variable-length list per element" without a `Vec<Vec<_>>` per element.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Ragged<T> {
    /// `n_rows + 1` offsets into `items`, starting at 0, non-decreasing.
    pub offsets: Vec<u32>,
    /// The concatenated rows.
    pub items: Vec<T>,
}

impl<T: Clone> Ragged<T> {
    /// An empty array with no rows.
    pub fn new() -> Self {
        Self { offsets: vec![0], items: Vec::new() }
    }

    /// Builds from explicit rows.
    pub fn from_rows<R: AsRef<[T]>>(rows: impl IntoIterator<Item = R>) -> Self {
        let mut r = Self::new();
        for row in rows {
            r.push_row(row.as_ref());
        }
        r
    }

    /// Builds `n` rows from `(row, item)` pairs; within a row, items keep the order of `pairs`
    /// (a stable counting sort), so the result is deterministic.
    pub fn from_pairs(n: usize, pairs: &[(u32, T)]) -> Self {
        let mut counts = vec![0u32; n + 1];
        for (r, _) in pairs {
            counts[*r as usize + 1] += 1;
        }
        for i in 0..n {
            counts[i + 1] += counts[i];
        }
        let offsets = counts.clone();
        let mut cursor = counts;
        let mut slots: Vec<Option<T>> = vec![None; pairs.len()];
        for (r, t) in pairs {
            let c = &mut cursor[*r as usize];
            slots[*c as usize] = Some(t.clone());
            *c += 1;
        }
        // Every slot was written exactly once: the counts above sum to pairs.len().
        let items = slots.into_iter().map(|s| s.expect("every slot filled")).collect();
        Self { offsets, items }
    }

    /// Appends one row.
    pub fn push_row(&mut self, row: &[T]) {
        self.items.extend_from_slice(row);
        self.offsets.push(self.items.len() as u32);
    }
}

impl<T> Ragged<T> {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Row `i`. Panics if `i >= len()`.
    pub fn row(&self, i: usize) -> &[T] {
        &self.items[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Iterator over the rows.
    pub fn rows(&self) -> impl Iterator<Item = &[T]> + '_ {
        (0..self.len()).map(move |i| self.row(i))
    }
}

/// Disjoint-set forest with path halving and union by size.
#[derive(Clone, Debug)]
pub struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    /// `n` singleton sets.
    pub fn new(n: usize) -> Self {
        Self { parent: (0..n as u32).collect(), size: vec![1; n] }
    }

    /// Representative of `x`'s set.
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = self.parent[x as usize];
        }
        x
    }

    /// Merges the sets of `a` and `b`; returns true if they were different.
    pub fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        let (big, small) = if self.size[ra as usize] >= self.size[rb as usize] { (ra, rb) } else { (rb, ra) };
        self.parent[small as usize] = big;
        self.size[big as usize] += self.size[small as usize];
        true
    }

    /// `(count, labels)`: labels are 0..count, numbered in order of each set's lowest member.
    pub fn labels(&mut self) -> (usize, Vec<u32>) {
        let n = self.parent.len();
        let mut root_label = vec![u32::MAX; n];
        let mut labels = vec![0u32; n];
        let mut count = 0u32;
        for i in 0..n as u32 {
            let r = self.find(i) as usize;
            if root_label[r] == u32::MAX {
                root_label[r] = count;
                count += 1;
            }
            labels[i as usize] = root_label[r];
        }
        (count as usize, labels)
    }
}

/// Connected components of an undirected graph given as adjacency rows; labels are numbered by
/// each component's lowest member. Out-of-range neighbours are ignored.
pub fn components(n: usize, adj: &Ragged<u32>) -> (usize, Vec<u32>) {
    let mut uf = UnionFind::new(n);
    for i in 0..adj.len().min(n) {
        for &j in adj.row(i) {
            if (j as usize) < n {
                uf.union(i as u32, j);
            }
        }
    }
    uf.labels()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ragged_from_pairs_is_stable() {
        let r = Ragged::from_pairs(3, &[(2, 'a'), (0, 'b'), (2, 'c'), (0, 'd')]);
        assert_eq!(r.len(), 3);
        assert_eq!(r.row(0), &['b', 'd']);
        assert!(r.row(1).is_empty());
        assert_eq!(r.row(2), &['a', 'c']);
    }

    #[test]
    fn components_label_by_lowest_member() {
        let adj = Ragged::from_rows([vec![3u32], vec![2], vec![1], vec![0], vec![]]);
        let (n, l) = components(5, &adj);
        assert_eq!(n, 3);
        assert_eq!(l, vec![0, 1, 1, 0, 2]);
    }
}
