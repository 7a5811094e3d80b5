//! Criterion group `cloth_fit` (spec §9): rendering at three image sizes and two supersampling
//! rates, angle maps at three filter lengths, the frame error, and one static and one waving
//! evaluation of the 12² swatch (to watch the ≤ 1 s / ≤ 2 s targets).

use cloth_fit::angle::{angle_map, AngleOptions};
use cloth_fit::fold_error::{frame_error, MetricOptions};
use cloth_fit::forward::{ForwardModel, ShellsForward};
use cloth_fit::objective::{EvalSetup, Objective};
use cloth_fit::params::{ParamId, ParamSpace};
use cloth_fit::presets::{default_ranges, fit_model, rig_spec, static_trial, waving_trial, FabricPreset};
use cloth_fit::render::{render_intensity, RenderOptions};
use cloth_fit::synthetic::{synthesize, Condition, SyntheticSource};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn bench(c: &mut Criterion) {
    let f = FabricPreset::Linen;
    let truth = f.params();
    let sizes = [(160u32, 120u32), (320, 240), (640, 480)];
    let e = waving_trial(f, 0, 12);
    let rig0 = rig_spec(320, 240).build().expect("rig").rig;
    let sim = ShellsForward.simulate(&truth, &e, &rig0, &fit_model()).expect("simulation");
    let faces = ShellsForward.faces(&fit_model());
    let q = &sim.frames[10];
    let mut g = c.benchmark_group("render");
    for &(w, h) in &sizes {
        let rig = rig_spec(w, h).build().expect("rig").rig;
        for ss in [1u32, 2] {
            let o = RenderOptions { supersample: ss, ..RenderOptions::default() };
            g.bench_function(BenchmarkId::new(format!("{w}x{h}"), format!("ss{ss}")), |b| {
                b.iter(|| render_intensity(q, &faces, &rig, &o))
            });
        }
    }
    g.finish();
    let mut g = c.benchmark_group("angle_map");
    for &(w, h) in &sizes {
        let rig = rig_spec(w, h).build().expect("rig").rig;
        let (img, sil) = render_intensity(q, &faces, &rig, &RenderOptions::default());
        for taps in [9usize, 13, 17] {
            let o = AngleOptions { taps, ..AngleOptions::default() };
            g.bench_function(BenchmarkId::new(format!("{w}x{h}"), format!("taps={taps}")), |b| {
                b.iter(|| angle_map(&img, &sil, &o))
            });
        }
    }
    g.finish();
    let mut g = c.benchmark_group("frame_error");
    for &(w, h) in &sizes {
        let rig = rig_spec(w, h).build().expect("rig").rig;
        let (i1, s1) = render_intensity(&sim.frames[8], &faces, &rig, &RenderOptions::default());
        let (i2, s2) = render_intensity(q, &faces, &rig, &RenderOptions::default());
        let (a, b2) = (angle_map(&i1, &s1, &AngleOptions::default()), angle_map(&i2, &s2, &AngleOptions::default()));
        g.bench_function(format!("{w}x{h}"), |b| b.iter(|| frame_error(&a, &b2, &MetricOptions::default())));
    }
    g.finish();
    let setup = EvalSetup {
        rig: rig0,
        model: fit_model(),
        render: Default::default(),
        angle: Default::default(),
        metric: Default::default(),
    };
    let space = ParamSpace::new(default_ranges(), ParamId::ALL.to_vec(), truth).expect("space");
    let mut g = c.benchmark_group("eval");
    g.sample_size(10);
    for (name, exp) in [("static", static_trial(f, 0, 5)), ("waving", waving_trial(f, 0, 50))] {
        let src = SyntheticSource::new(Condition::Matched, truth, &setup, Default::default());
        let t = [synthesize(&ShellsForward, &exp, &setup.rig, &src, &setup.angle).expect("truth").target];
        let mut k = 0.0;
        g.bench_function(name, |b| {
            b.iter(|| {
                // A fresh objective and a new point each time: no cache hits.
                let obj = Objective::new(&t, &ShellsForward, &space, &setup).expect("objective");
                k += 1.0;
                obj.eval_params(&[truth.with(ParamId::Bend, truth.bend * (1.0 + 1e-3 * k))])
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
