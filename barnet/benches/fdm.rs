//! Criterion benches of the force density method (spec §9): factorisation and solve for the
//! 12-free-node arm net and grid membranes, and one whole arm frame.

use barnet::analytic;
use barnet::deformer::{BarNetDeformer, Drivers, FrameOutput};
use barnet::presets::biceps_arm;
use barnet::{FdmOptions, FdmSolver};
use criterion::{criterion_group, criterion_main, Criterion};
use geom_core::math::Iso3;

fn bench(c: &mut Criterion) {
    for n in [10usize, 100] {
        let case = analytic::membrane_uniform(n, 1.0);
        let (loads, fixed) = case.split();
        c.bench_function(&format!("membrane_{n}x{n}_factor"), |b| {
            b.iter(|| FdmSolver::new(&case.net, &FdmOptions::default()).expect("valid net"))
        });
        let s = FdmSolver::new(&case.net, &FdmOptions::default()).expect("valid net");
        c.bench_function(&format!("membrane_{n}x{n}_solve"), |b| b.iter(|| s.solve(&loads, &fixed).expect("finite")));
    }
    let mut d = BarNetDeformer::new(&biceps_arm()).expect("valid arm");
    let pose = d.arm_pose(1.5, &Iso3::identity()).expect("pose");
    let drv = Drivers { joint_angles: vec![0.0, 1.5, 0.0], time: 0.0 };
    let mut out = FrameOutput::default();
    c.bench_function("arm_frame", |b| b.iter(|| d.deform(&pose, &drv, &mut out).expect("frame")));
}

criterion_group!(benches, bench);
criterion_main!(benches);
