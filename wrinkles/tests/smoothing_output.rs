//! Smoothing and output tests: T13 (cross-edge continuity), T14 (locality), T15 (temporal
//! Lipschitz), T17 (displaced mesh), T18 (area-consistent smoothing), bump normals.

mod common;

use std::collections::HashMap;

use common::*;
use geom_core::math::{Mat2, Pt3, Vec2};
use wrinkles::*;

fn bend(mesh: &RestMesh) -> Vec<Pt3> {
    // Non-uniform compression: x squeezed more at the top, a mild out-of-plane bulge.
    mesh.positions.iter().map(|p| Pt3::new(p.x * (1.0 - 0.8 * p.y), p.y, 0.05 * (p.x * 6.0).sin() * p.y)).collect()
}

/// T13: with VertexAverage, D evaluated from both triangles at 5 points on every shared edge
/// agrees (1e-12 m relative to max|D|); with PerTriangle it jumps under non-uniform strain.
#[test]
fn t13_cross_edge_continuity() {
    let mesh = grid_mesh(5, 0.25);
    let rig =
        precompute(&mesh, &[sinusoid(0.04, 10.0, 0.7), sinusoid(0.04, 100.0, 0.7)], &PrecomputeOptions::default())
            .unwrap();
    let def = bend(&mesh);
    let mut jumps = [0.0f64; 2];
    for (k, sm) in
        [Smoothing::VertexAverage { weights: VertexWeights::Area }, Smoothing::PerTriangle].into_iter().enumerate()
    {
        let mut a =
            WrinkleAnimator::new(rig.clone(), ModulationOptions { smoothing: sm, ..Default::default() }).unwrap();
        let fm = a.frame(&def).unwrap();
        let mut by_edge: HashMap<[u32; 2], Vec<(usize, usize, usize)>> = HashMap::new();
        for (t, f) in mesh.faces.iter().enumerate() {
            for c in 0..3 {
                let (u, v) = (f[c], f[(c + 1) % 3]);
                by_edge.entry([u.min(v), u.max(v)]).or_default().push((t, c, (c + 1) % 3));
            }
        }
        let mut dmax: f64 = 0.0;
        for (e, sides) in &by_edge {
            if sides.len() != 2 {
                continue;
            }
            for s in 1..=5 {
                let x = s as f64 / 6.0; // fraction from e[0] to e[1]
                let d: Vec<f64> = sides
                    .iter()
                    .map(|&(t, c0, c1)| {
                        let mut b = [0.0; 3];
                        let (ca, cb) = if mesh.faces[t][c0] == e[0] { (c0, c1) } else { (c1, c0) };
                        b[ca] = 1.0 - x;
                        b[cb] = x;
                        a.displacement(&fm, t, b)
                    })
                    .collect();
                dmax = dmax.max(d[0].abs());
                jumps[k] = jumps[k].max((d[0] - d[1]).abs());
            }
        }
        assert!(dmax > 0.0);
        if k == 0 {
            assert!(jumps[0] <= 1e-12 * dmax, "vertex average jump {}", jumps[0]);
        } else {
            assert!(jumps[1] > 1e-3 * dmax, "per-triangle should be patchy: {}", jumps[1]);
        }
    }
}

/// T14: a deformed patch leaves every vertex outside it at the identity modulation exactly.
#[test]
fn t14_locality() {
    let mesh = grid_mesh(6, 0.3);
    let rig = precompute(&mesh, &[sinusoid(0.04, 0.0, 0.7)], &PrecomputeOptions::default()).unwrap();
    let mut def = mesh.positions.clone();
    let moved = [8usize, 9, 15, 16]; // interior vertices of the 7 × 7 vertex grid
    for &v in &moved {
        def[v].x -= 0.01;
    }
    let mut touched = vec![false; def.len()];
    for f in &mesh.faces {
        if f.iter().any(|v| moved.contains(&(*v as usize))) {
            f.iter().for_each(|v| touched[*v as usize] = true);
        }
    }
    for mode in [ModulationMode::ExactFlatRest, ModulationMode::PrincipalLength] {
        let mut a = WrinkleAnimator::new(rig.clone(), ModulationOptions { mode, ..Default::default() }).unwrap();
        let fm = a.frame(&def).unwrap();
        let mut any = false;
        for (v, &tv) in touched.iter().enumerate() {
            if !tv {
                assert_eq!(fm.vertex_mod[v], 0.0, "{mode:?} vertex {v}");
            } else {
                any |= fm.vertex_mod[v] != 0.0;
            }
        }
        assert!(any, "the deformed patch must wrinkle");
    }
}

/// T15: compression direction rotating 90° in 2 s, two orthogonal patterns: halving the frame
/// interval halves max per-frame |ΔD| for n = 4 (ratio 2 ± 0.2); for n = ∞ it stays ≈ 1.
#[test]
fn t15_temporal_lipschitz() {
    let mesh = two_triangle_square(0.1);
    let rig = precompute(&mesh, &[sinusoid(0.0125, 0.0, 1.0), sinusoid(0.0125, 90.0, 1.0)], &exact_opts(1e-5)).unwrap();
    let probe = [(0usize, [0.3, 0.3, 0.4]), (1, [0.2, 0.5, 0.3])];
    let run = |fps: f64, power: f64| {
        let o = ModulationOptions {
            mode: ModulationMode::Linearized { strain: StrainMeasure::Green },
            blend: BlendOptions { variance: 0.15, power },
            h_max: HMax::Fixed(10.0),
            ..Default::default()
        };
        let mut a = WrinkleAnimator::new(rig.clone(), o).unwrap();
        let n = (2.0 * fps) as usize;
        let mut prev: Option<Vec<f64>> = None;
        let mut max_d: f64 = 0.0;
        for k in 0..=n {
            let th = std::f64::consts::FRAC_PI_2 * k as f64 / n as f64;
            let r = Mat2::new(th.cos(), -th.sin(), th.sin(), th.cos());
            let f = r * Mat2::new(0.92, 0.0, 0.0, 1.0) * r.transpose();
            let fm = a.frame(&deform(&mesh, &f)).unwrap();
            let d: Vec<f64> = probe.iter().map(|(t, b)| a.displacement(&fm, *t, *b)).collect();
            if let Some(p) = &prev {
                for (x, y) in d.iter().zip(p) {
                    max_d = max_d.max((x - y).abs());
                }
            }
            prev = Some(d);
        }
        max_d
    };
    let smooth = run(30.0, 4.0) / run(60.0, 4.0);
    assert!((smooth - 2.0).abs() < 0.2, "n = 4 ratio {smooth}");
    let pop = run(30.0, f64::INFINITY) / run(60.0, f64::INFINITY);
    assert!(pop < 1.3, "n = ∞ ratio {pop} (popping keeps the jump)");
}

/// T17: displaced mesh: V + E(L−1) + T(L−1)(L−2)/2 vertices, every edge in ≤ 2 faces, boundary
/// edges = coarse boundary × L; watertight under displacement (a valid geom-core TriMesh).
#[test]
fn t17_displaced_mesh_topology() {
    let mesh = grid_mesh(3, 0.15);
    let rig = precompute(&mesh, &[sinusoid(0.03, 20.0, 0.6)], &PrecomputeOptions::default()).unwrap();
    let (nv, nt, ne) = (mesh.positions.len(), mesh.faces.len(), rig.edges.len());
    let def = bend(&mesh);
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fm = a.frame(&def).unwrap();
    let coarse_boundary = 4 * 3;
    for l in [1u32, 2, 3, 6] {
        let dm = a.displaced_mesh(&def, &fm, l).unwrap();
        let l = l as usize;
        assert_eq!(dm.positions.len(), nv + ne * (l - 1) + nt * (l - 1) * l.saturating_sub(2) / 2);
        assert_eq!(dm.faces.len(), nt * l * l);
        let mut count: HashMap<[u32; 2], usize> = HashMap::new();
        for f in &dm.faces {
            for k in 0..3 {
                let (u, v) = (f[k], f[(k + 1) % 3]);
                *count.entry([u.min(v), u.max(v)]).or_default() += 1;
            }
        }
        assert!(count.values().all(|c| *c <= 2));
        assert_eq!(count.values().filter(|c| **c == 1).count(), coarse_boundary * l);
        let tm = dm.into_trimesh().unwrap();
        assert_eq!(tm.topology().n_boundary_edges(), coarse_boundary * l);
    }
}

/// Mean per-triangle linearised area residual |Σ_k C4_k y_k − C4 h_t| / C4 of the vertex values.
fn lin_residual(rig: &WrinkleRig, fm: &FrameModulation) -> f64 {
    let mut s = 0.0;
    for (t, f) in rig.mesh.faces.iter().enumerate() {
        let c = rig.coeff(t, 0);
        let r: f64 = (0..3).map(|k| c.c4_vertex[k] * fm.vertex_mod[f[k] as usize]).sum::<f64>() - c.c4 * fm.tri_h[t];
        s += r.abs() / c.c4;
    }
    s / rig.mesh.faces.len() as f64
}

/// T18: AreaConsistent smoothing: mean linearised residual ≥ 3× smaller than VertexAverage on a
/// non-uniform strain field; the matrix is factorised exactly once over 10 frames.
#[test]
fn t18_area_consistent() {
    let mesh = grid_mesh(6, 0.3);
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.8)], &PrecomputeOptions::default()).unwrap();
    let mean_c4 = rig.coeffs.iter().map(|c| c.c4).sum::<f64>() / rig.coeffs.len() as f64;
    let lin = ModulationMode::Linearized { strain: StrainMeasure::Green };
    let mut va = WrinkleAnimator::new(
        rig.clone(),
        ModulationOptions { mode: lin, h_max: HMax::Fixed(100.0), ..Default::default() },
    )
    .unwrap();
    let mut ac = WrinkleAnimator::new(
        rig.clone(),
        ModulationOptions {
            mode: lin,
            h_max: HMax::Fixed(100.0),
            smoothing: Smoothing::AreaConsistent { mu: 1e-3 * mean_c4 },
            ..Default::default()
        },
    )
    .unwrap();
    for k in 0..10 {
        let s = 0.02 * k as f64;
        let def: Vec<Pt3> =
            mesh.positions.iter().map(|p| Pt3::new(p.x * (1.0 - (0.1 + s) * p.y / 0.3), p.y, 0.0)).collect();
        let (fa, fb) = (va.frame(&def).unwrap(), ac.frame(&def).unwrap());
        let (ra, rb) = (lin_residual(&rig, &fa), lin_residual(&rig, &fb));
        assert!(rb * 3.0 <= ra, "frame {k}: LSQ {rb:e} vs average {ra:e}");
    }
    assert_eq!(ac.n_factorizations(), 1);
}

/// Bump normals: unit, finite, equal to the geometric normal of the displaced surface
/// (finite-difference tangent check on a flat compressed sheet).
#[test]
fn bump_normal_matches_displaced_surface() {
    let mesh = two_triangle_square(0.1);
    let rig = precompute(&mesh, &[sinusoid(0.025, 30.0, 0.8)], &PrecomputeOptions::default()).unwrap();
    let f = Mat2::new(0.85, 0.05, 0.0, 0.97);
    let def = deform(&mesh, &f);
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fm = a.frame(&def).unwrap();
    let rf = a.rig().frames[0].clone();
    let b = [0.3, 0.3, 0.4];
    let n = a.bump_normal(&def, &fm, 0, b);
    assert!((n.norm() - 1.0).abs() < 1e-12);
    // Surface X(x) = p(x) + D(x)·ẑ; tangents by central differences along local axes.
    let face = mesh.faces[0];
    let pos = |x: Vec2| {
        let lam12 = rf.dm_inv * x;
        let bb = [1.0 - lam12.x - lam12.y, lam12.x, lam12.y];
        let p: Vec<f64> = (0..3).map(|c| (0..3).map(|k| bb[k] * def[face[k] as usize][c]).sum()).collect();
        Pt3::new(p[0], p[1], p[2] + a.displacement(&fm, 0, bb))
    };
    let x0 = rf.dm * Vec2::new(b[1], b[2]);
    let h = 1e-7;
    let t1 = pos(x0 + Vec2::new(h, 0.0)) - pos(x0 - Vec2::new(h, 0.0));
    let t2 = pos(x0 + Vec2::new(0.0, h)) - pos(x0 - Vec2::new(0.0, h));
    let ng = t1.cross(&t2).normalize();
    assert!((ng - n).norm() < 1e-6, "{ng} vs {n}");
}

/// The baked modulation map holds the transformed, interpolated modulation (values within the
/// vertex range, covering the UV square); bad requests are errors.
#[test]
fn modulation_map_bake() {
    let mesh = grid_mesh(4, 0.2);
    let rig = precompute(&mesh, &[sinusoid(0.04, 0.0, 0.7)], &PrecomputeOptions::default()).unwrap();
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fm = a.frame(&bend(&mesh)).unwrap();
    let img = a.bake_modulation_map(&fm, 0, 64, 64).unwrap();
    let (lo, hi) = fm.vertex_mod.iter().fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(*v), h.max(*v)));
    assert!(hi > 0.0);
    for v in &img.data {
        let v = *v as f64;
        assert!(v >= lo - 1e-6 && v <= hi + 1e-6, "{v} outside [{lo}, {hi}]");
    }
    // Interior pixels are covered and vary (not all background).
    let max_px = img.data.iter().fold(0.0f32, |m, v| m.max(*v)) as f64;
    assert!(max_px > 0.5 * hi);
    assert!(matches!(a.bake_modulation_map(&fm, 3, 64, 64), Err(WrinkleError::InvalidOption(_))));
    assert!(matches!(a.bake_modulation_map(&fm, 0, 0, 64), Err(WrinkleError::InvalidOption(_))));
}
