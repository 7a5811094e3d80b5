//! Synthetic footage: the swatch rendered under the stripe projector (spec §3.3).
//!
//! Shading per sample: I = clamp(ambient + albedo · s(X) · max(0, n̂·l̂) · vis(X), 0, 1), with
//! s the projected stripe intensity at the world point X, n̂ the Phong-interpolated vertex
//! normal turned toward the camera, l̂ the direction to the projector centre, and vis the
//! optional projector shadow map (a depth render from the projector, compared with a bias of
//! 2 mm + the depth step to the neighbouring texels). geom-core's rasteriser does the
//! visibility: near-plane clipping, top-left fill rule, perspective-correct barycentrics,
//! z-buffer, two-sided, s × s stratified supersampling.

use geom_core::image::{ImageF32, ImageRgbF32, Mask};
use geom_core::math::{Mat34, Pt3, Vec3};
use geom_core::raster::{rasterize, Camera, GBuffer, NormalSpace, RasterOptions};
use geom_core::NONE;
use serde::{Deserialize, Serialize};

use crate::rig::Rig;

/// Rendering settings (spec §2 `RenderOptions`, §4.3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RenderOptions {
    /// Samples per pixel along each axis.
    pub supersample: u32,
    /// Projector shadow map on/off.
    pub shadows: bool,
    /// Ambient term.
    pub ambient: f64,
    /// Albedo.
    pub albedo: f64,
    /// Background intensity (dark backdrop).
    pub background: f64,
}

impl Default for RenderOptions {
    /// Supersampling 2, shadows on, ambient 0.05, albedo 0.8, background 0 (spec §4.3).
    fn default() -> Self {
        Self { supersample: 2, shadows: true, ambient: 0.05, albedo: 0.8, background: 0.0 }
    }
}

/// Everything rendered for one frame (spec §2 `RenderOutput`).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOutput {
    /// Intensity in [0, 1] (box-filtered samples).
    pub intensity: ImageF32,
    /// Depth w of the nearest sample (m), 0 where empty.
    pub depth: ImageF32,
    /// Camera-facing world normal as (n + 1)/2, black where empty.
    pub normal: ImageRgbF32,
    /// Pixels with coverage ≥ ½.
    pub silhouette: Mask,
}

/// Area-weighted vertex normals.
pub fn vertex_normals(p: &[Pt3], faces: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); p.len()];
    for f in faces {
        if f.iter().any(|&i| i as usize >= p.len()) {
            continue;
        }
        let [a, b, c] = f.map(|i| p[i as usize]);
        let fn_ = (b - a).cross(&(c - a));
        for &i in f {
            n[i as usize] += fn_;
        }
    }
    n
}

/// The projector's depth map over the window of its image that the mesh covers.
struct ShadowMap {
    cam: Camera,
    depth: Vec<f32>,
}

impl ShadowMap {
    fn new(proj: &Camera, p: &[Pt3], faces: &[[u32; 3]]) -> Option<Self> {
        let (mut x0, mut y0, mut x1, mut y1) = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for x in p {
            if let Some((q, _)) = proj.project(x) {
                x0 = x0.min(q.x);
                y0 = y0.min(q.y);
                x1 = x1.max(q.x);
                y1 = y1.max(q.y);
            }
        }
        let (w, h) = (proj.width as f64, proj.height as f64);
        let (x0, y0) = ((x0.floor() - 2.0).max(0.0), (y0.floor() - 2.0).max(0.0));
        let (x1, y1) = ((x1.ceil() + 2.0).min(w - 1.0), (y1.ceil() + 2.0).min(h - 1.0));
        if !(x1 >= x0 && y1 >= y0) {
            return None;
        }
        // Crop: pixel (x, y) of the window is pixel (x + x0, y + y0) of the projector.
        let mut t = Mat34::zeros();
        t.copy_from(&proj.p);
        for c in 0..4 {
            let r2 = t[(2, c)];
            t[(0, c)] -= x0 * r2;
            t[(1, c)] -= y0 * r2;
        }
        let cam = Camera { p: t, width: (x1 - x0) as u32 + 1, height: (y1 - y0) as u32 + 1 };
        let gb = rasterize(&cam, p, faces, &RasterOptions::default());
        Some(Self { cam, depth: gb.depth })
    }

    /// 1 when `x` is the surface nearest to the projector, 0 when something occludes it.
    fn visibility(&self, x: &Pt3) -> f64 {
        let Some((q, w)) = self.cam.project(x) else { return 0.0 };
        let (ix, iy) = (q.x.round(), q.y.round());
        let (wd, ht) = (self.cam.width as i64, self.cam.height as i64);
        let (ix, iy) = (ix as i64, iy as i64);
        if ix < 0 || iy < 0 || ix >= wd || iy >= ht {
            return 1.0;
        }
        let at = |x: i64, y: i64| -> f64 {
            let d = self.depth[(y.clamp(0, ht - 1) * wd + x.clamp(0, wd - 1)) as usize];
            d as f64
        };
        let d = at(ix, iy);
        if !d.is_finite() {
            return 1.0;
        }
        let mut slope = 0.0f64;
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let n = at(ix + dx, iy + dy);
            if n.is_finite() {
                slope = slope.max((n - d).abs());
            }
        }
        if w <= d + 0.002 + slope {
            1.0
        } else {
            0.0
        }
    }
}

/// The shading context of one frame.
struct Shader<'a> {
    p: &'a [Pt3],
    faces: &'a [[u32; 3]],
    vn: Vec<Vec3>,
    rig: &'a Rig,
    cam_c: Pt3,
    proj_c: Pt3,
    shadow: Option<ShadowMap>,
    o: &'a RenderOptions,
}

impl Shader<'_> {
    fn new<'a>(p: &'a [Pt3], faces: &'a [[u32; 3]], rig: &'a Rig, o: &'a RenderOptions) -> Shader<'a> {
        let shadow = if o.shadows { ShadowMap::new(&rig.projector.camera, p, faces) } else { None };
        Shader {
            p,
            faces,
            vn: vertex_normals(p, faces),
            rig,
            cam_c: rig.camera.center().unwrap_or(Pt3::origin()),
            proj_c: rig.projector.camera.center().unwrap_or(Pt3::origin()),
            shadow,
            o,
        }
    }

    fn shade(&self, face: u32, b: [f32; 3]) -> f32 {
        let f = self.faces[face as usize];
        let (b0, b1, b2) = (b[0] as f64, b[1] as f64, b[2] as f64);
        let [a, bb, c] = f.map(|i| self.p[i as usize]);
        let x = Pt3::from(a.coords * b0 + bb.coords * b1 + c.coords * b2);
        let [na, nb, nc] = f.map(|i| self.vn[i as usize]);
        let mut n = (na * b0 + nb * b1 + nc * b2).try_normalize(0.0).unwrap_or_else(Vec3::zeros);
        if n.dot(&(self.cam_c - x)) < 0.0 {
            n = -n;
        }
        let l = (self.proj_c - x).try_normalize(0.0).unwrap_or_else(Vec3::zeros);
        let lambert = n.dot(&l).max(0.0);
        let vis = match &self.shadow {
            Some(s) if lambert > 0.0 => s.visibility(&x),
            _ => 1.0,
        };
        let s = if lambert > 0.0 && vis > 0.0 { self.rig.projector.stripe(&x) } else { 0.0 };
        (self.o.ambient + self.o.albedo * s * lambert * vis).clamp(0.0, 1.0) as f32
    }
}

/// Silhouette from a G-buffer: pixels with at least half of their samples covered.
pub fn coverage_silhouette(gb: &GBuffer) -> Mask {
    let (w, h, ss) = (gb.width as usize, gb.height as usize, gb.ss as usize);
    let gw = w * ss;
    let mut data = vec![false; w * h];
    for (i, d) in data.iter_mut().enumerate() {
        let (x, y) = (i % w, i / w);
        let mut k = 0;
        for j in 0..ss {
            let row = (y * ss + j) * gw + x * ss;
            k += gb.face[row..row + ss].iter().filter(|&&f| f != NONE).count();
        }
        *d = 2 * k >= ss * ss;
    }
    Mask { width: gb.width, height: gb.height, data }
}

/// Intensity image and silhouette of one frame (the objective's fast path).
pub fn render_intensity(p: &[Pt3], faces: &[[u32; 3]], rig: &Rig, o: &RenderOptions) -> (ImageF32, Mask) {
    let ro = RasterOptions { supersample: o.supersample.max(1), ..RasterOptions::default() };
    render_with(p, faces, rig, &rig.camera, o, &ro)
}

fn render_with(
    p: &[Pt3],
    faces: &[[u32; 3]],
    rig: &Rig,
    cam: &Camera,
    o: &RenderOptions,
    ro: &RasterOptions,
) -> (ImageF32, Mask) {
    let gb = rasterize(cam, p, faces, ro);
    let sh = Shader::new(p, faces, rig, o);
    let img = gb.resolve(|f, b| sh.shade(f, b), o.background as f32);
    (img, coverage_silhouette(&gb))
}

/// Renders one frame with every output (spec §2 `render_frame`).
pub fn render_frame(p: &[Pt3], faces: &[[u32; 3]], rig: &Rig, o: &RenderOptions) -> RenderOutput {
    render_frame_with_camera(p, faces, rig, &rig.camera, o)
}

/// [`render_frame`] seen by another camera (the perturbed camera of the noise model); the
/// projector and shading are the rig's.
pub fn render_frame_with_camera(
    p: &[Pt3],
    faces: &[[u32; 3]],
    rig: &Rig,
    cam: &Camera,
    o: &RenderOptions,
) -> RenderOutput {
    let ro = RasterOptions { supersample: o.supersample.max(1), ..RasterOptions::default() };
    let gb = rasterize(cam, p, faces, &ro);
    let mut r2 = rig.clone();
    r2.camera = cam.clone();
    let sh = Shader::new(p, faces, &r2, o);
    let intensity = gb.resolve(|f, b| sh.shade(f, b), o.background as f32);
    let depth = gb.depth();
    let normal = gb.normals(cam, p, faces, NormalSpace::World, true);
    RenderOutput { intensity, depth, normal, silhouette: coverage_silhouette(&gb) }
}
