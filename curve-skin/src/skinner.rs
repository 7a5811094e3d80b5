//! The common skinner interface (spec §2.2): per-frame `prepare` (per-bone / per-curve work,
//! `f64` → `f32` once) and per-vertex `deform` over any vertex range, so rayon can split the
//! vertex stream into chunks. Outputs are bitwise identical for any chunking because every vertex
//! is computed independently.

use std::ops::Range;

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::Iso3;
use rayon::prelude::*;

use crate::error::Result;

/// Where `deform` writes: positions and optionally normals, both covering exactly the vertex range
/// being deformed.
pub struct DeformOutput<'a> {
    /// Deformed positions (m).
    pub positions: &'a mut [[f32; 3]],
    /// Deformed unit normals, if wanted (the skinner must have been given rest normals).
    pub normals: Option<&'a mut [[f32; 3]]>,
}

/// A skinning method: linear blend, dual quaternion or curve skeleton.
pub trait Skinner: Sync {
    /// Per-frame work from the posed joint world frames (`posed[j]`, e.g. from
    /// `forward_kinematics_local`). Errors when `posed` does not fit the bound skeleton.
    fn prepare(&mut self, sk: &SkinSkeleton, posed: &[Iso3]) -> Result<()>;
    /// Number of bound vertices.
    fn len(&self) -> usize;
    /// True when no vertex is bound.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Deforms vertices `range` into `out` (whose slices have `range.len()` entries).
    /// Panics if the slice lengths differ from the range (caller error).
    fn deform_range(&self, range: Range<usize>, out: DeformOutput<'_>);
    /// Deforms every vertex (single thread).
    fn deform(&self, out: DeformOutput<'_>) {
        self.deform_range(0..self.len(), out)
    }
}

/// Deforms every vertex in parallel chunks of `chunk` vertices (spec: 4096 by default) on the
/// current rayon pool. Bitwise equal to [`Skinner::deform`].
pub fn deform_par<S: Skinner + ?Sized>(s: &S, out: DeformOutput<'_>, chunk: usize) {
    let chunk = chunk.max(1);
    match out.normals {
        Some(n) => {
            out.positions.par_chunks_mut(chunk).zip(n.par_chunks_mut(chunk)).enumerate().for_each(|(i, (p, n))| {
                let a = i * chunk;
                s.deform_range(a..a + p.len(), DeformOutput { positions: p, normals: Some(n) })
            })
        }
        None => out.positions.par_chunks_mut(chunk).enumerate().for_each(|(i, p)| {
            let a = i * chunk;
            s.deform_range(a..a + p.len(), DeformOutput { positions: p, normals: None })
        }),
    }
}

/// Normalises a 3-vector in f32 (zero stays zero).
#[inline(always)]
pub(crate) fn normalize3(v: [f32; 3]) -> [f32; 3] {
    let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if n2 > 0.0 {
        let s = 1.0 / n2.sqrt();
        [v[0] * s, v[1] * s, v[2] * s]
    } else {
        v
    }
}
