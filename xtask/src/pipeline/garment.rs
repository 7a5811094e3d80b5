//! The garment stage of `pipeline/character`: a skirt generated from the rig
//! (`shells::garment::skirt`) or a garment OBJ with attached vertices, checked against the body
//! before any simulation, and its coarse skinning (weights transferred from the nearest body
//! points) that drives the attached vertices and serves as the tracking guide.

use std::path::{Path, PathBuf};

use geom_core::anim::JointRole;
use geom_core::collide::MeshQuery;
use geom_core::math::Pt3;
use geom_core::mesh::TriMesh;
use serde::Deserialize;
use shells::garment::{skirt, SkirtSpec};

use super::body::Character;
use crate::error::{Error, Result};

/// Which garment vertices follow the body.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Attach {
    /// These vertex indices.
    Vertices(Vec<u32>),
    /// Every vertex within `radius` (m) of the named rig joint at rest.
    NearJoint {
        /// Joint name of the rig (`hips`, `shoulders`, …).
        joint: String,
        /// Radius (m).
        radius: f64,
    },
}

/// Where the garment comes from.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum GarmentSource {
    /// A skirt from the rig: waist at `waist` of the way from the hips joint to the back
    /// joint, hem at `hem` of the way from the knees up to the hips.
    Skirt {
        /// Waist height as a fraction from hips (0) to back (1).
        waist: f64,
        /// Hem height as a fraction from knees (0) to hips (1).
        hem: f64,
        /// Flare half-angle (degrees).
        flare_deg: f64,
        /// Gap from the body (m).
        clearance: f64,
        /// Vertices around.
        segments: u32,
    },
    /// An OBJ garment in the character file's axes and units.
    Obj {
        /// Path (relative to the scene file).
        path: PathBuf,
        /// The vertices that follow the body.
        attach: Attach,
    },
}

/// A garment in the rig's frame (m) with its attached vertices.
pub struct Garment {
    /// Rest mesh (m).
    pub mesh: TriMesh,
    /// Vertices that follow the body.
    pub attached: Vec<u32>,
}

fn joint_pos(c: &Character, role: JointRole) -> Result<Pt3> {
    let i = c.skeleton.role(role).ok_or_else(|| Error::Run(format!("the rig has no {role:?} joint")))?;
    Ok(Pt3::from(c.skeleton.rest_globals()[i as usize].translation.vector))
}

/// Builds the garment and checks that it starts outside the body (by at least `gap` m).
pub fn build(src: &GarmentSource, c: &Character, gap: f64, resolve: impl Fn(&Path) -> PathBuf) -> Result<Garment> {
    let (g, name) = match src {
        GarmentSource::Skirt { waist, hem, flare_deg, clearance, segments } => {
            let hips = joint_pos(c, JointRole::Root)?;
            let back = joint_pos(c, JointRole::Spine)?;
            let knee = joint_pos(c, JointRole::LeftKnee)?.y.min(joint_pos(c, JointRole::RightKnee)?.y);
            let h = c.mesh.aabb().size().y;
            let spec = SkirtSpec {
                waist_y: hips.y + waist * (back.y - hips.y),
                hem_y: knee + hem * (hips.y - knee),
                axis: [hips.x, hips.z],
                clearance: *clearance,
                flare_deg: *flare_deg,
                segments: *segments,
                reach: 0.2 * h,
            };
            let g = skirt(&c.mesh, &spec).map_err(|e| Error::Run(format!("garment Skirt: {e}")))?;
            (
                Garment { mesh: TriMesh::new(g.positions, g.faces)?, attached: g.attached },
                "the generated skirt".to_string(),
            )
        }
        GarmentSource::Obj { path, attach } => {
            let p = resolve(path);
            let (pos, faces) = crate::cmd_rig::read_soup(&p)?;
            let pos: Vec<Pt3> = pos.iter().map(|x| c.orientation.point_to_canonical(x) * c.scale).collect();
            let mesh = TriMesh::new(pos, faces).map_err(|e| Error::Run(format!("{}: {e}", p.display())))?;
            let n = mesh.n_vertices() as u32;
            let attached: Vec<u32> = match attach {
                Attach::Vertices(v) => {
                    if let Some(bad) = v.iter().find(|&&i| i >= n) {
                        return Err(Error::Run(format!("{}: attached vertex {bad} of {n}", p.display())));
                    }
                    v.clone()
                }
                Attach::NearJoint { joint, radius } => {
                    let j = c.skeleton.find(joint).ok_or_else(|| {
                        Error::Run(format!("{}: attach joint '{joint}' is not in the rig", p.display()))
                    })?;
                    let at = Pt3::from(c.skeleton.rest_globals()[j as usize].translation.vector);
                    (0..n).filter(|&i| (mesh.positions[i as usize] - at).norm() <= *radius).collect()
                }
            };
            (Garment { mesh, attached }, p.display().to_string())
        }
    };
    let q = MeshQuery::new(&c.mesh)?;
    let (worst, v) = g
        .mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| (q.signed_distance(p), i))
        .fold((f64::INFINITY, 0), |a, b| if b.0 < a.0 { b } else { a });
    if worst.is_nan() || worst <= gap {
        return Err(Error::Run(format!(
            "{name}: vertex {v} starts {} the body (signed distance {worst:.4} m; the garment must start at least {gap} m outside it)",
            if worst < 0.0 { "inside" } else { "too close to" }
        )));
    }
    Ok(g)
}

/// Coarse skinning weights of the garment's vertices: each takes the weights of its nearest
/// body point (the barycentric blend of that triangle's vertices' rows), then the rows of the
/// free vertices are smoothed over the garment; the 4 largest are kept and renormalised.
pub fn transfer_weights(c: &Character, garment: &TriMesh, attached: &[u32]) -> Result<Vec<Vec<(u16, f32)>>> {
    let q = MeshQuery::new(&c.mesh)?;
    let rows = super::body::weight_rows(&c.weights);
    let nj = c.skeleton.len();
    // Dense rows: the nearest body point's weights (barycentric blend of its triangle's rows).
    let mut w: Vec<Vec<f32>> = garment
        .positions
        .iter()
        .map(|p| {
            let cl = q.closest(p);
            let t = c.mesh.faces[cl.face as usize];
            let mut row = vec![0f32; nj];
            for k in 0..3 {
                for &(j, x) in &rows[t[k] as usize] {
                    row[j as usize] += x * cl.bary[k] as f32;
                }
            }
            row
        })
        .collect();
    // Coarse: smoothed over the garment (neighbour averaging, `SMOOTH` passes), so that one
    // ring does not split between the two thighs; attached vertices keep their own rows.
    const SMOOTH: usize = 40;
    let edges = garment.topology().edges().to_vec();
    let fixed: std::collections::HashSet<u32> = attached.iter().copied().collect();
    for _ in 0..SMOOTH {
        let mut acc = vec![vec![0f32; nj]; w.len()];
        let mut deg = vec![0f32; w.len()];
        for e in &edges {
            for (a, b) in [(e[0], e[1]), (e[1], e[0])] {
                for j in 0..nj {
                    acc[a as usize][j] += w[b as usize][j];
                }
                deg[a as usize] += 1.0;
            }
        }
        for (v, row) in w.iter_mut().enumerate() {
            if deg[v] > 0.0 && !fixed.contains(&(v as u32)) {
                for j in 0..nj {
                    row[j] = 0.5 * row[j] + 0.5 * acc[v][j] / deg[v];
                }
            }
        }
    }
    Ok(w.iter()
        .map(|row| {
            let mut acc: Vec<(u16, f32)> =
                row.iter().enumerate().filter(|e| *e.1 > 0.0).map(|(j, &x)| (j as u16, x)).collect();
            acc.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            acc.truncate(4);
            let s: f32 = acc.iter().map(|e| e.1).sum();
            acc.iter().map(|&(j, w)| (j, w / s)).collect()
        })
        .collect())
}

/// Moves the attached vertices of every guide frame onto the body: each keeps the point of the
/// body surface nearest to it at rest (its triangle and barycentric coordinates) and its rest
/// distance along that triangle's normal, so the waistband rides at its clearance on the
/// deforming surface instead of being overtaken by it.
pub fn attach_to_body(c: &Character, g: &Garment, body_frames: &[Vec<Pt3>], guide: &mut [Vec<Pt3>]) -> Result<()> {
    let q = MeshQuery::new(&c.mesh)?;
    let embed: Vec<(u32, [f64; 3], f64)> = g
        .attached
        .iter()
        .map(|&v| {
            let (cl, sd) = q.closest_signed(&g.mesh.positions[v as usize]);
            (cl.face, cl.bary, sd)
        })
        .collect();
    for (b, f) in body_frames.iter().zip(guide.iter_mut()) {
        for (&v, &(face, w, d)) in g.attached.iter().zip(&embed) {
            let t = c.mesh.faces[face as usize].map(|i| b[i as usize]);
            let n = (t[1] - t[0]).cross(&(t[2] - t[0])).normalize();
            let p = Pt3::from(w[0] * t[0].coords + w[1] * t[1].coords + w[2] * t[2].coords);
            f[v as usize] = p + d * n;
        }
    }
    Ok(())
}
