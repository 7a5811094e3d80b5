//! G2P and particle advection of one simulation step (spec §3.1 stages 9 and 10), as free
//! functions so that the simulator and the micro-benchmarks run the same code.

use geom_core::math::{Pt3, Vec3};
use geom_core::NONE;
use rayon::prelude::*;

use crate::bcc::TetMesh;
use crate::octree::Octree;
use crate::particles::{ParticleFlags, Particles};
use crate::scene::FlipParams;
use crate::transfer::{pic_fraction, sample};

/// A tet velocity field (m/s, one value per tet) with its nodal averages: the pair the sub-tet
/// interpolation of spec §3.7 (`transfer::sample`) reads.
#[derive(Clone, Copy, Debug)]
pub struct TetField<'a> {
    /// Per-tet values.
    pub tet: &'a [Vec3],
    /// Per-node averages.
    pub nodal: &'a [Vec3],
}

impl TetField<'_> {
    /// The field at barycentric coordinates `l` of tet `t`.
    fn at(&self, mesh: &TetMesh, t: u32, l: &[f64; 4]) -> Vec3 {
        sample(mesh, self.tet, self.nodal, t, l)
    }
}

/// The mesh a step advects through: tets, the octree for point location, tet sizes (m).
#[derive(Clone, Copy, Debug)]
pub struct AdvectMesh<'a> {
    /// Tet mesh.
    pub mesh: &'a TetMesh,
    /// Its octree (walks and point location).
    pub octree: &'a Octree,
    /// Cube edge `h_t` of each tet (m).
    pub h_tet: &'a [f64],
}

/// G2P (spec §3.7): every located, non-ballistic particle takes the PIC/FLIP blend
/// `v ← a u_new(x) + (1 − a)(v + Δu(x))` with the radius-dependent PIC fraction `a`
/// (`transfer::pic_fraction`, `r_min` the finest particle radius). Ballistic and unlocated
/// particles keep their velocity.
pub fn g2p(mesh: &TetMesh, parts: &mut Particles, new: TetField, du: TetField, r_min: f64, fp: &FlipParams) {
    let (xs, vs, rs, ts, fl) = (&parts.x, &mut parts.v, &parts.r, &parts.tet, &parts.flags);
    vs.par_iter_mut().enumerate().for_each(|(i, v)| {
        if fl[i].has(ParticleFlags::BALLISTIC) || ts[i] == NONE {
            return;
        }
        let l = mesh.barycentric(ts[i], &xs[i]);
        let a = pic_fraction(rs[i], r_min, fp.pic_base, fp.pic_radius_exponent, fp.pic_floor);
        let vn = new.at(mesh, ts[i], &l);
        let dv = du.at(mesh, ts[i], &l);
        *v = vn * a + (*v + dv) * (1.0 - a);
    });
}

/// Advection (spec §3.8): each located, non-ballistic particle moves by RK2 (midpoint) through the
/// grid velocity in `n = ceil(|v| Δt / (h_t / 2))` substeps (1 … 64), walking its tet with every
/// velocity sample; the velocity at fraction `s` of the step is `new`, or with `old` (time-centred
/// advection) the linear-in-time field `(1 − s) old + s new`. Ballistic and unlocated particles fly
/// free: their velocity takes the gravity `kick` of the step (m/s, `g Δt_kick`, see
/// [`crate::scene::TimeIntegration`]), then they move by `v Δt`. Walls, obstacles and relocation
/// are the caller's. Returns the substeps beyond one per particle.
pub fn advect(
    m: &AdvectMesh,
    parts: &mut Particles,
    new: TetField,
    old: Option<TetField>,
    kick: Vec3,
    dt: f64,
) -> Vec<u32> {
    let (mesh, oct, h_tet) = (m.mesh, m.octree, m.h_tet);
    let (xs, vs, ts, fl) = (&mut parts.x, &mut parts.v, &mut parts.tet, &parts.flags);
    xs.par_iter_mut()
        .zip(vs.par_iter_mut())
        .zip(ts.par_iter_mut())
        .enumerate()
        .map(|(i, ((x, v), t))| {
            if fl[i].has(ParticleFlags::BALLISTIC) || *t == NONE {
                *v += kick;
                *x += *v * dt;
                return 0;
            }
            let h = h_tet[*t as usize];
            let n = ((v.norm() * dt) / (0.5 * h)).ceil().clamp(1.0, 64.0) as u32;
            let sdt = dt / f64::from(n);
            let vel = |p: &Pt3, hint: u32, s: f64| -> (Vec3, u32) {
                match mesh.walk(oct, hint, p) {
                    Some((tt, l)) => {
                        let un = new.at(mesh, tt, &l);
                        match old {
                            Some(o) if s < 1.0 => (un * s + o.at(mesh, tt, &l) * (1.0 - s), tt),
                            _ => (un, tt),
                        }
                    }
                    None => (Vec3::zeros(), hint),
                }
            };
            for k in 0..n {
                let s0 = f64::from(k) / f64::from(n);
                let (v1, t1) = vel(x, *t, s0);
                let mid = *x + v1 * (0.5 * sdt);
                let (v2, t2) = vel(&mid, t1, s0 + 0.5 / f64::from(n));
                *x += v2 * sdt;
                *t = t2;
            }
            n - 1
        })
        .collect()
}
