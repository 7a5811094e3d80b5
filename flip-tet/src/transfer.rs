//! Velocity transfers between particles and tets (spec §3.7): P2G with a smooth kernel and
//! coverage mask, extrapolation through nodal averages, nodal averages with free slip at box
//! walls, the sub-tet interpolation `I(x) = 4 m u_t + Σ_a (λ_a − m) ũ_a`, and the PIC/FLIP blend.

use geom_core::math::{Pt3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bcc::TetMesh;
use crate::particles::{ParticleFlags, Particles};

/// Transfer parameters (scene `transfer: (...)`, spec §4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TransferParams {
    /// P2G support radius in units of `h_t`.
    pub support: f64,
    /// Coverage for a valid tet, in units of one matching particle at the centre `(h_t/2)³`.
    pub omega_valid: f64,
    /// Coverage below which the P2G value is blended with the extrapolated one.
    pub omega_blend: f64,
    /// Extrapolation layers (`None`: `ceil(cfl) + 2`).
    pub extrapolation_layers: Option<u32>,
}

impl Default for TransferParams {
    fn default() -> Self {
        Self { support: 1.0, omega_valid: 0.1, omega_blend: 0.5, extrapolation_layers: None }
    }
}

/// Smooth kernel `W(d, h) = max(0, 1 − d²/h²)³` (spec §3.7, the paper's sizing kernel).
pub fn w_smooth(d: f64, h: f64) -> f64 {
    let s = 1.0 - d * d / (h * h);
    if s > 0.0 {
        s * s * s
    } else {
        0.0
    }
}

/// Per-tet velocity with validity mask (spec §2 `TetVelocity`).
#[derive(Clone, Debug, Default)]
pub struct TetVelocity {
    /// Velocity per tet (m/s).
    pub u: Vec<Vec3>,
    /// Validity per tet.
    pub valid: Vec<bool>,
    /// Coverage per tet relative to `v_ref` (P2G only; 0 otherwise).
    pub coverage: Vec<f64>,
}

/// P2G (spec §3.7): `u_t = Σ ω v / Σ ω`, `ω = vol_p W(|x_p − c_t|, support·h_t)` over
/// non-ballistic particles; valid when the coverage `Σω / (h_t/2)³ ≥ omega_valid`.
/// `h_tet` is the cube size of each tet's level. Gather per tet in parallel (deterministic).
pub fn particles_to_tets(mesh: &TetMesh, h_tet: &[f64], parts: &Particles, p: &TransferParams) -> TetVelocity {
    // Bounding-box tree of the particle positions (8 per leaf): its boxes prune empty air after a
    // few levels, where a k-d `nearest` from a far query point visits much of the tree (measured
    // on uniform 32: 5.9 s vs 0.05 s per step), and its `within` lists the same indices in the
    // same order as `KdTree::within` (P2G 5.5 s → 4.2 s on dam-break default, session 6).
    let occ = crate::surface::SphereTree::build(&parts.x, &vec![0.0; parts.len()]);
    // One tree query per group of nearby tets (the tets owned by one octree leaf, see
    // `tet_groups`) with a ball containing every tet's support ball, then each tet keeps the
    // candidates that pass `within`'s own test `dx² + dy² + dz² ≤ rad²` (same expression, same
    // rounding) in the same ascending order: the same particles summed in the same order as a
    // `within` query per tet, so the result is bitwise the same (session 9).
    let groups = tet_groups(mesh);
    let per_group: Vec<Vec<(u32, TetP2g)>> = groups
        .par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(cand, buf): &mut (Vec<u32>, Vec<u32>), g| {
                let (centre, big) =
                    covering_ball(g.iter().map(|&t| (mesh.centroid[t as usize], p.support * h_tet[t as usize])));
                occ.within(&centre, big, cand);
                g.iter()
                    .map(|&t| {
                        let c = mesh.centroid[t as usize];
                        let rad = p.support * h_tet[t as usize];
                        let r2 = rad * rad;
                        buf.clear();
                        buf.extend(cand.iter().copied().filter(|&i| {
                            let x = &parts.x[i as usize];
                            let (dx, dy, dz) = (c.x - x.x, c.y - x.y, c.z - x.z);
                            dx * dx + dy * dy + dz * dz <= r2
                        }));
                        (t, tet_average(parts, c, rad, 0.5 * h_tet[t as usize], buf, p.omega_valid))
                    })
                    .collect()
            },
        )
        .collect();
    let mut res = vec![(Vec3::zeros(), false, 0.0); mesh.tets.len()];
    for (t, r) in per_group.into_iter().flatten() {
        res[t as usize] = r;
    }
    TetVelocity {
        u: res.iter().map(|r| r.0).collect(),
        valid: res.iter().map(|r| r.1).collect(),
        coverage: res.iter().map(|r| r.2).collect(),
    }
}

/// One tet's P2G result: `(u, valid, coverage)`.
type TetP2g = (Vec3, bool, f64);

/// The P2G average of one tet from its support-ball particles `ids` (ascending: a fixed
/// summation order): `(u, valid, coverage)`, coverage in units of `v_ref = half_h³`; ballistic
/// particles are skipped; an empty sum gives `(0, invalid, 0)`.
fn tet_average(parts: &Particles, c: Pt3, rad: f64, half_h: f64, ids: &[u32], omega_valid: f64) -> TetP2g {
    let (mut sw, mut sv) = (0.0, Vec3::zeros());
    for &i in ids {
        let i = i as usize;
        if parts.flags[i].has(ParticleFlags::BALLISTIC) {
            continue;
        }
        let w = parts.volume(i) * w_smooth((parts.x[i] - c).norm(), rad);
        sw += w;
        sv += parts.v[i] * w;
    }
    let cov = sw / half_h.powi(3);
    if sw > 0.0 {
        (sv / sw, cov >= omega_valid, cov)
    } else {
        (Vec3::zeros(), false, 0.0)
    }
}

/// Partition of the tets into groups of neighbours for the gather: each tet goes to the
/// lowest-numbered octree leaf whose centre is one of its vertices (nodes `0..n_leaves` are the
/// leaf centres, `TetMesh::leaf_tets`); a tet with no centre vertex is a group of its own.
fn tet_groups(mesh: &TetMesh) -> Vec<Vec<u32>> {
    let n_leaves = mesh.leaf_tets.len();
    let mut groups: Vec<Vec<u32>> = vec![Vec::new(); n_leaves];
    for (t, tv) in mesh.tets.iter().enumerate() {
        match tv.iter().copied().filter(|&v| (v as usize) < n_leaves).min() {
            Some(l) => groups[l as usize].push(t as u32),
            None => groups.push(vec![t as u32]),
        }
    }
    groups.retain(|g| !g.is_empty());
    groups
}

/// A ball containing every ball `(c, r)` of `balls`: centred at the mean centre, radius the
/// largest `|c − centre| + r`, enlarged by a relative `1e−12` so that rounding in the containing
/// query cannot drop a point that a member ball's own test keeps.
fn covering_ball(balls: impl Iterator<Item = (Pt3, f64)> + Clone) -> (Pt3, f64) {
    let (mut s, mut n) = (Vec3::zeros(), 0usize);
    for (c, _) in balls.clone() {
        s += c.coords;
        n += 1;
    }
    let centre = Pt3::from(s / n.max(1) as f64);
    let r = balls.map(|(c, r)| (c - centre).norm() + r).fold(0.0, f64::max);
    (centre, r * (1.0 + 1e-12) + f64::MIN_POSITIVE)
}

/// Weak-coverage blend (spec §3.7): every valid tet with coverage `Ω < ω_blend` (in units of
/// `v_ref`) takes `u ← (Ω u_p2g + (ω_blend − Ω) u_ext) / ω_blend`, where `u_ext` is the value one
/// extrapolation pass gives it from the *well-covered* tets (`Ω ≥ ω_blend`): the mean over its
/// nodes of their volume-weighted averages of well-covered incident tets. A weak tet with no
/// well-covered tet around any of its nodes keeps its P2G value. Writes into `u` (which holds the
/// P2G values on entry) and returns the number of blended tets.
///
/// Why `u_ext` must exclude the weak tets themselves: the extrapolation leaves valid tets
/// unchanged, so blending with the extrapolated field of the ordinary mask (the first version of
/// this function) blended each weak tet with its own value, a no-op, and a few small particles
/// in a coarse tet kept imposing their velocity on it (the momentum artefact of spec §8
/// H-COARSE-LANDING).
pub fn blend_weak(mesh: &TetMesh, p2g: &TetVelocity, u: &mut [Vec3], p: &TransferParams) -> usize {
    let weak = |t: usize| p2g.valid[t] && p2g.coverage[t] < p.omega_blend;
    if !(0..u.len()).any(weak) {
        return 0;
    }
    let strong: Vec<bool> = (0..u.len()).map(|t| p2g.valid[t] && !weak(t)).collect();
    let nv = node_values(mesh, &p2g.u, &strong, 0);
    let mut n = 0;
    for (t, e) in u.iter_mut().enumerate() {
        if !weak(t) {
            continue;
        }
        let (mut s, mut c) = (Vec3::zeros(), 0usize);
        for &i in &mesh.tets[t] {
            if let Some(v) = nv[i as usize] {
                s += v;
                c += 1;
            }
        }
        if c > 0 {
            let ext = s / c as f64;
            let cov = p2g.coverage[t];
            *e = (p2g.u[t] * cov + ext * (p.omega_blend - cov)) / p.omega_blend;
            n += 1;
        }
    }
    n
}

/// Volume-weighted average at node `i` of `f(t)` over its incident tets where `f` gives a value;
/// `None` when none does. At the closed box walls of `wall_mask` (bit `2a + side` as in
/// `TetMesh::node_boundary`) the wall-normal component is removed (free slip for velocities,
/// `∂φ/∂n = 0` for the mirrored level set).
pub fn ring_average(mesh: &TetMesh, i: usize, wall_mask: u8, f: impl Fn(usize) -> Option<Vec3>) -> Option<Vec3> {
    let (mut s, mut w) = (Vec3::zeros(), 0.0);
    for &t in mesh.node_tets.row(i) {
        let t = t as usize;
        if let Some(x) = f(t) {
            s += x * mesh.volume[t];
            w += mesh.volume[t];
        }
    }
    if w == 0.0 {
        return None;
    }
    let mut v = s / w;
    let b = mesh.node_boundary[i] & wall_mask;
    for a in 0..3 {
        if b & (3 << (2 * a)) != 0 {
            v[a] = 0.0;
        }
    }
    Some(v)
}

/// Volume-weighted nodal average of the valid tets around each node; `None` where no incident
/// tet is valid. Free slip at the closed box walls of `wall_mask` (see [`ring_average`]).
pub fn node_values(mesh: &TetMesh, u: &[Vec3], valid: &[bool], wall_mask: u8) -> Vec<Option<Vec3>> {
    (0..mesh.nodes.len())
        .into_par_iter()
        .map(|i| ring_average(mesh, i, wall_mask, |t| valid[t].then(|| u[t])))
        .collect()
}

/// Extrapolation (spec §3.7): `layers` sweeps; each invalid tet with at least one node that has
/// a valid neighbour average takes the mean of those node values and becomes valid. Remaining
/// invalid tets get zero velocity. Returns the number of filled layers actually used.
pub fn extrapolate(mesh: &TetMesh, u: &mut [Vec3], valid: &mut [bool], layers: u32) -> u32 {
    let mut used = 0;
    for _ in 0..layers {
        if valid.iter().all(|&v| v) {
            break;
        }
        let nv = node_values(mesh, u, valid, 0);
        let upd: Vec<Option<Vec3>> = (0..mesh.tets.len())
            .into_par_iter()
            .map(|t| {
                if valid[t] {
                    return None;
                }
                let (mut s, mut c) = (Vec3::zeros(), 0usize);
                for &i in &mesh.tets[t] {
                    if let Some(v) = nv[i as usize] {
                        s += v;
                        c += 1;
                    }
                }
                (c > 0).then(|| s / c as f64)
            })
            .collect();
        let mut any = false;
        for (t, v) in upd.into_iter().enumerate() {
            if let Some(v) = v {
                u[t] = v;
                valid[t] = true;
                any = true;
            }
        }
        if !any {
            break;
        }
        used += 1;
    }
    for t in 0..u.len() {
        if !valid[t] {
            u[t] = Vec3::zeros();
        }
    }
    used
}

/// Nodal averages `ũ` over all tets (after extrapolation every tet counts), free slip at the
/// closed walls of `wall_mask` (`0x3f` = all six box faces).
pub fn node_average(mesh: &TetMesh, u: &[Vec3], wall_mask: u8) -> Vec<Vec3> {
    let all = vec![true; u.len()];
    node_values(mesh, u, &all, wall_mask).into_iter().map(|v| v.unwrap_or_else(Vec3::zeros)).collect()
}

/// Sub-tet interpolation (spec §3.7): `I(x) = 4 m u_t + Σ_a (λ_a − m) ũ_a`, `m = min_a λ_a`.
/// Exact at the centroid, continuous across faces, reproduces constants.
pub fn sample(mesh: &TetMesh, u: &[Vec3], nodal: &[Vec3], t: u32, bary: &[f64; 4]) -> Vec3 {
    let l = bary.map(|v| v.clamp(0.0, 1.0));
    let sum: f64 = l.iter().sum();
    let l = if sum > 0.0 { l.map(|v| v / sum) } else { [0.25; 4] };
    let m = l.iter().copied().fold(f64::INFINITY, f64::min);
    let tv = mesh.tets[t as usize];
    let mut r = u[t as usize] * (4.0 * m);
    for a in 0..4 {
        r += nodal[tv[a] as usize] * (l[a] - m);
    }
    r
}

/// PIC fraction of a particle (spec §3.7): `α = clamp(α₀ (r_min/r)^e, α_floor, 1)`.
pub fn pic_fraction(r: f64, r_min: f64, base: f64, exponent: f64, floor: f64) -> f64 {
    (base * (r_min / r).powf(exponent)).clamp(floor, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bcc::tetrahedralize;
    use crate::octree::{build_octree, OctreeSpec, SizeDemand};
    use geom_core::math::Pt3;

    fn mesh() -> (crate::octree::Octree, TetMesh) {
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), 2, 8).unwrap();
        let d = [SizeDemand { center: Pt3::new(0.4, 0.4, 0.4), pad: 0.1, level: 2 }];
        let o = build_octree(sp, &d);
        let m = tetrahedralize(&o).unwrap();
        (o, m)
    }

    /// T-INTERP: exact at centroids, continuous across faces, constants reproduced.
    #[test]
    fn interpolation_properties() {
        let (oct, m) = mesh();
        let mut rng = geom_core::rng::Rng::new(2);
        let u: Vec<Vec3> = (0..m.tets.len()).map(|_| rng.unit_vec3()).collect();
        let nodal = node_average(&m, &u, 0x3f);
        for t in 0..m.tets.len() {
            let v = sample(&m, &u, &nodal, t as u32, &[0.25; 4]);
            assert!((v - u[t]).norm() < 1e-14);
        }
        for t in 0..m.tets.len() {
            for a in 0..4 {
                let n = m.face_nbr[t][a];
                if n == geom_core::NONE {
                    continue;
                }
                let tv = m.tets[t];
                let f = [tv[(a + 1) % 4], tv[(a + 2) % 4], tv[(a + 3) % 4]];
                let x = Pt3::from(
                    m.nodes[f[0] as usize].coords * 0.2
                        + m.nodes[f[1] as usize].coords * 0.3
                        + m.nodes[f[2] as usize].coords * 0.5,
                );
                let va = sample(&m, &u, &nodal, t as u32, &m.barycentric(t as u32, &x));
                let vb = sample(&m, &u, &nodal, n, &m.barycentric(n, &x));
                assert!((va - vb).norm() < 1e-12);
            }
        }
        let c = Vec3::new(1.0, -2.0, 0.5);
        let uc = vec![c; m.tets.len()];
        let nc: Vec<Vec3> = vec![c; m.nodes.len()];
        let x = Pt3::new(0.33, 0.71, 0.12);
        let (t, l) = m.locate(&oct, &x).unwrap();
        assert!((sample(&m, &uc, &nc, t, &l) - c).norm() < 1e-14);
    }

    /// Weak-coverage blend: a weakly covered tet next to well-covered ones moves towards their
    /// velocity by the fraction `(ω_blend − Ω)/ω_blend`; well-covered tets are unchanged; with a
    /// single velocity everywhere the blend is exact (constants are reproduced).
    #[test]
    fn weak_blend_moves_weak_tets_towards_well_covered_neighbours() {
        let (_, m) = mesh();
        let n = m.tets.len();
        let p = TransferParams::default();
        let (a, b) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, -2.0, 0.0));
        // Tet 0 is weak (Ω = 0.2) with velocity b; every other tet is well covered with a.
        let p2g = TetVelocity {
            u: (0..n).map(|t| if t == 0 { b } else { a }).collect(),
            valid: vec![true; n],
            coverage: (0..n).map(|t| if t == 0 { 0.2 } else { 1.0 }).collect(),
        };
        let mut u = p2g.u.clone();
        assert_eq!(blend_weak(&m, &p2g, &mut u, &p), 1);
        let want = (b * 0.2 + a * 0.3) / 0.5;
        assert!((u[0] - want).norm() < 1e-14, "{:?} vs {want:?}", u[0]);
        assert!(u[1..].iter().all(|v| *v == a));
        // Constant field: the blend returns the constant.
        let pc = TetVelocity { u: vec![a; n], ..p2g.clone() };
        let mut uc = pc.u.clone();
        blend_weak(&m, &pc, &mut uc, &p);
        assert!(uc.iter().all(|v| (v - a).norm() < 1e-15));
    }

    /// T-P2G-CONST and T-EXTRAP: constant particle velocity gives the constant in every valid
    /// tet, extrapolation fills invalid tets with it.
    #[test]
    fn p2g_constant_and_extrapolation() {
        let (_, m) = mesh();
        let mut parts = Particles::default();
        let c = Vec3::new(0.3, 0.1, -0.2);
        for i in 0..10 {
            for j in 0..10 {
                for k in 0..5 {
                    parts.x.push(Pt3::new(0.05 + i as f64 * 0.1, 0.05 + k as f64 * 0.1, 0.05 + j as f64 * 0.1));
                    parts.v.push(c);
                    parts.r.push(0.025);
                    parts.phi.push(-1.0);
                    parts.flags.push(ParticleFlags::default());
                    parts.tet.push(geom_core::NONE);
                }
            }
        }
        let h: Vec<f64> = m.tet_level.iter().map(|&l| 0.5 / f64::from(1u32 << l)).collect();
        let mut tv = particles_to_tets(&m, &h, &parts, &TransferParams::default());
        let nvalid = tv.valid.iter().filter(|&&v| v).count();
        assert!(nvalid > 0 && nvalid < m.tets.len());
        for t in 0..m.tets.len() {
            if tv.valid[t] {
                assert!((tv.u[t] - c).norm() < 1e-14);
            }
        }
        let used = extrapolate(&m, &mut tv.u, &mut tv.valid, 10);
        assert!(used >= 1);
        assert!(tv.valid.iter().all(|&v| v));
        for u in &tv.u {
            assert!((u - c).norm() < 1e-14);
        }
    }

    /// The grouped gather of `particles_to_tets` (one query per leaf group, then each tet's own
    /// radius test) gives bitwise the result of one `SphereTree::within` query per tet (the
    /// session-8 code path, rebuilt here as the reference) on a graded mesh with 600 random
    /// particles of mixed radii and velocities, some ballistic, and with a wide support (2 h_t)
    /// where groups overlap most.
    #[test]
    fn grouped_gather_equals_per_tet_queries_bitwise() {
        let (_, m) = mesh();
        let mut rng = geom_core::rng::Rng::new(11);
        let mut parts = Particles::default();
        for i in 0..600 {
            let x = Pt3::new(rng.range(0.0, 1.0), rng.range(0.0, 0.7), rng.range(0.0, 1.0));
            parts.x.push(x);
            parts.v.push(rng.unit_vec3() * rng.range(0.1, 2.0));
            parts.r.push(rng.range(0.01, 0.05));
            parts.phi.push(-rng.range(0.0, 0.2));
            let mut f = ParticleFlags::default();
            if i % 37 == 0 {
                f.0 |= ParticleFlags::BALLISTIC;
            }
            parts.flags.push(f);
            parts.tet.push(geom_core::NONE);
        }
        let h: Vec<f64> = m.tet_level.iter().map(|&l| 0.5 / f64::from(1u32 << l)).collect();
        for support in [1.0, 2.0] {
            let tp = TransferParams { support, ..TransferParams::default() };
            let got = particles_to_tets(&m, &h, &parts, &tp);
            let occ = crate::surface::SphereTree::build(&parts.x, &vec![0.0; parts.len()]);
            let mut buf = Vec::new();
            for (t, &ht) in h.iter().enumerate() {
                let (c, rad) = (m.centroid[t], support * ht);
                occ.within(&c, rad, &mut buf);
                let want = tet_average(&parts, c, rad, 0.5 * ht, &buf, tp.omega_valid);
                assert_eq!(got.u[t], want.0, "tet {t}");
                assert_eq!(got.valid[t], want.1);
                assert_eq!(got.coverage[t].to_bits(), want.2.to_bits());
            }
            assert!(got.valid.iter().any(|&v| v) && got.valid.iter().any(|&v| !v));
        }
    }
}
