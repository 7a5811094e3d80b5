//! geom-core's own experiments: they show the foundation working on real input, end to end,
//! with its invariants as figures. Each is `run(&Params, Size, &mut dyn Recorder) ->
//! Result<Report>`, `Params` being the scene file's `params` block.
//!
//! - [`render`]: depth, normal, silhouette and shaded images of procedural meshes.
//! - [`subdivision`]: linear subdivision with its prolongation matrix and the cotangent
//!   Laplacian's identities, level by level.
//! - [`mocap`]: BVH clips through the reader, forward kinematics and a write/read round trip.
//! - [`solvers`]: accuracy against time of the sparse solvers (the `geom-core` benchmark).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::math::{Pt3, Vec3};
use crate::mesh::TriMesh;
use crate::procedural::{self, Diagonals, GridSpec, Plane};

#[cfg(feature = "anim")]
pub mod mocap;
pub mod render;
pub mod solvers;
pub mod subdivision;

/// A mesh a scene can name.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum MeshSource {
    /// `procedural::icosphere(radius, level)`.
    Icosphere {
        /// Radius (m).
        radius: f64,
        /// Subdivision level (20·4^level faces).
        level: u32,
    },
    /// `procedural::box_surface` of the given size (m), centred at the origin.
    Box {
        /// Edge lengths (m).
        size: [f64; 3],
        /// Segments per edge.
        segments: [u32; 3],
    },
    /// A square sheet in the XZ plane with a sinusoidal height field `amplitude·sin(2π x/λ)`.
    WavySheet {
        /// Side (m).
        size: f64,
        /// Quads per side.
        quads: u32,
        /// Height amplitude (m).
        amplitude: f64,
        /// Wavelength λ (m).
        wavelength: f64,
    },
    /// A mesh file (OBJ), relative to the experiment's root folder.
    File(PathBuf),
}

impl MeshSource {
    /// Builds the mesh; `root` is the folder a relative `File` path is taken from.
    pub fn build(&self, root: &Path) -> Result<TriMesh> {
        Ok(match self {
            MeshSource::Icosphere { radius, level } => procedural::icosphere(*radius, *level)?,
            MeshSource::Box { size, segments } => {
                let h = Vec3::new(size[0], size[1], size[2]) * 0.5;
                procedural::box_surface(Pt3::from(-h), Pt3::from(h), *segments, Diagonals::Alternating)?
            }
            MeshSource::WavySheet { size, quads, amplitude, wavelength } => {
                let g = procedural::grid(&GridSpec {
                    quads: [*quads, *quads],
                    size: [*size, *size],
                    plane: Plane::XZ,
                    diagonals: Diagonals::Alternating,
                    center: Pt3::origin(),
                })?;
                let p: Vec<Pt3> = g
                    .positions
                    .iter()
                    .map(|q| Pt3::new(q.x, q.y + amplitude * (std::f64::consts::TAU * q.x / wavelength).sin(), q.z))
                    .collect();
                g.with_positions(p)?
            }
            MeshSource::File(path) => crate::io::obj::read_tri(root.join(path))?,
        })
    }
}
