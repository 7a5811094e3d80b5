//! Procedural test geometry (spec §2.4): the capped cylinder arm with its two-bone skeleton and
//! ramp weights, and a capsule humanoid (straight tapered capsules per limb in a T-pose, on a
//! 22-joint skeleton) with simple inverse-distance weights.
//!
//! Tubes come from `geom_core::procedural::tube` ([`capsule`] moves its rings onto a tapered,
//! optionally rounded profile); distances to bone segments from `geom_core::query`.

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::{smoothstep, Pt3, Vec3};
use serde::{Deserialize, Serialize};

use geom_core::mesh::{NormalWeight, PolyMesh};
use geom_core::procedural::{tube, Caps, TubeSpec};
use geom_core::query::closest_point_segment;

use crate::error::{Result, SkinError};
use crate::weights::PackedWeights;

/// A triangle mesh for skinning (outward, counter-clockwise faces).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinMesh {
    /// Rest positions (m).
    pub positions: Vec<Pt3>,
    /// Triangles.
    pub tris: Vec<[u32; 3]>,
}

impl SkinMesh {
    /// Positions rounded to `f32`.
    pub fn positions_f32(&self) -> Vec<[f32; 3]> {
        self.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect()
    }

    /// Area-weighted vertex normals (unit; zero for isolated vertices).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        vertex_normals(&self.positions, &self.tris)
    }

    /// Appends another mesh.
    pub fn append(&mut self, o: &SkinMesh) {
        let off = self.positions.len() as u32;
        self.positions.extend_from_slice(&o.positions);
        self.tris.extend(o.tris.iter().map(|t| [t[0] + off, t[1] + off, t[2] + off]));
    }
}

/// Area-weighted unit vertex normals of any positions sharing `tris` (zero for isolated
/// vertices): `geom_core::mesh::vertex_normals` with [`NormalWeight::Area`].
pub fn vertex_normals<P: geom_core::math::AsPt3>(pos: &[P], tris: &[[u32; 3]]) -> Vec<Vec3> {
    geom_core::mesh::vertex_normals(tris, pos, NormalWeight::Area)
}

/// Closed tube along the segment `a → b`: `rings` rings of `segments` vertices, ring `i` at
/// parameter `t_i = i/(rings−1)` with radius `radius(t_i)`, closed by fan caps (one centre vertex
/// per end). `end_round` > 0 adds that many extra rings per end on a hemisphere of the end radius
/// (a capsule) before the cap vertex. Faces are outward.
///
/// The topology, vertex layout and ring frame are those of [`geom_core::procedural::tube`] (a unit
/// tube with [`Caps::Fan`], quads split along `(r,k)–(r+1,k+1)`); its rings are moved onto the
/// capsule profile. Errors: fewer than 2 rings or 3 segments, a zero-length axis, a non-finite or
/// non-positive radius.
pub fn capsule(
    a: Pt3,
    b: Pt3,
    radius: &dyn Fn(f64) -> f64,
    rings: usize,
    segments: usize,
    end_round: usize,
) -> Result<SkinMesh> {
    let axis = b - a;
    let len = axis.norm();
    if rings < 2 || segments < 3 || !(len > 0.0 && len.is_finite()) {
        return Err(SkinError::Param(format!(
            "capsule needs rings ≥ 2, segments ≥ 3 and a finite non-zero axis, got {rings}, {segments}, |b − a| = {len}"
        )));
    }
    let x = axis / len;
    // Ring list (centre, radius) from a to b, including the hemispherical end rings.
    let mut ring_list: Vec<(Pt3, f64)> = Vec::new();
    let r0 = radius(0.0);
    let r1 = radius(1.0);
    for k in (1..=end_round).rev() {
        let ang = std::f64::consts::FRAC_PI_2 * k as f64 / (end_round + 1) as f64;
        ring_list.push((a - x * (r0 * ang.sin()), r0 * ang.cos()));
    }
    for i in 0..rings {
        let t = i as f64 / (rings - 1) as f64;
        ring_list.push((a + axis * t, radius(t)));
    }
    for k in 1..=end_round {
        let ang = std::f64::consts::FRAC_PI_2 * k as f64 / (end_round + 1) as f64;
        ring_list.push((b + x * (r1 * ang.sin()), r1 * ang.cos()));
    }
    if let Some(i) = ring_list.iter().position(|(_, r)| !(*r > 0.0 && r.is_finite())) {
        return Err(SkinError::Param(format!("capsule ring {i}: radius must be positive and finite")));
    }
    let nr = ring_list.len();
    let spec = TubeSpec {
        radius: 1.0,
        length: 1.0,
        around: segments as u32,
        along: (nr - 1) as u32,
        start: Pt3::origin(),
        axis: x,
        caps: Caps::Fan,
    };
    let unit = tube(&spec)?;
    // Tube ring r is centred at (r/along)·x̂ with unit radius: move it onto the profile.
    let n = segments;
    let mut pos = Vec::with_capacity(unit.positions.len());
    for (r, (c, rad)) in ring_list.iter().enumerate() {
        let centre = Pt3::origin() + x * (r as f64 / (nr - 1) as f64);
        for k in 0..n {
            pos.push(c + (unit.positions[r * n + k] - centre) * *rad);
        }
    }
    pos.push(if end_round > 0 { a - x * r0 } else { a });
    pos.push(if end_round > 0 { b + x * r1 } else { b });
    let (tri, _) = PolyMesh { positions: pos, faces: unit.faces, uv: None }.triangulate_fan()?;
    Ok(SkinMesh { positions: tri.positions, tris: tri.faces })
}

/// The cylinder arm of spec §7: axis x ∈ [−bone_len, bone_len], joint (elbow) at the origin,
/// `rings` rings × `segments` around, flat fan caps; skeleton shoulder (x = −bone_len, root) →
/// elbow (0) → wrist (x = bone_len, leaf), rest frames with x along +x.
pub fn cylinder_arm(radius: f64, bone_len: f64, rings: usize, segments: usize) -> Result<(SkinMesh, SkinSkeleton)> {
    let a = Pt3::new(-bone_len, 0.0, 0.0);
    let b = Pt3::new(bone_len, 0.0, 0.0);
    let m = capsule(a, b, &|_| radius, rings.max(2), segments.max(3), 0)?;
    let sk = SkinSkeleton::from_positions(
        vec!["shoulder".into(), "elbow".into(), "wrist".into()],
        vec![None, Some(0), Some(1)],
        &[a, Pt3::origin(), b],
    )?;
    Ok((m, sk))
}

/// Weight ramp shape across the joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Ramp {
    /// Linear in x.
    Linear,
    /// Smoothstep in x.
    #[default]
    SmoothStep,
}

/// Two-bone ramp weights along x: bone 1's weight rises from 0 at `joint_x − half_width` to 1 at
/// `joint_x + half_width` (linear or smoothstep), bone 0 takes the rest.
pub fn ramp_weights<P: geom_core::math::AsPt3>(
    rest: &[P],
    joint_x: f64,
    half_width: f64,
    kind: Ramp,
) -> PackedWeights<2> {
    let mut out = PackedWeights { bone: Vec::with_capacity(rest.len()), w: Vec::with_capacity(rest.len()) };
    for p in rest {
        let xi = ((p.pt3().x - joint_x + half_width) / (2.0 * half_width)).clamp(0.0, 1.0);
        let w1 = match kind {
            Ramp::Linear => xi,
            Ramp::SmoothStep => smoothstep(0.0, 1.0, xi),
        };
        let w0 = 1.0 - w1;
        // Slot 0 holds the larger weight (the DQS pivot).
        if w1 > w0 {
            out.bone.push([1, 0]);
            out.w.push([w1 as f32, w0 as f32]);
        } else {
            out.bone.push([0, 1]);
            out.w.push([w0 as f32, w1 as f32]);
        }
    }
    out
}

/// A capsule humanoid: mesh, skeleton and the limb radius used for each vertex's piece.
#[derive(Clone, Debug)]
pub struct Humanoid {
    /// The mesh (separate closed capsules: torso, head, arms, legs, feet).
    pub mesh: SkinMesh,
    /// The skeleton (22 joints, T-pose facing +z, y up, 1.84 m).
    pub skeleton: SkinSkeleton,
    /// Piece index of every vertex (0 torso, 1 head, 2–3 arms, 4–5 legs, 6–7 feet).
    pub piece: Vec<u8>,
}

/// Joint names of the humanoid, in order.
pub const HUMANOID_JOINTS: [&str; 22] = [
    "pelvis",
    "spine",
    "chest",
    "neck",
    "head",
    "head_top",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
    "l_hand",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
    "r_hand",
    "l_hip",
    "l_knee",
    "l_ankle",
    "l_toe",
    "r_hip",
    "r_knee",
    "r_ankle",
    "r_toe",
];

/// The humanoid skeleton (positions in m).
pub fn humanoid_skeleton() -> Result<SkinSkeleton> {
    let p = |x: f64, y: f64, z: f64| Pt3::new(x, y, z);
    let pos = [
        p(0.0, 1.0, 0.0),
        p(0.0, 1.15, 0.0),
        p(0.0, 1.35, 0.0),
        p(0.0, 1.52, 0.0),
        p(0.0, 1.62, 0.0),
        p(0.0, 1.84, 0.0),
        p(0.2, 1.45, 0.0),
        p(0.48, 1.45, 0.0),
        p(0.74, 1.45, 0.0),
        p(0.86, 1.45, 0.0),
        p(-0.2, 1.45, 0.0),
        p(-0.48, 1.45, 0.0),
        p(-0.74, 1.45, 0.0),
        p(-0.86, 1.45, 0.0),
        p(0.1, 0.95, 0.0),
        p(0.1, 0.52, 0.0),
        p(0.1, 0.1, 0.0),
        p(0.1, 0.04, 0.16),
        p(-0.1, 0.95, 0.0),
        p(-0.1, 0.52, 0.0),
        p(-0.1, 0.1, 0.0),
        p(-0.1, 0.04, 0.16),
    ];
    let parent = vec![
        None,
        Some(0),
        Some(1),
        Some(2),
        Some(3),
        Some(4),
        Some(2),
        Some(6),
        Some(7),
        Some(8),
        Some(2),
        Some(10),
        Some(11),
        Some(12),
        Some(0),
        Some(14),
        Some(15),
        Some(16),
        Some(0),
        Some(18),
        Some(19),
        Some(20),
    ];
    Ok(SkinSkeleton::from_positions(HUMANOID_JOINTS.iter().map(|s| s.to_string()).collect(), parent, &pos)?)
}

/// The capsule humanoid at resolution `res` (1.0 ≈ 50k vertices; vertex count grows ∝ res²).
pub fn humanoid(res: f64) -> Result<Humanoid> {
    let sk = humanoid_skeleton()?;
    let n = |k: f64| ((k * res).round() as usize).max(3);
    let mut mesh = SkinMesh::default();
    let mut piece = Vec::new();
    let mut add = |m: SkinMesh, id: u8, mesh: &mut SkinMesh| {
        piece.extend(std::iter::repeat_n(id, m.positions.len()));
        mesh.append(&m);
    };
    let torso = |t: f64| {
        // hips 0.14 → waist 0.12 → chest 0.15 → neck 0.06
        let keys = [(0.0, 0.14), (0.35, 0.12), (0.7, 0.15), (0.88, 0.11), (1.0, 0.06)];
        let k = keys.windows(2).find(|w| t <= w[1].0).unwrap_or(&keys[3..5]);
        let u = ((t - k[0].0) / (k[1].0 - k[0].0)).clamp(0.0, 1.0);
        k[0].1 + (k[1].1 - k[0].1) * smoothstep(0.0, 1.0, u)
    };
    // Flat-ended torso: a rounded bottom would hang between the legs and bind to both thighs.
    add(capsule(Pt3::new(0.0, 0.92, 0.0), Pt3::new(0.0, 1.55, 0.0), &torso, n(130.0), n(96.0), 0)?, 0, &mut mesh);
    add(
        capsule(Pt3::new(0.0, 1.6, 0.0), Pt3::new(0.0, 1.76, 0.0), &|_| 0.09, n(40.0), n(64.0), n(12.0))?,
        1,
        &mut mesh,
    );
    // Limbs (arms, legs, feet), left then right: ends (x scaled by the side), radius profile,
    // rings, segments, rounded end rings, piece id of the left one.
    type Limb<'a> = ([f64; 3], [f64; 3], &'a dyn Fn(f64) -> f64, f64, f64, f64, u8);
    let limbs: [Limb; 3] = [
        ([0.16, 1.45, 0.0], [0.86, 1.45, 0.0], &|t| 0.055 - 0.025 * t, 150.0, 48.0, 6.0, 2),
        ([0.1, 0.98, 0.0], [0.1, 0.08, 0.0], &|t| 0.085 - 0.04 * t, 180.0, 48.0, 6.0, 4),
        ([0.1, 0.05, -0.03], [0.1, 0.04, 0.17], &|_| 0.04, 40.0, 32.0, 5.0, 6),
    ];
    for (a, b, radius, rings, segs, round, id) in limbs {
        for (s, side) in [(1.0, 0u8), (-1.0, 1u8)] {
            let (pa, pb) = (Pt3::new(a[0] * s, a[1], a[2]), Pt3::new(b[0] * s, b[1], b[2]));
            add(capsule(pa, pb, radius, n(rings), n(segs), n(round))?, id + side, &mut mesh);
        }
    }
    Ok(Humanoid { mesh, skeleton: sk, piece })
}

/// Simple inverse-distance weights (spec: a scene's "own simple weights" when no bone-heat
/// weights are given): `w_b ∝ (d_b + ε)^−power` over the bone segments owned by joint `b`
/// (`d_b` = distance to the nearest such segment, ε = 1e-4 m), rows normalised. Returns sparse
/// rows for [`PackedWeights::from_sparse`] / `SkinWeights::from_rows`.
pub fn inverse_distance_weights(rest: &[Pt3], sk: &SkinSkeleton, power: f64, min_w: f32) -> Vec<Vec<(u16, f32)>> {
    let children = sk.children();
    let segs: Vec<(usize, Pt3, Pt3)> = (0..sk.len())
        .flat_map(|j| {
            let a = Pt3::from(sk.rest_world[j].translation.vector);
            children[j].iter().map(move |&c| (j, a, c)).collect::<Vec<_>>()
        })
        .map(|(j, a, c)| (j, a, Pt3::from(sk.rest_world[c].translation.vector)))
        .collect();
    rest.iter()
        .map(|x| {
            let mut d = vec![f64::INFINITY; sk.len()];
            for (j, a, b) in &segs {
                d[*j] = d[*j].min((closest_point_segment(x, a, b).1 - x).norm());
            }
            let w: Vec<f64> = d.iter().map(|&d| if d.is_finite() { (d + 1e-4).powf(-power) } else { 0.0 }).collect();
            let s: f64 = w.iter().sum();
            let mut row: Vec<(u16, f32)> = w
                .iter()
                .enumerate()
                .filter(|(_, &w)| (w / s) as f32 >= min_w)
                .map(|(j, &w)| (j as u16, (w / s) as f32))
                .collect();
            if row.is_empty() {
                let (j, _) = d.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).unwrap_or((0, &0.0));
                row.push((j as u16, 1.0));
            }
            row
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::signed_volume;

    #[test]
    fn arm_is_closed_and_outward() {
        let (m, sk) = cylinder_arm(0.15, 1.0, 40, 24).unwrap();
        let v = signed_volume(&m.positions, &m.tris);
        // Prism volume of the polygonal cross-section: n/2·R²·sin(2π/n)·length.
        let exact = 12.0 * 0.15f64.powi(2) * (2.0 * std::f64::consts::PI / 24.0).sin() * 2.0;
        assert!((v - exact).abs() < 1e-12, "{v} vs {exact}");
        assert_eq!(sk.len(), 3);
        // Every edge is shared by exactly two faces (closed manifold).
        let mut edges = std::collections::HashMap::new();
        for t in &m.tris {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2));
    }

    #[test]
    fn capsule_and_humanoid_volumes_are_positive() {
        let c = capsule(Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0), &|t| 0.1 + 0.05 * t, 20, 16, 4).unwrap();
        assert!(signed_volume(&c.positions, &c.tris) > 0.0);
        let h = humanoid(0.25).unwrap();
        assert!(signed_volume(&h.mesh.positions, &h.mesh.tris) > 0.0);
        assert_eq!(h.piece.len(), h.mesh.positions.len());
    }

    #[test]
    fn ramp_weights_sum_to_one_and_cross_half_at_the_joint() {
        let pts =
            [Pt3::new(-1.0, 0.0, 0.0), Pt3::new(0.0, 0.1, 0.0), Pt3::new(0.05, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0)];
        let w = ramp_weights(&pts, 0.0, 0.15, Ramp::SmoothStep);
        for r in &w.w {
            assert!((r[0] + r[1] - 1.0).abs() < 1e-7);
            assert!(r[0] >= r[1]);
        }
        assert_eq!((w.bone[0][0], w.w[0][0]), (0, 1.0));
        assert_eq!((w.bone[3][0], w.w[3][0]), (1, 1.0));
        assert_eq!(w.w[1], [0.5, 0.5]);
    }
}
