//! The procedural test and training characters (rigging spec §3.13): humanoids built by
//! `geom_core::procedural::character` with ground-truth joints.
//!
//! Seeds 1000–1015 are the held-out test set (never used while tuning), with the paper's
//! proportion classes: well-proportioned (6), large arms + tiny legs (2), large legs + small
//! arms (2), thin limbs (2), large head (2), fingers (2). Seeds 0–61 are the training set.

use geom_core::procedural::character::HumanoidParams;
use geom_core::rng::Rng;

/// Class of a test character.
pub fn test_class(seed: u64) -> &'static str {
    match seed.saturating_sub(1000) {
        0..=5 => "well-proportioned",
        6..=7 => "large-arms-tiny-legs",
        8..=9 => "large-legs-small-arms",
        10..=11 => "thin-limbs",
        12..=13 => "large-head",
        _ => "fingers",
    }
}

fn jitter(rng: &mut Rng, p: &mut HumanoidParams) {
    p.arm_elevation_deg = rng.range(-55.0, -20.0);
    p.leg_spread_deg = rng.range(3.0, 14.0);
    p.torso_width = rng.range(0.9, 1.15);
    p.bumps = rng.range(0.1, 0.35);
}

/// Parameters of test character `seed` ∈ 1000..=1015.
pub fn test_params(seed: u64) -> HumanoidParams {
    let mut rng = Rng::new(seed ^ 0x5eed);
    let mut p = HumanoidParams { seed, ..Default::default() };
    jitter(&mut rng, &mut p);
    match test_class(seed) {
        "well-proportioned" => {
            p.arm = rng.range(0.9, 1.1);
            p.leg = rng.range(0.9, 1.1);
        }
        "large-arms-tiny-legs" => {
            p.arm = rng.range(1.3, 1.45);
            p.leg = rng.range(0.55, 0.7);
            p.limb_radius = 1.1;
        }
        "large-legs-small-arms" => {
            p.arm = rng.range(0.6, 0.7);
            p.leg = rng.range(1.25, 1.4);
        }
        "thin-limbs" => {
            p.limb_radius = rng.range(0.3, 0.4);
            p.bumps = 0.05;
        }
        "large-head" => {
            p.head = rng.range(1.5, 1.8);
        }
        _ => {
            p.fingers = if seed.is_multiple_of(2) { 4 } else { 5 };
        }
    }
    p
}

/// Parameters of training character `seed` ∈ 0..=61: random proportions over all classes.
pub fn train_params(seed: u64) -> HumanoidParams {
    let mut rng = Rng::new(seed ^ 0x7a1);
    let mut p = HumanoidParams { seed, ..Default::default() };
    jitter(&mut rng, &mut p);
    p.arm = rng.range(0.65, 1.4);
    p.leg = rng.range(0.6, 1.35);
    p.head = rng.range(0.9, 1.6);
    p.limb_radius = rng.range(0.45, 1.15);
    p.fingers = if rng.chance(0.2) { 4 } else { 0 };
    p
}
