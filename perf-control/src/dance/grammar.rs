//! The "Lindy-like" partner-dance grammar (spec §3.13, mirroring the paper's description of basic
//! Lindy Hop, Hsu et al. 2004 §6): four stances, three 4-beat transitions made of two 2-beat
//! halves, a handhold toggle at the end of a transition, 8-beat patterns of two transitions, and
//! the seven basic patterns of the training vocabulary.
//!
//! A segment label is (stance before the transition, transition, half, toggle), the toggle being
//! part of the label of half `b` only. The basic patterns hold 16 distinct segment labels; the
//! patterns whose four labels all occur in the training set ("composable") are 21: the 7 basic
//! ones and 14 novel ones.

use serde::{Deserialize, Serialize};

/// A stance of the couple.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Stance {
    /// Open (arm's length), leader's left hand holds the follower's right.
    O,
    /// Closed (close embrace), leader's left hand holds the follower's right.
    C,
    /// Open crosshand (right to right).
    OX,
    /// Closed crosshand.
    CX,
}

/// A 4-beat transition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Transition {
    /// Step: keeps open/closed.
    S,
    /// Inside turn: open → closed, the follower spins toward the leader (+360°).
    I,
    /// Outside turn: closed → open, the follower spins away (−360°).
    U,
}

/// Which 2-beat half of a transition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Half {
    /// Beats 1–2.
    A,
    /// Beats 3–4 (carries the toggle).
    B,
}

impl Stance {
    /// All four stances.
    pub const ALL: [Stance; 4] = [Stance::O, Stance::C, Stance::OX, Stance::CX];

    /// Closed (`C`, `CX`).
    pub fn closed(self) -> bool {
        matches!(self, Stance::C | Stance::CX)
    }

    /// Crosshand (`OX`, `CX`).
    pub fn crosshand(self) -> bool {
        matches!(self, Stance::OX | Stance::CX)
    }

    /// The stance with the given closedness and handhold.
    pub fn of(closed: bool, crosshand: bool) -> Stance {
        match (closed, crosshand) {
            (false, false) => Stance::O,
            (true, false) => Stance::C,
            (false, true) => Stance::OX,
            (true, true) => Stance::CX,
        }
    }

    /// The transitions allowed from this stance: `S` always, `I` from open, `U` from closed.
    pub fn transitions(self) -> [Transition; 2] {
        if self.closed() {
            [Transition::S, Transition::U]
        } else {
            [Transition::S, Transition::I]
        }
    }

    /// The stance after transition `t` with handhold toggle `toggle`, or `None` when `t` is not
    /// allowed from this stance.
    pub fn after(self, t: Transition, toggle: bool) -> Option<Stance> {
        let closed = match t {
            Transition::S => self.closed(),
            Transition::I if !self.closed() => true,
            Transition::U if self.closed() => false,
            _ => return None,
        };
        Some(Stance::of(closed, self.crosshand() ^ toggle))
    }

    /// Short name (`O`, `C`, `OX`, `CX`).
    pub fn name(self) -> &'static str {
        match self {
            Stance::O => "O",
            Stance::C => "C",
            Stance::OX => "OX",
            Stance::CX => "CX",
        }
    }
}

/// The semantic label of a two-beat segment (spec §3.13): what PC-4 compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct DanceLabel {
    /// Stance before the transition.
    pub stance: Stance,
    /// The transition.
    pub transition: Transition,
    /// Which half.
    pub half: Half,
    /// Handhold toggle at the end of the transition (always false for half `A`).
    pub toggle: bool,
}

impl std::fmt::Display for DanceLabel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let t = match self.transition {
            Transition::S => "S",
            Transition::I => "I",
            Transition::U => "U",
        };
        match self.half {
            Half::A => write!(f, "{}:{t}a", self.stance.name()),
            Half::B => write!(f, "{}:{t}b{}", self.stance.name(), u8::from(self.toggle)),
        }
    }
}

/// An 8-beat pattern: a start stance and two transitions with their toggles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Pattern {
    /// Stance at the start.
    pub start: Stance,
    /// The two transitions and their toggles.
    pub steps: [(Transition, bool); 2],
}

impl Pattern {
    /// The stance after the first transition and at the end, or `None` if not grammatical.
    pub fn stances(&self) -> Option<[Stance; 3]> {
        let s1 = self.start.after(self.steps[0].0, self.steps[0].1)?;
        let s2 = s1.after(self.steps[1].0, self.steps[1].1)?;
        Some([self.start, s1, s2])
    }

    /// The stance at the end (`None` if not grammatical).
    pub fn end(&self) -> Option<Stance> {
        self.stances().map(|s| s[2])
    }

    /// The four segment labels (`None` if not grammatical).
    pub fn labels(&self) -> Option<[DanceLabel; 4]> {
        let s = self.stances()?;
        let l = |i: usize, half: Half| DanceLabel {
            stance: s[i],
            transition: self.steps[i].0,
            half,
            toggle: half == Half::B && self.steps[i].1,
        };
        Some([l(0, Half::A), l(0, Half::B), l(1, Half::A), l(1, Half::B)])
    }

    /// The pattern whose segment labels are `labels`, if they form a grammatical pattern (the
    /// validity of a misread pattern, spec §3.14).
    pub fn from_labels(labels: &[DanceLabel; 4]) -> Option<Pattern> {
        let p = Pattern {
            start: labels[0].stance,
            steps: [(labels[0].transition, labels[1].toggle), (labels[2].transition, labels[3].toggle)],
        };
        (p.labels()? == *labels).then_some(p)
    }

    /// Every grammatical pattern (64), in a fixed order.
    pub fn all() -> Vec<Pattern> {
        let mut out = Vec::new();
        for s in Stance::ALL {
            for t0 in s.transitions() {
                for g0 in [false, true] {
                    let s1 = s.after(t0, g0).expect("allowed transition");
                    for t1 in s1.transitions() {
                        for g1 in [false, true] {
                            out.push(Pattern { start: s, steps: [(t0, g0), (t1, g1)] });
                        }
                    }
                }
            }
        }
        out
    }

    /// Parses `"C:S0 U1"`.
    pub fn parse(s: &str) -> Option<Pattern> {
        let (st, rest) = s.split_once(':')?;
        let start = Stance::ALL.into_iter().find(|x| x.name() == st.trim())?;
        let mut it = rest.split_whitespace().map(|w| {
            let mut c = w.chars();
            let t = match c.next()? {
                'S' => Transition::S,
                'I' => Transition::I,
                'U' => Transition::U,
                _ => return None,
            };
            let g = match c.next()? {
                '0' => false,
                '1' => true,
                _ => return None,
            };
            c.next().is_none().then_some((t, g))
        });
        let a = it.next()??;
        let b = it.next()??;
        if it.next().is_some() {
            return None;
        }
        let p = Pattern { start, steps: [a, b] };
        p.stances().map(|_| p)
    }
}

impl std::fmt::Display for Pattern {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let w = |(t, g): (Transition, bool)| {
            format!(
                "{}{}",
                match t {
                    Transition::S => "S",
                    Transition::I => "I",
                    Transition::U => "U",
                },
                u8::from(g)
            )
        };
        write!(f, "{}:{} {}", self.start.name(), w(self.steps[0]), w(self.steps[1]))
    }
}

/// The seven basic patterns of the training vocabulary (spec §3.13).
pub const BASIC: [&str; 7] = ["C:S0 S0", "C:S0 U0", "C:U1 I0", "O:I0 S0", "O:I0 U0", "O:I1 U0", "OX:S1 S0"];

/// The basic patterns, parsed.
pub fn basic_patterns() -> Vec<Pattern> {
    BASIC.iter().map(|s| Pattern::parse(s).expect("the basic patterns are grammatical")).collect()
}

/// The distinct segment labels of a set of patterns, sorted.
pub fn label_set(patterns: &[Pattern]) -> Vec<DanceLabel> {
    let mut v: Vec<DanceLabel> = patterns.iter().filter_map(Pattern::labels).flatten().collect();
    v.sort();
    v.dedup();
    v
}

/// Every grammatical pattern whose four segment labels all occur in `vocabulary`'s patterns
/// (the patterns the test dancers may improvise, spec §3.13), in [`Pattern::all`] order.
pub fn composable(vocabulary: &[Pattern]) -> Vec<Pattern> {
    let set = label_set(vocabulary);
    Pattern::all()
        .into_iter()
        .filter(|p| p.labels().is_some_and(|l| l.iter().all(|x| set.binary_search(x).is_ok())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spec §3.13: 64 grammatical patterns, 16 distinct labels in the basic set, 21 composable
    /// patterns of which 7 are basic and 14 novel.
    #[test]
    fn grammar_counts_match_the_spec() {
        assert_eq!(Pattern::all().len(), 64);
        let basic = basic_patterns();
        assert_eq!(label_set(&basic).len(), 16);
        let comp = composable(&basic);
        assert_eq!(comp.len(), 21);
        assert_eq!(comp.iter().filter(|p| basic.contains(p)).count(), 7);
        for p in Pattern::all() {
            assert_eq!(Pattern::parse(&p.to_string()), Some(p));
            assert_eq!(Pattern::from_labels(&p.labels().unwrap()), Some(p));
        }
        // `C:U1 I0` ends in CX; no basic pattern starts there.
        assert_eq!(Pattern::parse("C:U1 I0").unwrap().end(), Some(Stance::CX));
        assert!(!basic.iter().any(|p| p.start == Stance::CX));
        assert!(Pattern::parse("O:U0 S0").is_none(), "U is not allowed from open");
    }
}
