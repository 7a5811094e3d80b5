//! The paper's (and the spec's) expectations of a scene as boolean figures: each claim is a
//! `Bool` key checked to be true, and the scene also reports how many hold (`claims_met`) out of
//! how many it states (`claims_total`). A claim whose figure is missing (NaN: the run was too
//! short to measure it) counts as not met.

use geom_core::experiment::{Report, Target};

/// Collects a scene's claims; [`Claims::finish`] writes `claims_met` / `claims_total`.
#[derive(Debug, Default)]
pub struct Claims {
    met: u64,
    total: u64,
}

impl Claims {
    /// Records claim `key` (a flag in `r`, checked to be true against `source`).
    pub fn claim(&mut self, r: &mut Report, key: &str, holds: bool, source: &str) {
        r.flag(key, holds);
        r.check(key, Target::IsTrue, source);
        self.total += 1;
        self.met += u64::from(holds);
    }

    /// Records the claim "figure `value` meets `target`" as flag `key` (false when NaN).
    pub fn claim_target(&mut self, r: &mut Report, key: &str, value: f64, target: Target, source: &str) {
        self.claim(r, key, target.holds(value), source);
    }

    /// Claims met so far.
    pub fn met(&self) -> u64 {
        self.met
    }

    /// Claims stated so far.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Writes `claims_met` and `claims_total`.
    pub fn finish(self, r: &mut Report) {
        r.count("claims_met", self.met);
        r.count("claims_total", self.total);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A NaN figure never meets its claim; the counts add up.
    #[test]
    fn counts_and_nan() {
        let mut r = Report::default();
        let mut c = Claims::default();
        c.claim_target(&mut r, "a", 1.0, Target::AtLeast(0.5), "s");
        c.claim_target(&mut r, "b", f64::NAN, Target::AtLeast(0.5), "s");
        c.claim(&mut r, "c", false, "s");
        assert_eq!((c.met(), c.total()), (1, 3));
        c.finish(&mut r);
        assert_eq!(r.get_f64("claims_met"), 1.0);
        assert_eq!(r.get_f64("claims_total"), 3.0);
        assert!(!r.all_pass());
    }
}
