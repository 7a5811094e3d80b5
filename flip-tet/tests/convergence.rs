//! Spec §7 convergence tests (work in progress).

use flip_tet::bcc::tetrahedralize;
use flip_tet::octree::{Octree, OctreeSpec};
use geom_core::math::Pt3;

#[test]
fn probe_timing() {
    for n in [8u32, 16, 32] {
        let t0 = std::time::Instant::now();
        let sp = OctreeSpec::new(Pt3::origin(), Pt3::new(1.0, 1.0, 1.0), n, n).unwrap();
        let m = tetrahedralize(&Octree::uniform(sp, 0)).unwrap();
        println!("n {n}: {} nodes {} tets {:?}", m.nodes.len(), m.tets.len(), t0.elapsed());
    }
}
