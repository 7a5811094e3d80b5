//! Procedural characters with known joints (GEOM-CORE.md §3.6, rigging spec §3.13): a smooth
//! union of tapered capsules (round cones), ellipsoids and spheres laid along a ground-truth
//! skeleton, optionally with "blobby" sine noise, meshed by [`crate::iso::polygonize_to_count`].
//!
//! Axes: +Y up, the character faces +Z, its left is +X; the feet rest on `y = 0`. Lengths are
//! in units of `height` (the distance from the soles to the top of the head of the default
//! proportions). Joint names are those of rigging's human template ([`HUMANOID_JOINTS`]).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::iso::{polygonize_to_count, sdf};
use crate::math::{Iso3, Pt3, Vec3};
use crate::mesh::TriMesh;
use crate::rng::Rng;
use crate::spatial::Aabb;

/// A tapered capsule: the convex hull of the spheres `(a, ra)` and `(b, rb)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoundCone {
    /// First end centre.
    pub a: Pt3,
    /// Second end centre.
    pub b: Pt3,
    /// Radius at `a`.
    pub ra: f64,
    /// Radius at `b`.
    pub rb: f64,
}

/// Sine noise `Σ_k a_k sin(ω_k · x + φ_k)` added to a field. With `Σ_k a_k |ω_k| < 1` the sum
/// of a distance field and the noise still increases along every outward path, so the noise
/// cannot detach islands or pinch the solid apart.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bumps {
    /// `(ω_k, φ_k, a_k)`: wave vector (rad per length unit), phase (rad), amplitude (length).
    pub waves: Vec<(Vec3, f64, f64)>,
}

impl Bumps {
    /// The noise value at `p`.
    pub fn eval(&self, p: &Pt3) -> f64 {
        self.waves.iter().map(|(w, phi, a)| a * (w.dot(&p.coords) + phi).sin()).sum()
    }

    /// `Σ_k |a_k|`: the largest possible noise magnitude.
    pub fn amplitude(&self) -> f64 {
        self.waves.iter().map(|w| w.2.abs()).sum()
    }

    /// `Σ_k |a_k| |ω_k|`: the noise's Lipschitz constant (keep it below 1).
    pub fn lipschitz(&self) -> f64 {
        self.waves.iter().map(|(w, _, a)| a.abs() * w.norm()).sum()
    }
}

/// A character solid: the smooth union (polynomial smooth-min of width `smooth_k`) of round
/// cones, posed ellipsoids `(local → world pose, semi-axes)` and spheres `(centre, radius)`,
/// plus optional [`Bumps`]. Negative inside.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CharacterSdf {
    /// Tapered capsules along the bones.
    pub cones: Vec<RoundCone>,
    /// Ellipsoids (torso, body).
    pub ellipsoids: Vec<(Iso3, Vec3)>,
    /// Spheres (head).
    pub spheres: Vec<(Pt3, f64)>,
    /// Blend width of the smooth union (length).
    pub smooth_k: f64,
    /// Optional sine noise.
    pub bumps: Option<Bumps>,
}

impl CharacterSdf {
    /// Field value at `p` (negative inside). Primitives are combined in a fixed order (cones,
    /// ellipsoids, spheres), so the value is deterministic.
    pub fn eval(&self, p: &Pt3) -> f64 {
        let mut d = f64::INFINITY;
        let mut add = |x: f64| d = if d.is_finite() { sdf::smooth_min(d, x, self.smooth_k) } else { x };
        for c in &self.cones {
            add(sdf::round_cone(p, &c.a, &c.b, c.ra, c.rb));
        }
        for (pose, r) in &self.ellipsoids {
            add(sdf::ellipsoid(p, pose, r));
        }
        for (c, r) in &self.spheres {
            add(sdf::sphere(p, c, *r));
        }
        match &self.bumps {
            Some(b) => d + b.eval(p),
            None => d,
        }
    }

    /// A box containing the solid (primitive boxes grown by the noise amplitude).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::empty();
        for c in &self.cones {
            b = b.union(&Aabb::new(c.a, c.a).grow(c.ra)).union(&Aabb::new(c.b, c.b).grow(c.rb));
        }
        for (pose, r) in &self.ellipsoids {
            let c = Pt3::from(pose.translation.vector);
            b = b.union(&Aabb::new(c, c).grow(r.max()));
        }
        for (c, r) in &self.spheres {
            b = b.union(&Aabb::new(*c, *c).grow(*r));
        }
        b.grow(self.bumps.as_ref().map_or(0.0, |x| x.amplitude()))
    }
}

/// Joint names of the human template (rigging spec §3.5 table), in its order.
pub const HUMANOID_JOINTS: [&str; 18] = [
    "shoulders",
    "back",
    "hips",
    "head",
    "l_thigh",
    "l_knee",
    "l_ankle",
    "l_foot",
    "r_thigh",
    "r_knee",
    "r_ankle",
    "r_foot",
    "l_shoulder",
    "l_elbow",
    "l_hand",
    "r_shoulder",
    "r_elbow",
    "r_hand",
];

/// Parents of [`HUMANOID_JOINTS`].
pub const HUMANOID_PARENTS: [Option<usize>; 18] = [
    None,
    Some(0),
    Some(1),
    Some(0),
    Some(2),
    Some(4),
    Some(5),
    Some(6),
    Some(2),
    Some(8),
    Some(9),
    Some(10),
    Some(0),
    Some(12),
    Some(13),
    Some(0),
    Some(15),
    Some(16),
];

/// A named joint tree with rest positions: the ground truth of a generated character.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSet {
    /// Joint names.
    pub names: Vec<String>,
    /// Parent of each joint (smaller index), `None` for the root.
    pub parents: Vec<Option<usize>>,
    /// Rest positions (same units as the solid).
    pub rest: Vec<Pt3>,
}

/// Proportions and pose of a generated humanoid (rigging spec §3.13). Scales are relative to
/// the default proportions (1 = default).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct HumanoidParams {
    /// Overall scale: sole-to-crown height of the default proportions (length units).
    pub height: f64,
    /// Arm length scale.
    pub arm: f64,
    /// Leg length scale.
    pub leg: f64,
    /// Limb (arm and leg) radius scale; hands, feet, torso and head keep their size.
    pub limb_radius: f64,
    /// Shoulder and hip width scale.
    pub torso_width: f64,
    /// Head size scale.
    pub head: f64,
    /// Arm elevation about z at the shoulders (deg): 0 horizontal, negative down (−45 ≈ A pose).
    pub arm_elevation_deg: f64,
    /// Leg spread from vertical (deg).
    pub leg_spread_deg: f64,
    /// Fingers per hand (0 = mittens only, else 3–5).
    pub fingers: u8,
    /// Noise amplitude as a fraction of 0.03·height (0 = smooth).
    pub bumps: f64,
    /// Seed of the noise and of the ±4 % proportion jitter.
    pub seed: u64,
}

impl Default for HumanoidParams {
    fn default() -> Self {
        Self {
            height: 1.0,
            arm: 1.0,
            leg: 1.0,
            limb_radius: 1.0,
            torso_width: 1.0,
            head: 1.0,
            arm_elevation_deg: -40.0,
            leg_spread_deg: 8.0,
            fingers: 0,
            bumps: 0.0,
            seed: 0,
        }
    }
}

fn check_params(p: &HumanoidParams) -> Result<()> {
    let pos = [
        ("height", p.height),
        ("arm", p.arm),
        ("leg", p.leg),
        ("limb_radius", p.limb_radius),
        ("torso_width", p.torso_width),
        ("head", p.head),
    ];
    for (name, v) in pos {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::InvalidParameter(format!("humanoid: {name} = {v} must be positive")));
        }
    }
    if !(-90.0..=90.0).contains(&p.arm_elevation_deg) || !(0.0..=60.0).contains(&p.leg_spread_deg) {
        return Err(Error::InvalidParameter(format!(
            "humanoid: arm elevation {} ∉ [−90, 90] or leg spread {} ∉ [0, 60] degrees",
            p.arm_elevation_deg, p.leg_spread_deg
        )));
    }
    if !(0.0..=1.0).contains(&p.bumps) || p.fingers > 5 || (p.fingers > 0 && p.fingers < 3) {
        return Err(Error::InvalidParameter(format!(
            "humanoid: bumps {} ∉ [0, 1] or fingers {} ∉ {{0, 3, 4, 5}}",
            p.bumps, p.fingers
        )));
    }
    Ok(())
}

/// Seeded noise with `n` waves of wavelength ≈ `wavelength`, total amplitude `amp`, Lipschitz
/// constant capped at 0.9.
fn make_bumps(rng: &mut Rng, n: usize, amp: f64, wavelength: f64) -> Option<Bumps> {
    if amp <= 0.0 {
        return None;
    }
    let mut waves: Vec<(Vec3, f64, f64)> = (0..n)
        .map(|_| {
            let k = 2.0 * std::f64::consts::PI / (wavelength * rng.range(0.7, 1.3));
            (rng.unit_vec3() * k, rng.range(0.0, 2.0 * std::f64::consts::PI), amp / n as f64)
        })
        .collect();
    let b = Bumps { waves: waves.clone() };
    let lip = b.lipschitz();
    if lip > 0.9 {
        for w in &mut waves {
            w.2 *= 0.9 / lip;
        }
    }
    Some(Bumps { waves })
}

/// Builds a humanoid solid and its ground-truth joints ([`HUMANOID_JOINTS`] order).
///
/// Construction (rigging spec §3.13): tapered capsules along every limb bone (upper arm 0.045 H,
/// forearm 0.038 H, thigh 0.07 H, shin 0.05 H, times `limb_radius`), an ellipsoid torso with a
/// spine capsule, a neck, a sphere head, capsule feet and mitten hands (plus optional finger
/// capsules); smooth-union width 0.3 × the smallest radius. Leaf joints (hands, feet) sit at the
/// far end centre of the last capsule of their limb, the head joint at the head-sphere centre.
/// Errors: `InvalidParameter` naming an out-of-range parameter.
pub fn humanoid(p: &HumanoidParams) -> Result<(CharacterSdf, JointSet)> {
    check_params(p)?;
    let h = p.height;
    let mut rng = Rng::new(p.seed);
    let mut jit = || 1.0 + rng.range(-0.04, 0.04);
    let (thigh_len, shin_len) = (0.245 * p.leg * jit() * h, 0.235 * p.leg * jit() * h);
    let (upper_len, fore_len) = (0.17 * p.arm * jit() * h, 0.19 * p.arm * jit() * h);
    let hip_w = 0.055 * p.torso_width * jit() * h;
    let sh_w = 0.105 * p.torso_width * jit() * h;
    let spine = 0.29 * jit() * h;
    let head_r = 0.075 * p.head * h;
    let lr = p.limb_radius * h;
    let ankle_y = 0.045 * h;

    let spread = p.leg_spread_deg.to_radians();
    let elev = p.arm_elevation_deg.to_radians();
    let leg_dir = |s: f64| Vec3::new(s * spread.sin(), -spread.cos(), 0.0);
    let hips_y = ankle_y + (thigh_len + shin_len) * spread.cos();
    let hips = Pt3::new(0.0, hips_y, 0.0);
    let back = hips + Vec3::new(0.0, 0.4 * spine, -0.005 * h);
    let shoulders = hips + Vec3::new(0.0, spine, 0.0);
    let head = shoulders + Vec3::new(0.0, 0.06 * h + 0.9 * head_r, 0.01 * h);

    let mut rest = vec![Pt3::origin(); 18];
    rest[0] = shoulders;
    rest[1] = back;
    rest[2] = hips;
    rest[3] = head;
    let mut cones = Vec::new();
    let mut cone = |a: Pt3, b: Pt3, ra: f64, rb: f64| cones.push(RoundCone { a, b, ra, rb });
    let mut min_r = f64::INFINITY;
    let mut track = |r: f64| min_r = min_r.min(r);
    for (side, base) in [(1.0, 4usize), (-1.0, 8usize)] {
        let thigh = hips + Vec3::new(side * hip_w, 0.0, 0.0);
        let knee = thigh + leg_dir(side) * thigh_len + Vec3::new(0.0, 0.0, 0.012 * h);
        let ankle = Pt3::new(thigh.x + side * (thigh_len + shin_len) * spread.sin(), ankle_y, 0.0);
        let foot = ankle + Vec3::new(0.0, -0.012 * h, 0.11 * h);
        rest[base] = thigh;
        rest[base + 1] = knee;
        rest[base + 2] = ankle;
        rest[base + 3] = foot;
        cone(hips, thigh, 0.08 * h, 0.07 * lr.max(0.5 * h));
        cone(thigh, knee, 0.07 * lr, 0.055 * lr);
        cone(knee, ankle, 0.05 * lr, 0.04 * lr);
        cone(ankle, foot, 0.035 * h, 0.03 * h);
        track(0.04 * lr);
    }
    let arm_dir = |s: f64| Vec3::new(s * elev.cos(), elev.sin(), 0.0);
    for (side, base) in [(1.0, 12usize), (-1.0, 15usize)] {
        let sh = shoulders + Vec3::new(side * sh_w, -0.01 * h, 0.0);
        let elbow = sh + arm_dir(side) * upper_len + Vec3::new(0.0, 0.0, 0.02 * h);
        let hand = elbow + arm_dir(side) * fore_len + Vec3::new(0.0, 0.0, 0.03 * h);
        let wrist = elbow + (hand - elbow) * 0.72;
        rest[base] = sh;
        rest[base + 1] = elbow;
        rest[base + 2] = hand;
        cone(shoulders, sh, 0.055 * h, 0.05 * lr.max(0.8 * h));
        cone(sh, elbow, 0.045 * lr, 0.038 * lr);
        cone(elbow, wrist, 0.038 * lr, 0.03 * lr);
        cone(wrist, hand, 0.032 * h, 0.028 * h);
        track(0.03 * lr);
        if p.fingers > 0 {
            let u = (hand - wrist).normalize();
            let across = Vec3::new(0.0, 0.0, 1.0);
            for f in 0..p.fingers {
                let t = f as f64 / (p.fingers - 1) as f64 - 0.5;
                let a = hand - u * 0.015 * h + across * (t * 0.04 * h);
                let b = a + (u + across * t * 0.8).normalize() * 0.045 * h;
                cone(a, b, 0.011 * h, 0.009 * h);
                track(0.009 * h);
            }
        }
    }
    // Torso and head.
    cone(hips, back, 0.1 * h, 0.095 * h);
    cone(back, shoulders, 0.095 * h, 0.085 * h);
    cone(shoulders, head, 0.04 * h, 0.04 * h);
    let torso_c = hips + (shoulders - hips) * 0.5;
    let ellipsoids = vec![(
        Iso3::translation(torso_c.x, torso_c.y, torso_c.z),
        Vec3::new(0.125 * p.torso_width.sqrt() * h, 0.2 * h, 0.085 * h),
    )];
    let spheres = vec![(head, head_r)];
    let bumps = make_bumps(&mut rng, 8, p.bumps * 0.03 * h, 0.22 * h);
    let sdf = CharacterSdf { cones, ellipsoids, spheres, smooth_k: 0.3 * min_r, bumps };
    let joints = JointSet {
        names: HUMANOID_JOINTS.iter().map(|s| s.to_string()).collect(),
        parents: HUMANOID_PARENTS.to_vec(),
        rest,
    };
    Ok((sdf, joints))
}

/// Joint names of the quadruped (rigging spec §3.5): body root at the shoulders, spine to the
/// hips, neck and head, four legs of thigh/knee/foot, tail.
pub const QUADRUPED_JOINTS: [&str; 18] = [
    "shoulders",
    "back",
    "hips",
    "neck",
    "head",
    "lf_thigh",
    "lf_knee",
    "lf_foot",
    "rf_thigh",
    "rf_knee",
    "rf_foot",
    "lh_thigh",
    "lh_knee",
    "lh_foot",
    "rh_thigh",
    "rh_knee",
    "rh_foot",
    "tail",
];

/// Parents of [`QUADRUPED_JOINTS`].
pub const QUADRUPED_PARENTS: [Option<usize>; 18] = [
    None,
    Some(0),
    Some(1),
    Some(0),
    Some(3),
    Some(0),
    Some(5),
    Some(6),
    Some(0),
    Some(8),
    Some(9),
    Some(2),
    Some(11),
    Some(12),
    Some(2),
    Some(14),
    Some(15),
    Some(2),
];

/// Builds a horse/cat-like quadruped (body along z, head at +z) of body length `length`, leg
/// length `leg` × 0.5 length, limb radius scale `limb_radius`, noise `bumps` (fraction of
/// 0.03·length) and its ground-truth joints ([`QUADRUPED_JOINTS`] order).
pub fn quadruped(length: f64, leg: f64, limb_radius: f64, bumps: f64, seed: u64) -> Result<(CharacterSdf, JointSet)> {
    for (name, v) in [("length", length), ("leg", leg), ("limb_radius", limb_radius)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::InvalidParameter(format!("quadruped: {name} = {v} must be positive")));
        }
    }
    if !(0.0..=1.0).contains(&bumps) {
        return Err(Error::InvalidParameter(format!("quadruped: bumps {bumps} ∉ [0, 1]")));
    }
    let l = length;
    let mut rng = Rng::new(seed);
    let leg_len = 0.5 * leg * l;
    let body_y = leg_len + 0.05 * l;
    let shoulders = Pt3::new(0.0, body_y, 0.3 * l);
    let back = Pt3::new(0.0, body_y + 0.01 * l, 0.0);
    let hips = Pt3::new(0.0, body_y, -0.3 * l);
    let neck = shoulders + Vec3::new(0.0, 0.18 * l, 0.12 * l);
    let head = neck + Vec3::new(0.0, 0.08 * l, 0.12 * l);
    let tail = hips + Vec3::new(0.0, 0.05 * l, -0.35 * l);
    let mut rest = vec![shoulders, back, hips, neck, head];
    let r = limb_radius * l;
    let mut cones = vec![
        RoundCone { a: shoulders, b: neck, ra: 0.07 * l, rb: 0.05 * l },
        RoundCone { a: neck, b: head, ra: 0.05 * l, rb: 0.06 * l },
        RoundCone { a: hips, b: tail, ra: 0.035 * r, rb: 0.015 * r },
    ];
    for (girdle, front) in [(shoulders, true), (hips, false)] {
        for side in [1.0, -1.0] {
            let thigh = girdle + Vec3::new(side * 0.09 * l, -0.04 * l, 0.0);
            let knee = thigh + Vec3::new(0.0, -0.5 * leg_len, if front { 0.03 } else { -0.04 } * l);
            let foot = Pt3::new(thigh.x, 0.025 * l, thigh.z + 0.02 * l);
            rest.extend([thigh, knee, foot]);
            cones.push(RoundCone { a: girdle, b: thigh, ra: 0.09 * l, rb: 0.06 * r.max(0.6 * l) });
            cones.push(RoundCone { a: thigh, b: knee, ra: 0.055 * r, rb: 0.04 * r });
            cones.push(RoundCone { a: knee, b: foot, ra: 0.04 * r, rb: 0.03 * r });
        }
    }
    rest.push(tail);
    let body_c = back;
    let ellipsoids = vec![(Iso3::translation(body_c.x, body_c.y, body_c.z), Vec3::new(0.14 * l, 0.13 * l, 0.42 * l))];
    let spheres = vec![(head, 0.07 * l)];
    let bumps = make_bumps(&mut rng, 8, bumps * 0.03 * l, 0.22 * l);
    let sdf = CharacterSdf { cones, ellipsoids, spheres, smooth_k: 0.3 * 0.015 * r, bumps };
    let joints = JointSet {
        names: QUADRUPED_JOINTS.iter().map(|s| s.to_string()).collect(),
        parents: QUADRUPED_PARENTS.to_vec(),
        rest,
    };
    Ok((sdf, joints))
}

/// Meshes a character solid with about `target_vertices` vertices (±10 %) by
/// [`polygonize_to_count`]. If the result has more than one component (a limb thinner than
/// about the grid spacing breaks apart), the spacing is reduced by 15 % at a time, up to 12 times,
/// until the mesh is connected (rigging spec §3.13); the vertex count then exceeds the target.
/// Errors from the polygonizer are passed on; `InvalidParameter` if it never connects.
pub fn build_mesh(sdf: &CharacterSdf, target_vertices: usize) -> Result<TriMesh> {
    let f = |p: &Pt3| sdf.eval(p);
    let bounds = sdf.bounds();
    let (mut m, mut h) = polygonize_to_count(&f, bounds, target_vertices, 0.1)?;
    for _ in 0..12 {
        if m.topology().face_components().0 == 1 {
            return Ok(m);
        }
        h *= 0.85;
        let b = Aabb::new(bounds.min - Vec3::repeat(2.0 * h), bounds.max + Vec3::repeat(2.0 * h));
        m = crate::iso::polygonize(&f, &crate::iso::PolygonizeOptions { bounds: b, h })?;
    }
    if m.topology().face_components().0 == 1 {
        return Ok(m);
    }
    Err(Error::InvalidParameter(format!("character mesh stays disconnected down to spacing {h}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_truth_joints_are_inside_and_mesh_is_one_closed_component() {
        let p = HumanoidParams { bumps: 0.3, seed: 5, fingers: 4, ..Default::default() };
        let (sdf, js) = humanoid(&p).expect("valid parameters");
        assert_eq!(js.rest.len(), 18);
        for (j, q) in js.rest.iter().enumerate() {
            assert!(sdf.eval(q) < 0.0, "joint {} outside", js.names[j]);
        }
        let m = build_mesh(&sdf, 4000).expect("meshes");
        assert!(m.topology().is_closed());
        assert_eq!(m.topology().face_components().0, 1);
        assert!((m.n_vertices() as f64 - 4000.0).abs() <= 400.0, "{} vertices", m.n_vertices());
        assert!(crate::mesh::signed_volume(&m.faces, &m.positions) > 0.0);
        // Same seed ⇒ bit-identical mesh.
        let m2 = build_mesh(&humanoid(&p).expect("valid").0, 4000).expect("meshes");
        assert_eq!(m.positions, m2.positions);
        assert!(humanoid(&HumanoidParams { arm: -1.0, ..Default::default() }).is_err());
    }

    #[test]
    fn quadruped_joints_inside() {
        let (sdf, js) = quadruped(1.0, 1.0, 1.0, 0.2, 3).expect("valid");
        for (j, q) in js.rest.iter().enumerate() {
            assert!(sdf.eval(q) < 0.0, "joint {} outside", js.names[j]);
        }
        assert!(quadruped(1.0, 1.0, 1.0, 2.0, 3).is_err());
    }
}
