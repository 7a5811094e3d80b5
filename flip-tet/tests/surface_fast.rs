//! The fast level-set path (pruned sphere-union tree, hulls only where they can matter, pruned
//! pairs and triplets) against the exhaustive reference evaluation on random particle sets.
//!
//! Tolerance: bitwise equality. Every pruning step skips only terms that are provably not below the
//! running minimum (with a `1e−9 band` margin against rounding) and evaluates the surviving terms
//! with the same expressions, and `min` does not depend on the order, so the two paths must agree
//! exactly, not merely to a tolerance.

use flip_tet::particles::{ParticleFlags, Particles};
use flip_tet::surface::{LevelSetSampler, SurfaceMethod, SurfaceParams, Walls};
use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;

/// A graded pool: fine particles (radius `r0`) in the top layer, `2 r0` below, `4 r0` deeper, each
/// jittered by up to a quarter of its radius, with `φ_p` = height minus the surface height (so
/// deep particles get large interior radii), a few ballistic particles and a random spray above.
fn graded_pool(rng: &mut Rng, r0: f64) -> Particles {
    let mut p = Particles::default();
    let (lx, lz, depth) = (0.3, 0.2, 0.16);
    let mut y_top = depth;
    for (k, thick) in [(0u32, 0.03f64), (1, 0.05), (2, 0.08)] {
        let r = r0 * f64::from(1u32 << k);
        let y_bot = (y_top - thick).max(0.0);
        let (nx, ny, nz) =
            ((lx / (2.0 * r)) as usize, ((y_top - y_bot) / (2.0 * r)).round() as usize, (lz / (2.0 * r)) as usize);
        for i in 0..nx {
            for j in 0..ny {
                for l in 0..nz {
                    let jit = |rng: &mut Rng| rng.range(-0.25 * r, 0.25 * r);
                    let x = Pt3::new(
                        r * (2 * i + 1) as f64 + jit(rng),
                        y_top - r * (2 * j + 1) as f64 + jit(rng),
                        r * (2 * l + 1) as f64 + jit(rng),
                    );
                    p.push(x, Vec3::zeros(), r, x.y - depth);
                }
            }
        }
        y_top = y_bot;
    }
    for _ in 0..60 {
        let x = Pt3::new(rng.range(0.0, lx), rng.range(depth, depth + 0.06), rng.range(0.0, lz));
        let phi = if rng.range(0.0, 1.0) < 0.3 { f64::NAN } else { rng.range(-0.01, 0.03) };
        p.push(x, Vec3::zeros(), r0 * f64::from(1u32 << (rng.range(0.0, 2.99) as u32)), phi);
    }
    let n = p.len();
    for i in (0..n).step_by(97) {
        p.flags[i] = ParticleFlags(ParticleFlags::BALLISTIC);
    }
    p
}

fn check(parts: &Particles, params: &SurfaceParams, walls: &Walls, rng: &mut Rng, queries: usize) -> usize {
    let s = LevelSetSampler::new(parts, params, walls);
    let mut inside_band = 0;
    for _ in 0..queries {
        // Points over the whole pool and above it; local sizes from the finest to the coarsest.
        let q = Pt3::new(rng.range(-0.02, 0.32), rng.range(-0.02, 0.26), rng.range(-0.02, 0.22));
        let h = [0.004, 0.008, 0.016, 0.032][rng.range(0.0, 3.99) as usize];
        let fast = s.value(&q, h);
        let slow = s.value_exhaustive(&q, h);
        assert_eq!(fast.to_bits(), slow.to_bits(), "q = {q:?}, h = {h}: fast {fast} vs exhaustive {slow}");
        if fast.abs() < s.band(h) {
            inside_band += 1;
        }
    }
    inside_band
}

#[test]
fn fast_level_set_equals_exhaustive_bitwise() {
    let mut rng = Rng::new(11);
    let parts = graded_pool(&mut rng, 0.002);
    let walls = Walls {
        min: Pt3::origin(),
        max: Pt3::new(0.3, 0.3, 0.2),
        mirror: [true, true, true, false, true, false],
        node_in_solid: None,
    };
    let params = SurfaceParams::default();
    let n = check(&parts, &params, &walls, &mut rng, 1500);
    // The samples must exercise the band (hull evaluation), not only clamped values.
    assert!(n > 300, "only {n} samples inside the band");
    let l3 = SurfaceParams { hull_l: 3.0, neighbours: 16, ..SurfaceParams::default() };
    check(&parts, &l3, &Walls::none(), &mut rng, 400);
    let su = SurfaceParams { method: SurfaceMethod::SphereUnion, ..SurfaceParams::default() };
    check(&parts, &su, &walls, &mut rng, 400);
}

#[test]
fn fast_level_set_on_random_clouds() {
    // Unstructured clouds of random radii and random stored φ (including deep values), several
    // seeds: no lattice structure for the pruning to rely on.
    for seed in 0..4 {
        let mut rng = Rng::new(100 + seed);
        let mut p = Particles::default();
        for _ in 0..1500 {
            let x = Pt3::new(rng.range(0.0, 0.3), rng.range(0.0, 0.24), rng.range(0.0, 0.2));
            p.push(x, Vec3::zeros(), rng.range(0.001, 0.01), rng.range(-0.08, 0.01));
        }
        check(&p, &SurfaceParams::default(), &Walls::none(), &mut rng, 400);
    }
    // No particles at all: the band value everywhere.
    let mut rng = Rng::new(1);
    check(&Particles::default(), &SurfaceParams::default(), &Walls::none(), &mut rng, 20);
}

#[test]
fn node_level_set_is_exact_where_it_matters() {
    // level_set_on_nodes skips the hulls at air nodes whose sphere-union value exceeds h + δ.
    // Against the exhaustive reference on a graded mesh: every node whose exact value is ≤ h_q is
    // bitwise equal; the others are > h_q in both and differ by at most δ (hull_reach).
    use flip_tet::bcc::tetrahedralize;
    use flip_tet::octree::{build_octree, OctreeSpec, SizeDemand};
    use flip_tet::surface::{level_set_on_nodes, redistance_interior};
    let mut rng = Rng::new(21);
    let parts = graded_pool(&mut rng, 0.003);
    let spec = OctreeSpec::new(Pt3::origin(), Pt3::new(0.32, 0.32, 0.32), 4, 32).expect("box");
    let demands: Vec<SizeDemand> = (0..40)
        .map(|i| SizeDemand {
            center: Pt3::new(0.3 * (i % 8) as f64 / 7.0, 0.16, 0.2 * (i / 8) as f64 / 4.0),
            pad: 0.02,
            level: 3,
        })
        .collect();
    let mesh = tetrahedralize(&build_octree(spec, &demands)).expect("graded mesh");
    let params = SurfaceParams::default();
    let walls = Walls::none();
    let fast = level_set_on_nodes(&mesh, &parts, &params, &walls);
    let s = LevelSetSampler::new(&parts, &params, &walls);
    let mut slow: Vec<f64> = mesh.nodes.iter().zip(&mesh.node_h).map(|(q, &h)| s.value_exhaustive(q, h)).collect();
    let bands: Vec<f64> = mesh.node_h.iter().map(|&h| s.band(h)).collect();
    redistance_interior(&mesh.nodes, &mesh.node_nbrs, &bands, &mut slow);
    let delta = s.hull_reach();
    let (mut equal, mut near) = (0, 0);
    for i in 0..mesh.nodes.len() {
        let h = mesh.node_h[i];
        if fast[i].to_bits() == slow[i].to_bits() {
            equal += 1;
            near += usize::from(slow[i].abs() <= h);
            continue;
        }
        assert!(slow[i] > h && fast[i] > h, "node {i}: fast {} vs exact {} (h {h})", fast[i], slow[i]);
        assert!(fast[i] >= slow[i] && fast[i] - slow[i] <= delta, "node {i}: {} vs {}", fast[i], slow[i]);
    }
    assert!(near > 100, "only {near} nodes near the surface");
    // The skip is exercised (some far air nodes differ) but most nodes are bitwise equal.
    assert!(equal < mesh.nodes.len() && equal > mesh.nodes.len() / 2, "{equal} of {}", mesh.nodes.len());
}
