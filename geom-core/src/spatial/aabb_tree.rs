//! [`AabbTree`]: a binary bounding-volume hierarchy over boxes, built by median splits.

use super::Aabb;

/// Largest number of primitives stored in one leaf.
const LEAF_SIZE: usize = 4;

/// One tree node. Internal nodes have `count == 0` and children `a` (left) and `b` (right);
/// leaves hold `order[a .. a + count]`.
#[derive(Clone, Debug)]
struct Node {
    bbox: Aabb,
    a: u32,
    b: u32,
    count: u32,
}

impl Node {
    fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A bounding-volume hierarchy over a fixed list of boxes (one per primitive: a triangle, an edge,
/// a particle …), for broad-phase collision detection and box queries.
///
/// Built top-down: each node splits its primitives at the median of the box centres along the
/// longest axis of the centres' bounding box (ties broken by primitive index), down to leaves of
/// at most four primitives. The build is deterministic, and so is the order in which the queries
/// report hits (depth first, left child first). Positions that move can be followed with
/// [`AabbTree::refit`] (the topology of the tree is kept; rebuild from time to time when the
/// motion is large, e.g. every 50 steps as in SH).
#[derive(Clone, Debug)]
pub struct AabbTree {
    /// Nodes in preorder: a parent comes before its children, the root is node 0.
    nodes: Vec<Node>,
    /// Primitive indices in leaf order.
    order: Vec<u32>,
    /// `boxes[k]` is the box of primitive `order[k]` (leaf order, for cache-friendly tests).
    boxes: Vec<Aabb>,
    /// Number of primitives.
    n: usize,
}

impl AabbTree {
    /// Builds the tree over `boxes` (primitive `i` has box `boxes[i]`). An empty slice gives an
    /// empty tree whose queries report nothing.
    pub fn build(boxes: &[Aabb]) -> Self {
        let n = boxes.len();
        let mut tree = Self {
            nodes: Vec::with_capacity(2 * n / LEAF_SIZE + 1),
            order: (0..n as u32).collect(),
            boxes: Vec::new(),
            n,
        };
        if n == 0 {
            return tree;
        }
        let centers: Vec<[f64; 3]> = boxes.iter().map(|b| b.center().into()).collect();
        tree.build_node(boxes, &centers, 0, n);
        tree.boxes = tree.order.iter().map(|&i| boxes[i as usize]).collect();
        tree
    }

    /// Recursively builds the subtree over `order[lo..hi]`; returns its node index.
    fn build_node(&mut self, boxes: &[Aabb], centers: &[[f64; 3]], lo: usize, hi: usize) -> u32 {
        let id = self.nodes.len() as u32;
        let bbox = self.order[lo..hi].iter().fold(Aabb::empty(), |acc, &i| acc.union(&boxes[i as usize]));
        self.nodes.push(Node { bbox, a: lo as u32, b: 0, count: (hi - lo) as u32 });
        if hi - lo <= LEAF_SIZE {
            return id;
        }
        // Split axis: longest side of the centres' box (more robust than the boxes' own extent
        // when a few large boxes overlap many small ones).
        let mut cb = Aabb::empty();
        for &i in &self.order[lo..hi] {
            cb.extend(&centers[i as usize].into());
        }
        let axis = cb.longest_axis();
        let mid = lo + (hi - lo) / 2;
        // Total order (coordinate, then index) so that the partition is deterministic; NaN
        // centres compare as equal coordinates and fall back on the index.
        self.order[lo..hi].select_nth_unstable_by(mid - lo, |&i, &j| {
            let (ci, cj) = (centers[i as usize][axis], centers[j as usize][axis]);
            ci.partial_cmp(&cj).unwrap_or(std::cmp::Ordering::Equal).then(i.cmp(&j))
        });
        let left = self.build_node(boxes, centers, lo, mid);
        let right = self.build_node(boxes, centers, mid, hi);
        let node = &mut self.nodes[id as usize];
        node.a = left;
        node.b = right;
        node.count = 0;
        id
    }

    /// Number of primitives.
    pub fn len(&self) -> usize {
        self.n
    }

    /// `true` for a tree over no primitives.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The box around everything (empty for an empty tree).
    pub fn root_aabb(&self) -> Aabb {
        self.nodes.first().map_or_else(Aabb::empty, |n| n.bbox)
    }

    /// Updates every node box for new primitive boxes, keeping the tree structure. Cost O(n).
    ///
    /// # Panics
    /// If `boxes.len()` differs from the number of primitives the tree was built with (a
    /// programming error, not a data error).
    pub fn refit(&mut self, boxes: &[Aabb]) {
        assert_eq!(boxes.len(), self.n, "AabbTree::refit: {} boxes for a tree over {}", boxes.len(), self.n);
        // Preorder storage: children have larger indices than their parent, so a reverse sweep
        // visits children first.
        for k in (0..self.nodes.len()).rev() {
            let node = &self.nodes[k];
            let bbox = if node.is_leaf() {
                let (s, c) = (node.a as usize, node.count as usize);
                let mut bb = Aabb::empty();
                for k in s..s + c {
                    self.boxes[k] = boxes[self.order[k] as usize];
                    bb = bb.union(&self.boxes[k]);
                }
                bb
            } else {
                self.nodes[node.a as usize].bbox.union(&self.nodes[node.b as usize].bbox)
            };
            self.nodes[k].bbox = bbox;
        }
    }

    /// The leaf's slots `k` (indices into `order` and `boxes`).
    fn leaf_slots(node: &Node) -> std::ops::Range<usize> {
        node.a as usize..(node.a + node.count) as usize
    }

    /// Calls `f(i)` for every primitive whose box overlaps `b` (closed boxes: touching counts).
    /// Order: depth first, left child first, leaf items in tree order.
    pub fn query(&self, b: &Aabb, mut f: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k as usize];
            if !node.bbox.overlaps(b) {
                continue;
            }
            if node.is_leaf() {
                for k in Self::leaf_slots(node) {
                    if self.boxes[k].overlaps(b) {
                        f(self.order[k]);
                    }
                }
            } else {
                stack.push(node.b);
                stack.push(node.a);
            }
        }
    }

    /// Calls `f(i, j)` with `i < j` exactly once for every pair of primitives whose boxes
    /// overlap (the boxes the tree was built or last refitted with).
    ///
    /// The order is deterministic (a fixed traversal of the tree); sort the pairs if a canonical
    /// order is needed.
    pub fn self_pairs(&self, mut f: impl FnMut(u32, u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut emit = |k: usize, l: usize| {
            if self.boxes[k].overlaps(&self.boxes[l]) {
                let (i, j) = (self.order[k], self.order[l]);
                if i < j {
                    f(i, j)
                } else {
                    f(j, i)
                }
            }
        };
        // Each unordered pair of distinct leaves is visited once, from their lowest common
        // ancestor: (self, k) tasks spawn (self, left), (self, right) and (left, right).
        let mut stack: Vec<(u32, u32)> = vec![(0, 0)];
        while let Some((p, q)) = stack.pop() {
            let (np, nq) = (&self.nodes[p as usize], &self.nodes[q as usize]);
            if p == q {
                if np.is_leaf() {
                    let r = Self::leaf_slots(np);
                    for k in r.clone() {
                        for l in k + 1..r.end {
                            emit(k, l);
                        }
                    }
                } else {
                    stack.push((np.a, np.b));
                    stack.push((np.b, np.b));
                    stack.push((np.a, np.a));
                }
                continue;
            }
            if !np.bbox.overlaps(&nq.bbox) {
                continue;
            }
            match (np.is_leaf(), nq.is_leaf()) {
                (true, true) => {
                    for k in Self::leaf_slots(np) {
                        for l in Self::leaf_slots(nq) {
                            emit(k, l);
                        }
                    }
                }
                // Descend into the internal node (the larger box first when both are internal).
                (true, false) => {
                    stack.push((p, nq.b));
                    stack.push((p, nq.a));
                }
                (false, true) => {
                    stack.push((np.b, q));
                    stack.push((np.a, q));
                }
                (false, false) => {
                    if np.bbox.diag() >= nq.bbox.diag() {
                        stack.push((np.b, q));
                        stack.push((np.a, q));
                    } else {
                        stack.push((p, nq.b));
                        stack.push((p, nq.a));
                    }
                }
            }
        }
    }

    /// Calls `f(i, j)` once for every primitive `i` of `self` and `j` of `other` whose boxes
    /// overlap. Deterministic order.
    pub fn pairs_with(&self, other: &AabbTree, mut f: impl FnMut(u32, u32)) {
        if self.nodes.is_empty() || other.nodes.is_empty() {
            return;
        }
        let mut stack: Vec<(u32, u32)> = vec![(0, 0)];
        while let Some((p, q)) = stack.pop() {
            let (np, nq) = (&self.nodes[p as usize], &other.nodes[q as usize]);
            if !np.bbox.overlaps(&nq.bbox) {
                continue;
            }
            let descend_p = !np.is_leaf() && (nq.is_leaf() || np.bbox.diag() >= nq.bbox.diag());
            if np.is_leaf() && nq.is_leaf() {
                for k in Self::leaf_slots(np) {
                    for l in Self::leaf_slots(nq) {
                        if self.boxes[k].overlaps(&other.boxes[l]) {
                            f(self.order[k], other.order[l]);
                        }
                    }
                }
            } else if descend_p {
                stack.push((np.b, q));
                stack.push((np.a, q));
            } else {
                stack.push((p, nq.b));
                stack.push((p, nq.a));
            }
        }
    }
}
