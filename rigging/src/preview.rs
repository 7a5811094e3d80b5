//! A picture of a rig: the character seen from the front and from its left side (Lambert
//! shading through `geom_core::raster`), the embedded skeleton drawn over it (bones as lines,
//! joints as dots, the left side in a different colour), side by side in one RGB image.

use geom_core::image::ImageRgbF32;
use geom_core::math::{Pt3, Vec3};
use geom_core::raster::{lambert_preview, Camera, RasterOptions};

use crate::error::Result;

/// Front and side views of `positions`/`faces` (+Y up, facing +Z) with the bones `(parent,
/// child)` between `joints` drawn on top; `left[j]` marks joints on the character's left (drawn
/// blue, the others red). Each view is `size × size` pixels; orthographic-like (a narrow field of
/// view from far away).
pub fn rig_preview(
    positions: &[Pt3],
    faces: &[[u32; 3]],
    joints: &[Pt3],
    bones: &[(usize, usize)],
    left: &[bool],
    size: u32,
) -> Result<ImageRgbF32> {
    let b = geom_core::spatial::Aabb::from_points(positions);
    let c = b.center();
    let ext = b.size().max().max(1e-12);
    let fov = 10.0f64;
    let dist = 0.6 * ext / (0.5 * fov.to_radians()).tan();
    let views = [Vec3::z(), Vec3::x()];
    let mut img = ImageRgbF32::new(2 * size, size, [0.0; 3]);
    let o = RasterOptions { supersample: 2, ..Default::default() };
    for (k, dir) in views.iter().enumerate() {
        let cam = Camera::look_at(&(c + dir * dist), &c, &Vec3::y(), fov, size, size)?;
        let shade = lambert_preview(&cam, positions, faces, &(dir + Vec3::y() * 0.5), &o);
        let x0 = k as u32 * size;
        for y in 0..size {
            for x in 0..size {
                let v = shade.at(x, y);
                img.set(x0 + x, y, [0.55 * v, 0.55 * v, 0.55 * v]);
            }
        }
        let px = |p: &Pt3| {
            let h = cam.homogeneous(p);
            (h.x / h.z + x0 as f64, h.y / h.z)
        };
        for &(a, bb) in bones {
            let col = if left.get(bb).copied().unwrap_or(false) { [0.3, 0.6, 1.0] } else { [1.0, 0.35, 0.2] };
            line(&mut img, px(&joints[a]), px(&joints[bb]), col, (x0, x0 + size));
        }
        for (j, p) in joints.iter().enumerate() {
            let col = if left.get(j).copied().unwrap_or(false) { [0.6, 0.85, 1.0] } else { [1.0, 0.9, 0.3] };
            let (x, y) = px(p);
            for dy in -2i64..=2 {
                for dx in -2i64..=2 {
                    if dx * dx + dy * dy <= 5 {
                        put(&mut img, x.round() as i64 + dx, y.round() as i64 + dy, col, (x0, x0 + size));
                    }
                }
            }
        }
    }
    Ok(img)
}

fn put(img: &mut ImageRgbF32, x: i64, y: i64, c: [f32; 3], xr: (u32, u32)) {
    if x >= xr.0 as i64 && x < xr.1 as i64 && y >= 0 && y < img.height as i64 {
        img.set(x as u32, y as u32, c);
    }
}

/// A two-pixel-wide line by DDA, clipped to the view's columns.
fn line(img: &mut ImageRgbF32, a: (f64, f64), b: (f64, f64), c: [f32; 3], xr: (u32, u32)) {
    if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
        return;
    }
    let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).clamp(1, 100_000);
    for i in 0..=n {
        let t = i as f64 / n as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        for (dx, dy) in [(0, 0), (1, 0), (0, 1)] {
            put(img, x.round() as i64 + dx, y.round() as i64 + dy, c, xr);
        }
    }
}
