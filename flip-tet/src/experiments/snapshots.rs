//! Rendered PNG snapshots of the liquid surface of a run (issue 5: "surfaces written per frame,
//! with rendered PNG snapshots in the report").
//!
//! Four frames per run — the first, the last and two in between — are shaded with geom-core's
//! software rasteriser (Lambert, one directional light, gray on black) from one fixed camera per
//! scene and handed to the recorder as `snapshots/frame_NNNN.png` as the run reaches them, and
//! side by side as `surface_snapshots.png` at the end. Nothing is rendered when the recorder
//! discards its outputs.

use geom_core::image::{png_gray8_bytes, ImageF32};
use geom_core::math::{Pt3, Vec3};
use geom_core::raster::{lambert_preview, Camera, RasterOptions};
use geom_core::record::Recorder;

use crate::error::Result;
use crate::scene::Scene;
use crate::sim::FlipTetSim;

/// Width and height of one snapshot (pixels).
const SIZE: (u32, u32) = (480, 320);
/// Gap between the snapshots of the strip (pixels).
const GAP: u32 = 4;

/// The snapshots of one run.
pub struct Snapshots {
    /// Frame numbers to render, ascending.
    pub frames: Vec<u64>,
    cam: Camera,
    prefix: String,
    /// The images rendered so far.
    pub images: Vec<ImageF32>,
}

impl Snapshots {
    /// Frames `0, F/3, 2F/3, F` of the `F = round(duration · fps)` frames; camera looking at the
    /// domain centre from the front-right-above direction `(0.45, 0.55, 1)` at 1.2 domain
    /// diagonals (the thin `z` slab of the dam break is seen from its open side). Outputs are
    /// named under `prefix` (`""` or a sub-folder with a trailing slash).
    pub fn new(scene: &Scene, prefix: &str) -> Result<Self> {
        let last = (scene.duration * scene.fps).round().max(0.0) as u64;
        let mut frames = vec![0, last / 3, (2 * last) / 3, last];
        frames.dedup();
        let (lo, hi) = (scene.min(), scene.max());
        let target = Pt3::from((lo.coords + hi.coords) / 2.0);
        let eye = target + Vec3::new(0.45, 0.55, 1.0).normalize() * (1.2 * (hi - lo).norm());
        let cam = Camera::look_at(&eye, &target, &Vec3::y(), 35.0, SIZE.0, SIZE.1)?;
        Ok(Self { frames, cam, prefix: prefix.to_string(), images: Vec::new() })
    }

    /// Renders `frame` if it is one of the chosen frames (an empty surface gives a black image).
    pub fn frame(&mut self, sim: &FlipTetSim, frame: u64, rec: &mut dyn Recorder) -> Result<()> {
        if !self.frames.contains(&frame) || !rec.keeps_outputs() {
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
        rec.file(&format!("{}snapshots/frame_{frame:04}.png", self.prefix), &png_gray8_bytes(&img)?)?;
        self.images.push(img);
        Ok(())
    }

    /// The rendered snapshots side by side as `surface_snapshots.png` (nothing if none).
    pub fn finish(self, rec: &mut dyn Recorder) -> Result<()> {
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
        rec.file(&format!("{}surface_snapshots.png", self.prefix), &png_gray8_bytes(&strip)?)?;
        Ok(())
    }
}
