//! The toolkit's one random number generator (GEOM-CORE.md §3.2): [`Rng`], PCG32 (XSH-RR output,
//! 64-bit LCG state, odd increment selecting the stream; M. E. O'Neill, "PCG: A Family of Simple
//! Fast Space-Efficient Statistically Good Algorithms for Random Number Generation", 2014),
//! seeded through [`splitmix64`] (Steele, Lea, Flood, "Fast splittable pseudorandom number
//! generators", OOPSLA 2014).
//!
//! Everything random in the workspace draws from here, so results are reproducible from a seed on
//! every platform. For parallel work give every item its own [`Rng::stream`]`(seed, item)`: the
//! draws then do not depend on scheduling.

use crate::math::Vec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// One SplitMix64 step: advances `x` by the golden-ratio increment and returns the mixed value.
/// A bijection of the new state, so it also hashes seed tuples without collisions, e.g.
/// `let mut h = s; splitmix64(&mut h); h ^= t; splitmix64(&mut h)`.
pub fn splitmix64(x: &mut u64) -> u64 {
    *x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// PCG32 generator (XSH-RR). Small (16 bytes), `Clone` and serialisable, so a simulation can be
/// checkpointed with its random state.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rng {
    state: u64,
    /// Stream selector; always odd.
    inc: u64,
}

/// The PCG32 LCG multiplier.
const PCG_MULT: u64 = 6364136223846793005;

impl Rng {
    /// The generator for `seed`: the PCG initial state and stream both come from SplitMix64 of
    /// `seed`, so nearby seeds (0, 1, 2 …) give unrelated sequences.
    pub fn new(seed: u64) -> Rng {
        let mut s = seed;
        let init_state = splitmix64(&mut s);
        let init_seq = splitmix64(&mut s);
        Rng::from_pcg_seed(init_state, init_seq)
    }

    /// An independent generator for item `id` under `seed` (a clip, a particle, a worker): for a
    /// fixed seed, distinct ids get distinct PCG increments (distinct sequences, not offsets of
    /// one sequence) and unrelated starting states. Use it to make parallel loops deterministic.
    pub fn stream(seed: u64, id: u64) -> Rng {
        let mut s = seed;
        let a = splitmix64(&mut s);
        let b = splitmix64(&mut s);
        // `splitmix64` is a bijection of its state, so `c` is distinct for distinct ids.
        let mut t = id ^ b;
        let c = splitmix64(&mut t);
        Rng::from_pcg_seed(a ^ c, c)
    }

    /// Seeds exactly like the reference `pcg32_srandom_r(initstate, initseq)` of the PCG paper's
    /// C implementation (for cross-checking against published output).
    pub fn from_pcg_seed(init_state: u64, init_seq: u64) -> Rng {
        let mut r = Rng { state: 0, inc: (init_seq << 1) | 1 };
        r.next_u32();
        r.state = r.state.wrapping_add(init_state);
        r.next_u32();
        r
    }

    /// Next 32 uniformly distributed bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Next 64 bits: two 32-bit outputs, the first in the high half.
    pub fn next_u64(&mut self) -> u64 {
        let hi = self.next_u32() as u64;
        let lo = self.next_u32() as u64;
        (hi << 32) | lo
    }

    /// Uniform in `[0, 1)` with 53 random bits (every multiple of 2⁻⁵³ equally likely).
    pub fn f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`; returns `lo` if `hi ≤ lo`. (A draw that rounds up to `hi` is redrawn.)
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        if hi <= lo || lo.is_nan() || hi.is_nan() {
            return lo;
        }
        loop {
            let r = lo + (hi - lo) * self.f64();
            if r < hi || !r.is_finite() {
                return r;
            }
        }
    }

    /// Uniform integer in `[0, n)`, without modulo bias (Lemire's multiply-and-reject,
    /// "Fast Random Integer Generation in an Interval", ACM TOMACS 2019). Returns 0 for `n = 0`.
    pub fn below(&mut self, n: usize) -> usize {
        let n = n as u64;
        if n == 0 {
            return 0;
        }
        let mut m = self.next_u64() as u128 * n as u128;
        if (m as u64) < n {
            let threshold = n.wrapping_neg() % n;
            while (m as u64) < threshold {
                m = self.next_u64() as u128 * n as u128;
            }
        }
        (m >> 64) as usize
    }

    /// `true` with probability `p` (clamped to `[0, 1]`).
    pub fn chance(&mut self, p: f64) -> bool {
        self.f64() < p
    }

    /// Uniformly distributed direction on the unit sphere (Archimedes: uniform height, uniform
    /// azimuth).
    pub fn unit_vec3(&mut self) -> Vec3 {
        let z = 2.0 * self.f64() - 1.0;
        let phi = TAU * self.f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// Uniform random permutation in place (Fisher–Yates).
    pub fn shuffle<T>(&mut self, items: &mut [T]) {
        for i in (1..items.len()).rev() {
            let j = self.below(i + 1);
            items.swap(i, j);
        }
    }

    /// Standard normal sample (mean 0, variance 1) by Box–Muller, using the cosine branch only:
    /// no cached spare, so every call consumes exactly two `u64` draws and results do not depend
    /// on how calls interleave.
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.f64(); // (0, 1]: the log is finite
        let u2 = self.f64();
        (-2.0 * u1.ln()).sqrt() * (TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Independent transcription of the reference C code (pcg_basic.c: pcg32_random_r and
    /// pcg32_srandom_r), written with explicit `u64` arithmetic rather than the struct above.
    fn reference_pcg32(initstate: u64, initseq: u64, n: usize) -> Vec<u32> {
        let mut state: u64 = 0;
        let inc: u64 = (initseq << 1) | 1;
        let step = |state: &mut u64| -> u32 {
            let oldstate = *state;
            *state = oldstate.wrapping_mul(6364136223846793005u64).wrapping_add(inc);
            let xorshifted: u32 = (((oldstate >> 18) ^ oldstate) >> 27) as u32;
            let rot: u32 = (oldstate >> 59) as u32;
            (xorshifted >> rot) | (xorshifted << ((rot.wrapping_neg()) & 31))
        };
        step(&mut state);
        state = state.wrapping_add(initstate);
        step(&mut state);
        (0..n).map(|_| step(&mut state)).collect()
    }

    #[test]
    fn matches_published_pcg32_demo_output() {
        // pcg32-demo (pcg-c-basic) with seed 42, sequence 54, first round.
        let mut r = Rng::from_pcg_seed(42, 54);
        let got: Vec<u32> = (0..6).map(|_| r.next_u32()).collect();
        assert_eq!(got, vec![0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e]);
        assert_eq!(got, reference_pcg32(42, 54, 6));
    }

    #[test]
    fn golden_values_through_splitmix_seeding() {
        // SplitMix64 reference values for state 0 (Vigna's splitmix64.c): first outputs.
        let mut s = 0u64;
        assert_eq!(splitmix64(&mut s), 0xe220a8397b1dcdaf);
        assert_eq!(splitmix64(&mut s), 0x6e789e6aa1b965f4);
        // new(seed) = PCG seeded with the first two SplitMix64 outputs of the seed.
        for seed in [0u64, 1, 12345, u64::MAX] {
            let mut s = seed;
            let (a, b) = (splitmix64(&mut s), splitmix64(&mut s));
            let want = reference_pcg32(a, b, 100);
            let mut r = Rng::new(seed);
            let got: Vec<u32> = (0..100).map(|_| r.next_u32()).collect();
            assert_eq!(got, want, "seed {seed}");
        }
        // Pinned values of the public API (they must never change: scenes depend on them).
        let mut r = Rng::new(0);
        let first = r.next_u64();
        let mut s = 0u64;
        let (a, b) = (splitmix64(&mut s), splitmix64(&mut s));
        let w = reference_pcg32(a, b, 2);
        assert_eq!(first, ((w[0] as u64) << 32) | w[1] as u64);
    }

    #[test]
    fn streams_differ_and_are_reproducible() {
        let a: Vec<u32> = {
            let mut r = Rng::stream(7, 0);
            (0..8).map(|_| r.next_u32()).collect()
        };
        let b: Vec<u32> = {
            let mut r = Rng::stream(7, 1);
            (0..8).map(|_| r.next_u32()).collect()
        };
        let a2: Vec<u32> = {
            let mut r = Rng::stream(7, 0);
            (0..8).map(|_| r.next_u32()).collect()
        };
        assert_eq!(a, a2);
        assert_ne!(a, b);
        // Distinct increments for distinct ids.
        let incs: std::collections::BTreeSet<u64> = (0..1000).map(|i| Rng::stream(3, i).inc).collect();
        assert_eq!(incs.len(), 1000);
    }

    #[test]
    fn f64_range_and_moments() {
        let mut r = Rng::new(1);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let x = r.f64();
            assert!((0.0..1.0).contains(&x));
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let var = sum2 / n as f64 - mean * mean;
        // Standard error of the mean: sqrt(1/12/n) ≈ 6.5e-4; allow 5σ.
        assert!((mean - 0.5).abs() < 3.3e-3, "{mean}");
        assert!((var - 1.0 / 12.0).abs() < 2e-3, "{var}");
        for _ in 0..1000 {
            let x = r.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
        }
        assert_eq!(r.range(1.0, 1.0), 1.0);
    }

    #[test]
    fn below_is_unbiased_and_in_range() {
        let mut r = Rng::new(5);
        let n = 7;
        let mut counts = [0usize; 7];
        let draws = 70_000;
        for _ in 0..draws {
            let k = r.below(n);
            assert!(k < n);
            counts[k] += 1;
        }
        // Chi-square with 6 dof: 99.9th percentile ≈ 22.5.
        let e = draws as f64 / n as f64;
        let chi2: f64 = counts.iter().map(|&c| (c as f64 - e).powi(2) / e).sum();
        assert!(chi2 < 22.5, "chi2 = {chi2}, {counts:?}");
        assert_eq!(r.below(0), 0);
        assert_eq!(r.below(1), 0);
        // A bound near 2^64 exercises the rejection path without bias checks.
        assert!(r.below(usize::MAX) < usize::MAX);
    }

    #[test]
    fn normal_moments() {
        let mut r = Rng::new(9);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let kurt = xs.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n as f64 / (var * var);
        // SE of the mean 2.2e-3, of the variance 3.2e-3, of the kurtosis ≈ 1.1e-2; 5σ bounds.
        assert!(mean.abs() < 1.2e-2, "{mean}");
        assert!((var - 1.0).abs() < 1.6e-2, "{var}");
        assert!((kurt - 3.0).abs() < 6e-2, "{kurt}");
        assert!(xs.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn unit_vec3_is_unit_and_isotropic() {
        let mut r = Rng::new(13);
        let mut mean = Vec3::zeros();
        let n = 50_000;
        for _ in 0..n {
            let v = r.unit_vec3();
            assert!((v.norm() - 1.0).abs() < 1e-14);
            mean += v;
        }
        // Each component has variance 1/3: SE of the mean 2.6e-3; 5σ.
        assert!((mean / n as f64).norm() < 1.3e-2 * 3f64.sqrt());
    }

    #[test]
    fn shuffle_is_a_permutation_and_uniform() {
        let mut r = Rng::new(21);
        let mut v: Vec<usize> = (0..50).collect();
        r.shuffle(&mut v);
        let mut s = v.clone();
        s.sort();
        assert_eq!(s, (0..50).collect::<Vec<_>>());
        // All 6 orders of 3 items roughly equally likely.
        let mut counts = std::collections::BTreeMap::new();
        for _ in 0..60_000 {
            let mut a = [0, 1, 2];
            r.shuffle(&mut a);
            *counts.entry(a).or_insert(0usize) += 1;
        }
        assert_eq!(counts.len(), 6);
        let chi2: f64 = counts.values().map(|&c| (c as f64 - 10_000.0).powi(2) / 10_000.0).sum();
        assert!(chi2 < 20.5, "{counts:?}"); // 5 dof, 99.9th percentile
        let mut empty: [u8; 0] = [];
        r.shuffle(&mut empty);
    }

    #[test]
    fn serde_round_trip_resumes_the_sequence() {
        let mut r = Rng::new(99);
        r.next_u32();
        let json = serde_json::to_string(&r).unwrap();
        let mut back: Rng = serde_json::from_str(&json).unwrap();
        assert_eq!(back.next_u64(), r.next_u64());
    }
}
