//! Guide meshes and animations of the paper's scenes (spec §6), built procedurally because the
//! paper's artist data and motion capture are unavailable: the flag's coarse grid, the twisting
//! box (§5.2), the backflipping bag rig (§5.3), the X-shaped "Xavier" character with a walk /
//! headwind / electrocution clip (§5.4; a stand-in for the paper's character, no character
//! generator exists in geom-core) and the pulsating sphere of Fig. 4.

use std::sync::Arc;

use geom_core::math::{smoothstep, Mat3, Pt3, UnitQuat, Vec3};
use geom_core::mesh::{taubin_smooth, SmoothWeight, TriMesh};
use geom_core::procedural::{box_surface, grid, icosphere, Diagonals, GridSpec, Plane};

use crate::error::Result;
use crate::guide::{GuideAnimation, ProceduralFn};

/// The flag's coarse design mesh (spec §6.1): 7 × 5 vertices, 1.2 × 0.8 m, alternating
/// diagonals, horizontal (XZ plane) centred at (0, 2, 0); UVs in metres.
pub fn flag_coarse() -> Result<TriMesh> {
    Ok(grid(&GridSpec {
        quads: [6, 4],
        size: [1.2, 0.8],
        plane: Plane::XZ,
        diagonals: Diagonals::Alternating,
        center: Pt3::new(0.0, 2.0, 0.0),
    })?)
}

/// Top-face rotation angle (rad) and vertical offset (m) of the box guide at time t (§6.2).
pub fn box_top_motion(t: f64) -> (f64, f64) {
    let a_max = 150f64.to_radians();
    let a = if t <= 2.0 {
        a_max * smoothstep(0.0, 1.0, t / 2.0)
    } else if t <= 2.5 {
        a_max
    } else if t <= 3.5 {
        a_max * (1.0 - smoothstep(0.0, 1.0, t - 2.5))
    } else {
        0.0
    };
    let y = if (3.5..=4.5).contains(&t) { -0.2 * (4.0 * std::f64::consts::PI * (t - 3.5)).sin() } else { 0.0 };
    (a, y)
}

/// The twisting box guide (§6.2): cube [−0.5,0.5]×[0,1]×[−0.5,0.5], bottom fixed, top face a
/// rigid copy rotated about +y through (0, 1, 0) and bobbed; still after 4.5 s (abrupt stop).
pub fn box_guide(duration: f64) -> Result<GuideAnimation> {
    let m = box_surface(Pt3::new(-0.5, 0.0, -0.5), Pt3::new(0.5, 1.0, 0.5), [1, 1, 1], Diagonals::Alternating)?;
    let rest = m.positions.clone();
    let f: ProceduralFn = Arc::new(move |t: f64| {
        let (a, dy) = box_top_motion(t);
        let r = UnitQuat::from_axis_angle(&Vec3::y_axis(), a);
        rest.iter()
            .map(|p| {
                if p.y > 0.5 {
                    let c = Vec3::new(0.0, 1.0, 0.0);
                    Pt3::from(r * (p.coords - c) + c + Vec3::new(0.0, dy, 0.0))
                } else {
                    *p
                }
            })
            .collect()
    });
    GuideAnimation::procedural(m, f, duration)
}

/// The coarse sack of §6.3 (88 vertices, 158 triangles, open top): 16-gon rings of radius 0.2 m
/// at y = 0, 0.125, …, 0.5 and an inner octagon of radius 0.1 m at y = 0; faces outward.
pub fn bag_mesh() -> Result<TriMesh> {
    let tau = std::f64::consts::TAU;
    let mut p = Vec::new();
    for r in 0..5 {
        for k in 0..16 {
            let a = tau * k as f64 / 16.0;
            p.push(Pt3::new(0.2 * a.cos(), 0.125 * r as f64, 0.2 * a.sin()));
        }
    }
    for m in 0..8 {
        let a = tau * m as f64 / 8.0;
        p.push(Pt3::new(0.1 * a.cos(), 0.0, 0.1 * a.sin()));
    }
    let o = |r: usize, k: usize| (16 * r + k % 16) as u32;
    let i = |m: usize| (80 + m % 8) as u32;
    let mut f: Vec<[u32; 3]> = Vec::new();
    for r in 0..4 {
        for k in 0..16 {
            f.push([o(r, k), o(r + 1, k + 1), o(r, k + 1)]);
            f.push([o(r, k), o(r + 1, k), o(r + 1, k + 1)]);
        }
    }
    for m in 0..8 {
        f.push([i(m), o(0, 2 * m), o(0, 2 * m + 1)]);
        f.push([i(m), o(0, 2 * m + 1), i(m + 1)]);
        f.push([i(m + 1), o(0, 2 * m + 1), o(0, 2 * m + 2)]);
    }
    for k in 1..7 {
        f.push([i(0), i(k), i(k + 1)]);
    }
    // Orient outward: side faces away from the axis, bottom faces down.
    for t in f.iter_mut() {
        let [a, b, c] = t.map(|v| p[v as usize]);
        let n = (b - a).cross(&(c - a));
        let cen = (a.coords + b.coords + c.coords) / 3.0;
        let bottom = a.y == 0.0 && b.y == 0.0 && c.y == 0.0;
        let out = if bottom { Vec3::new(0.0, -1.0, 0.0) } else { Vec3::new(cen.x, 0.0, cen.z) };
        if n.dot(&out) < 0.0 {
            t.swap(1, 2);
        }
    }
    Ok(TriMesh::new(p, f)?)
}

/// Bag rig pose at time t (§6.3): (root scale (xz, y), root pitch (rad), centre offset, B1 pitch).
fn bag_pose(t: f64) -> (Vec3, f64, Vec3, f64) {
    let s = |a: f64, b: f64| smoothstep(a, b, t);
    let lerp = |a: f64, b: f64, u: f64| a + (b - a) * u;
    let d = f64::to_radians;
    let (scale, b1);
    let (mut pitch, mut centre) = (0.0, Vec3::zeros());
    if t < 0.4 {
        let u = s(0.0, 0.4);
        scale = Vec3::new(lerp(1.0, 1.25, u), lerp(1.0, 0.6, u), lerp(1.0, 1.25, u));
        b1 = d(35.0) * u;
    } else if t < 0.6 {
        let u = s(0.4, 0.6);
        scale = Vec3::new(lerp(1.25, 0.9, u), lerp(0.6, 1.15, u), lerp(1.25, 0.9, u));
        b1 = lerp(d(35.0), d(-15.0), u);
    } else if t < 1.4 {
        let tau = t - 0.6;
        centre = Vec3::new(0.0, 3.92 * tau - 0.5 * 9.81 * tau * tau, -0.5 * tau / 0.8);
        pitch = -std::f64::consts::TAU * s(0.6, 1.4);
        scale = Vec3::new(0.9, 1.15, 0.9);
        b1 = d(-15.0);
    } else {
        // Landing at 1.4 s: instantaneous stop, squash and whip, recover 1.5–2.2 s.
        centre = Vec3::new(0.0, 0.0, -0.5);
        let squash = s(1.4, 1.48);
        let whip = s(1.4, 1.5);
        let rec = s(1.5, 2.2);
        let sy = lerp(lerp(1.15, 0.55, squash), 1.0, rec);
        let sxz = lerp(lerp(0.9, 1.2, squash), 1.0, rec);
        scale = Vec3::new(sxz, sy, sxz);
        b1 = lerp(lerp(d(-15.0), d(50.0), whip), 0.0, rec);
    }
    (scale, pitch, centre, b1)
}

/// B1 pitch gain of the bag rig used by the scenes (spec §6.3: raised when the guide would
/// not self-intersect; see the test `bag_guide_self_intersects`).
pub const BAG_B1_GAIN: f64 = 2.0;

/// The bag guide (§6.3): two-bone linear blend skinning (B0 root at the bottom centre, B1 at
/// y = 0.25, w₁ = smoothstep(0.15, 0.35, y_rest)) playing the crouch / backflip / landing clip.
/// `b1_gain` scales the B1 pitch (the spec raises it when the guide does not self-intersect).
pub fn bag_guide(duration: f64, b1_gain: f64) -> Result<GuideAnimation> {
    let m = bag_mesh()?;
    let rest = m.positions.clone();
    let f: ProceduralFn = Arc::new(move |t: f64| {
        let (scale, pitch, centre, b1) = bag_pose(t);
        let mid = Vec3::new(0.0, 0.25, 0.0);
        let rp = UnitQuat::from_axis_angle(&Vec3::x_axis(), pitch);
        let r1 = UnitQuat::from_axis_angle(&Vec3::x_axis(), b1 * b1_gain);
        rest.iter()
            .map(|x| {
                let w1 = smoothstep(0.15, 0.35, x.y);
                // B1 bends the upper part about the joint at y = 0.25 (rest space).
                let x1 = r1 * (x.coords - mid) + mid;
                let local = (1.0 - w1) * x.coords + w1 * x1;
                let scaled = Vec3::new(local.x * scale.x, local.y * scale.y, local.z * scale.z);
                let ms = Vec3::new(0.0, 0.25 * scale.y, 0.0);
                Pt3::from(rp * (scaled - ms) + ms + centre)
            })
            .collect()
    });
    GuideAnimation::procedural(m, f, duration)
}

/// Radius factor r(t)/0.5 = 1 + 0.25 sin ϑ(t) of the pulsating sphere, ϑ = 2π∫f with f = 0.1 Hz on
/// [0, 2) s and 4 Hz afterwards.
pub fn sphere_scale(t: f64) -> f64 {
    let th = std::f64::consts::TAU * (0.1 * t.min(2.0) + 4.0 * (t - 2.0).max(0.0));
    1.0 + 0.25 * th.sin()
}

/// The pulsating sphere of Fig. 4 (§6.6): icosphere level 1 (42 vertices), radius
/// r(t) = 0.5(1 + 0.25 sin ϑ(t)), ϑ = 2π∫f, f = 0.1 Hz on [0, 2) s and 4 Hz afterwards.
pub fn pulsating_sphere(duration: f64) -> Result<GuideAnimation> {
    let m = icosphere(0.5, 1)?;
    let rest = m.positions.clone();
    let f: ProceduralFn = Arc::new(move |t: f64| {
        let s = sphere_scale(t);
        rest.iter().map(|p| Pt3::from(p.coords * s)).collect()
    });
    GuideAnimation::procedural(m, f, duration)
}

/// The Xavier stand-in (§6.4): mesh, per-vertex skinning data and the procedural clip.
#[derive(Clone, Debug)]
pub struct Xavier {
    /// The 3038-vertex X-shaped closed surface (rest pose, lowest vertex at y = 0).
    pub mesh: TriMesh,
    /// Per vertex: (limb index 0..4, limb membership weights) — limb L at angle 45° + 90°·L.
    pub membership: Vec<[f64; 4]>,
    /// Per vertex: radial limb coordinate s = ρR(φ)/1.27 (rest parameters, before smoothing).
    pub s: Vec<f64>,
    /// Minimum triangle angle (degrees) and max/min edge-length ratio of the mesh.
    pub quality: (f64, f64),
}

impl Xavier {
    /// Per vertex, the largest linear-blend-skinning weight of the rig of [`xavier_guide`] (root,
    /// and an upper and a lower bone per limb): < 0.8 near a joint (Fig. 7's seam–joint
    /// alignment).
    pub fn max_skin_weight(&self) -> Vec<f64> {
        self.membership
            .iter()
            .zip(&self.s)
            .map(|(mb, &s)| {
                let root = 1.0 - smoothstep(0.25, 0.4, s);
                let up = smoothstep(0.25, 0.4, s) * (1.0 - smoothstep(0.55, 0.7, s));
                let lo = smoothstep(0.55, 0.7, s);
                mb.iter().flat_map(|w| [w * up, w * lo]).fold(root, f64::max)
            })
            .collect()
    }
}

/// Xavier's cloth (`tracks/xavier`, spec §6.4): 0.2 kg/m², Et = 3000 N/m, ν = 0.3, k_B = 2e-5 J,
/// stiffness-proportional damping β = 5e-4 s.
pub fn xavier_material() -> shells::Material {
    shells::Material {
        density: 0.2,
        membrane: shells::MembraneLaw::Isotropic { young_thickness: 3000.0, poisson: 0.3, compression_softening: None },
        bending: 2e-5,
        damping: shells::Damping::Rayleigh { alpha: 0.0, beta: 5e-4 },
        plasticity: None,
    }
}

/// Xavier's cloth as a plain `shells` simulation in [`xavier_material`] with gravity only (no
/// contact, no wind), starting on the guide's first frame: the untracked system of the solver
/// benchmarks (`benches/tracking.rs`, `examples/kkt_orderings.rs`).
pub fn xavier_sim(x: &Xavier, guide: &GuideAnimation) -> shells::Result<shells::ShellSim> {
    let mut g0 = vec![Pt3::origin(); guide.n_vertices()];
    guide.sample(0.0, &mut g0);
    shells::ShellSim::new(shells::ShellSceneDesc {
        rest: x.mesh.positions.clone(),
        faces: x.mesh.faces.clone(),
        uv: None,
        initial: Some(g0),
        initial_velocity: None,
        material: xavier_material(),
        effects: shells::Effects { gravity: Some(Vec3::new(0.0, -9.81, 0.0)), ..shells::Effects::default() },
        constraints: vec![],
        integrator: shells::IntegratorSettings::default(),
        t0: 0.0,
    })
}

/// Builds the Xavier mesh and its rig data (spec §6.4): box surface 31 × 36 × 6 segments mapped
/// to an X by ρ = max(|u|,|w|), φ = atan2(w, u), R(φ) = 0.50 + 0.77 sin²(2φ), then 10 Taubin
/// passes (λ = 0.5, μ = −0.53).
pub fn xavier() -> Result<Xavier> {
    let b = box_surface(Pt3::new(-1.0, -1.0, -1.0), Pt3::new(1.0, 1.0, 1.0), [31, 36, 6], Diagonals::Alternating)?;
    let mut p = b.positions.clone();
    let mut membership = Vec::with_capacity(p.len());
    let mut s_all = Vec::with_capacity(p.len());
    for q in p.iter_mut() {
        let (u, w, d) = (q.x, q.y, q.z);
        let rho = u.abs().max(w.abs());
        let phi = w.atan2(u);
        let s2 = (2.0 * phi).sin().powi(2);
        let r = 0.50 + 0.77 * s2;
        *q = Pt3::new(rho * r * phi.cos(), rho * r * phi.sin(), d * 0.10 * (1.0 - 0.5 * rho * s2));
        let mut m = [0.0; 4];
        for (l, ml) in m.iter_mut().enumerate() {
            let pl = (45.0 + 90.0 * l as f64).to_radians();
            *ml = (phi - pl).cos().max(0.0).powi(8);
        }
        let tot: f64 = m.iter().sum();
        if tot > 0.0 {
            m.iter_mut().for_each(|x| *x /= tot);
        } else {
            m = [0.25; 4];
        }
        membership.push(m);
        s_all.push(rho * r / 1.27);
    }
    let topo = b.topology().clone();
    taubin_smooth(&topo, &mut p, 10, 0.5, -0.53, SmoothWeight::Uniform, None);
    let ymin = p.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
    p.iter_mut().for_each(|q| q.y -= ymin);
    let mesh = TriMesh::new(p, b.faces.clone())?;
    // Quality: min angle and edge ratio.
    let (mut amin, mut emin, mut emax) = (180.0f64, f64::INFINITY, 0.0f64);
    for f in &mesh.faces {
        let x = f.map(|v| mesh.positions[v as usize]);
        for k in 0..3 {
            let (a, bb, c) = (x[k], x[(k + 1) % 3], x[(k + 2) % 3]);
            let (e1, e2) = (bb - a, c - a);
            let ang = e1.angle(&e2).to_degrees();
            amin = amin.min(ang);
            emin = emin.min(e1.norm());
            emax = emax.max(e1.norm());
        }
    }
    Ok(Xavier { mesh, membership, s: s_all, quality: (amin, emax / emin) })
}

/// Joint angles of the Xavier clip at time t (§6.4): per limb (in-plane swing of the upper bone,
/// out-of-plane bend of the lower bone) in radians, root travel along x (m), bob (m), lean (rad).
fn xavier_pose(t: f64) -> ([(f64, f64); 4], f64, f64, f64) {
    let d = f64::to_radians;
    let tau = std::f64::consts::TAU;
    let mut limbs = [(0.0, 0.0); 4];
    let walk_phase = tau * t; // 1 Hz
    let travel;
    let (mut bob, mut lean) = (0.0, 0.0);
    let walk = |limbs: &mut [(f64, f64); 4], amp_leg: f64, amp_arm: f64| {
        // Limbs 0, 1 are arms (45°, 135°), 2, 3 legs (225°, 315°); legs in antiphase.
        limbs[2] = (amp_leg * walk_phase.sin(), d(35.0) * walk_phase.sin().max(0.0));
        limbs[3] = (-amp_leg * walk_phase.sin(), d(35.0) * (-walk_phase.sin()).max(0.0));
        limbs[0] = (-amp_arm * walk_phase.sin(), 0.0);
        limbs[1] = (amp_arm * walk_phase.sin(), 0.0);
    };
    if t < 4.0 {
        walk(&mut limbs, d(20.0), d(15.0));
        travel = 0.8 * t;
        bob = 0.03 * (2.0 * walk_phase).sin().abs();
    } else if t < 7.0 {
        walk(&mut limbs, d(12.0), d(6.0));
        let raise = d(25.0) * smoothstep(4.0, 4.5, t);
        limbs[0].0 -= raise;
        limbs[1].0 += raise;
        travel = 3.2 + 0.3 * (t - 4.0);
        bob = 0.015 * (2.0 * walk_phase).sin().abs();
        lean = d(12.0) * smoothstep(4.0, 4.5, t) * (1.0 - smoothstep(6.5, 7.0, t));
    } else {
        travel = 4.1;
        let (amp, f) = if t < 8.5 {
            (d(8.0), 12.0)
        } else if t < 9.0 {
            (d(20.0), 3.0)
        } else {
            (0.0, 0.0)
        };
        for (l, lb) in limbs.iter_mut().enumerate() {
            let ph = 1.3 * l as f64;
            *lb = (amp * (tau * f * t + ph).sin(), amp * (tau * f * t + 2.0 * ph).cos());
        }
    }
    (limbs, travel, bob, lean)
}

/// The Xavier guide (§6.4): linear blend skinning with a root and an upper and lower bone per
/// limb (split at 0.65 of the limb length), weights from limb membership and radial position,
/// each frame shifted vertically so the lowest vertex touches y = 0.
pub fn xavier_guide(x: &Xavier, duration: f64) -> Result<GuideAnimation> {
    let rest = x.mesh.positions.clone();
    let centre = {
        let c = rest.iter().fold(Vec3::zeros(), |a, p| a + p.coords) / rest.len() as f64;
        Pt3::from(Vec3::new(c.x, c.y, 0.0))
    };
    let weights: Vec<(f64, [f64; 4], [f64; 4])> = x
        .membership
        .iter()
        .zip(&x.s)
        .map(|(m, &s)| {
            let up = smoothstep(0.25, 0.4, s) * (1.0 - smoothstep(0.55, 0.7, s));
            let lo = smoothstep(0.55, 0.7, s);
            (1.0 - smoothstep(0.25, 0.4, s), m.map(|w| w * up), m.map(|w| w * lo))
        })
        .collect();
    let f: ProceduralFn = Arc::new(move |t: f64| {
        let (limbs, travel, bob, lean) = xavier_pose(t);
        let root_r: Mat3 = UnitQuat::from_axis_angle(&Vec3::x_axis(), -lean).to_rotation_matrix().into_inner();
        // Per limb: the upper joint at 0.32·1.27 m and the lower at 0.65·1.27 m along the limb.
        let mut up_t = [(Mat3::identity(), Vec3::zeros()); 4];
        let mut lo_t = [(Mat3::identity(), Vec3::zeros()); 4];
        for l in 0..4 {
            let pl = (45.0 + 90.0 * l as f64).to_radians();
            let dir = Vec3::new(pl.cos(), pl.sin(), 0.0);
            let j1 = centre.coords + 0.32 * 1.27 * dir;
            let j2 = centre.coords + 0.65 * 1.27 * dir;
            let r1: Mat3 = UnitQuat::from_axis_angle(&Vec3::z_axis(), limbs[l].0).to_rotation_matrix().into_inner();
            let perp = nalgebra::Unit::new_normalize(Vec3::new(-pl.sin(), pl.cos(), 0.0));
            let r2: Mat3 = UnitQuat::from_axis_angle(&perp, limbs[l].1).to_rotation_matrix().into_inner();
            // x ↦ R1 (x − j1) + j1 ; lower: x ↦ R1 (R2 (x − j2) + j2 − j1) + j1.
            up_t[l] = (r1, j1 - r1 * j1);
            lo_t[l] = (r1 * r2, r1 * (j2 - r2 * j2 - j1) + j1);
        }
        let mut out: Vec<Pt3> = rest
            .iter()
            .zip(&weights)
            .map(|(p, (wr, wu, wl))| {
                let mut v = *wr * p.coords;
                for l in 0..4 {
                    v += wu[l] * (up_t[l].0 * p.coords + up_t[l].1) + wl[l] * (lo_t[l].0 * p.coords + lo_t[l].1);
                }
                Pt3::from(root_r * (v - centre.coords) + centre.coords + Vec3::new(travel, bob, 0.0))
            })
            .collect();
        let ymin = out.iter().map(|q| q.y).fold(f64::INFINITY, f64::min);
        out.iter_mut().for_each(|q| q.y -= ymin);
        out
    });
    GuideAnimation::procedural(x.mesh.clone(), f, duration)
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::mesh::subdivide_linear;

    /// §6.3: the bag reproduces 88 → 1297 vertices; §6.4: Xavier has 3038 vertices, 6072
    /// triangles and the asserted quality (min angle ≥ 7°, edge ratio ≤ 10).
    #[test]
    fn scene_mesh_sizes() {
        let b = bag_mesh().expect("bag");
        assert_eq!((b.n_vertices(), b.n_faces()), (88, 158));
        assert_eq!(subdivide_linear(&b, 2).0.n_vertices(), 1297);
        let x = xavier().expect("xavier");
        assert_eq!((x.mesh.n_vertices(), x.mesh.n_faces()), (3038, 6072));
        assert!(x.quality.0 >= 7.0 && x.quality.1 <= 10.0, "quality {:?}", x.quality);
        let f = flag_coarse().expect("flag");
        assert_eq!(subdivide_linear(&f, 3).0.n_vertices(), 1617);
        let bx = box_guide(6.0).expect("box");
        assert_eq!(subdivide_linear(&bx.rest, 4).0.n_vertices(), 1538);
    }

    /// The box top is a rigid copy: edge lengths of the top face are preserved at any time.
    #[test]
    fn box_top_is_rigid() {
        let g = box_guide(6.0).expect("box");
        let mut p = vec![Pt3::origin(); 8];
        let top: Vec<usize> = (0..8).filter(|&i| g.rest.positions[i].y > 0.5).collect();
        for t in [0.3, 1.7, 2.2, 3.0, 3.9, 4.4, 5.0] {
            g.sample(t, &mut p);
            for &a in &top {
                for &b in &top {
                    let d0 = (g.rest.positions[a] - g.rest.positions[b]).norm();
                    assert!(((p[a] - p[b]).norm() - d0).abs() < 1e-12);
                }
            }
        }
        // Abrupt stop at 4.5 s while moving at ≈ 2.5 m/s.
        let (_, y1) = box_top_motion(4.5 - 1e-4);
        assert!((y1 / 1e-4).abs() > 2.0);
    }
}

#[cfg(test)]
mod bag_tests {
    use super::*;

    /// §6.3: the naive rig must self-intersect during crouch or landing (counted on 61 frames).
    #[test]
    fn bag_guide_self_intersects() {
        let g = bag_guide(3.0, BAG_B1_GAIN).expect("bag");
        let mut p = vec![Pt3::origin(); g.n_vertices()];
        let mut hits = Vec::new();
        for k in 0..=60 {
            let t = k as f64 * 0.05;
            g.sample(t, &mut p);
            let n = shells::collision::count_self_intersections(&p, &g.rest.faces);
            if n > 0 {
                hits.push((t, n));
            }
        }
        assert!(!hits.is_empty(), "guide never self-intersects");
    }
}
