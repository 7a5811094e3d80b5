//! Binary glTF 2.0 (`.glb`) writer: static triangle meshes ([`static_glb`]) and one skinned mesh
//! with its joint hierarchy, inverse bind matrices, `JOINTS_0`/`WEIGHTS_0` and an optional
//! animation of joint rotations and root translation ([`skinned_glb`]).
//!
//! The JSON document is built with the `gltf-json` crate (the typed glTF schema of the gltf-rs
//! project), so field names, enums and index types follow the specification; this module lays
//! out the one binary buffer (every view 4-byte aligned) and the GLB container (12-byte header,
//! a JSON chunk padded with spaces, a BIN chunk padded with zeros; glTF 2.0 §4.4).
//!
//! Conventions of glTF, which the caller provides: metres, +Y up, a character facing +Z. Data
//! are written as `f32`. What the Khronos validator checks is done here: `POSITION` has min/max;
//! normals are unit length (recomputed from the faces when not given, zero ones replaced by +Y);
//! each vertex keeps its four largest weights, renormalised in `f32` so the sum is 1 to within
//! `f32` rounding, unused slots carry joint 0 with weight 0; the skinned mesh's node is a scene
//! root without a transform; inverse bind matrices are the inverses of the rest world transforms
//! (rigid, so the last row is exactly `0 0 0 1`); animation times are strictly increasing and
//! rotations unit quaternions.
//!
//! ```
//! use geom_core::io::gltf::{static_glb, StaticMesh};
//! use geom_core::procedural::icosphere;
//! let s = icosphere(0.5, 1).unwrap();
//! let glb = static_glb(&[StaticMesh { name: "ball", positions: &s.positions, faces: &s.faces }]).unwrap();
//! assert_eq!(&glb[0..4], b"glTF");
//! ```

use std::collections::BTreeMap;

use gltf_json as json;
use json::validation::{Checked, USize64};

use crate::anim::skin::{SkinSkeleton, SkinWeights};
use crate::anim::{Motion, Pose, Skeleton};
use crate::error::{Error, Result};
use crate::math::{Iso3, Pt3, UnitQuat, Vec3};
use crate::mesh::{vertex_normals, NormalWeight};

/// One joint of a skinned glTF: its name, parent (earlier index) and local rest transform
/// relative to the parent (for a root: its world rest transform).
#[derive(Clone, Debug, PartialEq)]
pub struct GltfJoint {
    /// Name (written as the node name).
    pub name: String,
    /// Parent joint, always an earlier index; `None` for roots.
    pub parent: Option<usize>,
    /// Local rest translation (m).
    pub translation: Vec3,
    /// Local rest rotation.
    pub rotation: UnitQuat,
}

impl GltfJoint {
    /// The joints of an animation skeleton (`anim::Skeleton`: identity rest rotations, local
    /// translation = offset; a root's translation is its rest position).
    pub fn from_skeleton(s: &Skeleton) -> Vec<GltfJoint> {
        s.joints
            .iter()
            .map(|j| GltfJoint {
                name: j.name.clone(),
                parent: j.parent.map(|p| p as usize),
                translation: j.offset,
                rotation: UnitQuat::identity(),
            })
            .collect()
    }

    /// The joints of a skinning skeleton (local rest transform `rest_world_p⁻¹ · rest_world_j`).
    pub fn from_skin_skeleton(s: &SkinSkeleton) -> Vec<GltfJoint> {
        (0..s.len())
            .map(|j| {
                let local = match s.parent[j] {
                    Some(p) => s.rest_world[p].inverse() * s.rest_world[j],
                    None => s.rest_world[j],
                };
                GltfJoint {
                    name: s.names[j].clone(),
                    parent: s.parent[j],
                    translation: local.translation.vector,
                    rotation: local.rotation,
                }
            })
            .collect()
    }
}

/// An animation: per frame, every joint's local rotation and the local translation of joint 0
/// (its parent-less position, m). Sampled linearly (rotations by slerp) between frames.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfAnimation {
    /// Name.
    pub name: String,
    /// Frame times (s), strictly increasing.
    pub times: Vec<f64>,
    /// Local rotation of every joint, per frame.
    pub rotations: Vec<Vec<UnitQuat>>,
    /// Translation of joint 0 per frame (m).
    pub root_translation: Vec<Vec3>,
}

impl GltfAnimation {
    /// A motion clip on its skeleton (joints as [`GltfJoint::from_skeleton`]): local rotations as
    /// stored, root translation = root world position. Position channels of non-root joints
    /// are not animated.
    pub fn from_motion(m: &Motion, name: &str) -> GltfAnimation {
        let n = m.len();
        GltfAnimation {
            name: name.into(),
            times: (0..n).map(|f| f as f64 * m.frame_time).collect(),
            rotations: (0..n).map(|f| m.frame_rot(f).to_vec()).collect(),
            root_translation: m.root_pos.clone(),
        }
    }

    /// Poses on a skinning skeleton (joints as [`GltfJoint::from_skin_skeleton`]): the posed
    /// local frame is `L⁰_j · R(rot_j)` (`anim::skin::forward_kinematics_local`), so the node
    /// rotation is `L⁰_j.rotation · rot_j`; joint 0 moves to `root_pos` with rotation
    /// `rest_world_0.rotation · rot_0`. Skinning skeletons with several roots are not supported
    /// (the other roots would not follow the root translation).
    pub fn from_skin_poses(s: &SkinSkeleton, times: &[f64], poses: &[Pose], name: &str) -> Result<GltfAnimation> {
        if times.len() != poses.len() {
            return Err(Error::DimensionMismatch { what: "animation times", expected: poses.len(), got: times.len() });
        }
        if s.parent.iter().skip(1).any(|p| p.is_none()) {
            return Err(Error::InvalidParameter("glTF animation: the skinning skeleton has several roots".into()));
        }
        let joints = GltfJoint::from_skin_skeleton(s);
        let mut rotations = Vec::with_capacity(poses.len());
        for p in poses {
            if p.rot.len() != s.len() {
                return Err(Error::DimensionMismatch { what: "pose rotations", expected: s.len(), got: p.rot.len() });
            }
            rotations.push(joints.iter().zip(&p.rot).map(|(j, r)| j.rotation * r).collect());
        }
        Ok(GltfAnimation {
            name: name.into(),
            times: times.to_vec(),
            rotations,
            root_translation: poses.iter().map(|p| p.root_pos).collect(),
        })
    }
}

/// A static triangle mesh.
#[derive(Clone, Copy, Debug)]
pub struct StaticMesh<'a> {
    /// Name of its mesh and node.
    pub name: &'a str,
    /// Vertex positions (m).
    pub positions: &'a [Pt3],
    /// Triangles.
    pub faces: &'a [[u32; 3]],
}

/// A skinned triangle mesh.
#[derive(Clone, Copy, Debug)]
pub struct SkinnedMesh<'a> {
    /// Name of the mesh, its node and the skin.
    pub name: &'a str,
    /// Bind-pose vertex positions (m).
    pub positions: &'a [Pt3],
    /// Triangles.
    pub faces: &'a [[u32; 3]],
    /// The joint hierarchy (parents before children).
    pub joints: &'a [GltfJoint],
    /// Per-vertex weights; joint indices index `joints`.
    pub weights: &'a SkinWeights,
    /// An optional animation of the joints.
    pub animation: Option<&'a GltfAnimation>,
}

/// Buffer, views and accessors under construction.
struct Doc {
    root: json::Root,
    bin: Vec<u8>,
}

fn comp(c: json::accessor::ComponentType) -> Checked<json::accessor::GenericComponentType> {
    Checked::Valid(json::accessor::GenericComponentType(c))
}

/// A primitive's vertex attributes (semantic → accessor).
type Attributes = BTreeMap<Checked<json::mesh::Semantic>, json::Index<json::Accessor>>;

/// One vertex's four strongest joints and their weights.
type Packed4 = (Vec<[u16; 4]>, Vec<[f32; 4]>);

impl Doc {
    fn new() -> Self {
        let root = json::Root {
            asset: json::Asset {
                generator: Some(format!("geom-core {} (gltf-json)", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        };
        Doc { root, bin: Vec::new() }
    }

    /// Appends `bytes` as a new 4-byte aligned view.
    fn view(&mut self, bytes: &[u8], target: Option<json::buffer::Target>) -> json::Index<json::buffer::View> {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let off = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64(bytes.len() as u64),
            byte_offset: Some(USize64(off as u64)),
            byte_stride: None,
            name: None,
            target: target.map(Checked::Valid),
            extensions: Default::default(),
            extras: Default::default(),
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn accessor(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
        c: json::accessor::ComponentType,
        ty: json::accessor::Type,
        count: usize,
        minmax: Option<(Vec<f32>, Vec<f32>)>,
    ) -> json::Index<json::Accessor> {
        let view = self.view(bytes, target);
        let (min, max) = match minmax {
            Some((a, b)) => (Some(json::Value::from(a)), Some(json::Value::from(b))),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64(count as u64),
            component_type: comp(c),
            extensions: Default::default(),
            extras: Default::default(),
            type_: Checked::Valid(ty),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn vec3(
        &mut self,
        v: &[[f32; 3]],
        target: Option<json::buffer::Target>,
        minmax: bool,
    ) -> json::Index<json::Accessor> {
        let mm = minmax.then(|| {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for p in v {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo.to_vec(), hi.to_vec())
        });
        let bytes: Vec<u8> = v.iter().flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes())).collect();
        self.accessor(&bytes, target, json::accessor::ComponentType::F32, json::accessor::Type::Vec3, v.len(), mm)
    }

    fn indices(&mut self, faces: &[[u32; 3]]) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = faces.iter().flat_map(|t| t.iter().flat_map(|i| i.to_le_bytes())).collect();
        self.accessor(
            &bytes,
            Some(json::buffer::Target::ElementArrayBuffer),
            json::accessor::ComponentType::U32,
            json::accessor::Type::Scalar,
            faces.len() * 3,
            None,
        )
    }

    /// Positions, normals and indices of one mesh: the primitive's attributes.
    fn geometry(&mut self, positions: &[Pt3], faces: &[[u32; 3]]) -> Result<(Attributes, json::Index<json::Accessor>)> {
        check_geometry(positions, faces)?;
        let pos: Vec<[f32; 3]> = positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let nrm: Vec<[f32; 3]> = vertex_normals(faces, positions, NormalWeight::Area).iter().map(unit_f32).collect();
        let mut attrs = BTreeMap::new();
        let arr = Some(json::buffer::Target::ArrayBuffer);
        attrs.insert(Checked::Valid(json::mesh::Semantic::Positions), self.vec3(&pos, arr, true));
        attrs.insert(Checked::Valid(json::mesh::Semantic::Normals), self.vec3(&nrm, arr, false));
        let idx = self.indices(faces);
        Ok((attrs, idx))
    }

    fn mesh(
        &mut self,
        name: &str,
        attrs: BTreeMap<Checked<json::mesh::Semantic>, json::Index<json::Accessor>>,
        idx: json::Index<json::Accessor>,
    ) -> json::Index<json::Mesh> {
        self.root.push(json::Mesh {
            extensions: Default::default(),
            extras: Default::default(),
            name: Some(name.into()),
            primitives: vec![json::mesh::Primitive {
                attributes: attrs,
                extensions: Default::default(),
                extras: Default::default(),
                indices: Some(idx),
                material: None,
                mode: Checked::Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        })
    }

    /// The GLB container of the document.
    fn finish(mut self, scene_nodes: Vec<json::Index<json::Node>>) -> Result<Vec<u8>> {
        let scene = self.root.push(json::Scene {
            extensions: Default::default(),
            extras: Default::default(),
            name: None,
            nodes: scene_nodes,
        });
        self.root.scene = Some(scene);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.buffers.push(json::Buffer {
            byte_length: USize64(self.bin.len() as u64),
            name: None,
            uri: None,
            extensions: Default::default(),
            extras: Default::default(),
        });
        let mut text =
            self.root.to_vec().map_err(|e| Error::InvalidParameter(format!("glTF JSON serialisation: {e}")))?;
        while !text.len().is_multiple_of(4) {
            text.push(b' ');
        }
        let total = 12 + 8 + text.len() + 8 + self.bin.len();
        let total32 = u32::try_from(total)
            .map_err(|_| Error::InvalidParameter(format!("glTF: {total} bytes exceed the 4 GiB of a GLB file")))?;
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&total32.to_le_bytes());
        out.extend_from_slice(&(text.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&text);
        out.extend_from_slice(&(self.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&self.bin);
        Ok(out)
    }
}

fn node(name: &str) -> json::Node {
    json::Node {
        camera: None,
        children: None,
        extensions: Default::default(),
        extras: Default::default(),
        matrix: None,
        mesh: None,
        name: Some(name.into()),
        rotation: None,
        scale: None,
        translation: None,
        skin: None,
        weights: None,
    }
}

/// A unit `f32` vector (+Y for a zero or non-finite one).
fn unit_f32(n: &Vec3) -> [f32; 3] {
    let v = [n.x as f32, n.y as f32, n.z as f32];
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if l > 1e-20 && l.is_finite() {
        [v[0] / l, v[1] / l, v[2] / l]
    } else {
        [0.0, 1.0, 0.0]
    }
}

fn quat_f32(q: &UnitQuat) -> [f32; 4] {
    let v = [q.i as f32, q.j as f32, q.k as f32, q.w as f32];
    let l = v.iter().map(|x| x * x).sum::<f32>().sqrt();
    v.map(|x| x / l)
}

fn check_geometry(positions: &[Pt3], faces: &[[u32; 3]]) -> Result<()> {
    if positions.is_empty() || faces.is_empty() {
        return Err(Error::InvalidParameter("glTF: a mesh needs vertices and triangles".into()));
    }
    if let Some(v) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite() && c.abs() < f32::MAX as f64)) {
        return Err(Error::NonFiniteVertex { vertex: v as u32 });
    }
    for (f, t) in faces.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(Error::IndexOutOfRange { face: f as u32, vertex: v });
        }
    }
    Ok(())
}

/// Static meshes, each on its own node at the scene root, as GLB bytes. Errors: an empty mesh,
/// non-finite positions, out-of-range indices.
pub fn static_glb(meshes: &[StaticMesh]) -> Result<Vec<u8>> {
    let mut d = Doc::new();
    let mut nodes = Vec::new();
    for m in meshes {
        let (attrs, idx) = d.geometry(m.positions, m.faces)?;
        let mesh = d.mesh(m.name, attrs, idx);
        nodes.push(d.root.push(json::Node { mesh: Some(mesh), ..node(m.name) }));
    }
    d.finish(nodes)
}

/// Four largest weights of every vertex, renormalised in `f32` (the largest absorbs the rounding
/// so that the `f32` sum is as close to 1 as it gets); unused slots are joint 0 with weight 0.
fn pack4(w: &SkinWeights, n: usize, joints: usize) -> Result<Packed4> {
    if w.len() != n {
        return Err(Error::DimensionMismatch { what: "skin weight rows", expected: n, got: w.len() });
    }
    let mut js = Vec::with_capacity(n);
    let mut ws = Vec::with_capacity(n);
    for v in 0..n {
        let (j, x) = w.row(v);
        let mut row: Vec<(u16, f32)> = j.iter().copied().zip(x.iter().copied()).filter(|&(_, x)| x > 0.0).collect();
        if let Some(&(bad, _)) = row.iter().find(|&&(j, _)| j as usize >= joints) {
            return Err(Error::InvalidParameter(format!("skin weights: vertex {v} names joint {bad} of {joints}")));
        }
        if row.iter().any(|(_, x)| !x.is_finite()) {
            return Err(Error::NonFinite("skin weights"));
        }
        row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        row.truncate(4);
        let sum: f64 = row.iter().map(|&(_, x)| x as f64).sum();
        if sum.is_nan() || sum <= 0.0 {
            return Err(Error::InvalidParameter(format!("skin weights: vertex {v} has no positive weight")));
        }
        let mut jj = [0u16; 4];
        let mut ww = [0f32; 4];
        for (k, &(j, x)) in row.iter().enumerate() {
            jj[k] = j;
            ww[k] = (x as f64 / sum) as f32;
        }
        let rest: f32 = ww[1..].iter().sum();
        ww[0] = 1.0 - rest;
        js.push(jj);
        ws.push(ww);
    }
    Ok((js, ws))
}

/// World rest transforms of the joints (parents first).
fn rest_world(joints: &[GltfJoint]) -> Result<Vec<Iso3>> {
    let mut out: Vec<Iso3> = Vec::with_capacity(joints.len());
    for (j, jt) in joints.iter().enumerate() {
        let local = Iso3::from_parts(nalgebra::Translation3::from(jt.translation), jt.rotation);
        out.push(match jt.parent {
            None => local,
            Some(p) if p < j => out[p] * local,
            Some(p) => {
                return Err(Error::InvalidParameter(format!(
                    "glTF joint {j} ('{}') has parent {p}: parents must come first",
                    jt.name
                )))
            }
        });
    }
    Ok(out)
}

/// One skinned mesh with its joints, skin and optional animation, as GLB bytes. Errors: an
/// empty mesh or skeleton, more than 65 536 joints, non-finite data, joint parents out of order,
/// a weight row count different from the vertex count, a vertex without positive weight, an
/// animation whose sizes do not match or whose times are not strictly increasing.
pub fn skinned_glb(m: &SkinnedMesh) -> Result<Vec<u8>> {
    let nj = m.joints.len();
    if nj == 0 || nj > u16::MAX as usize + 1 {
        return Err(Error::InvalidParameter(format!("glTF skin: {nj} joints (1 … 65536 supported)")));
    }
    let world = rest_world(m.joints)?;
    if world.iter().any(|w| !w.to_homogeneous().iter().all(|c| c.is_finite())) {
        return Err(Error::NonFinite("glTF joint rest transforms"));
    }
    let (js, ws) = pack4(m.weights, m.positions.len(), nj)?;
    let mut d = Doc::new();
    let (mut attrs, idx) = d.geometry(m.positions, m.faces)?;
    let arr = Some(json::buffer::Target::ArrayBuffer);
    let jb: Vec<u8> = js.iter().flat_map(|r| r.iter().flat_map(|x| x.to_le_bytes())).collect();
    let ja = d.accessor(&jb, arr, json::accessor::ComponentType::U16, json::accessor::Type::Vec4, js.len(), None);
    let wb: Vec<u8> = ws.iter().flat_map(|r| r.iter().flat_map(|x| x.to_le_bytes())).collect();
    let wa = d.accessor(&wb, arr, json::accessor::ComponentType::F32, json::accessor::Type::Vec4, ws.len(), None);
    attrs.insert(Checked::Valid(json::mesh::Semantic::Joints(0)), ja);
    attrs.insert(Checked::Valid(json::mesh::Semantic::Weights(0)), wa);
    let mesh = d.mesh(m.name, attrs, idx);
    // Joint nodes first (node j = joint j), then the mesh node.
    let mut children: Vec<Vec<json::Index<json::Node>>> = vec![Vec::new(); nj];
    for (j, jt) in m.joints.iter().enumerate() {
        if let Some(p) = jt.parent {
            children[p].push(json::Index::new(j as u32));
        }
    }
    for (j, jt) in m.joints.iter().enumerate() {
        let t = jt.translation;
        let c = std::mem::take(&mut children[j]);
        d.root.push(json::Node {
            children: (!c.is_empty()).then_some(c),
            translation: Some([t.x as f32, t.y as f32, t.z as f32]),
            rotation: Some(json::scene::UnitQuaternion(quat_f32(&jt.rotation))),
            ..node(&jt.name)
        });
    }
    let ibm: Vec<u8> = world
        .iter()
        .flat_map(|w| {
            let mut a = w.inverse().to_homogeneous();
            // Rigid: the last row is exactly 0 0 0 1.
            a[(3, 0)] = 0.0;
            a[(3, 1)] = 0.0;
            a[(3, 2)] = 0.0;
            a[(3, 3)] = 1.0;
            a.as_slice().iter().flat_map(|x| (*x as f32).to_le_bytes()).collect::<Vec<u8>>()
        })
        .collect();
    let ibm = d.accessor(&ibm, None, json::accessor::ComponentType::F32, json::accessor::Type::Mat4, nj, None);
    let roots: Vec<json::Index<json::Node>> =
        (0..nj).filter(|&j| m.joints[j].parent.is_none()).map(|j| json::Index::new(j as u32)).collect();
    let skin = d.root.push(json::Skin {
        extensions: Default::default(),
        extras: Default::default(),
        inverse_bind_matrices: Some(ibm),
        joints: (0..nj).map(|j| json::Index::new(j as u32)).collect(),
        name: Some(m.name.into()),
        skeleton: (roots.len() == 1).then(|| roots[0]),
    });
    let mesh_node = d.root.push(json::Node { mesh: Some(mesh), skin: Some(skin), ..node(m.name) });
    if let Some(a) = m.animation {
        animation(&mut d, a, nj)?;
    }
    let mut scene_nodes = roots;
    scene_nodes.push(mesh_node);
    d.finish(scene_nodes)
}

fn animation(d: &mut Doc, a: &GltfAnimation, nj: usize) -> Result<()> {
    let n = a.times.len();
    if n == 0 || a.rotations.len() != n || a.root_translation.len() != n {
        return Err(Error::DimensionMismatch {
            what: "glTF animation frames (times, rotations, root translations)",
            expected: n,
            got: a.rotations.len().min(a.root_translation.len()),
        });
    }
    if let Some(f) = a.rotations.iter().position(|r| r.len() != nj) {
        return Err(Error::DimensionMismatch {
            what: "glTF animation rotations",
            expected: nj,
            got: a.rotations[f].len(),
        });
    }
    let t: Vec<f32> = a.times.iter().map(|&x| x as f32).collect();
    if !t.iter().all(|x| x.is_finite())
        || t.windows(2).any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        return Err(Error::InvalidParameter("glTF animation: times must be finite and strictly increasing".into()));
    }
    if a.root_translation.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
        return Err(Error::NonFinite("glTF animation root translation"));
    }
    let tb: Vec<u8> = t.iter().flat_map(|x| x.to_le_bytes()).collect();
    let input = d.accessor(
        &tb,
        None,
        json::accessor::ComponentType::F32,
        json::accessor::Type::Scalar,
        n,
        Some((vec![t[0]], vec![t[n - 1]])),
    );
    let mut samplers = Vec::new();
    let mut channels = Vec::new();
    let mut add = |d: &mut Doc, bytes: Vec<u8>, ty, node: usize, path| {
        let output = d.accessor(&bytes, None, json::accessor::ComponentType::F32, ty, n, None);
        channels.push(json::animation::Channel {
            sampler: json::Index::new(samplers.len() as u32),
            target: json::animation::Target {
                extensions: Default::default(),
                extras: Default::default(),
                node: json::Index::new(node as u32),
                path: Checked::Valid(path),
            },
            extensions: Default::default(),
            extras: Default::default(),
        });
        samplers.push(json::animation::Sampler {
            extensions: Default::default(),
            extras: Default::default(),
            input,
            interpolation: Checked::Valid(json::animation::Interpolation::Linear),
            output,
        });
    };
    let tr: Vec<u8> = a
        .root_translation
        .iter()
        .flat_map(|v| [v.x as f32, v.y as f32, v.z as f32])
        .flat_map(|x| x.to_le_bytes())
        .collect();
    add(d, tr, json::accessor::Type::Vec3, 0, json::animation::Property::Translation);
    for j in 0..nj {
        let mut prev: Option<UnitQuat> = None;
        let mut bytes = Vec::with_capacity(16 * n);
        for f in 0..n {
            let mut q = a.rotations[f][j];
            if !q.coords.iter().all(|c| c.is_finite()) {
                return Err(Error::NonFinite("glTF animation rotation"));
            }
            // Same hemisphere as the previous key, so linear interpolation takes the short way.
            if prev.is_some_and(|p| p.coords.dot(&q.coords) < 0.0) {
                q = UnitQuat::new_unchecked(-q.into_inner());
            }
            prev = Some(q);
            bytes.extend(quat_f32(&q).iter().flat_map(|x| x.to_le_bytes()));
        }
        add(d, bytes, json::accessor::Type::Vec4, j, json::animation::Property::Rotation);
    }
    d.root.push(json::Animation {
        extensions: Default::default(),
        extras: Default::default(),
        channels,
        name: Some(a.name.clone()),
        samplers,
    });
    Ok(())
}

/// The triangles of a binary glTF file (`.glb`): every triangle primitive (mode 4) of every mesh
/// node of the default scene (the first scene, else every root node), with the nodes' transforms
/// applied, as one soup in the file's units (vertices are not welded). Errors name the byte
/// offset or the JSON pointer of what is wrong: not a GLB, a truncated chunk, a missing buffer,
/// an accessor outside its view, non-float positions, indices out of range.
pub fn read_glb_triangles(bytes: &[u8]) -> Result<(Vec<Pt3>, Vec<[u32; 3]>)> {
    let perr = |msg: String| Error::Parse { format: "glb", line: 0, msg };
    let u32_at = |o: usize| -> Result<u32> {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| perr(format!("truncated at byte {o}")))
    };
    if bytes.get(0..4) != Some(b"glTF") {
        return Err(perr("not a binary glTF file (no 'glTF' magic at byte 0)".into()));
    }
    if u32_at(4)? != 2 {
        return Err(perr(format!("container version {} (only 2 is supported)", u32_at(4)?)));
    }
    let json_len = u32_at(12)? as usize;
    if bytes.get(16..20) != Some(b"JSON") {
        return Err(perr("the first chunk (byte 16) is not JSON".into()));
    }
    let text = bytes.get(20..20 + json_len).ok_or_else(|| perr(format!("JSON chunk of {json_len} bytes truncated")))?;
    let root = json::Root::from_slice(text).map_err(|e| perr(format!("JSON chunk: {e}")))?;
    let bin_at = 20 + json_len;
    let bin: &[u8] = if bytes.len() >= bin_at + 8 && &bytes[bin_at + 4..bin_at + 8] == b"BIN\0" {
        let n = u32_at(bin_at)? as usize;
        bytes.get(bin_at + 8..bin_at + 8 + n).ok_or_else(|| perr(format!("BIN chunk of {n} bytes truncated")))?
    } else {
        &[]
    };
    // The bytes of accessor `a`: (data, element stride, count).
    let view_of = |a: usize| -> Result<(&[u8], usize, usize, json::accessor::ComponentType, json::accessor::Type)> {
        let acc = root.accessors.get(a).ok_or_else(|| perr(format!("/accessors/{a} does not exist")))?;
        let (Checked::Valid(ct), Checked::Valid(ty)) = (&acc.component_type, &acc.type_) else {
            return Err(perr(format!("/accessors/{a}: invalid type")));
        };
        let vi = acc.buffer_view.ok_or_else(|| perr(format!("/accessors/{a}: no bufferView (sparse-only data)")))?;
        let v =
            root.buffer_views.get(vi.value()).ok_or_else(|| perr(format!("/bufferViews/{} missing", vi.value())))?;
        if v.buffer.value() != 0 || root.buffers.first().is_some_and(|b| b.uri.is_some()) {
            return Err(perr(format!("/bufferViews/{}: data outside the GLB's BIN chunk", vi.value())));
        }
        let elem = ct.0.size() * ty.multiplicity();
        let stride = v.byte_stride.map(|s| s.0).unwrap_or(elem);
        let start =
            v.byte_offset.map(|o| o.0 as usize).unwrap_or(0) + acc.byte_offset.map(|o| o.0 as usize).unwrap_or(0);
        let count = acc.count.0 as usize;
        let end = start + if count == 0 { 0 } else { stride * (count - 1) + elem };
        let view_end = v.byte_offset.map(|o| o.0 as usize).unwrap_or(0) + v.byte_length.0 as usize;
        if end > view_end || end > bin.len() {
            return Err(perr(format!("/accessors/{a}: {count} elements run past the end of their data")));
        }
        Ok((&bin[start..], stride, count, ct.0, *ty))
    };
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    let mut stack: Vec<(usize, nalgebra::Matrix4<f64>)> =
        match root.scene.or(root.scenes.first().map(|_| json::Index::new(0))) {
            Some(sc) => root
                .scenes
                .get(sc.value())
                .ok_or_else(|| perr(format!("/scenes/{} missing", sc.value())))?
                .nodes
                .iter()
                .map(|n| (n.value(), nalgebra::Matrix4::identity()))
                .collect(),
            None => {
                let mut child = vec![false; root.nodes.len()];
                for n in &root.nodes {
                    for c in n.children.iter().flatten() {
                        if let Some(x) = child.get_mut(c.value()) {
                            *x = true;
                        }
                    }
                }
                (0..root.nodes.len()).filter(|&i| !child[i]).map(|i| (i, nalgebra::Matrix4::identity())).collect()
            }
        };
    let mut visited = 0usize;
    while let Some((ni, parent)) = stack.pop() {
        visited += 1;
        if visited > 1_000_000 {
            return Err(perr("the node hierarchy has a cycle".into()));
        }
        let n = root.nodes.get(ni).ok_or_else(|| perr(format!("/nodes/{ni} does not exist")))?;
        let local = match n.matrix {
            Some(m) => nalgebra::Matrix4::from_column_slice(&m.map(|x| x as f64)),
            None => {
                let t = n.translation.unwrap_or([0.0; 3]);
                let r = n.rotation.map(|q| q.0).unwrap_or([0.0, 0.0, 0.0, 1.0]);
                let s = n.scale.unwrap_or([1.0; 3]);
                let q = UnitQuat::new_normalize(nalgebra::Quaternion::new(
                    r[3] as f64,
                    r[0] as f64,
                    r[1] as f64,
                    r[2] as f64,
                ));
                nalgebra::Matrix4::new_translation(&Vec3::new(t[0] as f64, t[1] as f64, t[2] as f64))
                    * q.to_homogeneous()
                    * nalgebra::Matrix4::new_nonuniform_scaling(&Vec3::new(s[0] as f64, s[1] as f64, s[2] as f64))
            }
        };
        let world = parent * local;
        for c in n.children.iter().flatten() {
            stack.push((c.value(), world));
        }
        let Some(mi) = n.mesh else { continue };
        let mesh = root.meshes.get(mi.value()).ok_or_else(|| perr(format!("/meshes/{} does not exist", mi.value())))?;
        for (pi, p) in mesh.primitives.iter().enumerate() {
            if p.mode != Checked::Valid(json::mesh::Mode::Triangles) {
                continue;
            }
            let pa = p
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions))
                .ok_or_else(|| perr(format!("/meshes/{}/primitives/{pi}: no POSITION attribute", mi.value())))?;
            let (data, stride, count, ct, ty) = view_of(pa.value())?;
            if ct != json::accessor::ComponentType::F32 || ty != json::accessor::Type::Vec3 {
                return Err(perr(format!("/accessors/{}: POSITION must be float VEC3", pa.value())));
            }
            let base = positions.len() as u32;
            for k in 0..count {
                let e = &data[k * stride..k * stride + 12];
                let c = |i: usize| f32::from_le_bytes([e[4 * i], e[4 * i + 1], e[4 * i + 2], e[4 * i + 3]]) as f64;
                let q = world.transform_point(&Pt3::new(c(0), c(1), c(2)));
                positions.push(q);
            }
            let idx: Vec<u32> = match p.indices {
                None => (0..count as u32).collect(),
                Some(ia) => {
                    let (d, st, n, ct, _) = view_of(ia.value())?;
                    (0..n)
                        .map(|k| {
                            let e = &d[k * st..];
                            match ct {
                                json::accessor::ComponentType::U8 => Ok(e[0] as u32),
                                json::accessor::ComponentType::U16 => Ok(u16::from_le_bytes([e[0], e[1]]) as u32),
                                json::accessor::ComponentType::U32 => Ok(u32::from_le_bytes([e[0], e[1], e[2], e[3]])),
                                _ => Err(perr(format!("/accessors/{}: indices must be unsigned integers", ia.value()))),
                            }
                        })
                        .collect::<Result<_>>()?
                }
            };
            if let Some(bad) = idx.iter().find(|&&i| i as usize >= count) {
                return Err(perr(format!("/meshes/{}/primitives/{pi}: index {bad} ≥ {count} vertices", mi.value())));
            }
            faces.extend(idx.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
        }
    }
    if faces.is_empty() {
        return Err(perr("no triangle primitive in the file's scene".into()));
    }
    Ok((positions, faces))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::anim::skin::SkinWeights;
    use crate::procedural::icosphere;

    /// The JSON chunk of a GLB, parsed.
    fn json_of(glb: &[u8]) -> json::Root {
        assert_eq!(&glb[0..4], b"glTF");
        assert_eq!(u32::from_le_bytes(glb[4..8].try_into().unwrap()), 2);
        assert_eq!(u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize, glb.len());
        let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        assert_eq!(len % 4, 0);
        let bin_len = u32::from_le_bytes(glb[20 + len..24 + len].try_into().unwrap()) as usize;
        assert_eq!(&glb[24 + len..28 + len], b"BIN\0");
        assert_eq!(28 + len + bin_len, glb.len());
        json::Root::from_slice(&glb[20..20 + len]).unwrap()
    }

    #[test]
    fn static_mesh_layout() {
        let s = icosphere(0.5, 1).unwrap();
        let glb = static_glb(&[StaticMesh { name: "ball", positions: &s.positions, faces: &s.faces }]).unwrap();
        let r = json_of(&glb);
        assert_eq!(r.meshes.len(), 1);
        assert_eq!(r.nodes.len(), 1);
        let pos = &r.accessors[0];
        assert_eq!(pos.count.0 as usize, s.positions.len());
        assert!(pos.min.is_some() && pos.max.is_some());
        assert_eq!(r.accessors[2].count.0 as usize, 3 * s.faces.len());
        assert!(static_glb(&[StaticMesh { name: "x", positions: &s.positions, faces: &[[0, 1, 9999]] }]).is_err());
        let mut bad = s.positions.clone();
        bad[3].x = f64::NAN;
        assert!(static_glb(&[StaticMesh { name: "x", positions: &bad, faces: &s.faces }]).is_err());
    }

    #[test]
    fn glb_triangles_read_back() {
        let s = icosphere(0.5, 1).unwrap();
        let glb = static_glb(&[StaticMesh { name: "ball", positions: &s.positions, faces: &s.faces }]).unwrap();
        let (p, f) = read_glb_triangles(&glb).unwrap();
        assert_eq!(f, s.faces);
        for (a, b) in p.iter().zip(&s.positions) {
            assert!((a - b).norm() < 1e-7);
        }
        assert!(read_glb_triangles(b"glTF").is_err());
        assert!(read_glb_triangles(&glb[..glb.len() / 2]).is_err());
        assert!(read_glb_triangles(b"hello world, not a glb").is_err());
    }

    #[test]
    fn skinned_mesh_with_animation() {
        let s = icosphere(0.5, 1).unwrap();
        let sk = Skeleton::from_joint_positions(
            &["root".to_string(), "tip".to_string()],
            &[None, Some(0)],
            &[Pt3::new(0.0, -0.5, 0.0), Pt3::new(0.0, 0.5, 0.0)],
        )
        .unwrap();
        let joints = GltfJoint::from_skeleton(&sk);
        let rows: Vec<Vec<(u16, f32)>> =
            s.positions.iter().map(|p| vec![(0, (0.5 - p.y) as f32 + 1e-3), (1, (0.5 + p.y) as f32 + 1e-3)]).collect();
        let w = SkinWeights::from_rows(&rows).unwrap();
        let times = vec![0.0, 0.5, 1.0];
        let rot = |a: f64| vec![UnitQuat::identity(), UnitQuat::from_axis_angle(&Vec3::z_axis(), a)];
        let anim = GltfAnimation {
            name: "bend".into(),
            times: times.clone(),
            rotations: vec![rot(0.0), rot(0.5), rot(1.0)],
            root_translation: vec![Vec3::new(0.0, -0.5, 0.0); 3],
        };
        let m = SkinnedMesh {
            name: "ball",
            positions: &s.positions,
            faces: &s.faces,
            joints: &joints,
            weights: &w,
            animation: Some(&anim),
        };
        let glb = skinned_glb(&m).unwrap();
        let r = json_of(&glb);
        assert_eq!(r.skins.len(), 1);
        assert_eq!(r.skins[0].joints.len(), 2);
        assert_eq!(r.animations[0].channels.len(), 3);
        assert_eq!(r.nodes.len(), 3);
        // Weight rows in the file sum to 1 in f32.
        let bin_start = glb.len() - {
            let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
            glb.len() - 28 - len
        };
        let wv = &r.buffer_views[r.accessors[4].buffer_view.unwrap().value()];
        let off = bin_start + wv.byte_offset.unwrap().0 as usize;
        for v in 0..s.positions.len() {
            let x: Vec<f32> = (0..4)
                .map(|k| f32::from_le_bytes(glb[off + 16 * v + 4 * k..off + 16 * v + 4 * k + 4].try_into().unwrap()))
                .collect();
            assert!((x.iter().sum::<f32>() - 1.0).abs() <= 2.0 * f32::EPSILON, "{x:?}");
        }
        // Bad input: times not increasing, wrong rotation count, weights of another mesh.
        let bad = GltfAnimation { times: vec![0.0, 0.0, 1.0], ..anim.clone() };
        assert!(skinned_glb(&SkinnedMesh { animation: Some(&bad), ..m }).is_err());
        let bad = GltfAnimation { rotations: vec![vec![UnitQuat::identity()]; 3], ..anim.clone() };
        assert!(skinned_glb(&SkinnedMesh { animation: Some(&bad), ..m }).is_err());
        let w2 = SkinWeights::from_rows(&rows[..5]).unwrap();
        assert!(skinned_glb(&SkinnedMesh { weights: &w2, ..m }).is_err());
    }
}
