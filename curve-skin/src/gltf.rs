//! glTF 2.0 export of a skinned character (LBS weights, the only skinning glTF viewers run):
//! one mesh (POSITION, NORMAL, JOINTS_0, WEIGHTS_0, u32 indices), one node per joint with its
//! rest local transform, a skin with inverse bind matrices `rest_world_j⁻¹`, and optionally an
//! animation (per-joint rotation channels and the root translation) sampled from poses. The
//! binary buffer is embedded as a base64 data URI, so the `.gltf` file is self-contained.

use std::path::Path;

use geom_core::anim::skin::SkinSkeleton;
use geom_core::math::Iso3;
use serde_json::{json, Value};

use crate::error::{Result, SkinError};
use crate::poses::SkinPose;
use crate::weights::PackedWeights;

/// Standard base64 (RFC 4648) with padding.
pub fn base64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = ((b[0] as u32) << 16) | ((b[1] as u32) << 8) | b[2] as u32;
        s.push(T[(n >> 18) as usize & 63] as char);
        s.push(T[(n >> 12) as usize & 63] as char);
        s.push(if c.len() > 1 { T[(n >> 6) as usize & 63] as char } else { '=' });
        s.push(if c.len() > 2 { T[n as usize & 63] as char } else { '=' });
    }
    s
}

struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn push(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let off = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let mut v = json!({"buffer": 0, "byteOffset": off, "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    fn accessor(
        &mut self,
        view: usize,
        ctype: u32,
        count: usize,
        ty: &str,
        minmax: Option<(Vec<f64>, Vec<f64>)>,
    ) -> usize {
        let mut a = json!({"bufferView": view, "componentType": ctype, "count": count, "type": ty});
        if let Some((lo, hi)) = minmax {
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn f32s(&mut self, v: &[f32], ty: &str, n: usize, target: Option<u32>, minmax: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.push(&bytes, target);
        let comps = v.len() / n.max(1);
        let mm = if minmax && n > 0 {
            let mut lo = vec![f64::INFINITY; comps];
            let mut hi = vec![f64::NEG_INFINITY; comps];
            for (i, &x) in v.iter().enumerate() {
                lo[i % comps] = lo[i % comps].min(x as f64);
                hi[i % comps] = hi[i % comps].max(x as f64);
            }
            Some((lo, hi))
        } else {
            None
        };
        self.accessor(view, 5126, n, ty, mm)
    }
}

fn local_rest(sk: &SkinSkeleton, j: usize) -> Iso3 {
    match sk.parent[j] {
        Some(p) => sk.rest_world[p].inverse() * sk.rest_world[j],
        None => sk.rest_world[j],
    }
}

fn quat_json(q: &geom_core::math::UnitQuat) -> [f32; 4] {
    [q.i as f32, q.j as f32, q.k as f32, q.w as f32]
}

/// The glTF JSON document of a skinned mesh; `anim` = (times in s, poses) adds one animation.
/// Errors: sizes differ, no joint, more than 65 535 joints.
pub fn to_gltf(
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    tris: &[[u32; 3]],
    sk: &SkinSkeleton,
    weights: &PackedWeights<4>,
    anim: Option<(&[f64], &[SkinPose])>,
) -> Result<Value> {
    let n = positions.len();
    if normals.len() != n {
        return Err(SkinError::Size { what: "glTF normals", expected: n, got: normals.len() });
    }
    if weights.len() != n {
        return Err(SkinError::Size { what: "glTF weights", expected: n, got: weights.len() });
    }
    if sk.is_empty() {
        return Err(SkinError::EmptySkeleton);
    }
    weights.check_bones(sk.len())?;
    let mut b = Builder { bin: Vec::new(), views: Vec::new(), accessors: Vec::new() };
    let flat = |v: &[[f32; 3]]| v.iter().flat_map(|p| p.iter().copied()).collect::<Vec<f32>>();
    let pos = b.f32s(&flat(positions), "VEC3", n, Some(34962), true);
    let nor = b.f32s(&flat(normals), "VEC3", n, Some(34962), false);
    let jb: Vec<u8> = weights.bone.iter().flat_map(|r| r.iter().flat_map(|x| x.to_le_bytes())).collect();
    let jv = b.push(&jb, Some(34962));
    let joints = b.accessor(jv, 5123, n, "VEC4", None);
    let wf: Vec<f32> = weights.w.iter().flat_map(|r| r.iter().copied()).collect();
    let wts = b.f32s(&wf, "VEC4", n, Some(34962), false);
    let ib: Vec<u8> = tris.iter().flat_map(|t| t.iter().flat_map(|x| x.to_le_bytes())).collect();
    let iv = b.push(&ib, Some(34963));
    let idx = b.accessor(iv, 5125, tris.len() * 3, "SCALAR", None);
    // Inverse bind matrices, column-major.
    let ibm: Vec<f32> = sk
        .rest_world
        .iter()
        .flat_map(|w| w.inverse().to_homogeneous().as_slice().iter().map(|&x| x as f32).collect::<Vec<_>>())
        .collect();
    let ibm_acc = b.f32s(&ibm, "MAT4", sk.len(), None, false);

    // Nodes 0..J are the joints, node J is the mesh.
    let children = sk.children();
    let mut nodes: Vec<Value> = (0..sk.len())
        .map(|j| {
            let l = local_rest(sk, j);
            let t = l.translation.vector;
            let mut v = json!({
                "name": sk.names[j],
                "translation": [t.x as f32, t.y as f32, t.z as f32],
                "rotation": quat_json(&l.rotation),
            });
            if !children[j].is_empty() {
                v["children"] = json!(children[j]);
            }
            v
        })
        .collect();
    nodes.push(json!({"name": "skin_mesh", "mesh": 0, "skin": 0}));
    let roots: Vec<usize> = (0..sk.len()).filter(|&j| sk.parent[j].is_none()).collect();
    let mut scene_nodes = roots.clone();
    scene_nodes.push(sk.len());

    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "curve-skin"},
        "scene": 0,
        "scenes": [{"nodes": scene_nodes}],
        "nodes": nodes,
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": pos, "NORMAL": nor, "JOINTS_0": joints, "WEIGHTS_0": wts},
            "indices": idx, "mode": 4
        }]}],
        "skins": [{"joints": (0..sk.len()).collect::<Vec<_>>(), "inverseBindMatrices": ibm_acc, "skeleton": roots[0]}],
    });

    if let Some((times, poses)) = anim {
        if times.len() != poses.len() || times.is_empty() {
            return Err(SkinError::Size { what: "glTF animation poses", expected: times.len(), got: poses.len() });
        }
        let tf: Vec<f32> = times.iter().map(|&t| t as f32).collect();
        let t_acc = {
            let bytes: Vec<u8> = tf.iter().flat_map(|x| x.to_le_bytes()).collect();
            let v = b.push(&bytes, None);
            let lo = tf.iter().copied().fold(f32::INFINITY, f32::min) as f64;
            let hi = tf.iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
            b.accessor(v, 5126, tf.len(), "SCALAR", Some((vec![lo], vec![hi])))
        };
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for j in 0..sk.len() {
            let l = local_rest(sk, j);
            let rot: Vec<f32> = poses.iter().flat_map(|p| quat_json(&(l.rotation * p.rot[j]))).collect();
            let acc = b.f32s(&rot, "VEC4", poses.len(), None, false);
            samplers.push(json!({"input": t_acc, "output": acc, "interpolation": "LINEAR"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": j, "path": "rotation"}}));
        }
        let shift0 = sk.rest_world[0].translation.vector;
        for &r in &roots {
            let tr: Vec<f32> = poses
                .iter()
                .flat_map(|p| {
                    let t = sk.rest_world[r].translation.vector + (p.root_pos - shift0);
                    [t.x as f32, t.y as f32, t.z as f32]
                })
                .collect();
            let acc = b.f32s(&tr, "VEC3", poses.len(), None, false);
            samplers.push(json!({"input": t_acc, "output": acc, "interpolation": "LINEAR"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": r, "path": "translation"}}));
        }
        doc["animations"] = json!([{"name": "clip", "samplers": samplers, "channels": channels}]);
    }
    doc["bufferViews"] = json!(b.views);
    doc["accessors"] = json!(b.accessors);
    doc["buffers"] = json!([{
        "byteLength": b.bin.len(),
        "uri": format!("data:application/octet-stream;base64,{}", base64(&b.bin)),
    }]);
    Ok(doc)
}

/// Writes [`to_gltf`] to `path` (a `.gltf` JSON file). Errors: those of `to_gltf`, and I/O
/// errors naming the path.
pub fn write_gltf(
    path: &Path,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    tris: &[[u32; 3]],
    sk: &SkinSkeleton,
    weights: &PackedWeights<4>,
    anim: Option<(&[f64], &[SkinPose])>,
) -> Result<()> {
    let doc = to_gltf(positions, normals, tris, sk, weights, anim)?;
    let text = serde_json::to_string(&doc).map_err(|e| SkinError::Param(format!("glTF serialisation: {e}")))?;
    std::fs::write(path, text).map_err(|e| SkinError::Core(geom_core::Error::Io(e)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::{cylinder_arm, ramp_weights, Ramp};

    #[test]
    fn base64_known_values() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn document_is_consistent() {
        let (m, sk) = cylinder_arm(0.15, 1.0, 10, 8).unwrap();
        let w2 = ramp_weights(&m.positions, 0.0, 0.15, Ramp::SmoothStep);
        let w = PackedWeights::<4> {
            bone: w2.bone.iter().map(|b| [b[0], b[1], 0, 0]).collect(),
            w: w2.w.iter().map(|x| [x[0], x[1], 0.0, 0.0]).collect(),
        };
        let p = m.positions_f32();
        let nrm: Vec<[f32; 3]> = m.vertex_normals().iter().map(|v| [v.x as f32, v.y as f32, v.z as f32]).collect();
        let poses = vec![SkinPose::rest(&sk); 3];
        let doc = to_gltf(&p, &nrm, &m.tris, &sk, &w, Some((&[0.0, 0.5, 1.0], &poses))).unwrap();
        let len = doc["buffers"][0]["byteLength"].as_u64().unwrap() as usize;
        for v in doc["bufferViews"].as_array().unwrap() {
            let end = v["byteOffset"].as_u64().unwrap() + v["byteLength"].as_u64().unwrap();
            assert!(end as usize <= len);
            assert_eq!(v["byteOffset"].as_u64().unwrap() % 4, 0);
        }
        assert_eq!(doc["accessors"][0]["count"].as_u64().unwrap() as usize, p.len());
        assert_eq!(doc["nodes"].as_array().unwrap().len(), sk.len() + 1);
        assert_eq!(doc["animations"][0]["channels"].as_array().unwrap().len(), sk.len() + 1);
        // Data URI decodes to the declared length.
        let uri = doc["buffers"][0]["uri"].as_str().unwrap();
        let b64 = uri.split(',').nth(1).unwrap();
        assert_eq!(b64.len(), len.div_ceil(3) * 4);
    }
}
