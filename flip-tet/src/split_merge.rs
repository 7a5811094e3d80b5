//! Particle split and merge against the leaf sizes of a new octree (spec §3.10), run at every
//! remesh before the mesh is rebuilt.
//!
//! A particle's target radius is the leaf size at its position divided by `C_H` (eight
//! particles per finest cube of edge `h` have radius `h / 4`). A non-ballistic particle larger
//! than `split_ratio` × its target is split in two halves of equal volume (`r / ∛2`), placed
//! symmetrically about the old centre; one smaller than `merge_ratio` × its target is merged with
//! its nearest untouched non-ballistic neighbour, volume-weighted. Both conserve `Σ r³` and
//! `Σ r³ v` exactly. New particles just inside the old interface are then snapped tangent to it
//! (`φ_p = −r`), so that a split or merge at the surface does not move the level set.
//!
//! Free functions of the particles, the new octree and the old level set (not methods of the
//! simulator), so that the criterion micro-benchmark runs the same code on a cloned state.

use geom_core::math::{Pt3, Vec3};
use geom_core::rng::Rng;
use geom_core::spatial::KdTree;

use crate::bcc::TetMesh;
use crate::error::{Result, SimError};
use crate::octree::Octree;
use crate::particles::{ParticleFlags, Particles};
use crate::scene::ParticleParams;
use crate::sizing::C_H;

/// Maximum number of split passes and of merge passes per remesh: a particle far above its
/// target halves its volume once per pass, so nine passes cover a size ratio of 8 (three levels).
const MAX_PASSES: usize = 9;

/// Particles looked at when searching a merge partner.
const MERGE_NEIGHBOURS: usize = 8;

/// What one split/merge pass changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SplitMergeCounts {
    /// Splits done (each adds one particle).
    pub split: usize,
    /// Merges done (each removes one particle).
    pub merged: usize,
    /// Splitting stopped at `max_particles` (the run goes on unless `budget_is_error`).
    pub budget_hit: bool,
}

/// The level set of the mesh the particles are leaving, read by the surface snap.
#[derive(Clone, Copy, Debug)]
pub struct OldLevelSet<'a> {
    /// The old mesh (the particles' tet hints refer to it).
    pub mesh: &'a TetMesh,
    /// Its octree (point location).
    pub octree: &'a Octree,
    /// Node values of `φ` on it (m).
    pub phi: &'a [f64],
}

impl OldLevelSet<'_> {
    /// `φ` (m) and `∇φ` at `x`, walking from the tet `hint`; `None` outside the mesh.
    pub fn at(&self, hint: u32, x: &Pt3) -> Option<(f64, Vec3)> {
        let (t, _) = self.mesh.walk(self.octree, hint, x)?;
        Some((self.mesh.interpolate(t, x, self.phi), self.mesh.gradient(t, self.phi)))
    }
}

/// Splits and merges `parts` against the leaf sizes of `new_oct`, then snaps the new particles
/// to the interface of `old`; `rng` draws the split offsets.
///
/// Errors: `ParticleBudgetExceeded` when the particle count reaches `pp.max_particles` and
/// `pp.budget_is_error` is set (particles split so far stay split).
pub fn split_merge(
    parts: &mut Particles,
    new_oct: &Octree,
    pp: &ParticleParams,
    rng: &mut Rng,
    old: &OldLevelSet,
) -> Result<SplitMergeCounts> {
    let mut counts = SplitMergeCounts::default();
    split_passes(parts, new_oct, pp, rng, &mut counts)?;
    counts.merged = merge_passes(parts, new_oct, pp);
    snap_new_particles(parts, pp.snap_factor, old);
    Ok(counts)
}

/// Target radius at `x`: the new octree's leaf size there over `C_H`.
fn target_radius(new_oct: &Octree, x: &Pt3) -> f64 {
    new_oct.leaf_h(new_oct.leaf_at(x)) / C_H
}

/// Split passes: every non-ballistic particle above `split_ratio` × its target radius is split
/// in two (`r / ∛2` each, offsets `±o`, `|o|` uniform in `[0, r/2)` in a random direction).
fn split_passes(
    parts: &mut Particles,
    new_oct: &Octree,
    pp: &ParticleParams,
    rng: &mut Rng,
    counts: &mut SplitMergeCounts,
) -> Result<()> {
    for _ in 0..MAX_PASSES {
        let n0 = parts.len();
        let mut any = false;
        for i in 0..n0 {
            if parts.is_ballistic(i) {
                continue;
            }
            let needs_split = parts.r[i] > pp.split_ratio * target_radius(new_oct, &parts.x[i]);
            if !needs_split {
                continue;
            }
            if parts.len() >= pp.max_particles {
                counts.budget_hit = true;
                if pp.budget_is_error {
                    return Err(SimError::ParticleBudgetExceeded { limit: pp.max_particles });
                }
                break;
            }
            let r = parts.r[i];
            let rc = r / 2f64.cbrt();
            let off = rng.unit_vec3() * (0.5 * r * rng.f64());
            let x = parts.x[i];
            parts.x[i] = x + off;
            parts.r[i] = rc;
            let (v, phi) = (parts.v[i], parts.phi[i]);
            parts.push(x - off, v, rc, phi);
            let last = parts.len() - 1;
            parts.flags[last].0 |= ParticleFlags::NEW_THIS_REMESH;
            parts.flags[i].0 |= ParticleFlags::NEW_THIS_REMESH;
            parts.tet[last] = parts.tet[i];
            counts.split += 1;
            any = true;
        }
        if !any {
            break;
        }
    }
    Ok(())
}

/// Merge passes: a non-ballistic particle below `merge_ratio` × its target radius merges with
/// the nearest of its [`MERGE_NEIGHBOURS`] neighbours not yet touched in this pass (position,
/// velocity and stored `φ_p` volume-weighted, `r = ∛(r_i³ + r_j³)`). Returns the merges done.
fn merge_passes(parts: &mut Particles, new_oct: &Octree, pp: &ParticleParams) -> usize {
    let mut merged = 0;
    for _ in 0..MAX_PASSES {
        let tree = KdTree::build(&parts.x);
        let n = parts.len();
        let mut touched = vec![false; n];
        let mut keep = vec![true; n];
        let mut any = false;
        let mut buf = Vec::new();
        for i in 0..n {
            if touched[i] || parts.is_ballistic(i) || parts.r[i] >= pp.merge_ratio * target_radius(new_oct, &parts.x[i])
            {
                continue;
            }
            tree.knn(&parts.x[i], MERGE_NEIGHBOURS, &mut buf);
            let partner =
                buf.iter().map(|&(j, _)| j as usize).find(|&j| j != i && !touched[j] && !parts.is_ballistic(j));
            let Some(j) = partner else { continue };
            let (vi, vj) = (parts.r[i].powi(3), parts.r[j].powi(3));
            let w = vi + vj;
            parts.x[i] = Pt3::from((parts.x[i].coords * vi + parts.x[j].coords * vj) / w);
            parts.v[i] = (parts.v[i] * vi + parts.v[j] * vj) / w;
            parts.phi[i] = (parts.phi[i] * vi + parts.phi[j] * vj) / w;
            parts.r[i] = w.cbrt();
            parts.flags[i].0 |= ParticleFlags::NEW_THIS_REMESH;
            touched[i] = true;
            touched[j] = true;
            keep[j] = false;
            merged += 1;
            any = true;
        }
        parts.retain(&keep);
        if !any {
            break;
        }
    }
    merged
}

/// Surface snap of the particles flagged new in this remesh: one with `−snap r < φ < 0` in the
/// old level set is moved along `∇φ` until it is tangent to the interface (`φ = −r`).
fn snap_new_particles(parts: &mut Particles, snap: f64, old: &OldLevelSet) {
    for i in 0..parts.len() {
        if !parts.flags[i].has(ParticleFlags::NEW_THIS_REMESH) {
            continue;
        }
        if let Some((phi, g)) = old.at(parts.tet[i], &parts.x[i]) {
            let r = parts.r[i];
            if phi < 0.0 && phi > -snap * r && g.norm() > 0.0 {
                let n = g / g.norm();
                parts.x[i] -= n * (phi + r);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bcc::tetrahedralize;
    use crate::octree::OctreeSpec;

    /// Unit cube, coarsest 2, finest 8 cubes per axis: levels 0..=2, h = 0.5, 0.25, 0.125 m.
    fn spec() -> OctreeSpec {
        OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), 2, 8).expect("unit-cube spec")
    }

    /// Old mesh (uniform at `level`) with the planar level set `φ = y − 0.5`.
    fn old_state(level: u8) -> (Octree, TetMesh, Vec<f64>) {
        let oct = Octree::uniform(spec(), level);
        let mesh = tetrahedralize(&oct).expect("uniform octree tetrahedralizes");
        let phi = mesh.nodes.iter().map(|x| x.y - 0.5).collect();
        (oct, mesh, phi)
    }

    fn moments(p: &Particles) -> (f64, Vec3) {
        (0..p.len()).fold((0.0, Vec3::zeros()), |(m, q), i| (m + p.r[i].powi(3), q + p.v[i] * p.r[i].powi(3)))
    }

    /// Particles sized for `from_level`, deep below the surface at `y = 0.5`, with varied velocities.
    fn deep_particles(from_level: u8, n: usize) -> Particles {
        let r = spec().h(from_level) / C_H;
        let mut p = Particles::default();
        for k in 0..n {
            let s = k as f64 / n as f64;
            p.push(Pt3::new(0.1 + 0.8 * s, 0.1 + 0.1 * s, 0.3 + 0.4 * s), Vec3::new(s, -1.0, 2.0 * s), r, -0.3);
        }
        p
    }

    #[test]
    fn refining_splits_and_coarsening_merges_conserving_volume_and_momentum() {
        let (oct0, mesh, phi) = old_state(0);
        let old = OldLevelSet { mesh: &mesh, octree: &oct0, phi: &phi };
        let pp = ParticleParams::default();
        // Coarse particles against the finest octree: each splits down to within split_ratio
        // of h_min / C_H (two levels = volume / 64, i.e. 63 splits per particle at most).
        let mut p = deep_particles(0, 5);
        let before = moments(&p);
        let c = split_merge(&mut p, &Octree::uniform(spec(), 2), &pp, &mut Rng::new(3), &old).expect("no budget");
        let after = moments(&p);
        assert_eq!(c.merged, 0);
        assert_eq!(p.len(), 5 + c.split);
        let target = spec().h(2) / C_H;
        assert!(p.r.iter().all(|&r| r <= pp.split_ratio * target), "a particle was left too large");
        // Σ r³ and Σ r³ v: each split keeps them exactly up to the rounding of r/∛2 (≤ 1e−15 relative).
        assert!((after.0 - before.0).abs() <= 1e-13 * before.0, "volume {} vs {}", after.0, before.0);
        assert!((after.1 - before.1).norm() <= 1e-13 * before.1.norm());
        assert!(!c.budget_hit);
        // Back to the coarsest octree: merges bring the count down and conserve both moments.
        let c2 = split_merge(&mut p, &oct0, &pp, &mut Rng::new(3), &old).expect("no budget");
        let back = moments(&p);
        assert_eq!(c2.split, 0);
        assert!(c2.merged > 0 && p.len() + c2.merged == 5 + c.split);
        assert!((back.0 - before.0).abs() <= 1e-13 * before.0);
        assert!((back.1 - before.1).norm() <= 1e-13 * before.1.norm());
    }

    #[test]
    fn budget_stops_splitting_or_errors() {
        let (oct0, mesh, phi) = old_state(0);
        let old = OldLevelSet { mesh: &mesh, octree: &oct0, phi: &phi };
        let fine = Octree::uniform(spec(), 2);
        let pp = ParticleParams { max_particles: 12, ..ParticleParams::default() };
        let mut p = deep_particles(0, 5);
        let c = split_merge(&mut p, &fine, &pp, &mut Rng::new(3), &old).expect("budget is a flag");
        assert!(c.budget_hit && p.len() == 12, "{c:?}, {} particles", p.len());
        let strict = ParticleParams { budget_is_error: true, ..pp };
        let err = split_merge(&mut deep_particles(0, 5), &fine, &strict, &mut Rng::new(3), &old).unwrap_err();
        assert!(matches!(err, SimError::ParticleBudgetExceeded { limit: 12 }), "{err:?}");
    }

    #[test]
    fn new_particles_just_inside_the_surface_are_snapped_tangent_to_it() {
        let (oct0, mesh, phi) = old_state(1);
        let old = OldLevelSet { mesh: &mesh, octree: &oct0, phi: &phi };
        let pp = ParticleParams::default();
        // One particle sized for level 1 with its centre 0.01 m below the surface y = 0.5: after
        // splitting against the finest octree, halves within snap_factor · r of the surface sit
        // tangent to it (φ = −r, i.e. y = 0.5 − r); deeper ones keep their place.
        let mut p = Particles::default();
        let r0 = spec().h(1) / C_H;
        p.push(Pt3::new(0.43, 0.49, 0.57), Vec3::zeros(), r0, -0.01);
        p.tet[0] = mesh.locate(&oct0, &p.x[0]).expect("inside").0;
        let c = split_merge(&mut p, &Octree::uniform(spec(), 2), &pp, &mut Rng::new(11), &old).expect("no budget");
        assert!(c.split > 0);
        let mut snapped = 0;
        for i in 0..p.len() {
            let (x, r) = (p.x[i], p.r[i]);
            if (x.y - (0.5 - r)).abs() <= 1e-12 {
                snapped += 1;
            } else {
                assert!(
                    x.y - 0.5 <= -pp.snap_factor * r || x.y > 0.5,
                    "particle {i} at y = {} (r = {r}) not snapped",
                    x.y
                );
            }
        }
        assert!(snapped > 0, "no particle snapped");
    }
}
