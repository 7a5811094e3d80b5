//! Test helpers: small random databases with smooth signals.
#![allow(dead_code)]

use geom_core::math::Vec3;
use geom_core::rng::Rng;
use perf_control::{MappingDb, PointTrack, SegmentLabel, Take};

/// A smooth random track: each point does a random walk in velocity.
pub fn smooth_track(rng: &mut Rng, frames: usize, k: usize, rate: f64) -> PointTrack {
    let mut data = vec![Vec3::zeros(); frames * k];
    for p in 0..k {
        let mut pos = Vec3::new(rng.range(-1.0, 1.0), rng.range(0.0, 1.5), rng.range(-1.0, 1.0));
        let mut vel = Vec3::new(rng.range(-0.3, 0.3), rng.range(-0.1, 0.1), rng.range(-0.3, 0.3));
        for f in 0..frames {
            data[f * k + p] = pos;
            vel += Vec3::new(rng.range(-0.2, 0.2), rng.range(-0.05, 0.05), rng.range(-0.2, 0.2));
            pos += vel * 0.3;
        }
    }
    PointTrack::new(rate, k, data)
}

/// One take whose segments have the given lengths (intervals), random smooth control (`kc`
/// points) and target (`kt` points) at `rate`.
pub fn random_take(rng: &mut Rng, seg_lengths: &[usize], kc: usize, kt: usize, rate: f64) -> Take {
    let n: usize = seg_lengths.iter().sum::<usize>() + 1;
    let mut boundaries = vec![0];
    for l in seg_lengths {
        boundaries.push(boundaries[boundaries.len() - 1] + l);
    }
    Take {
        control: smooth_track(rng, n, kc, rate),
        target: smooth_track(rng, n, kt, rate),
        source: None,
        boundaries,
        labels: vec![SegmentLabel::None; seg_lengths.len()],
        annotations: None,
    }
}

/// A database at the takes' native rate.
pub fn random_db(seed: u64, seg_lengths: &[usize], kc: usize, kt: usize, rate: f64) -> MappingDb {
    let mut rng = Rng::new(seed);
    MappingDb::from_takes(vec![random_take(&mut rng, seg_lengths, kc, kt, rate)], rate).unwrap()
}
