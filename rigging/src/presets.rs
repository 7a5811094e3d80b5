//! The paper's setups as library calls (spec §3.13, §6, §8): generated characters with ground
//! truth, the quadruped, the too-thin character, the defective copies of a character that the
//! odd-shapes experiment feeds to [`crate::autorig`], and the two-capsule arm of the bone-heat
//! figure (paper Fig. 8).
//!
//! The held-out test set and the training set themselves are in [`crate::characters`].
//!
//! ```
//! use rigging::presets::humanoid_character;
//! use rigging::characters::test_params;
//! let (mesh, truth) = humanoid_character(&test_params(1000), 1500).unwrap();
//! assert_eq!(truth.rest.len(), 18);
//! assert!(mesh.topology().is_closed());
//! ```

use geom_core::iso::{polygonize, sdf, PolygonizeOptions};
use geom_core::math::{Pt3, Vec3};
use geom_core::mesh::TriMesh;
use geom_core::procedural::character::{build_mesh, humanoid, quadruped, HumanoidParams, JointSet};
use geom_core::spatial::Aabb;

use crate::characters::test_params;
use crate::error::Result;

/// A generated humanoid (spec §3.13) meshed with about `target_vertices` vertices, and its
/// ground-truth joints (template order of [`crate::SkeletonTemplate::human`]).
pub fn humanoid_character(p: &HumanoidParams, target_vertices: usize) -> Result<(TriMesh, JointSet)> {
    let (sdf, truth) = humanoid(p)?;
    Ok((build_mesh(&sdf, target_vertices)?, truth))
}

/// The quadruped of the odd-shapes experiment (body length 1, default legs and limbs, noise 0.2,
/// seeded) meshed with about `target_vertices` vertices, and its ground truth (template order of
/// [`crate::SkeletonTemplate::quadruped`]).
pub fn quadruped_character(seed: u64, target_vertices: usize) -> Result<(TriMesh, JointSet)> {
    let (sdf, truth) = quadruped(1.0, 1.0, 1.0, 0.2, seed)?;
    Ok((build_mesh(&sdf, target_vertices)?, truth))
}

/// The too-thin character of spec §3.13: test character `seed` with limbs at 0.3 × the default
/// radius and no noise. Rigged with τ = 0.008 its limbs are about 1.5 τ thick, below the 2 τ
/// surface filter of the medial samples (spec §3.2): a hard case that must fail gracefully.
pub fn too_thin_params(seed: u64) -> HumanoidParams {
    HumanoidParams { limb_radius: 0.3, bumps: 0.0, ..test_params(seed) }
}

/// τ (normalized units) at which [`too_thin_params`] characters are rigged.
pub const TOO_THIN_TAU: f64 = 0.008;

/// A copy of a character with one real-world defect (spec §8), as a raw triangle soup.
#[derive(Clone, Debug)]
pub struct DefectCase {
    /// Case name (`duplicates`, `inverted`, `components`, `components_keep_largest`, `holes`,
    /// `nonmanifold`).
    pub name: &'static str,
    /// Vertex positions (the input's units).
    pub positions: Vec<Pt3>,
    /// Triangles.
    pub faces: Vec<[u32; 3]>,
    /// Whether the case is rigged with `keep_largest_component`.
    pub keep_largest: bool,
}

/// The defective copies of `mesh` (spec §8), in the order of the odd-shapes experiment:
/// - `duplicates`: every face on its own three vertices (a triangle soup; welded back);
/// - `inverted`: every face flipped (re-oriented outward);
/// - `components` / `components_keep_largest`: a floating sphere of radius 0.05 beside the
///   character (refused, or rigged keeping the largest component);
/// - `holes`: the first three faces removed (refused);
/// - `nonmanifold`: a fin of two faces on the first edge (a non-manifold edge; refused).
pub fn defect_cases(mesh: &TriMesh) -> Result<Vec<DefectCase>> {
    let case = |name, positions, faces, keep_largest| DefectCase { name, positions, faces, keep_largest };
    let mut out = Vec::new();
    let mut dp = Vec::new();
    let mut df = Vec::new();
    for t in &mesh.faces {
        let base = dp.len() as u32;
        dp.extend(t.iter().map(|&v| mesh.positions[v as usize]));
        df.push([base, base + 1, base + 2]);
    }
    out.push(case("duplicates", dp, df, false));
    let inv: Vec<[u32; 3]> = mesh.faces.iter().map(|t| [t[0], t[2], t[1]]).collect();
    out.push(case("inverted", mesh.positions.clone(), inv, false));
    let ball = geom_core::procedural::icosphere(0.05, 2)?;
    let mut cp = mesh.positions.clone();
    let base = cp.len() as u32;
    cp.extend(ball.positions.iter().map(|x| x + Vec3::new(0.6, 0.1, 0.0)));
    let mut cf = mesh.faces.clone();
    cf.extend(ball.faces.iter().map(|t| t.map(|v| v + base)));
    out.push(case("components", cp.clone(), cf.clone(), false));
    out.push(case("components_keep_largest", cp, cf, true));
    out.push(case("holes", mesh.positions.clone(), mesh.faces[3..].to_vec(), false));
    let mut np = mesh.positions.clone();
    np.push(mesh.positions[mesh.faces[0][0] as usize] + Vec3::new(0.0, 0.0, 0.2));
    let mut nf = mesh.faces.clone();
    let fin = (np.len() - 1) as u32;
    nf.push([mesh.faces[0][0], mesh.faces[0][1], fin]);
    nf.push([mesh.faces[0][1], mesh.faces[0][0], fin]);
    out.push(case("nonmanifold", np, nf, false));
    Ok(out)
}

/// Two capsules of radius `r` along `a → b → c` (one joint at `b`), polygonized with grid spacing
/// `h` (normalized units): the arm of the bone-heat experiments.
pub fn two_capsules(a: Pt3, b: Pt3, c: Pt3, r: f64, h: f64) -> Result<TriMesh> {
    let f = move |p: &Pt3| sdf::union(sdf::capsule(p, &a, &b, r), sdf::capsule(p, &b, &c, r));
    let bb = Aabb::from_points(&[a, b, c]).grow(r + 3.0 * h);
    Ok(polygonize(&f, &PolygonizeOptions { bounds: bb, h })?)
}

/// The bent arm of the heat-two-bone experiment (paper Fig. 8): shoulder → elbow along +x,
/// elbow → hand along +y (90°), in the z = 0.5 plane. Returns (shoulder, elbow, hand).
pub fn bent_arm_joints() -> (Pt3, Pt3, Pt3) {
    (Pt3::new(0.15, 0.3, 0.5), Pt3::new(0.5, 0.3, 0.5), Pt3::new(0.5, 0.7, 0.5))
}

/// The straight two-bone cylinder of the transition-width check (spec §7.4 g): length 0.8 along
/// x, joint in the middle. Returns (start, joint, end).
pub fn straight_arm_joints() -> (Pt3, Pt3, Pt3) {
    (Pt3::new(0.1, 0.5, 0.5), Pt3::new(0.5, 0.5, 0.5), Pt3::new(0.9, 0.5, 0.5))
}

/// A long-necked quadruped (giraffe-like, the hard case of issue 23 where the unbounded search
/// blew up): [`quadruped_character`]'s body with the neck raised to `neck` × the body length
/// above the shoulders and reaching forward half as far, the head at its end.
pub fn long_necked_quadruped(seed: u64, neck: f64, target_vertices: usize) -> Result<(TriMesh, JointSet)> {
    let (mut sdf, mut truth) = quadruped(1.0, 1.0, 1.0, 0.2, seed)?;
    let (shoulders, old_neck, old_head) = (truth.rest[0], truth.rest[3], truth.rest[4]);
    let new_neck = shoulders + Vec3::new(0.0, neck, 0.5 * neck);
    let new_head = new_neck + (old_head - old_neck);
    // Cones 0 and 1 are shoulders → neck and neck → head; sphere 0 is the head.
    sdf.cones[0].b = new_neck;
    sdf.cones[1].a = new_neck;
    sdf.cones[1].b = new_head;
    sdf.spheres[0].0 = new_head;
    truth.rest[3] = new_neck;
    truth.rest[4] = new_head;
    Ok((build_mesh(&sdf, target_vertices)?, truth))
}
