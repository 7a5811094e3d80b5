//! Adaptive signed distance field (rigging spec §3.1): an octree over the unit cube whose leaves
//! interpolate exact signed distances (pseudo-normal sign, `geom_core::collide::MeshQuery`)
//! trilinearly, refined wherever the interpolant misses the exact value by more than `tau` at
//! any of the 19 non-corner points of the cell's 3×3×3 lattice. Cells entirely outside are
//! never refined (the crop test).

use std::collections::HashMap;

use geom_core::collide::MeshQuery;
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;

use crate::error::{Result, RigError};

/// Lattice resolution: coordinates are integers in `0..=LATTICE` at the finest level (depth ≤ 10
/// cells, midpoints one level finer).
const LATTICE: u32 = 1 << 11;
const NONE: u32 = u32::MAX;

/// One octree leaf: lattice origin and size, the 8 exact corner values (bit order x, y, z).
#[derive(Clone, Copy, Debug)]
struct Leaf {
    lo: [u32; 3],
    size: u32,
    v: [f64; 8],
}

/// Build statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DfStats {
    /// Number of leaves.
    pub leaves: usize,
    /// Deepest level reached.
    pub depth: u32,
    /// Exact distance evaluations.
    pub exact_evals: usize,
}

/// The adaptive distance field of a normalized mesh (coordinates in [0, 1]³). Negative inside.
#[derive(Clone, Debug)]
pub struct DistanceField {
    /// Per node: index of the first of 8 children, or `NONE` for a leaf.
    child: Vec<u32>,
    /// Per node: leaf index (valid when `child == NONE`).
    leaf_of: Vec<u32>,
    leaves: Vec<Leaf>,
    tau: f64,
    stats: DfStats,
}

struct Builder<'a> {
    q: &'a MeshQuery,
    cache: HashMap<u64, f64>,
    tau: f64,
    max_depth: u32,
    child: Vec<u32>,
    leaf_of: Vec<u32>,
    leaves: Vec<Leaf>,
    depth: u32,
}

fn key(p: [u32; 3]) -> u64 {
    p[0] as u64 | ((p[1] as u64) << 21) | ((p[2] as u64) << 42)
}

fn to_pt(p: [u32; 3]) -> Pt3 {
    let s = 1.0 / LATTICE as f64;
    Pt3::new(p[0] as f64 * s, p[1] as f64 * s, p[2] as f64 * s)
}

/// Trilinear interpolation of corner values `v` at local coordinates `t ∈ [0, 1]³`.
fn trilinear(v: &[f64; 8], t: [f64; 3]) -> f64 {
    let [x, y, z] = t;
    let c00 = v[0] * (1.0 - x) + v[1] * x;
    let c10 = v[2] * (1.0 - x) + v[3] * x;
    let c01 = v[4] * (1.0 - x) + v[5] * x;
    let c11 = v[6] * (1.0 - x) + v[7] * x;
    let c0 = c00 * (1.0 - y) + c10 * y;
    let c1 = c01 * (1.0 - y) + c11 * y;
    c0 * (1.0 - z) + c1 * z
}

/// Gradient of the trilinear interpolant with respect to local coordinates.
fn trilinear_grad(v: &[f64; 8], t: [f64; 3]) -> Vec3 {
    let [x, y, z] = t;
    let lerp = |a: f64, b: f64, s: f64| a * (1.0 - s) + b * s;
    let gx = lerp(lerp(v[1] - v[0], v[3] - v[2], y), lerp(v[5] - v[4], v[7] - v[6], y), z);
    let gy = lerp(lerp(v[2] - v[0], v[3] - v[1], x), lerp(v[6] - v[4], v[7] - v[5], x), z);
    let gz = lerp(lerp(v[4] - v[0], v[5] - v[1], x), lerp(v[6] - v[2], v[7] - v[3], x), y);
    Vec3::new(gx, gy, gz)
}

impl Builder<'_> {
    fn exact(&mut self, p: [u32; 3]) -> f64 {
        let q = self.q;
        *self.cache.entry(key(p)).or_insert_with(|| q.signed_distance(&to_pt(p)))
    }
}

impl DistanceField {
    /// Builds the field of a closed, outward-oriented mesh in normalized coordinates with
    /// tolerance `tau` and depth cap `max_depth` (≤ 10). Errors if the mesh is not closed.
    pub fn build(mesh: &TriMesh, tau: f64, max_depth: u32) -> Result<Self> {
        if !(tau > 0.0 && tau.is_finite() && (1..=10).contains(&max_depth)) {
            return Err(RigError::InvalidParameter(format!("distance field: tau {tau}, max depth {max_depth}")));
        }
        let q = MeshQuery::new(mesh)?;
        let mut b = Builder {
            q: &q,
            cache: HashMap::new(),
            tau,
            max_depth,
            child: Vec::new(),
            leaf_of: Vec::new(),
            leaves: Vec::new(),
            depth: 0,
        };
        b.build_iter();
        let stats = DfStats { leaves: b.leaves.len(), depth: b.depth, exact_evals: b.cache.len() };
        Ok(Self { child: b.child, leaf_of: b.leaf_of, leaves: b.leaves, tau, stats })
    }

    /// The tolerance the field was built with.
    pub fn tau(&self) -> f64 {
        self.tau
    }

    /// Build statistics.
    pub fn stats(&self) -> DfStats {
        self.stats
    }

    fn leaf(&self, p: &Pt3) -> (&Leaf, [f64; 3]) {
        let c = [p.x, p.y, p.z].map(|x| (x.clamp(0.0, 1.0) * LATTICE as f64).min(LATTICE as f64 - 1e-9));
        let mut node = 0usize;
        let mut lo = [0u32; 3];
        let mut size = LATTICE;
        while self.child[node] != NONE {
            size /= 2;
            let mut k = 0;
            for a in 0..3 {
                if c[a] >= (lo[a] + size) as f64 {
                    k |= 1 << a;
                    lo[a] += size;
                }
            }
            node = self.child[node] as usize + k;
        }
        let l = &self.leaves[self.leaf_of[node] as usize];
        let t = std::array::from_fn(|a| ((c[a] - l.lo[a] as f64) / l.size as f64).clamp(0.0, 1.0));
        (l, t)
    }

    /// Interpolated signed distance at `p` (clamped into the unit cube); negative inside.
    pub fn eval(&self, p: &Pt3) -> f64 {
        let (l, t) = self.leaf(p);
        trilinear(&l.v, t)
    }

    /// Gradient of the leaf's trilinear interpolant at `p` (discontinuous across leaves: the
    /// medial-surface detector relies on it).
    pub fn grad(&self, p: &Pt3) -> Vec3 {
        let (l, t) = self.leaf(p);
        trilinear_grad(&l.v, t) * (LATTICE as f64 / l.size as f64)
    }

    /// Whether every point of segment `ab` is inside up to `margin` (sphere tracing: at `x`
    /// with `φ = eval(x)`, fail if `φ > margin`, else advance by `max(τ/2, −φ)`).
    pub fn segment_inside(&self, a: &Pt3, b: &Pt3, margin: f64) -> bool {
        let d = b - a;
        let len = d.norm();
        let mut s = 0.0;
        loop {
            let x = a + d * if len > 0.0 { s / len } else { 0.0 };
            let phi = self.eval(&x);
            if phi > margin {
                return false;
            }
            if len - s <= -phi {
                return true;
            }
            s += (self.tau * 0.5).max(-phi);
            if s >= len {
                return self.eval(b) <= margin;
            }
        }
    }

    /// Calls `f(origin, size, corner values)` for every leaf (unit-cube coordinates).
    pub fn for_each_leaf(&self, mut f: impl FnMut(Pt3, f64, &[f64; 8])) {
        for l in &self.leaves {
            f(to_pt(l.lo), l.size as f64 / LATTICE as f64, &l.v);
        }
    }
}

impl Builder<'_> {
    /// Breadth-first construction so that the 8 children of a node are contiguous.
    fn build_iter(&mut self) {
        // (node id, lo, size, depth, known_inside)
        let mut queue = std::collections::VecDeque::new();
        self.child.push(NONE);
        self.leaf_of.push(NONE);
        queue.push_back((0u32, [0u32; 3], LATTICE, 0u32, false));
        while let Some((id, lo, size, depth, known_inside)) = queue.pop_front() {
            self.depth = self.depth.max(depth);
            let (split, inside, v) = self.decide(lo, size, depth, known_inside);
            if split {
                let half = size / 2;
                let first = self.child.len() as u32;
                self.child[id as usize] = first;
                for c in 0..8u32 {
                    self.child.push(NONE);
                    self.leaf_of.push(NONE);
                    let clo = [lo[0] + (c & 1) * half, lo[1] + ((c >> 1) & 1) * half, lo[2] + ((c >> 2) & 1) * half];
                    queue.push_back((first + c, clo, half, depth + 1, inside));
                }
            } else {
                self.leaf_of[id as usize] = self.leaves.len() as u32;
                self.leaves.push(Leaf { lo, size, v });
            }
        }
    }

    fn decide(&mut self, lo: [u32; 3], size: u32, depth: u32, known_inside: bool) -> (bool, bool, [f64; 8]) {
        let v: [f64; 8] = std::array::from_fn(|c| {
            let c = c as u32;
            self.exact([lo[0] + (c & 1) * size, lo[1] + ((c >> 1) & 1) * size, lo[2] + ((c >> 2) & 1) * size])
        });
        let mut inside = known_inside;
        if depth >= self.max_depth {
            return (false, inside, v);
        }
        let half = size / 2;
        let dc = self.exact([lo[0] + half, lo[1] + half, lo[2] + half]);
        let hd = size as f64 / LATTICE as f64 * 3f64.sqrt() / 2.0;
        if !inside {
            if dc > hd {
                return (false, false, v);
            }
            if dc < -hd {
                inside = true;
            }
        }
        for k in 0..27u32 {
            let t = [k % 3, (k / 3) % 3, k / 9];
            if t.iter().all(|&c| c != 1) {
                continue;
            }
            let e = self.exact([lo[0] + t[0] * half, lo[1] + t[1] * half, lo[2] + t[2] * half]);
            if (trilinear(&v, t.map(|c| c as f64 * 0.5)) - e).abs() > self.tau {
                return (true, inside, v);
            }
        }
        (false, inside, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::procedural::icosphere;

    fn sphere_mesh() -> TriMesh {
        let s = icosphere(0.4, 5).expect("icosphere");
        let p = s.positions.iter().map(|q| q + Vec3::repeat(0.5)).collect();
        s.with_positions(p).expect("same topology")
    }

    #[test]
    fn sphere_field_within_tolerance_inside() {
        let m = sphere_mesh();
        let tau = 0.004;
        let df = DistanceField::build(&m, tau, 8).expect("builds");
        let c = Pt3::new(0.5, 0.5, 0.5);
        let mut rng = geom_core::rng::Rng::new(1);
        let chord = 1.2e-4;
        for _ in 0..3000 {
            let p = Pt3::new(rng.f64(), rng.f64(), rng.f64());
            let exact = (p - c).norm() - 0.4;
            let d = df.eval(&p);
            if exact < 0.0 {
                assert!((d - exact).abs() <= tau + chord + 1e-9, "at {p}: {d} vs {exact}");
            }
            if exact.abs() > 2.0 * tau {
                assert_eq!(d < 0.0, exact < 0.0, "sign at {p}");
            }
        }
        assert!(df.segment_inside(&Pt3::new(0.3, 0.5, 0.5), &Pt3::new(0.7, 0.5, 0.5), 0.0));
        assert!(!df.segment_inside(&Pt3::new(0.3, 0.5, 0.5), &Pt3::new(0.99, 0.5, 0.5), 0.0));
        // Gradient points outward, unit length up to the interpolation error.
        let g = df.grad(&Pt3::new(0.7, 0.52, 0.5));
        assert!(g.normalize().dot(&(Pt3::new(0.7, 0.52, 0.5) - c).normalize()) > 0.95);
        let st = df.stats();
        assert!(st.leaves > 100 && st.depth <= 8 && st.exact_evals > st.leaves);
    }
}
