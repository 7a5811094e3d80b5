//! Rendered PNG snapshots of the liquid surface of the dynamic flip-tet scenes (issue 5: "surfaces
//! written as OBJ/PLY per frame, with rendered PNG snapshots in the report").
//!
//! Four frames per run — the first, the last and two in between — are shaded with geom-core's
//! software rasteriser (Lambert, one directional light, gray on black) from one fixed camera per
//! scene, written as `snapshots/frame_NNNN.png` as the run reaches them (a long run that stops
//! keeps the ones it rendered), and side by side as `surface_snapshots.png` at the end, which the
//! report embeds.

use std::path::{Path, PathBuf};

use flip_tet::scene::Scene;
use flip_tet::sim::FlipTetSim;
use geom_core::image::{write_png_gray8, ImageF32};
use geom_core::math::{Pt3, Vec3};
use geom_core::raster::{lambert_preview, Camera, RasterOptions};

use crate::error::Result;

/// Width and height of one snapshot (pixels).
const SIZE: (u32, u32) = (480, 320);
/// Gap between the snapshots of the strip (pixels).
const GAP: u32 = 4;

/// The snapshots of one run.
pub(crate) struct Snapshots {
    /// Frame numbers to render, ascending.
    frames: Vec<u64>,
    cam: Camera,
    dir: PathBuf,
    out: PathBuf,
    images: Vec<ImageF32>,
}

impl Snapshots {
    /// Frames `0, F/3, 2F/3, F` of the `F = round(duration · fps)` frames; camera looking at the
    /// domain centre from the front-right-above direction `(0.45, 0.55, 1)` at 1.2 domain
    /// diagonals (the thin `z` slab of the dam break is seen from its open side).
    pub(crate) fn new(scene: &Scene, out: &Path) -> Result<Self> {
        let last = (scene.duration * scene.fps).round().max(0.0) as u64;
        let mut frames = vec![0, last / 3, (2 * last) / 3, last];
        frames.dedup();
        let (lo, hi) = (scene.min(), scene.max());
        let target = Pt3::from((lo.coords + hi.coords) / 2.0);
        let eye = target + Vec3::new(0.45, 0.55, 1.0).normalize() * (1.2 * (hi - lo).norm());
        let cam = Camera::look_at(&eye, &target, &Vec3::y(), 35.0, SIZE.0, SIZE.1)?;
        Ok(Self { frames, cam, dir: out.join("snapshots"), out: out.to_path_buf(), images: Vec::new() })
    }

    /// Renders `frame` if it is one of the chosen frames (an empty surface gives a black image).
    pub(crate) fn frame(&mut self, sim: &FlipTetSim, frame: u64) -> Result<()> {
        if !self.frames.contains(&frame) {
            return Ok(());
        }
        let img = match sim.surface() {
            Some(m) if m.n_faces() > 0 => lambert_preview(
                &self.cam,
                &m.positions,
                &m.faces,
                &Vec3::new(0.3, 1.0, 0.5),
                &RasterOptions { supersample: 2, ..Default::default() },
            ),
            _ => ImageF32::new(SIZE.0, SIZE.1, 0.0),
        };
        crate::out::ensure_dir(&self.dir)?;
        write_png_gray8(self.dir.join(format!("frame_{frame:04}.png")), &img)?;
        self.images.push(img);
        Ok(())
    }

    /// Writes the rendered snapshots side by side as `surface_snapshots.png` (nothing if none).
    pub(crate) fn finish(self) -> Result<()> {
        if self.images.is_empty() {
            return Ok(());
        }
        let n = self.images.len() as u32;
        let mut strip = ImageF32::new(n * SIZE.0 + (n - 1) * GAP, SIZE.1, 1.0);
        for (k, img) in self.images.iter().enumerate() {
            let x0 = k as u32 * (SIZE.0 + GAP);
            for y in 0..img.height.min(SIZE.1) {
                for x in 0..img.width.min(SIZE.0) {
                    strip.set(x0 + x, y, img.data[(y * img.width + x) as usize]);
                }
            }
        }
        write_png_gray8(self.out.join("surface_snapshots.png"), &strip)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A short drop into a pool: four frames are chosen, each rendered frame shows liquid (lit
    /// pixels) on the black background, and the strip has the four side by side.
    #[test]
    fn snapshots_of_a_short_run() {
        let text = r#"(domain: (min: (0.0, 0.0, 0.0), max: (0.5, 0.5, 0.5)),
            resolution: (coarsest: 4, finest: 8), duration: 0.1, fps: 30.0,
            liquid: [Box(min: (0.0, 0.0, 0.0), max: (0.5, 0.125, 0.5))])"#;
        let scene: Scene = ron::from_str(text).expect("scene");
        let dir = std::env::temp_dir().join(format!("ft-snap-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let mut snaps = Snapshots::new(&scene, &dir).expect("camera");
        assert_eq!(snaps.frames, vec![0, 1, 2, 3]);
        let mut sim = FlipTetSim::new(&scene).expect("sim");
        snaps.frame(&sim, 0).expect("render");
        let mut frame = 0;
        while sim.time() < scene.duration - 1e-9 {
            if sim.step().expect("step").frame_end {
                frame += 1;
                snaps.frame(&sim, frame).expect("render");
            }
        }
        assert_eq!(snaps.images.len(), 4);
        for img in &snaps.images {
            let lit = img.data.iter().filter(|&&v| v > 0.05).count();
            assert!(lit > 1000, "the pool is visible: {lit} lit pixels");
        }
        snaps.finish().expect("strip");
        assert!(dir.join("surface_snapshots.png").is_file());
        assert!(dir.join("snapshots/frame_0003.png").is_file());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
