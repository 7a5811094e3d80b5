//! Triangle setup (near-plane clipping, projection, fill rule) and the banded parallel
//! scan conversion behind [`rasterize`] and [`rasterize_uv`].

use rayon::prelude::*;

use super::camera::Camera;
use super::gbuffer::GBuffer;
use crate::math::{Pt2, Pt3, Vec3};
use crate::NONE;

/// Rasteriser settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterOptions {
    /// Samples per pixel along each axis: `s × s` stratified samples at offsets
    /// `(i + ½)/s − ½` from the pixel centre (1 = the pixel centre only; 0 is treated as 1).
    pub supersample: u32,
    /// Near clipping plane: geometry with depth `w < near_w` is clipped away (same units as `w`).
    pub near_w: f64,
    /// Drop triangles whose back (`(b − a) × (c − a)` pointing away from the camera) is seen.
    /// Off by default: open surfaces such as cloth are rendered two-sided.
    pub cull_back: bool,
}

impl Default for RasterOptions {
    /// One sample per pixel, near plane at `w = 0.01`, two-sided.
    fn default() -> Self {
        Self { supersample: 1, near_w: 0.01, cull_back: false }
    }
}

/// A screen-space triangle ready for scan conversion, in sample-grid coordinates (sample
/// centres at integers).
struct ScreenTri {
    /// Corner positions, ordered so that the interior has positive edge functions.
    v: [[f64; 2]; 3],
    /// `1/w` at each corner (1 for texture space).
    inv_w: [f64; 3],
    /// Barycentric coordinates of each corner with respect to the original face.
    bary: [[f64; 3]; 3],
    /// Whether samples exactly on edge `i` (opposite corner `i`) are inside (top-left rule).
    owns_edge: [bool; 3],
    /// Inclusive sample bounding box `[x0, x1] × [y0, y1]`, clamped to the grid.
    bbox: [u32; 4],
    face: u32,
}

/// Edge function of the directed edge `a → b` at `p`: `(b − a) × (p − a)`, evaluated with the end
/// points in a canonical (lexicographic) order and negated when swapped, so that
/// `edge(a, b, p) = −edge(b, a, p)` holds exactly in floating point. This is what makes two
/// triangles sharing an edge partition the samples on it.
#[inline]
fn edge(a: &[f64; 2], b: &[f64; 2], p: &[f64; 2]) -> f64 {
    let raw = |a: &[f64; 2], b: &[f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
    if (a[0], a[1]) > (b[0], b[1]) {
        -raw(b, a)
    } else {
        raw(a, b)
    }
}

/// Top-left rule for an edge `a → b` of a triangle whose interior is on the positive side:
/// samples on the edge belong to the triangle iff its inward normal `(−(b_y − a_y), b_x − a_x)`
/// points right (a "left" edge) or, for a horizontal edge, down (a "top" edge, y down). The
/// neighbour across the edge has the opposite normal, so exactly one of the two owns it.
#[inline]
fn owns(a: &[f64; 2], b: &[f64; 2]) -> bool {
    let (nx, ny) = (-(b[1] - a[1]), b[0] - a[0]);
    nx > 0.0 || (nx == 0.0 && ny > 0.0)
}

/// Builds the screen triangle(s) of one convex polygon (fan from its first corner). `pts` are
/// sample-grid positions, `inv_w` and `bary` per corner.
fn push_fan(pts: &[[f64; 2]], inv_w: &[f64], bary: &[[f64; 3]], face: u32, grid: (u32, u32), out: &mut Vec<ScreenTri>) {
    for k in 1..pts.len().saturating_sub(1) {
        let idx = [0, k, k + 1];
        let mut v = idx.map(|i| pts[i]);
        let mut iw = idx.map(|i| inv_w[i]);
        let mut b = idx.map(|i| bary[i]);
        let area = edge(&v[0], &v[1], &v[2]);
        if !(area.is_finite() && area != 0.0) {
            continue;
        }
        if area < 0.0 {
            v.swap(1, 2);
            iw.swap(1, 2);
            b.swap(1, 2);
        }
        let owns_edge = [owns(&v[1], &v[2]), owns(&v[2], &v[0]), owns(&v[0], &v[1])];
        let lo = |k: usize| v.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = |k: usize| v.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        // Samples are at integers: the covered range is [⌈min⌉, ⌊max⌋], clamped to the grid.
        let clamp = |x: f64, n: u32| x.clamp(-1.0, n as f64);
        let (x0, x1) = (clamp(lo(0).ceil(), grid.0), clamp(hi(0).floor(), grid.0));
        let (y0, y1) = (clamp(lo(1).ceil(), grid.1), clamp(hi(1).floor(), grid.1));
        if x1 < 0.0 || y1 < 0.0 || x0 >= grid.0 as f64 || y0 >= grid.1 as f64 || x0 > x1 || y0 > y1 {
            continue;
        }
        let bbox = [
            x0.max(0.0) as u32,
            x1.min(grid.0 as f64 - 1.0) as u32,
            y0.max(0.0) as u32,
            y1.min(grid.1 as f64 - 1.0) as u32,
        ];
        out.push(ScreenTri { v, inv_w: iw, bary: b, owns_edge, bbox, face });
    }
}

/// Clips face `face` (corners `x`, vertex indices `vid`) against `w ≥ near_w` in homogeneous
/// image space and appends its screen triangles.
fn setup_face(
    c: &Camera,
    x: [&Pt3; 3],
    vid: [u32; 3],
    face: u32,
    o: &RasterOptions,
    ss: u32,
    out: &mut Vec<ScreenTri>,
) {
    let h: [Vec3; 3] = x.map(|p| c.homogeneous(p));
    if h.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
        return;
    }
    if o.cull_back {
        let det = nalgebra::Matrix3::from_columns(&h).determinant();
        if det * c.handedness() >= 0.0 {
            return;
        }
    }
    let near = o.near_w;
    let unit = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    // Sutherland–Hodgman against one plane: at most 4 corners.
    let mut poly_h: Vec<Vec3> = Vec::with_capacity(4);
    let mut poly_b: Vec<[f64; 3]> = Vec::with_capacity(4);
    for i in 0..3 {
        let j = (i + 1) % 3;
        let (in_i, in_j) = (h[i].z >= near, h[j].z >= near);
        if in_i {
            poly_h.push(h[i]);
            poly_b.push(unit[i]);
        }
        if in_i != in_j {
            // Interpolate from the corner with the smaller vertex index, so that the faces
            // sharing this edge compute bitwise the same clipped point.
            let (s, e) = if vid[i] <= vid[j] { (i, j) } else { (j, i) };
            let t = (near - h[s].z) / (h[e].z - h[s].z);
            let p = h[s] + (h[e] - h[s]) * t;
            poly_h.push(Vec3::new(p.x, p.y, near));
            let mut b = [0.0; 3];
            b[s] = 1.0 - t;
            b[e] = t;
            poly_b.push(b);
        }
    }
    if poly_h.len() < 3 {
        return;
    }
    let s = ss as f64;
    let pts: Vec<[f64; 2]> =
        poly_h.iter().map(|p| [(p.x / p.z + 0.5) * s - 0.5, (p.y / p.z + 0.5) * s - 0.5]).collect();
    let inv_w: Vec<f64> = poly_h.iter().map(|p| 1.0 / p.z).collect();
    push_fan(&pts, &inv_w, &poly_b, face, (c.width * ss, c.height * ss), out);
}

/// Height of a band of sample rows processed as one parallel task.
const BAND: u32 = 16;

/// Scan-converts `tris` into a fresh G-buffer of `width × height` pixels with `ss × ss` samples.
/// `perspective`: interpolate with `1/w` and store `w`; otherwise affine barycentrics and depth 0.
fn scan(width: u32, height: u32, ss: u32, tris: &[ScreenTri], perspective: bool) -> GBuffer {
    let (gw, gh) = (width * ss, height * ss);
    let n = gw as usize * gh as usize;
    let mut gb =
        GBuffer { width, height, ss, depth: vec![f32::INFINITY; n], face: vec![NONE; n], bary: vec![[0.0; 3]; n] };
    if n == 0 {
        return gb;
    }
    let n_bands = gh.div_ceil(BAND) as usize;
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); n_bands];
    for (k, t) in tris.iter().enumerate() {
        for b in (t.bbox[2] / BAND)..=(t.bbox[3] / BAND) {
            bins[b as usize].push(k as u32);
        }
    }
    let band_len = BAND as usize * gw as usize;
    gb.depth
        .par_chunks_mut(band_len)
        .zip(gb.face.par_chunks_mut(band_len))
        .zip(gb.bary.par_chunks_mut(band_len))
        .zip(bins.par_iter())
        .enumerate()
        .for_each(|(band, (((depth, face), bary), bin))| {
            let y_base = band as u32 * BAND;
            let y_end = y_base + (depth.len() / gw as usize) as u32;
            for &k in bin {
                let t = &tris[k as usize];
                let (ya, yb) = (t.bbox[2].max(y_base), t.bbox[3].min(y_end - 1));
                for y in ya..=yb {
                    for x in t.bbox[0]..=t.bbox[1] {
                        let p = [x as f64, y as f64];
                        let e = [edge(&t.v[1], &t.v[2], &p), edge(&t.v[2], &t.v[0], &p), edge(&t.v[0], &t.v[1], &p)];
                        if !(0..3).all(|i| e[i] > 0.0 || (e[i] == 0.0 && t.owns_edge[i])) {
                            continue;
                        }
                        let sum = e[0] + e[1] + e[2];
                        let (w, mu) = if perspective {
                            let q = [e[0] * t.inv_w[0], e[1] * t.inv_w[1], e[2] * t.inv_w[2]];
                            let qs = q[0] + q[1] + q[2];
                            (1.0 / qs * sum, [q[0] / qs, q[1] / qs, q[2] / qs])
                        } else {
                            (0.0, [e[0] / sum, e[1] / sum, e[2] / sum])
                        };
                        let wf = w as f32;
                        let s = (y - y_base) as usize * gw as usize + x as usize;
                        // Strictly nearer only (ties keep the lower face); NaN never wins.
                        if wf.partial_cmp(&depth[s]) != Some(std::cmp::Ordering::Less) {
                            continue;
                        }
                        let mut b = [0.0f64; 3];
                        for (i, m) in mu.iter().enumerate() {
                            for (bj, tb) in b.iter_mut().zip(&t.bary[i]) {
                                *bj += m * tb;
                            }
                        }
                        depth[s] = wf;
                        face[s] = t.face;
                        bary[s] = b.map(|v| v as f32);
                    }
                }
            }
        });
    gb
}

/// Rasterises the triangles `faces` over positions `p` seen by camera `c` into a [`GBuffer`]
/// holding, per sample, the depth `w` of the nearest surface (+∞ where empty), its face index
/// ([`NONE`] where empty) and the perspective-correct barycentric coordinates of the sample
/// in that face (corner order of `faces[f]`).
///
/// Triangles are clipped against `w = near_w` (so geometry behind or through the camera is
/// handled), rendered two-sided unless `o.cull_back`, and filled with the top-left rule. Faces
/// with an index outside `p` or non-finite corners are skipped.
pub fn rasterize(c: &Camera, p: &[Pt3], faces: &[[u32; 3]], o: &RasterOptions) -> GBuffer {
    let ss = o.supersample.max(1);
    let per_face: Vec<Vec<ScreenTri>> = faces
        .par_iter()
        .enumerate()
        .map(|(f, vid)| {
            let mut out = Vec::new();
            if vid.iter().all(|&v| (v as usize) < p.len()) {
                let x = vid.map(|v| &p[v as usize]);
                setup_face(c, x, *vid, f as u32, o, ss, &mut out);
            }
            out
        })
        .collect();
    let tris: Vec<ScreenTri> = per_face.into_iter().flatten().collect();
    scan(c.width, c.height, ss, &tris, true)
}

/// Rasterises 2-D triangles given in pixel coordinates of a `width × height` image (texture
/// space; same pixel convention as the camera: `(0, 0)` is the centre of the top-left pixel,
/// y down) with `ss × ss` samples per pixel (0 is treated as 1). Barycentrics are affine, the
/// stored depth is 0 where covered, and where triangles overlap the lower index wins.
///
/// To rasterise texture coordinates `(u, v) ∈ [0, 1]²` with `v` up, pass
/// `(u · width − ½, (1 − v) · height − ½)`.
pub fn rasterize_uv(width: u32, height: u32, tris: &[[Pt2; 3]], ss: u32) -> GBuffer {
    let ss = ss.max(1);
    let s = ss as f64;
    let unit = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut screen = Vec::with_capacity(tris.len());
    for (f, t) in tris.iter().enumerate() {
        let pts = t.map(|q| [(q.x + 0.5) * s - 0.5, (q.y + 0.5) * s - 0.5]);
        push_fan(&pts, &[1.0; 3], &unit, f as u32, (width * ss, height * ss), &mut screen);
    }
    scan(width, height, ss, &screen, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ring of random triangles around the camera, some crossing the near plane.
    fn scene() -> (Camera, Vec<Pt3>, Vec<[u32; 3]>) {
        let c = Camera::look_at(&Pt3::new(0.0, 0.0, 2.0), &Pt3::origin(), &Vec3::y(), 70.0, 97, 61).expect("camera");
        let mut rng = crate::rng::Rng::new(3);
        let p: Vec<Pt3> =
            (0..300).map(|_| Pt3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), rng.range(-2.0, 3.0))).collect();
        let f: Vec<[u32; 3]> = (0..100u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        (c, p, f)
    }

    #[test]
    fn bitwise_identical_on_one_and_two_threads() {
        let (c, p, f) = scene();
        let o = RasterOptions { supersample: 2, ..RasterOptions::default() };
        let run = |n: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("thread pool");
            pool.install(|| rasterize(&c, &p, &f, &o))
        };
        let (a, b) = (run(1), run(2));
        assert!(a.face.iter().any(|&x| x != NONE));
        assert_eq!(a, b);
    }

    #[test]
    fn edge_function_is_exactly_antisymmetric() {
        let mut rng = crate::rng::Rng::new(9);
        for _ in 0..10_000 {
            let a = [rng.range(-100.0, 100.0), rng.range(-100.0, 100.0)];
            let b = [rng.range(-100.0, 100.0), rng.range(-100.0, 100.0)];
            let p = [rng.range(-100.0, 100.0), rng.range(-100.0, 100.0)];
            assert_eq!(edge(&a, &b, &p), -edge(&b, &a, &p));
            assert_ne!(owns(&a, &b), owns(&b, &a));
        }
    }
}
