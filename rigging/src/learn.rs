//! Learning the penalty weights Γ by the max-margin method (rigging spec §3.12, paper §3.2):
//! for each training character with good-embedding feature vectors p_j and bad ones q_j, the
//! optimization margin of a unit Γ ≥ 0 is min_j Γ·q_j − min_j Γ·p_j; maximise the smallest
//! margin over characters. The objective is non-convex and piecewise linear, so: Nelder–Mead
//! (own implementation) from random starts in [0, 1]⁹, then shrink the sampling cube around the
//! best point (×0.5) and repeat.

use geom_core::rng::Rng;

use crate::options::GAMMA_PUBLISHED;

/// Feature vectors (b1 … b9) of one training character's labelled embeddings.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CharacterExamples {
    /// Good embeddings.
    pub good: Vec<[f64; 9]>,
    /// Bad embeddings.
    pub bad: Vec<[f64; 9]>,
}

/// Learning options.
#[derive(Clone, Debug, PartialEq)]
pub struct LearnOptions {
    /// Random starts per round.
    pub n_starts: usize,
    /// Shrink rounds.
    pub rounds: usize,
    /// Nelder–Mead iterations per start.
    pub iters: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for LearnOptions {
    fn default() -> Self {
        Self { n_starts: 50, rounds: 6, iters: 400, seed: 1 }
    }
}

fn unit(x: &[f64; 9]) -> Option<[f64; 9]> {
    let a = x.map(f64::abs);
    let n = a.iter().map(|v| v * v).sum::<f64>().sqrt();
    (n > 0.0 && n.is_finite()).then(|| a.map(|v| v / n))
}

fn dot(a: &[f64; 9], b: &[f64; 9]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The minimum margin over characters that have both good and bad examples for Γ (|Γ| is
/// normalized to unit length, signs dropped). `+∞` when no character has both kinds.
pub fn margin(gamma: &[f64; 9], ex: &[CharacterExamples]) -> f64 {
    let Some(g) = unit(gamma) else { return f64::NEG_INFINITY };
    ex.iter()
        .filter(|c| !c.good.is_empty() && !c.bad.is_empty())
        .map(|c| {
            let best_bad = c.bad.iter().map(|q| dot(&g, q)).fold(f64::INFINITY, f64::min);
            let best_good = c.good.iter().map(|p| dot(&g, p)).fold(f64::INFINITY, f64::min);
            best_bad - best_good
        })
        .fold(f64::INFINITY, f64::min)
}

/// Nelder–Mead minimisation of `f` from `x0` with initial simplex step `step` (standard
/// coefficients 1, 2, ½, ½). Returns the best point and value.
pub fn nelder_mead(f: &dyn Fn(&[f64; 9]) -> f64, x0: [f64; 9], step: f64, iters: usize) -> ([f64; 9], f64) {
    let mut s: Vec<([f64; 9], f64)> = (0..10)
        .map(|k| {
            let mut x = x0;
            if k > 0 {
                x[k - 1] += step;
            }
            (x, f(&x))
        })
        .collect();
    for _ in 0..iters {
        s.sort_by(|a, b| a.1.total_cmp(&b.1));
        let mut c = [0.0; 9];
        for (x, _) in &s[..9] {
            for d in 0..9 {
                c[d] += x[d] / 9.0;
            }
        }
        let worst = s[9];
        let at = |t: f64| -> [f64; 9] { std::array::from_fn(|d| c[d] + t * (worst.0[d] - c[d])) };
        let xr = at(-1.0);
        let fr = f(&xr);
        if fr < s[0].1 {
            let xe = at(-2.0);
            let fe = f(&xe);
            s[9] = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < s[8].1 {
            s[9] = (xr, fr);
        } else {
            let xc = at(0.5);
            let fc = f(&xc);
            if fc < worst.1 {
                s[9] = (xc, fc);
            } else {
                let best = s[0].0;
                for k in 1..10 {
                    let x: [f64; 9] = std::array::from_fn(|d| best[d] + 0.5 * (s[k].0[d] - best[d]));
                    s[k] = (x, f(&x));
                }
            }
        }
    }
    s.sort_by(|a, b| a.1.total_cmp(&b.1));
    s[0]
}

/// Maximises the minimum margin (spec §3.12). Returns Γ rescaled to the norm of the published
/// weights (the rejection bound of §3.7 is absolute) and the margin of the unit direction. A
/// non-positive margin means the basis penalties cannot separate good from bad embeddings.
pub fn max_margin(ex: &[CharacterExamples], o: &LearnOptions) -> ([f64; 9], f64) {
    let f = |g: &[f64; 9]| -margin(g, ex);
    let mut rng = Rng::new(o.seed);
    let mut centre = unit(&GAMMA_PUBLISHED).expect("published weights are non-zero");
    let mut best = (centre, margin(&centre, ex));
    let mut half = 0.5;
    for _ in 0..o.rounds {
        for _ in 0..o.n_starts {
            let x0: [f64; 9] = std::array::from_fn(|d| (centre[d] + rng.range(-half, half)).clamp(0.0, 1.0));
            let (x, fx) = nelder_mead(&f, x0, half * 0.2, o.iters);
            if let Some(u) = unit(&x) {
                if -fx > best.1 {
                    best = (u, -fx);
                }
            }
        }
        centre = best.0;
        half *= 0.5;
    }
    let norm = GAMMA_PUBLISHED.iter().map(|v| v * v).sum::<f64>().sqrt();
    (best.0.map(|v| v * norm), best.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separable_examples_get_a_positive_margin() {
        // Good embeddings are low in feature 0, bad ones high; feature 1 is noise.
        let ex: Vec<CharacterExamples> = (0..5)
            .map(|k| {
                let mut good = [0.0; 9];
                good[1] = 1.0 + k as f64 * 0.1;
                let mut bad = [0.0; 9];
                bad[0] = 1.0;
                bad[1] = 0.5;
                CharacterExamples { good: vec![good], bad: vec![bad] }
            })
            .collect();
        let (g, m) = max_margin(&ex, &LearnOptions { n_starts: 10, rounds: 3, iters: 200, seed: 3 });
        assert!(m > 0.0, "margin {m}");
        assert!(margin(&g, &ex) > 0.0);
        assert!(g[0] > g[1]);
    }

    #[test]
    fn nelder_mead_finds_a_quadratic_minimum() {
        let f = |x: &[f64; 9]| x.iter().enumerate().map(|(i, v)| (v - i as f64 * 0.1).powi(2)).sum::<f64>();
        let (x, fx) = nelder_mead(&f, [0.5; 9], 0.2, 3000);
        assert!(fx < 1e-8, "{fx} at {x:?}");
    }
}
