//! Broad phase: a uniform spatial hash of swept, inflated boxes. Candidate pairs come out sorted
//! and deduplicated, so everything downstream runs in a fixed order (deterministic).

use geom_core::math::Pt3;
use std::collections::HashMap;

/// Axis-aligned box.
#[derive(Clone, Copy, Debug)]
pub struct Bx {
    /// Minimum corner.
    pub lo: Pt3,
    /// Maximum corner.
    pub hi: Pt3,
}

impl Bx {
    /// Box of points grown by `margin`.
    pub fn of(points: &[Pt3], margin: f64) -> Self {
        let mut lo = points[0];
        let mut hi = points[0];
        for p in &points[1..] {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let m = geom_core::math::Vec3::repeat(margin);
        Bx { lo: lo - m, hi: hi + m }
    }

    /// True when the boxes overlap (closed).
    pub fn overlaps(&self, o: &Bx) -> bool {
        (0..3).all(|k| self.lo[k] <= o.hi[k] && o.lo[k] <= self.hi[k])
    }
}

/// Spatial hash of boxes.
pub struct Grid {
    cell: f64,
    map: HashMap<(i64, i64, i64), Vec<u32>>,
}

impl Grid {
    /// Cell size `cell` (> 0); boxes are inserted with [`Grid::insert`].
    pub fn new(cell: f64) -> Self {
        Self { cell, map: HashMap::new() }
    }

    fn range(&self, b: &Bx) -> ([i64; 3], [i64; 3]) {
        let f = |x: f64| (x / self.cell).floor() as i64;
        ([f(b.lo.x), f(b.lo.y), f(b.lo.z)], [f(b.hi.x), f(b.hi.y), f(b.hi.z)])
    }

    /// Inserts box `id`.
    pub fn insert(&mut self, id: u32, b: &Bx) {
        let (lo, hi) = self.range(b);
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    self.map.entry((i, j, k)).or_default().push(id);
                }
            }
        }
    }

    /// Calls `f` for every id whose cells the box touches (ids may repeat).
    pub fn query(&self, b: &Bx, mut f: impl FnMut(u32)) {
        let (lo, hi) = self.range(b);
        for i in lo[0]..=hi[0] {
            for j in lo[1]..=hi[1] {
                for k in lo[2]..=hi[2] {
                    if let Some(v) = self.map.get(&(i, j, k)) {
                        for &id in v {
                            f(id);
                        }
                    }
                }
            }
        }
    }
}

/// Sorted index pairs.
pub type Pairs = Vec<(u32, u32)>;

/// Candidate (vertex, triangle) and (edge, edge) pairs whose boxes overlap, sorted, without
/// pairs that share a vertex.
pub fn candidate_pairs(
    tris: &[[u32; 3]],
    edges: &[[u32; 2]],
    vbox: &[Bx],
    tbox: &[Bx],
    ebox: &[Bx],
    cell: f64,
) -> (Pairs, Pairs) {
    let mut vt = Vec::new();
    let mut ee = Vec::new();
    let mut g = Grid::new(cell);
    for (t, b) in tbox.iter().enumerate() {
        g.insert(t as u32, b);
    }
    for (v, b) in vbox.iter().enumerate() {
        g.query(b, |t| {
            let tri = tris[t as usize];
            if !tri.contains(&(v as u32)) && b.overlaps(&tbox[t as usize]) {
                vt.push((v as u32, t));
            }
        });
    }
    vt.sort_unstable();
    vt.dedup();
    let mut g = Grid::new(cell);
    for (e, b) in ebox.iter().enumerate() {
        g.insert(e as u32, b);
    }
    for (e, b) in ebox.iter().enumerate() {
        let ea = edges[e];
        g.query(b, |f| {
            if f as usize > e {
                let eb = edges[f as usize];
                if !eb.contains(&ea[0]) && !eb.contains(&ea[1]) && b.overlaps(&ebox[f as usize]) {
                    ee.push((e as u32, f));
                }
            }
        });
    }
    ee.sort_unstable();
    ee.dedup();
    (vt, ee)
}
