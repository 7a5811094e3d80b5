//! Criterion group `skinning` (spec §9): LBS (K = 4), DQS (K = 4) and curve skin (K = 64 table)
//! on the cylinder arm bent 60° and twisted 45°, at 10k / 100k / 1M vertices, positions only and
//! with normals, one thread.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use curve_skin::curve::{build_curve_skeleton, JointCurveDefaults, TopologyRules};
use curve_skin::poses::{axis_deg, SkinPose};
use curve_skin::procedural::{cylinder_arm, ramp_weights, Ramp};
use curve_skin::{CurveOptions, CurveSkin, DeformOutput, Dqs, Lbs, PackedWeights, Skinner};
use geom_core::math::Vec3;

fn weights4(w2: &PackedWeights<2>) -> PackedWeights<4> {
    PackedWeights {
        bone: w2.bone.iter().map(|b| [b[0], b[1], 0, 0]).collect(),
        w: w2.w.iter().map(|w| [w[0], w[1], 0.0, 0.0]).collect(),
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("skinning");
    g.sample_size(10);
    for &n in &[10_000usize, 100_000, 1_000_000] {
        let segs = 64;
        let (mesh, sk) = cylinder_arm(0.15, 1.0, n / segs, segs).expect("arm");
        let rest = mesh.positions_f32();
        let normals: Vec<[f32; 3]> =
            mesh.vertex_normals().iter().map(|v| [v.x as f32, v.y as f32, v.z as f32]).collect();
        let w = weights4(&ramp_weights(&mesh.positions, 0.0, 0.15, Ramp::SmoothStep));
        let mut pose = SkinPose::rest(&sk);
        pose.set_world(&sk, 1, axis_deg(Vec3::z(), 60.0) * axis_deg(Vec3::x(), 45.0));
        let posed = pose.globals(&sk);
        let mut lbs = Lbs::new(rest.clone(), Some(normals.clone()), w.clone()).expect("lbs");
        lbs.prepare(&sk, &posed).expect("prepare");
        let mut dqs = Dqs::new(rest.clone(), Some(normals.clone()), w).expect("dqs");
        dqs.prepare(&sk, &posed).expect("prepare");
        let cs = build_curve_skeleton(&sk, &TopologyRules::default(), &JointCurveDefaults::default());
        let mut cur = CurveSkin::new(&sk, cs, &mesh.positions, Some(&normals), CurveOptions::default()).expect("curve");
        cur.prepare(&sk, &posed).expect("prepare");
        let mut pos = vec![[0f32; 3]; rest.len()];
        let mut nor = vec![[0f32; 3]; rest.len()];
        g.throughput(Throughput::Elements(rest.len() as u64));
        let skinners: [(&str, &dyn Skinner); 3] = [("lbs4", &lbs), ("dqs4", &dqs), ("curve64", &cur)];
        for (name, s) in skinners {
            g.bench_with_input(BenchmarkId::new(format!("{name}/pos"), n), &n, |b, _| {
                b.iter(|| s.deform(DeformOutput { positions: &mut pos, normals: None }))
            });
            g.bench_with_input(BenchmarkId::new(format!("{name}/pos+nrm"), n), &n, |b, _| {
                b.iter(|| s.deform(DeformOutput { positions: &mut pos, normals: Some(&mut nor) }))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
