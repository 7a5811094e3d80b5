//! A sanity figure of the skinned body (issue 23, pipe2): the largest edge strain
//! |ℓ/ℓ̄ − 1| of the body mesh over the posed frames (ℓ̄ the rest length, ℓ the length in a
//! frame), where and when it happens, and which bones weight the two vertices of the worst
//! edge. A skinned character stretches a little at its joints; an edge stretched several times
//! its length is a tear (weights mixing bones that move apart), which the garment then gets
//! caught in.

use geom_core::anim::skin::SkinWeights;
use geom_core::anim::Skeleton;
use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;

/// The worst body edge over the frames.
#[derive(Clone, Debug, Default)]
pub struct BodyStrain {
    /// Largest |ℓ/ℓ̄ − 1| over edges and frames (NaN if a position is NaN).
    pub max: f64,
    /// Frame index of the worst.
    pub frame: usize,
    /// Its edge (body vertex indices).
    pub edge: [u32; 2],
    /// Per frame, the largest strain.
    pub per_frame: Vec<f64>,
}

/// Measures the body's edge strain over `frames` (positions per frame, m) against `rest`.
pub fn measure(rest: &TriMesh, frames: &[Vec<Pt3>]) -> BodyStrain {
    let edges = rest.topology().edges().to_vec();
    let len0: Vec<f64> =
        edges.iter().map(|e| (rest.positions[e[1] as usize] - rest.positions[e[0] as usize]).norm()).collect();
    let mut out = BodyStrain::default();
    for (f, x) in frames.iter().enumerate() {
        let mut worst = (0.0f64, 0usize);
        for (k, e) in edges.iter().enumerate() {
            let s = ((x[e[1] as usize] - x[e[0] as usize]).norm() / len0[k] - 1.0).abs();
            if s.is_nan() || s > worst.0 {
                worst = (s, k);
                if s.is_nan() {
                    break;
                }
            }
        }
        out.per_frame.push(worst.0);
        if !out.max.is_nan() && (worst.0.is_nan() || worst.0 > out.max) {
            out.max = worst.0;
            out.frame = f;
            out.edge = edges.get(worst.1).copied().unwrap_or([0, 0]);
        }
    }
    out
}

/// "v12 (left_hip 0.52, right_hip 0.48)": a vertex and the bones weighting it.
pub fn describe_vertex(v: u32, w: &SkinWeights, sk: &Skeleton) -> String {
    let (j, x) = w.row(v as usize);
    let bones: Vec<String> =
        j.iter().zip(x).map(|(&j, &x)| format!("{} {:.2}", sk.joints[j as usize].name, x)).collect();
    format!("v{v} ({})", bones.join(", "))
}
