//! The example database (spec §3.2): takes (synchronized control/target recordings with a
//! segmentation), cut into instances resampled at the working rate, plus the per-point weights.

use crate::dance::grammar::{DanceLabel, Half, Stance, Transition};
use crate::error::{check_finite, PcError, Result};
use crate::track::{prefilter, PointTrack};
use geom_core::anim::Motion;
use serde::{Deserialize, Serialize};

/// Body side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Side {
    /// Left.
    Left,
    /// Right.
    Right,
}

/// Semantic label of one instance (domain-specific, opaque to the algorithm).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SegmentLabel {
    /// One walking step, starting with a plant of `lead_foot`.
    Step {
        /// The foot planted at the start of the step.
        lead_foot: Side,
    },
    /// One two-beat segment of a partner dance (spec §3.13): the dance label (stance before the
    /// transition, transition, half, handhold toggle) and the index of its 8-beat pattern in the
    /// take.
    Dance {
        /// Stance before the transition.
        stance: Stance,
        /// The 4-beat transition.
        transition: Transition,
        /// Which 2-beat half.
        half: Half,
        /// Handhold toggle at the end of the transition (half `B` only).
        toggle: bool,
        /// Index of the 8-beat pattern in its take.
        pattern: u16,
    },
    /// No label.
    None,
}

impl SegmentLabel {
    /// The dance label of a [`SegmentLabel::Dance`] (without the pattern index), else `None`.
    pub fn dance(&self) -> Option<DanceLabel> {
        match *self {
            SegmentLabel::Dance { stance, transition, half, toggle, .. } => {
                Some(DanceLabel { stance, transition, half, toggle })
            }
            _ => None,
        }
    }
}

/// One recorded example performance.
#[derive(Clone, Debug)]
pub struct Take {
    /// Control signal at the native rate.
    pub control: PointTrack,
    /// Target signal, same frames as the control.
    pub target: PointTrack,
    /// Full-body target at the native rate (for skeletal output), same frames.
    pub source: Option<Motion>,
    /// Segmentation in native frames: strictly increasing, first 0, last `len − 1`.
    pub boundaries: Vec<usize>,
    /// One label per segment (`boundaries.len() − 1`).
    pub labels: Vec<SegmentLabel>,
    /// Per-frame annotations (a bit set per native frame, e.g. which hands are joined), copied to
    /// the output by [`crate::output::propagate`] (spec §3.11); `None` when the take has none.
    pub annotations: Option<Vec<u64>>,
}

/// One example segment at the working rate (spec §3.2): `n_s + 1` samples, first and last at
/// the segment's ends.
#[derive(Clone, Debug)]
pub struct Instance {
    /// `a_s`: control samples.
    pub control: PointTrack,
    /// `b_s`: target samples, same timing.
    pub target: PointTrack,
    /// (take, first native frame, last native frame).
    pub source: (u32, usize, usize),
    /// Semantic label.
    pub label: SegmentLabel,
    /// Per-sample annotations at the working rate (nearest native frame), if the take has them.
    pub annotations: Option<Vec<u64>>,
}

impl Instance {
    /// `n_s`: intervals at the working rate.
    pub fn n(&self) -> usize {
        self.control.len() - 1
    }
}

/// The database of instances at one working rate.
#[derive(Clone, Debug)]
pub struct MappingDb {
    /// Instances (after clustering: the kept representatives).
    pub instances: Vec<Instance>,
    /// The takes they come from.
    pub takes: Vec<Take>,
    /// Working rate (Hz).
    pub working_rate_hz: f64,
    /// Per control point weight `w_p` (default 1).
    pub control_weights: Vec<f64>,
    /// Per target point weight (continuity term; default 1).
    pub target_weights: Vec<f64>,
    /// Warnings (segments dropped as too short …).
    pub warnings: Vec<String>,
}

fn validate_takes(takes: &[Take]) -> Result<(usize, usize, f64)> {
    let first = takes.first().ok_or_else(|| PcError::EmptyDatabase("no take".into()))?;
    let (kc, kt, rate) = (first.control.n_points, first.target.n_points, first.control.rate_hz);
    if !(rate.is_finite() && rate > 0.0) {
        return Err(PcError::BadParameter { name: "take rate", msg: format!("{rate} Hz must be positive") });
    }
    for (i, t) in takes.iter().enumerate() {
        let what = |s: &str| format!("take {i} {s}");
        if t.control.n_points != kc || kc == 0 {
            return Err(PcError::PointCountMismatch { what: what("control"), expected: kc, got: t.control.n_points });
        }
        if t.target.n_points != kt || kt == 0 {
            return Err(PcError::PointCountMismatch { what: what("target"), expected: kt, got: t.target.n_points });
        }
        for (s, r) in [("control", t.control.rate_hz), ("target", t.target.rate_hz)] {
            if (r - rate).abs() > 1e-9 * rate {
                return Err(PcError::RateMismatch { what: what(s), expected: rate, got: r });
            }
        }
        check_finite(&what("control"), &t.control.data, kc)?;
        check_finite(&what("target"), &t.target.data, kt)?;
        let n = t.control.len();
        if t.target.len() != n {
            return Err(PcError::BadParameter {
                name: "take",
                msg: format!("take {i}: control has {n} frames, target {}", t.target.len()),
            });
        }
        let b = &t.boundaries;
        let ok = b.len() >= 2 && b[0] == 0 && b[b.len() - 1] + 1 == n && b.windows(2).all(|w| w[0] < w[1]);
        if !ok {
            return Err(PcError::BadParameter {
                name: "boundaries",
                msg: format!("take {i}: must increase strictly from 0 to {} ({} given)", n.saturating_sub(1), b.len()),
            });
        }
        if t.annotations.as_ref().is_some_and(|a| a.len() != n) {
            return Err(PcError::BadParameter {
                name: "annotations",
                msg: format!(
                    "take {i}: {} annotation frames for {n} frames",
                    t.annotations.as_ref().map_or(0, |a| a.len())
                ),
            });
        }
        if t.labels.len() != b.len() - 1 {
            return Err(PcError::BadParameter {
                name: "labels",
                msg: format!("take {i}: {} labels for {} segments", t.labels.len(), b.len() - 1),
            });
        }
    }
    Ok((kc, kt, rate))
}

/// Resamples native frames `[fa, fb]` of `t` to `n + 1` samples.
fn resample_segment(t: &PointTrack, fa: usize, fb: usize, n: usize, rate: f64) -> PointTrack {
    let mut out = Vec::with_capacity((n + 1) * t.n_points);
    for k in 0..=n {
        let u = if k == n { fb as f64 } else { fa as f64 + k as f64 * (fb - fa) as f64 / n as f64 };
        t.sample(u, &mut out);
    }
    PointTrack::new(rate, t.n_points, out)
}

impl MappingDb {
    /// Cuts every take into instances at `working_rate_hz` (spec §3.2): segment `[f_a, f_b]` gets
    /// `n_s = round((f_b − f_a)·working/native)` intervals, sampled linearly from the takes after
    /// a box pre-filter of width `round(native/working)` (none when the rates are equal);
    /// segments with `n_s < 1` are dropped with a warning. Errors: no take or no instance left
    /// (`EmptyDatabase`), non-finite data, inconsistent point counts or rates, bad boundaries.
    pub fn from_takes(takes: Vec<Take>, working_rate_hz: f64) -> Result<Self> {
        let (kc, kt, _native) = validate_takes(&takes)?;
        if !(working_rate_hz.is_finite() && working_rate_hz > 0.0) {
            return Err(PcError::BadParameter {
                name: "working_rate_hz",
                msg: format!("{working_rate_hz} must be positive"),
            });
        }
        let mut db = MappingDb {
            instances: vec![],
            takes,
            working_rate_hz,
            control_weights: vec![1.0; kc],
            target_weights: vec![1.0; kt],
            warnings: vec![],
        };
        let all: Vec<(u32, usize, usize, SegmentLabel)> = db
            .takes
            .iter()
            .enumerate()
            .flat_map(|(ti, t)| t.boundaries.windows(2).zip(&t.labels).map(move |(w, l)| (ti as u32, w[0], w[1], *l)))
            .collect();
        db.instances = db.build_instances(&all, working_rate_hz);
        if db.instances.is_empty() {
            return Err(PcError::EmptyDatabase(format!(
                "every segment is shorter than one interval at {working_rate_hz} Hz"
            )));
        }
        Ok(db)
    }

    fn build_instances(&mut self, segs: &[(u32, usize, usize, SegmentLabel)], rate: f64) -> Vec<Instance> {
        let native = self.takes[0].control.rate_hz;
        let factor = (native / rate).round().max(1.0) as usize;
        let filtered: Vec<(PointTrack, PointTrack)> = self
            .takes
            .iter()
            .map(|t| {
                if factor > 1 {
                    // Box pre-filter without decimation (same width as `PointTrack::downsample`).
                    (prefilter(&t.control, factor), prefilter(&t.target, factor))
                } else {
                    (t.control.clone(), t.target.clone())
                }
            })
            .collect();
        let mut out = Vec::new();
        for &(ti, fa, fb, label) in segs {
            let n = ((fb - fa) as f64 * rate / native).round() as usize;
            if n < 1 {
                self.warnings.push(format!("take {ti} segment [{fa}, {fb}] dropped: {n} intervals at {rate} Hz"));
                continue;
            }
            let (c, t) = &filtered[ti as usize];
            let annotations = self.takes[ti as usize].annotations.as_ref().map(|a| {
                (0..=n).map(|k| a[(fa as f64 + k as f64 * (fb - fa) as f64 / n as f64).round() as usize]).collect()
            });
            out.push(Instance {
                control: resample_segment(c, fa, fb, n, rate),
                target: resample_segment(t, fa, fb, n, rate),
                source: (ti, fa, fb),
                label,
                annotations,
            });
        }
        out
    }

    /// The same instances (same indices, same order) rebuilt at another rate, e.g. the full rate
    /// for the refinement of §3.8. Instances too short at the new rate are an error (indices must
    /// be kept).
    pub fn at_rate(&self, rate_hz: f64) -> Result<MappingDb> {
        if !(rate_hz.is_finite() && rate_hz > 0.0) {
            return Err(PcError::BadParameter { name: "rate_hz", msg: format!("{rate_hz} must be positive") });
        }
        let segs: Vec<_> = self.instances.iter().map(|i| (i.source.0, i.source.1, i.source.2, i.label)).collect();
        let mut db = MappingDb {
            instances: vec![],
            takes: self.takes.clone(),
            working_rate_hz: rate_hz,
            control_weights: self.control_weights.clone(),
            target_weights: self.target_weights.clone(),
            warnings: vec![],
        };
        db.instances = db.build_instances(&segs, rate_hz);
        if db.instances.len() != self.instances.len() {
            return Err(PcError::EmptyDatabase(format!("instances too short at {rate_hz} Hz: {:?}", db.warnings)));
        }
        Ok(db)
    }

    /// Points per control frame.
    pub fn control_points(&self) -> usize {
        self.control_weights.len()
    }

    /// Points per target frame.
    pub fn target_points(&self) -> usize {
        self.target_weights.len()
    }
}
