//! The paper's error metric between two angle-map sequences (Bhat et al. 2003 §4, eqs. 5–9;
//! spec §3.6).
//!
//! For frame k with overlap O_k = V_real ∧ V_sim and fold mask M_k (M_real, or M_real ∨ M_sim):
//!
//! E_fold,k = Σ_{p ∈ O_k} M_k(p) · Δθ(p)²      (eq. 5, Δθ = wrap_π(θ_real − θ_sim))
//! E_silh,k = Σ_p |A_real(p) − A_sim(p)|        (eqs. 6–7, raw silhouettes)
//! E_k      = E_fold,k + α E_silh,k             (eq. 8, α = 0.1 in the paper)
//! E        = Σ_k E_k                            (eq. 9)

use serde::{Deserialize, Serialize};

use crate::angle::{wrap_pi, AngleFrame};
use crate::error::{FitError, Result};

/// Which fold mask weights the angle differences.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum MaskMode {
    /// M_real only (the literal reading of eq. 5).
    Real,
    /// M_real ∨ M_sim (default: also penalises spurious simulated folds).
    #[default]
    Union,
}

/// Metric settings (spec §4.2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MetricOptions {
    /// Silhouette weight α (eq. 8).
    pub alpha: f64,
    /// Fold mask source.
    pub mask: MaskMode,
}

impl Default for MetricOptions {
    /// α = 0.1 (paper), union mask.
    fn default() -> Self {
        Self { alpha: 0.1, mask: MaskMode::Union }
    }
}

/// The error of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameError {
    /// E_fold,k (rad² · px).
    pub fold: f64,
    /// E_silh,k (px).
    pub silh: f64,
    /// E_k = E_fold + α E_silh.
    pub total: f64,
}

/// Errors of one frame pair (eq. 8). The frames must have the same size.
pub fn frame_error(real: &AngleFrame, sim: &AngleFrame, o: &MetricOptions) -> Result<FrameError> {
    let (a, b) = (&real.theta, &sim.theta);
    if (a.width, a.height) != (b.width, b.height) {
        return Err(FitError::ImageSizeMismatch {
            what: "simulated angle frame".into(),
            expected: (a.width, a.height),
            got: (b.width, b.height),
        });
    }
    let mut fold = 0.0f64;
    let mut silh = 0u64;
    for i in 0..a.data.len() {
        silh += (real.silhouette.data[i] != sim.silhouette.data[i]) as u64;
        if !(real.valid.data[i] && sim.valid.data[i]) {
            continue;
        }
        let m = match o.mask {
            MaskMode::Real => real.fold_mask.data[i],
            MaskMode::Union => real.fold_mask.data[i] || sim.fold_mask.data[i],
        };
        if m {
            let d = wrap_pi(a.data[i] as f64 - b.data[i] as f64);
            fold += d * d;
        }
    }
    let silh = silh as f64;
    Ok(FrameError { fold, silh, total: fold + o.alpha * silh })
}

/// E of eq. 9 and the per-frame errors. Errors: different frame counts (`SequenceMismatch`) or
/// sizes (`ImageSizeMismatch`).
pub fn sequence_error(real: &[AngleFrame], sim: &[AngleFrame], o: &MetricOptions) -> Result<(f64, Vec<FrameError>)> {
    if real.len() != sim.len() {
        return Err(FitError::SequenceMismatch { what: "angle frames".into(), expected: real.len(), got: sim.len() });
    }
    let per: Vec<FrameError> = real.iter().zip(sim).map(|(r, s)| frame_error(r, s, o)).collect::<Result<_>>()?;
    Ok((per.iter().map(|e| e.total).sum(), per))
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom_core::image::{ImageF32, Mask};

    fn frame(theta: f32, sil: &[bool], fold: &[bool]) -> AngleFrame {
        let n = sil.len() as u32;
        AngleFrame {
            theta: ImageF32::new(n, 1, theta),
            strength: ImageF32::new(n, 1, 1.0),
            valid: Mask::from_data(n, 1, sil.to_vec()).unwrap(),
            fold_mask: Mask::from_data(n, 1, fold.to_vec()).unwrap(),
            silhouette: Mask::from_data(n, 1, sil.to_vec()).unwrap(),
        }
    }

    /// Spec T11.
    #[test]
    fn metric_properties() {
        let o = MetricOptions::default();
        let a = frame(0.3, &[true, true, true, false], &[true, false, true, false]);
        let e = frame_error(&a, &a, &o).unwrap();
        assert_eq!(e.total, 0.0);
        // 89° vs −89°: Δ = 2°.
        let p = frame(89f32.to_radians(), &[true], &[true]);
        let q = frame((-89f32).to_radians(), &[true], &[true]);
        let d = frame_error(&p, &q, &o).unwrap();
        assert!((d.fold.sqrt() - 2f64.to_radians()).abs() < 1e-6);
        // Silhouette = XOR count; linear in α; masks.
        let b = frame(0.1, &[true, false, true, true], &[false, false, false, false]);
        let e = frame_error(&a, &b, &o).unwrap();
        assert_eq!(e.silh, 2.0);
        // Union: pixels 0 and 2 (both valid, folded in a); Real the same here.
        assert!((e.fold - 2.0 * 0.2f64.powi(2)).abs() < 1e-7);
        let e2 = frame_error(&a, &b, &MetricOptions { alpha: 0.2, ..o }).unwrap();
        assert!((e2.total - e2.fold - 2.0 * (e.total - e.fold)).abs() < 1e-12);
        assert!(e.total >= 0.0);
        // Spurious simulated folds count only with the union mask.
        let c = frame(0.1, &[true, true, true, false], &[false, true, false, false]);
        let none = frame(0.3, &[true, true, true, false], &[false, false, false, false]);
        assert_eq!(frame_error(&none, &c, &MetricOptions { mask: MaskMode::Real, ..o }).unwrap().fold, 0.0);
        assert!(frame_error(&none, &c, &o).unwrap().fold > 0.0);
        assert!(matches!(sequence_error(std::slice::from_ref(&a), &[], &o), Err(FitError::SequenceMismatch { .. })));
    }

    /// Spec §8: an empty silhouette in one frame gives E_fold = 0 and E_silh = the other area.
    #[test]
    fn empty_silhouette_frame() {
        let a = frame(0.3, &[true, true, true], &[true, true, true]);
        let empty = frame(0.0, &[false, false, false], &[false, false, false]);
        let e = frame_error(&a, &empty, &MetricOptions::default()).unwrap();
        assert_eq!(e.fold, 0.0);
        assert_eq!(e.silh, 3.0);
    }
}
