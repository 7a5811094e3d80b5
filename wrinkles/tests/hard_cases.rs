//! Stress test of the hard cases of spec §8: every case must give finite output or a clear
//! error, never a panic or NaN.

mod common;

use common::*;
use geom_core::math::{Mat2, Pt2, Pt3};
use geom_core::mesh::Uv;
use wrinkles::*;

fn all_finite(fm: &FrameModulation) -> bool {
    fm.tri_h
        .iter()
        .chain(&fm.tri_mf_lin)
        .chain(&fm.tri_weight)
        .chain(&fm.vertex_mod)
        .chain(&fm.vertex_weight)
        .all(|v| v.is_finite())
        && fm.vertex_normals.iter().all(|n| n.iter().all(|c| c.is_finite()))
}

#[test]
fn empty_mesh_and_no_patterns() {
    let empty = RestMesh::new(vec![], vec![], Uv::PerVertex(vec![])).unwrap();
    let rig = precompute(&empty, &[sinusoid(0.1, 0.0, 0.5)], &PrecomputeOptions::default()).unwrap();
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fm = a.frame(&[]).unwrap();
    assert!(fm.tri_h.is_empty() && fm.vertex_mod.is_empty());
    assert!(a.displaced_mesh(&[], &fm, 4).unwrap().positions.is_empty());

    let mesh = grid_mesh(2, 0.1);
    let rig = precompute(&mesh, &[], &PrecomputeOptions::default()).unwrap();
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fm = a.frame(&mesh.positions).unwrap();
    assert!(fm.tri_h.is_empty());
    assert_eq!(a.displacement(&fm, 0, [0.2, 0.3, 0.5]), 0.0);
    let dm = a.displaced_mesh(&mesh.positions, &fm, 3).unwrap();
    for (p, q) in dm.positions.iter().zip(&mesh.positions) {
        assert_eq!(p, q); // coarse vertices first, undisplaced
    }
}

#[test]
fn topology_mismatch_and_non_finite_input() {
    let mesh = grid_mesh(2, 0.1);
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.5)], &PrecomputeOptions::default()).unwrap();
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let err = a.frame(&mesh.positions[1..]).unwrap_err();
    assert!(matches!(err, WrinkleError::TopologyMismatch { expected: 9, got: 8 }), "{err}");
    let mut bad = mesh.positions.clone();
    bad[4].y = f64::NAN;
    assert!(matches!(a.frame(&bad), Err(WrinkleError::NonFinitePosition { vertex: 4 })));
    bad[4].y = f64::INFINITY;
    assert!(matches!(a.frame(&bad), Err(WrinkleError::NonFinitePosition { vertex: 4 })));
    // Bad rest input.
    let uv = Uv::PerVertex(vec![Pt2::origin(); 3]);
    assert!(matches!(
        RestMesh::new(vec![Pt3::origin(); 3], vec![[0, 1, 5]], uv.clone()),
        Err(WrinkleError::BadFace { face: 0, index: 5, .. })
    ));
    let m = geom_core::procedural::grid(&Default::default()).unwrap();
    let no_uv = geom_core::mesh::TriMesh::new(m.positions.clone(), m.faces.clone()).unwrap();
    assert!(matches!(RestMesh::from_trimesh(&no_uv), Err(WrinkleError::MissingUv)));
    // Bad options.
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.5)], &PrecomputeOptions::default()).unwrap();
    for o in [
        ModulationOptions { h_max: HMax::Fixed(-1.0), ..Default::default() },
        ModulationOptions { temporal_alpha: 0.0, ..Default::default() },
        ModulationOptions { blend: BlendOptions { variance: -0.1, power: 4.0 }, ..Default::default() },
        ModulationOptions { blend: BlendOptions { variance: 0.1, power: 0.5 }, ..Default::default() },
    ] {
        assert!(matches!(WrinkleAnimator::new(rig.clone(), o), Err(WrinkleError::InvalidOption(_))));
    }
    assert!(matches!(
        precompute(&mesh, &[], &PrecomputeOptions { tolerance: 0.0, ..Default::default() }),
        Err(WrinkleError::InvalidOption(_))
    ));
}

/// Zero-area rest triangle: `DegenerateRest`, excluded from averaging; neighbours unaffected.
#[test]
fn degenerate_rest_triangle() {
    let mut mesh = grid_mesh(2, 0.1);
    // Append a zero-area sliver on the boundary using a new collinear vertex.
    let n = mesh.positions.len() as u32;
    mesh.positions.push(Pt3::new(0.025, 0.0, 0.0)); // on edge 0–1 (collinear with vertices 0, 1)
    let Uv::PerVertex(uv) = &mut mesh.uvs else { unreachable!() };
    uv.push(Pt2::new(0.025, 0.0));
    mesh.faces.push([0, 1, n]);
    let mesh = RestMesh::new(mesh.positions.clone(), mesh.faces.clone(), mesh.uvs.clone()).unwrap();
    let clean = grid_mesh(2, 0.1);
    let pats = [sinusoid(0.03, 0.0, 0.5)];
    let rig = precompute(&mesh, &pats, &PrecomputeOptions::default()).unwrap();
    let rig0 = precompute(&clean, &pats, &PrecomputeOptions::default()).unwrap();
    assert_eq!(rig.coeff(mesh.faces.len() - 1, 0).status, CoeffStatus::DegenerateRest);
    let f = Mat2::new(0.85, 0.0, 0.0, 1.0);
    let (d, d0) = (deform(&mesh, &f), deform(&clean, &f));
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let mut a0 = WrinkleAnimator::new(rig0, ModulationOptions::default()).unwrap();
    let (fm, fm0) = (a.frame(&d).unwrap(), a0.frame(&d0).unwrap());
    assert!(all_finite(&fm));
    assert_eq!(fm.diag.degenerate_rest, 1);
    for v in 0..clean.positions.len() {
        assert_eq!(fm.vertex_mod[v], fm0.vertex_mod[v], "vertex {v}");
    }
}

/// Collapsed (zero deformed area) and inverted triangles; extreme compression clipped at h_max;
/// extreme stretch gives 0 (flat modes) and a clipped-at-0 linear factor.
#[test]
fn collapsed_inverted_extreme() {
    let mesh = grid_mesh(3, 0.15);
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.8)], &PrecomputeOptions::default()).unwrap();
    let modes = [
        ModulationMode::Linearized { strain: StrainMeasure::Green },
        ModulationMode::Linearized { strain: StrainMeasure::PaperAbd },
        ModulationMode::ExactWrinkledRest,
        ModulationMode::ExactFlatRest,
        ModulationMode::PrincipalLength,
    ];
    // Vertex 10 = (2, 2) moved onto its boundary neighbour 11 = (3, 2): triangles holding both
    // collapse exactly. Vertex 5 = (1, 1) pushed past its right neighbour: part of its fan flips
    // while the surrounding vertex normals still point to +z.
    let dx = 0.05;
    let mut def = mesh.positions.clone();
    def[10] = def[11];
    def[5].x += 1.6 * dx;
    for mode in modes {
        let mut a = WrinkleAnimator::new(rig.clone(), ModulationOptions { mode, ..Default::default() }).unwrap();
        let fm = a.frame(&def).unwrap();
        assert!(all_finite(&fm), "{mode:?}");
        assert!(fm.diag.collapsed > 0 && fm.diag.inverted > 0, "{mode:?}: {:?}", fm.diag);
        let hm = a.h_max()[0];
        assert!(fm.tri_h.iter().all(|h| (0.0..=hm).contains(h)));
        let dm = a.displaced_mesh(&def, &fm, 4).unwrap();
        assert!(dm.positions.iter().all(|p| p.coords.iter().all(|c| c.is_finite())));
        for t in 0..mesh.faces.len() {
            let n = a.bump_normal(&def, &fm, t, [0.2, 0.3, 0.5]);
            assert!(n.iter().all(|c| c.is_finite()) && (n.norm() - 1.0).abs() < 1e-9);
        }
        // Extreme compression (c = 0.05): clipped at h_max, counted.
        let fm = a.frame(&deform(&mesh, &Mat2::new(0.05, 0.0, 0.0, 1.0))).unwrap();
        assert!(fm.tri_h.iter().all(|h| *h <= hm) && fm.diag.clipped > 0, "{mode:?} {:?} {hm}", fm.tri_h);
        // The unmet area is reported, not an error.
        let d = deform(&mesh, &Mat2::new(0.05, 0.0, 0.0, 1.0));
        let rep = a.area_report(&d, &fm, AreaCheck::PerTriangle).unwrap();
        assert!(rep.max_rel.is_finite() && rep.max_rel > 1e-3);
        // Extreme stretch (c = 3).
        let fm = a.frame(&deform(&mesh, &Mat2::new(3.0, 0.0, 0.0, 1.0))).unwrap();
        match mode {
            ModulationMode::ExactFlatRest | ModulationMode::PrincipalLength | ModulationMode::ExactWrinkledRest => {
                assert!(fm.tri_h.iter().all(|h| *h == 0.0))
            }
            _ => assert!(fm.tri_h.iter().all(|h| *h == 0.0) && fm.diag.clipped_zero == mesh.faces.len()),
        }
    }
}

/// Tiny η (slopes 1e-4): the linear mode's h is huge and clipped; the exact flat mode's
/// physical amplitude h·η does not depend on η. Huge slopes (s = 5): finite coefficients.
#[test]
fn tiny_and_huge_slopes() {
    let mesh = two_triangle_square(0.1);
    let f = Mat2::new(0.9, 0.0, 0.0, 1.0);
    let amp = |s: f64| {
        let rig = precompute(&mesh, &[sinusoid(0.0125, 0.0, s)], &exact_opts(1e-6)).unwrap();
        (h_of(&rig, ModulationMode::ExactFlatRest, &f, 0) * rig.eta[0], rig)
    };
    let (a_small, rig) = amp(1e-4);
    let (a_ref, _) = amp(0.5);
    assert!((a_small - a_ref).abs() < 1e-6 * a_ref, "{a_small} vs {a_ref}");
    let mut lin = WrinkleAnimator::new(
        rig,
        ModulationOptions { mode: ModulationMode::Linearized { strain: StrainMeasure::Green }, ..Default::default() },
    )
    .unwrap();
    let fm = lin.frame(&deform(&mesh, &f)).unwrap();
    assert!(fm.tri_mf_lin[0] > 1e6 && fm.tri_h[0] == lin.h_max()[0]);
    let (a_big, rig) = amp(5.0);
    assert!(a_big.is_finite() && rig.coeffs.iter().all(|c| c.k.iter().all(|v| v.is_finite()) && c.c4.is_finite()));
}

/// > 50 periods per triangle with a shallow depth cap: `Unconverged`, error estimate > 0, finite.
#[test]
fn very_high_frequency_pattern() {
    let mesh = two_triangle_square(0.1);
    let rig = precompute(
        &mesh,
        &[sinusoid(0.1 / 60.0, 17.0, 1.0)],
        &PrecomputeOptions { tolerance: 1e-6, max_depth: 3, gradient_bins: 72, gradient_samples: true },
    )
    .unwrap();
    for c in &rig.coeffs {
        assert_eq!(c.status, CoeffStatus::Unconverged);
        assert!(c.quad_error > 0.0 && c.c4.is_finite() && c.area_wrinkled.is_finite());
    }
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    assert!(all_finite(&a.frame(&deform(&mesh, &Mat2::new(0.8, 0.0, 0.0, 1.0))).unwrap()));
}

/// UV-degenerate triangle and constant pattern beside a valid one: weight goes to the valid one.
#[test]
fn degenerate_uv_and_constant_pattern_weights() {
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(0.1, 0.0, 0.0), Pt3::new(0.0, 0.1, 0.0)];
    let uv = Uv::PerVertex(vec![Pt2::new(0.0, 0.0), Pt2::new(0.1, 0.0), Pt2::new(0.2, 0.0)]);
    let mesh = RestMesh::new(p, vec![[0, 1, 2]], uv).unwrap();
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.5)], &PrecomputeOptions::default()).unwrap();
    assert_eq!(rig.coeff(0, 0).status, CoeffStatus::DegenerateUv);

    let mesh = two_triangle_square(0.1);
    let cst =
        WrinklePattern::new(&PatternSource::Procedural(Procedural::Constant { value: 1.0 }), PatternOptions::default())
            .unwrap();
    let rig = precompute(&mesh, &[cst, sinusoid(0.02, 0.0, 0.5)], &PrecomputeOptions::default()).unwrap();
    let mut a = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fm = a.frame(&deform(&mesh, &Mat2::new(0.9, 0.0, 0.0, 1.0))).unwrap();
    for t in 0..2 {
        assert_eq!((fm.tri_weight[2 * t], fm.tri_weight[2 * t + 1]), (0.0, 1.0));
    }
}

/// Singular LSQ system (μ = 0 and a vertex touching only a degenerate triangle) is reported at
/// construction.
#[test]
fn singular_smoothing_system() {
    let mut mesh = grid_mesh(2, 0.1);
    let n = mesh.positions.len() as u32;
    mesh.positions.push(Pt3::new(0.025, 0.0, 0.0));
    let Uv::PerVertex(uv) = &mut mesh.uvs else { unreachable!() };
    uv.push(Pt2::new(0.025, 0.0));
    mesh.faces.push([0, 1, n]);
    let mesh = RestMesh::new(mesh.positions.clone(), mesh.faces.clone(), mesh.uvs.clone()).unwrap();
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.5)], &PrecomputeOptions::default()).unwrap();
    let o = ModulationOptions { smoothing: Smoothing::AreaConsistent { mu: 0.0 }, ..Default::default() };
    let err = WrinkleAnimator::new(rig.clone(), o).unwrap_err();
    assert!(matches!(err, WrinkleError::SingularSmoothingSystem { pattern: 0, .. }), "{err}");
    // With μ > 0 the smoothness term makes it SPD.
    let o = ModulationOptions { smoothing: Smoothing::AreaConsistent { mu: 1e-6 }, ..Default::default() };
    let mut a = WrinkleAnimator::new(rig, o).unwrap();
    assert!(all_finite(&a.frame(&deform(&mesh, &Mat2::new(0.9, 0.0, 0.0, 1.0))).unwrap()));
}

/// Large frame jumps: output follows the input; the temporal filter is a convex combination
/// (bounded by the raw values), no blow-up over alternating extremes.
#[test]
fn large_frame_jumps_and_temporal_filter() {
    let mesh = grid_mesh(3, 0.15);
    let rig = precompute(&mesh, &[sinusoid(0.03, 0.0, 0.8)], &PrecomputeOptions::default()).unwrap();
    let mut a =
        WrinkleAnimator::new(rig.clone(), ModulationOptions { temporal_alpha: 0.3, ..Default::default() }).unwrap();
    let hm = a.h_max()[0];
    for k in 0..40 {
        let c = if k % 2 == 0 { 0.3 } else { 2.0 };
        let fm = a.frame(&deform(&mesh, &Mat2::new(c, 0.0, 0.0, 1.0))).unwrap();
        assert!(fm.vertex_mod.iter().all(|y| (0.0..=hm).contains(y)));
    }
    a.reset_temporal();
    let fm = a.frame(&deform(&mesh, &Mat2::new(0.8, 0.0, 0.0, 1.0))).unwrap();
    let mut raw = WrinkleAnimator::new(rig, ModulationOptions::default()).unwrap();
    let fr = raw.frame(&deform(&mesh, &Mat2::new(0.8, 0.0, 0.0, 1.0))).unwrap();
    assert_eq!(fm.vertex_mod, fr.vertex_mod); // after reset the first frame is unfiltered
}

/// Blend with δ → 0: all factors equal or v = 0 → ties split evenly, no NaN.
#[test]
fn blend_ties() {
    let mesh = two_triangle_square(0.1);
    let rig = precompute(&mesh, &[sinusoid(0.02, 0.0, 0.5), sinusoid(0.02, 0.0, 0.5)], &PrecomputeOptions::default())
        .unwrap();
    for v in [0.0, 0.03] {
        let mut a = WrinkleAnimator::new(
            rig.clone(),
            ModulationOptions { blend: BlendOptions { variance: v, power: 4.0 }, ..Default::default() },
        )
        .unwrap();
        let fm = a.frame(&mesh.positions).unwrap();
        assert!(fm.tri_weight.iter().all(|w| (*w - 0.5).abs() < 1e-12), "{:?}", fm.tri_weight);
    }
}
