//! Procedural meshes (GEOM-CORE.md §3.6): planar grids, tubes, subdivided boxes and icospheres,
//! used by scenes (the specs are serde types for RON scene files) and by tests.
//!
//! UVs are metres of material space: `u` along the first axis (or around a tube), `v` along the
//! second axis (or along the tube's axis). Every generator validates its parameters and returns
//! [`crate::Error::InvalidParameter`] naming the bad one.

mod boxes;
pub mod character;
mod grid;
mod icosphere;
mod tube;

pub use boxes::box_surface;
pub use grid::{grid, Diagonals, GridSpec, Plane};
pub use icosphere::{icosphere, ICOSPHERE_MAX_LEVEL};
pub use tube::{tube, Caps, TubeSpec};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Pt3, Vec3};

    #[test]
    fn specs_round_trip_through_ron_and_default_missing_fields() {
        let g = GridSpec {
            quads: [3, 4],
            size: [1.5, 2.0],
            plane: Plane::XZ,
            diagonals: Diagonals::Backward,
            center: Pt3::new(0.0, 1.0, 0.0),
        };
        let text = ron::to_string(&g).expect("GridSpec serialises");
        assert_eq!(ron::from_str::<GridSpec>(&text).expect("and parses back"), g);
        let partial: GridSpec = ron::from_str("(quads: (32, 32), plane: XZ)").expect("missing fields default");
        assert_eq!(partial, GridSpec { quads: [32, 32], plane: Plane::XZ, ..GridSpec::default() });
        let t = TubeSpec { axis: Vec3::new(0.0, 1.0, 0.0), caps: Caps::Fan, ..TubeSpec::default() };
        let text = ron::to_string(&t).expect("TubeSpec serialises");
        assert_eq!(ron::from_str::<TubeSpec>(&text).expect("and parses back"), t);
    }

    #[test]
    fn invalid_parameters_are_errors_not_panics() {
        use crate::Error;
        let bad = |r: crate::Result<crate::mesh::TriMesh>| matches!(r, Err(Error::InvalidParameter(_)));
        assert!(bad(grid(&GridSpec { quads: [0, 3], ..Default::default() })));
        assert!(bad(grid(&GridSpec { size: [1.0, f64::NAN], ..Default::default() })));
        assert!(bad(icosphere(-1.0, 1)));
        assert!(bad(icosphere(1.0, ICOSPHERE_MAX_LEVEL + 1)));
        assert!(matches!(tube(&TubeSpec { around: 2, ..Default::default() }), Err(Error::InvalidParameter(_))));
        assert!(matches!(
            tube(&TubeSpec { axis: Vec3::zeros(), ..Default::default() }),
            Err(Error::InvalidParameter(_))
        ));
    }
}
