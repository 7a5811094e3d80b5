//! §7 tests 5 and 6: rigid-motion invariance of the element energies, zero net force and torque
//! per element, and the rest state as an equilibrium.

use geom_core::math::{Pt3, UnitQuat, Vec3};
use geom_core::rng::Rng;
use shells::kernels::bending::{bending_element, Hinge};
use shells::kernels::membrane::{membrane_element, Membrane, TriRest};
use shells::{hinge_angle, HessianMode};

fn rigid(rng: &mut Rng) -> (UnitQuat, Vec3) {
    let axis = nalgebra::Unit::new_normalize(rng.unit_vec3());
    (UnitQuat::from_axis_angle(&axis, rng.range(-3.0, 3.0)), 5.0 * rng.unit_vec3())
}

fn rp(rng: &mut Rng) -> Pt3 {
    Pt3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))
}

#[test]
fn invariance() {
    let mut rng = Rng::new(21);
    let laws = [
        Membrane::isotropic(1000.0, 0.3),
        Membrane::orthotropic(900.0, 300.0, 80.0, 50.0),
        Membrane::Softened { mu: 300.0, lambda: 100.0, s: 0.2 },
    ];
    for _ in 0..200 {
        // Membrane.
        let x0 = [Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.1, 0.0), Pt3::new(0.2, 0.9, 0.0)];
        let t = TriRest::new(&x0, None).expect("non-degenerate");
        let x: [Pt3; 3] = x0.map(|p| p + 0.3 * (rp(&mut rng) - Pt3::origin()));
        let (r, tr) = rigid(&mut rng);
        let y = x.map(|p| r * p + tr);
        for law in &laws {
            let (e, g, _) = membrane_element(&t, law, &x, HessianMode::Full);
            let (ey, _, _) = membrane_element(&t, law, &y, HessianMode::Full);
            assert!((e - ey).abs() <= 1e-12 * e.abs().max(1e-12), "{e} {ey}");
            let f: Vec<Vec3> = (0..3).map(|a| -g.fixed_rows::<3>(3 * a).into_owned()).collect();
            let scale = f.iter().map(|v| v.norm()).fold(0.0, f64::max).max(1e-300);
            assert!(f.iter().sum::<Vec3>().norm() <= 1e-10 * scale);
            let torque: Vec3 = (0..3).map(|a| x[a].coords.cross(&f[a])).sum();
            assert!(torque.norm() <= 1e-10 * scale);
        }
        // Bending.
        let hx = [rp(&mut rng), rp(&mut rng), rp(&mut rng), rp(&mut rng)];
        if shells::kernels::hinge::hinge_is_collapsed(&hx) {
            continue;
        }
        let h = Hinge { v: [0, 1, 2, 3], rest_theta: 0.3, weight: 2.0, stiffness: 0.5, edge_len: 1.0, area_sum: 1.0 };
        let hy = hx.map(|p| r * p + tr);
        let (e, g, _) = bending_element(&h, &hx, HessianMode::Full);
        let (ey, _, _) = bending_element(&h, &hy, HessianMode::Full);
        assert!((e - ey).abs() <= 1e-12 * e.abs().max(1e-12));
        let f: Vec<Vec3> = (0..4).map(|a| -g.fixed_rows::<3>(3 * a).into_owned()).collect();
        let scale = f.iter().map(|v| v.norm()).fold(0.0, f64::max).max(1e-300);
        assert!(f.iter().sum::<Vec3>().norm() <= 1e-10 * scale);
        let torque: Vec3 = (0..4).map(|a| hx[a].coords.cross(&f[a])).sum();
        assert!(torque.norm() <= 1e-10 * scale, "{}", torque.norm() / scale);
    }
}

#[test]
fn rest_is_equilibrium() {
    let mut rng = Rng::new(22);
    for _ in 0..100 {
        let x = [rp(&mut rng), rp(&mut rng), rp(&mut rng)];
        if let Some(t) = TriRest::new(&x, None) {
            let (e, g, _) = membrane_element(&t, &Membrane::isotropic(2000.0, 0.3), &x, HessianMode::Full);
            assert!(e.abs() <= 1e-12 && g.amax() <= 1e-12 * 2000.0);
        }
        let hx = [rp(&mut rng), rp(&mut rng), rp(&mut rng), rp(&mut rng)];
        let h = Hinge {
            v: [0, 1, 2, 3],
            rest_theta: hinge_angle(&hx),
            weight: 2.0,
            stiffness: 0.5,
            edge_len: 1.0,
            area_sum: 1.0,
        };
        let (e, g, _) = bending_element(&h, &hx, HessianMode::Full);
        assert_eq!(e, 0.0);
        assert_eq!(g.amax(), 0.0);
    }
}
