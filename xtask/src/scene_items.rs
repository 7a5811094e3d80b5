//! `scene.json`: the context items of a run (`SceneItem`: obstacles, the floor, pinned vertices,
//! the frame rate) as the experiment recorded them, kept in the run folder so that previews, USD
//! files and the report can be rebuilt from the folder alone.
//!
//! ```json
//! { "items": [ { "mesh": { "name": "obstacle-0", "positions": [[0,0,0], …], "faces": [[0,1,2], …] } },
//!              { "ground": { "y": 0.0 } },
//!              { "pinned": { "sequence": "frames", "vertices": [0, 12] } },
//!              { "frame_rate": { "fps": 30.0 } } ] }
//! ```

use std::path::Path;

use geom_core::math::Pt3;
use geom_core::record::SceneItem;
use serde_json::{json, Value};

use crate::error::{io_err, Error, Result};
use crate::out::write_atomic;

/// The file name inside a run folder.
pub const FILE: &str = "scene.json";

fn item_json(it: &SceneItem) -> Value {
    match it {
        SceneItem::Mesh { name, positions, faces } => json!({ "mesh": {
            "name": name,
            "positions": positions.iter().map(|p| [p.x, p.y, p.z]).collect::<Vec<_>>(),
            "faces": faces,
        }}),
        SceneItem::Ground { y } => json!({ "ground": { "y": y } }),
        SceneItem::Pinned { sequence, vertices } => json!({ "pinned": { "sequence": sequence, "vertices": vertices } }),
        SceneItem::FrameRate { fps } => json!({ "frame_rate": { "fps": fps } }),
    }
}

fn bad(path: &Path, what: &str) -> Error {
    Error::Run(format!("{}: {what}", path.display()))
}

fn item_from(path: &Path, v: &Value) -> Result<SceneItem> {
    let obj = v.as_object().filter(|o| o.len() == 1).ok_or_else(|| bad(path, "an item is not {\"kind\": {…}}"))?;
    let (kind, body) = obj.iter().next().expect("one entry, checked above");
    let num =
        |k: &str| body.get(k).and_then(Value::as_f64).ok_or_else(|| bad(path, &format!("{kind}: no number '{k}'")));
    Ok(match kind.as_str() {
        "mesh" => {
            let positions: Vec<[f64; 3]> =
                serde_json::from_value(body.get("positions").cloned().unwrap_or(Value::Null))
                    .map_err(|e| bad(path, &format!("mesh positions: {e}")))?;
            let faces: Vec<[u32; 3]> = serde_json::from_value(body.get("faces").cloned().unwrap_or(Value::Null))
                .map_err(|e| bad(path, &format!("mesh faces: {e}")))?;
            if let Some(f) = faces.iter().position(|f| f.iter().any(|&i| i as usize >= positions.len())) {
                return Err(bad(path, &format!("mesh face {f} refers to a missing vertex")));
            }
            SceneItem::Mesh {
                name: body.get("name").and_then(Value::as_str).unwrap_or("").to_string(),
                positions: positions.into_iter().map(|p| Pt3::new(p[0], p[1], p[2])).collect(),
                faces,
            }
        }
        "ground" => SceneItem::Ground { y: num("y")? },
        "pinned" => SceneItem::Pinned {
            sequence: body.get("sequence").and_then(Value::as_str).unwrap_or("").to_string(),
            vertices: serde_json::from_value(body.get("vertices").cloned().unwrap_or(Value::Null))
                .map_err(|e| bad(path, &format!("pinned vertices: {e}")))?,
        },
        "frame_rate" => SceneItem::FrameRate { fps: num("fps")? },
        other => return Err(bad(path, &format!("unknown item kind '{other}'"))),
    })
}

/// Writes `dir/scene.json` (nothing when there are no items).
pub fn write(dir: &Path, items: &[SceneItem]) -> Result<()> {
    if items.is_empty() {
        return Ok(());
    }
    let v = json!({ "items": items.iter().map(item_json).collect::<Vec<_>>() });
    let text = serde_json::to_string(&v).map_err(|e| Error::Run(e.to_string()))?;
    write_atomic(&dir.join(FILE), (text + "\n").as_bytes())
}

/// Reads `dir/scene.json` (no items when there is none); a malformed file is an error naming it.
pub fn read(dir: &Path) -> Result<Vec<SceneItem>> {
    let path = dir.join(FILE);
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| bad(&path, &e.to_string()))?;
    let items = v.get("items").and_then(Value::as_array).ok_or_else(|| bad(&path, "no \"items\" list"))?;
    items.iter().map(|i| item_from(&path, i)).collect()
}

/// The recorded frame rate, if any.
pub fn frame_rate(items: &[SceneItem]) -> Option<f64> {
    items.iter().find_map(|i| match i {
        SceneItem::FrameRate { fps } if *fps > 0.0 && fps.is_finite() => Some(*fps),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_round_trip() {
        let dir = std::env::temp_dir().join(format!("xtask-items-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let items = vec![
            SceneItem::Mesh {
                name: "tank".into(),
                positions: vec![Pt3::origin(), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.5, 0.0)],
                faces: vec![[0, 1, 2]],
            },
            SceneItem::Ground { y: -0.25 },
            SceneItem::Pinned { sequence: "frames".into(), vertices: vec![0, 7] },
            SceneItem::FrameRate { fps: 30.0 },
        ];
        write(&dir, &items).unwrap();
        assert_eq!(read(&dir).unwrap(), items);
        assert_eq!(frame_rate(&items), Some(30.0));
        std::fs::write(dir.join(FILE), "{\"items\": [{\"mesh\": {\"positions\": [[0,0,0]], \"faces\": [[0,1,2]]}}]}")
            .unwrap();
        assert!(read(&dir).unwrap_err().to_string().contains("missing vertex"));
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(read(&dir).unwrap().is_empty());
    }
}
