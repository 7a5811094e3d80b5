//! [`GBuffer`]: per-sample rasterisation results and the images resolved from them.

use rayon::prelude::*;

use super::camera::Camera;
use crate::image::{ImageF32, ImageRgbF32, Mask};
use crate::math::{Pt3, Vec3};
use crate::NONE;

/// Per-sample output of [`super::rasterize`] / [`super::rasterize_uv`].
///
/// Samples form a `(width · ss) × (height · ss)` grid stored row-major: sample `(sx, sy)` is at
/// index `sy · width · ss + sx` and belongs to pixel `(sx / ss, sy / ss)`.
#[derive(Clone, Debug, PartialEq)]
pub struct GBuffer {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel along each axis.
    pub ss: u32,
    /// Depth `w` of the visible surface per sample (+∞ where empty; 0 for texture space).
    pub depth: Vec<f32>,
    /// Face index per sample ([`NONE`] where empty).
    pub face: Vec<u32>,
    /// Perspective-correct barycentric coordinates in the visible face (corner order of the
    /// face), zero where empty.
    pub bary: Vec<[f32; 3]>,
}

/// Coordinate frame of the normals in [`GBuffer::normals`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalSpace {
    /// World coordinates.
    World,
    /// The camera frame of [`Camera::view_rotation`] (OpenCV: x right, y down, z forward; a
    /// surface facing the camera has a negative z component).
    Camera,
}

impl GBuffer {
    /// Sample indices of pixel `(x, y)`.
    fn pixel_samples(&self, x: u32, y: u32) -> impl Iterator<Item = usize> + '_ {
        let (ss, gw) = (self.ss as usize, (self.width * self.ss) as usize);
        (0..ss).flat_map(move |j| {
            let row = (y as usize * ss + j) * gw + x as usize * ss;
            row..row + ss
        })
    }

    /// Applies `f(x, y)` to every pixel in parallel (row-major, deterministic).
    fn per_pixel<T: Send>(&self, f: impl Fn(u32, u32) -> T + Sync) -> Vec<T> {
        let w = self.width as usize;
        (0..w * self.height as usize).into_par_iter().map(|i| f((i % w) as u32, (i / w) as u32)).collect()
    }

    /// Fraction of covered samples per pixel, in `[0, 1]`.
    pub fn coverage(&self) -> ImageF32 {
        let n = (self.ss * self.ss) as f32;
        let data = self.per_pixel(|x, y| self.pixel_samples(x, y).filter(|&s| self.face[s] != NONE).count() as f32 / n);
        ImageF32 { width: self.width, height: self.height, data }
    }

    /// Pixels whose coverage exceeds `thr` (`thr = 0`: any sample covered; `0.5`: majority).
    pub fn silhouette(&self, thr: f32) -> Mask {
        let cov = self.coverage();
        Mask { width: self.width, height: self.height, data: cov.data.iter().map(|&c| c > thr).collect() }
    }

    /// Depth of the nearest sample per pixel (0 where no sample is covered).
    pub fn depth(&self) -> ImageF32 {
        let data = self.per_pixel(|x, y| {
            let d = self.pixel_samples(x, y).map(|s| self.depth[s]).fold(f32::INFINITY, f32::min);
            if d.is_finite() {
                d
            } else {
                0.0
            }
        });
        ImageF32 { width: self.width, height: self.height, data }
    }

    /// Box-filtered shading: per pixel, the mean over its samples of `shade(face, bary)` for
    /// covered samples and `background` for empty ones.
    pub fn resolve(&self, shade: impl Fn(u32, [f32; 3]) -> f32 + Sync, background: f32) -> ImageF32 {
        let n = (self.ss * self.ss) as f64;
        let data = self.per_pixel(|x, y| {
            let sum: f64 = self
                .pixel_samples(x, y)
                .map(|s| if self.face[s] == NONE { background } else { shade(self.face[s], self.bary[s]) } as f64)
                .sum();
            (sum / n) as f32
        });
        ImageF32 { width: self.width, height: self.height, data }
    }

    /// Colour version of [`GBuffer::resolve`].
    pub fn resolve_rgb(&self, shade: impl Fn(u32, [f32; 3]) -> [f32; 3] + Sync, background: [f32; 3]) -> ImageRgbF32 {
        let n = (self.ss * self.ss) as f64;
        let data = self.per_pixel(|x, y| {
            let mut acc = [0.0f64; 3];
            for s in self.pixel_samples(x, y) {
                let c = if self.face[s] == NONE { background } else { shade(self.face[s], self.bary[s]) };
                for k in 0..3 {
                    acc[k] += c[k] as f64;
                }
            }
            acc.map(|v| (v / n) as f32)
        });
        ImageRgbF32 { width: self.width, height: self.height, data }
    }

    /// Normal image encoded as colour `(n + 1) / 2` (background black), for the mesh
    /// `(p, faces)` this buffer was rasterised from with camera `c`.
    ///
    /// Normals are flat face normals, or with `smooth` the barycentric interpolation of
    /// area-weighted vertex normals (normalised per sample); they are flipped to face the camera
    /// on back-facing triangles (two-sided rendering), then expressed in `space` and averaged
    /// over the pixel's covered samples. Faces with out-of-range indices render black.
    pub fn normals(&self, c: &Camera, p: &[Pt3], faces: &[[u32; 3]], space: NormalSpace, smooth: bool) -> ImageRgbF32 {
        let valid = |f: &[u32; 3]| f.iter().all(|&v| (v as usize) < p.len());
        let face_n: Vec<Vec3> = faces
            .iter()
            .map(|f| {
                if !valid(f) {
                    return Vec3::zeros();
                }
                let [a, b, d] = f.map(|v| p[v as usize]);
                (b - a).cross(&(d - a))
            })
            .collect();
        let vert_n: Vec<Vec3> = if smooth {
            let mut vn = vec![Vec3::zeros(); p.len()];
            for (f, n) in faces.iter().zip(&face_n) {
                if valid(f) {
                    for &v in f {
                        vn[v as usize] += n;
                    }
                }
            }
            vn
        } else {
            Vec::new()
        };
        let front: Vec<bool> = faces
            .iter()
            .map(|f| valid(f) && c.is_front_facing(&p[f[0] as usize], &p[f[1] as usize], &p[f[2] as usize]))
            .collect();
        let r = c.view_rotation();
        let n = (self.ss * self.ss) as f64;
        let data = self.per_pixel(|x, y| {
            let mut acc = Vec3::zeros();
            for s in self.pixel_samples(x, y) {
                let f = self.face[s];
                if f == NONE || f as usize >= faces.len() || !valid(&faces[f as usize]) {
                    continue;
                }
                let fi = f as usize;
                let mut nn = if smooth {
                    let b = self.bary[s];
                    let vs = faces[fi];
                    vert_n[vs[0] as usize] * b[0] as f64
                        + vert_n[vs[1] as usize] * b[1] as f64
                        + vert_n[vs[2] as usize] * b[2] as f64
                } else {
                    face_n[fi]
                };
                nn = nn.try_normalize(0.0).unwrap_or_else(Vec3::zeros);
                if !front[fi] {
                    nn = -nn;
                }
                if space == NormalSpace::Camera {
                    nn = r * nn;
                }
                acc += (nn + Vec3::repeat(1.0)) * 0.5;
            }
            [(acc.x / n) as f32, (acc.y / n) as f32, (acc.z / n) as f32]
        });
        ImageRgbF32 { width: self.width, height: self.height, data }
    }
}
