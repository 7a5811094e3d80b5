//! Dance metrics (spec §3.14, PC-4): semantic accuracy of the follower's two-beat segments and
//! 8-beat patterns, rhythm, follower accuracy in closed and open stances, handhold annotations,
//! and the confusion of segment labels.
//!
//! - Each true two-beat segment takes the label of the output segment covering its midpoint; the
//!   two-beat error rate is the share of mismatches; a pattern matches when its four labels do; a
//!   mismatched pattern is *valid* when its four output labels still form a grammatical pattern.
//! - Rhythm: for every output boundary inside the input, the distance to the nearest true two-beat
//!   boundary, in frames of the interpretation's rate.
//! - Follower accuracy: RMS over frames of the mean squared distance of the four follower points to
//!   the truth, split by the true stance (closed / open).

use std::collections::BTreeMap;

use crate::dance::grammar::{DanceLabel, Pattern};
use crate::data::duet::DuetTruth;
use crate::db::MappingDb;
use crate::dp::Interpretation;
use crate::track::PointTrack;

/// The dance label of the output segment covering time `secs`, if any segment covers it and its
/// instance carries a dance label.
pub fn label_at(db: &MappingDb, it: &Interpretation, secs: f64) -> Option<DanceLabel> {
    let pos = secs * it.rate_hz;
    let s = it.segments.iter().find(|s| (s.start as f64) <= pos && pos <= s.end as f64)?;
    db.instances[s.instance as usize].label.dance()
}

/// Per true two-beat segment: the output label at its midpoint.
pub fn segment_labels(db: &MappingDb, it: &Interpretation, truth: &DuetTruth) -> Vec<Option<DanceLabel>> {
    truth.segments.iter().map(|&(a, b, _)| label_at(db, it, 0.5 * (a + b))).collect()
}

/// The output label of every input frame (the segment covering it; a shared boundary frame
/// belongs to the later segment), at the interpretation's rate.
pub fn frame_labels(db: &MappingDb, it: &Interpretation) -> Vec<crate::db::SegmentLabel> {
    let mut out = vec![crate::db::SegmentLabel::None; it.frames];
    for s in &it.segments {
        let l = db.instances[s.instance as usize].label;
        for f in s.start.max(0)..=s.end.min(it.frames as i64 - 1) {
            out[f as usize] = l;
        }
    }
    out
}

/// Semantic figures of one or several dances (sums, so dances can be added).
#[derive(Clone, Debug, Default)]
pub struct Semantics {
    /// True two-beat segments.
    pub segments: usize,
    /// Mismatched two-beat segments.
    pub segment_errors: usize,
    /// Patterns.
    pub patterns: usize,
    /// Patterns whose four labels all match.
    pub pattern_matches: usize,
    /// Mismatched patterns whose output labels form a grammatical pattern.
    pub mismatches_valid: usize,
    /// Distinct true patterns.
    pub unique: Vec<Pattern>,
    /// `(true label, output label)` counts.
    pub confusion: BTreeMap<(DanceLabel, Option<DanceLabel>), usize>,
}

impl Semantics {
    /// Adds one dance: its truth and the output label of each of its two-beat segments.
    pub fn add(&mut self, truth: &DuetTruth, out: &[Option<DanceLabel>]) {
        for (&(_, _, t), o) in truth.segments.iter().zip(out) {
            self.segments += 1;
            if *o != Some(t) {
                self.segment_errors += 1;
            }
            *self.confusion.entry((t, *o)).or_default() += 1;
        }
        for (k, p) in truth.patterns.iter().enumerate() {
            if 4 * k + 4 > out.len().min(truth.segments.len()) {
                break;
            }
            self.patterns += 1;
            if !self.unique.contains(p) {
                self.unique.push(*p);
            }
            let got: Vec<Option<DanceLabel>> = out[4 * k..4 * k + 4].to_vec();
            let want = p.labels().expect("generated patterns are grammatical");
            if got.iter().zip(&want).all(|(g, w)| *g == Some(*w)) {
                self.pattern_matches += 1;
            } else if let [Some(a), Some(b), Some(c), Some(d)] = got[..] {
                if Pattern::from_labels(&[a, b, c, d]).is_some() {
                    self.mismatches_valid += 1;
                }
            }
        }
    }

    /// Two-beat error rate (mismatches over segments).
    pub fn error_rate(&self) -> f64 {
        self.segment_errors as f64 / self.segments as f64
    }

    /// Share of mismatched patterns that are still grammatical (NaN without mismatches).
    pub fn valid_share(&self) -> f64 {
        let bad = self.patterns - self.pattern_matches;
        if bad == 0 {
            f64::NAN
        } else {
            self.mismatches_valid as f64 / bad as f64
        }
    }

    /// Distinct true patterns not among `basic`.
    pub fn novel(&self, basic: &[Pattern]) -> usize {
        self.unique.iter().filter(|p| !basic.contains(p)).count()
    }
}

/// Rhythm errors (frames of the interpretation's rate): every output boundary inside the input
/// against the nearest true two-beat boundary.
pub fn rhythm_errors(it: &Interpretation, truth: &DuetTruth) -> Vec<f64> {
    let mut bounds: Vec<f64> = truth.segments.iter().map(|s| s.0).collect();
    if let Some(l) = truth.segments.last() {
        bounds.push(l.1);
    }
    it.segments
        .iter()
        .skip(1)
        .filter(|s| s.start > 0 && s.start < it.frames as i64 - 1)
        .map(|s| {
            let t = s.start as f64 / it.rate_hz;
            bounds.iter().map(|b| (b - t).abs()).fold(f64::INFINITY, f64::min) * it.rate_hz
        })
        .collect()
}

/// Follower accuracy split by the true stance: (sum of squared distances, frames) for closed and
/// for open frames; per frame the mean over points of the squared distance (m²).
#[derive(Clone, Copy, Debug, Default)]
pub struct StanceError {
    /// Closed frames: Σ mean squared distance, count.
    pub closed: (f64, usize),
    /// Open frames.
    pub open: (f64, usize),
}

impl StanceError {
    /// Adds a dance's output against its true follower.
    pub fn add(&mut self, out: &PointTrack, truth_target: &PointTrack, truth: &DuetTruth) {
        let n = out.len().min(truth_target.len()).min(truth.annotations.len());
        let k = out.n_points;
        for f in 0..n {
            let e: f64 =
                out.frame(f).iter().zip(truth_target.frame(f)).map(|(a, b)| (a - b).norm_squared()).sum::<f64>()
                    / k as f64;
            let slot = if truth.closed(f) { &mut self.closed } else { &mut self.open };
            slot.0 += e;
            slot.1 += 1;
        }
    }

    /// RMS in closed stances (m).
    pub fn closed_rms(&self) -> f64 {
        (self.closed.0 / self.closed.1 as f64).sqrt()
    }

    /// RMS in open stances (m).
    pub fn open_rms(&self) -> f64 {
        (self.open.0 / self.open.1 as f64).sqrt()
    }
}

/// Frames whose propagated annotation equals the truth, and frames compared.
pub fn annotation_hits(propagated: &[u64], truth: &[u64]) -> (usize, usize) {
    let n = propagated.len().min(truth.len());
    (propagated.iter().zip(truth).take(n).filter(|(a, b)| a == b).count(), n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dance::grammar::basic_patterns;

    fn truth_of(patterns: &[Pattern]) -> DuetTruth {
        let segments = patterns
            .iter()
            .flat_map(|p| p.labels().unwrap())
            .enumerate()
            .map(|(i, l)| (i as f64, i as f64 + 1.0, l))
            .collect();
        DuetTruth { patterns: patterns.to_vec(), bpm: 120.0, segments, annotations: vec![] }
    }

    /// A perfect output scores 0 errors; one misread toggle in a last segment keeps its pattern
    /// valid; a misread stance makes it invalid; a missing label counts as an error.
    #[test]
    fn semantics_count_errors_and_validity() {
        let pats: Vec<Pattern> = ["O:I1 U0", "OX:S1 S0"].iter().map(|s| Pattern::parse(s).unwrap()).collect();
        // "O:I1 U0" ends in OX, then "OX:S1 S0" ends in O.
        let t = truth_of(&pats);
        let perfect: Vec<Option<DanceLabel>> = t.segments.iter().map(|s| Some(s.2)).collect();
        let mut s = Semantics::default();
        s.add(&t, &perfect);
        assert_eq!((s.segments, s.segment_errors, s.pattern_matches), (8, 0, 2));
        assert!(s.valid_share().is_nan(), "no mismatches: the share is undefined");
        let mut out = perfect.clone();
        let mut l = out[7].unwrap();
        l.toggle = !l.toggle; // last segment of pattern 2: still grammatical
        out[7] = Some(l);
        let mut l = out[0].unwrap();
        l.stance = crate::dance::grammar::Stance::C; // C with I is not grammatical
        out[0] = Some(l);
        let mut s = Semantics::default();
        s.add(&t, &out);
        assert_eq!((s.segment_errors, s.pattern_matches, s.mismatches_valid), (2, 0, 1));
        assert_eq!(s.error_rate(), 0.25);
        assert_eq!(s.valid_share(), 0.5);
        assert_eq!(s.novel(&basic_patterns()), 0, "both patterns are basic");
        assert_eq!(s.novel(&[]), 2);
        let mut s = Semantics::default();
        s.add(&t, &[None; 8]);
        assert_eq!(s.segment_errors, 8);
    }

    /// Frames whose annotation matches.
    #[test]
    fn annotation_hits_count_equal_frames() {
        assert_eq!(annotation_hits(&[1, 2, 4, 4], &[1, 2, 5]), (2, 3));
    }
}
