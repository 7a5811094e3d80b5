//! [`tube`]: an open or capped cylinder of quads (WR's tube, CS's and BN's arms wrap it).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::graph::Ragged;
use crate::math::{Pt2, Pt3, Vec3};
use crate::mesh::PolyMesh;

/// How the ends of a [`tube`] are closed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Caps {
    /// Open ends (two boundary loops).
    #[default]
    Open,
    /// Each end closed by a fan of triangles around an extra centre vertex.
    Fan,
}

/// A cylinder of `around × along` quads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TubeSpec {
    /// Radius (m), > 0.
    pub radius: f64,
    /// Length along the axis (m), > 0.
    pub length: f64,
    /// Vertices per ring, ≥ 3.
    pub around: u32,
    /// Quad rows along the axis, ≥ 1 (rings are one more).
    pub along: u32,
    /// Centre of the first ring (m).
    pub start: Pt3,
    /// Axis direction (normalised internally; must be non-zero).
    pub axis: Vec3,
    /// End closure.
    pub caps: Caps,
}

impl Default for TubeSpec {
    /// A 1 m long, 5 cm radius open tube along +X from the origin, 16 × 10 quads.
    fn default() -> Self {
        Self {
            radius: 0.05,
            length: 1.0,
            around: 16,
            along: 10,
            start: Pt3::origin(),
            axis: Vec3::x(),
            caps: Caps::Open,
        }
    }
}

/// The ring frame of a tube: unit `e1 ⟂ â` from the world axis least aligned with `â` (first
/// such axis on ties), `e2 = â × e1`, so `(e1, e2, â)` is right-handed.
pub(crate) fn ring_frame(a: &Vec3) -> (Vec3, Vec3) {
    let m = a.abs();
    let helper = if m.x <= m.y && m.x <= m.z {
        Vec3::x()
    } else if m.y <= m.z {
        Vec3::y()
    } else {
        Vec3::z()
    };
    let e1 = (helper - helper.dot(a) * a).normalize();
    (e1, a.cross(&e1))
}

/// Tube as a [`PolyMesh`]: vertex `(ring r, k) = r·around + k` at
/// `start + (r/along)·length·â + radius·(cos φ_k e1 + sin φ_k e2)`, `φ_k = 2πk/around` with the
/// frame of `ring_frame` (for `axis = +Z`: `e1 = +X`, `e2 = +Y`). Faces: quads
/// `[(r,k), (r,k+1), (r+1,k+1), (r+1,k)]` in row-major order (`r` outer), pointing outward; with
/// [`Caps::Fan`] the centre of ring 0 (index `(along+1)·around`) and of the last ring (the next
/// index) get triangle fans pointing along −â and +â, appended after the quads.
///
/// UVs (per vertex, metres): `u = k·2πR/around` around, `v = r·length/along` along. There are
/// no seam vertices (the layout above is fixed), so the last quad column wraps from
/// `u = 2πR(around−1)/around` back to 0: split the seam yourself if you need continuous UVs.
/// Cap centres get `u = 0`.
///
/// Errors: [`Error::InvalidParameter`] naming the bad field.
pub fn tube(s: &TubeSpec) -> Result<PolyMesh> {
    if !(s.radius > 0.0 && s.radius.is_finite()) {
        return Err(Error::InvalidParameter(format!("tube radius must be positive and finite, got {}", s.radius)));
    }
    if !(s.length > 0.0 && s.length.is_finite()) {
        return Err(Error::InvalidParameter(format!("tube length must be positive and finite, got {}", s.length)));
    }
    if s.around < 3 || s.along < 1 {
        return Err(Error::InvalidParameter(format!(
            "tube needs around ≥ 3 and along ≥ 1, got {} and {}",
            s.around, s.along
        )));
    }
    let an = s.axis.norm();
    if !(an > 0.0 && an.is_finite() && s.start.coords.iter().all(|c| c.is_finite())) {
        return Err(Error::InvalidParameter("tube axis must be non-zero and finite, start finite".into()));
    }
    let nv = (s.along as u64 + 1) * s.around as u64 + 2;
    if nv > 1 << 31 {
        return Err(Error::InvalidParameter(format!("tube with {nv} vertices is too large")));
    }
    let a = s.axis / an;
    let (e1, e2) = ring_frame(&a);
    let (n, m) = (s.around, s.along);
    let circ = 2.0 * std::f64::consts::PI * s.radius;
    let mut positions = Vec::with_capacity(nv as usize);
    let mut uv = Vec::with_capacity(nv as usize);
    for r in 0..=m {
        let t = s.length * r as f64 / m as f64;
        let c = s.start + t * a;
        for k in 0..n {
            let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            positions.push(c + s.radius * (phi.cos() * e1 + phi.sin() * e2));
            uv.push(Pt2::new(circ * k as f64 / n as f64, t));
        }
    }
    let mut faces = Ragged::new();
    for r in 0..m {
        for k in 0..n {
            let k1 = (k + 1) % n;
            faces.push_row(&[r * n + k, r * n + k1, (r + 1) * n + k1, (r + 1) * n + k]);
        }
    }
    if s.caps == Caps::Fan {
        let (c0, c1) = ((m + 1) * n, (m + 1) * n + 1);
        positions.push(s.start);
        uv.push(Pt2::new(0.0, 0.0));
        positions.push(s.start + s.length * a);
        uv.push(Pt2::new(0.0, s.length));
        for k in 0..n {
            faces.push_row(&[c0, (k + 1) % n, k]);
        }
        for k in 0..n {
            faces.push_row(&[c1, m * n + k, m * n + (k + 1) % n]);
        }
    }
    Ok(PolyMesh { positions, faces, uv: Some(uv) })
}
