//! Spec §7 tests of image formation and I/O: T3 (rasteriser coverage, area, depth), T4
//! (perspective-correct interpolation), T5 (predicted stripe period), T10 (planar swatch has no
//! folds, a Gaussian fold is found), T22 (PNG I/O of every colour type; corrupt files name the
//! file).

use cloth_fit::angle::{angle_map, AngleOptions};
use cloth_fit::footage::load_png_sequence;
use cloth_fit::presets::rig_spec;
use cloth_fit::reference::stripe_period_on_projector_plane;
use cloth_fit::render::{render_frame, RenderOptions};
use cloth_fit::FitError;
use geom_core::image::{ImageF32, Mask};
use geom_core::math::{Pt3, Vec3};
use geom_core::raster::{rasterize, Camera, RasterOptions};
use geom_core::NONE;

fn camera() -> Camera {
    Camera::look_at(&Pt3::new(0.0, -1.2, 0.0), &Pt3::new(0.0, 0.0, 0.0), &Vec3::z(), 40.0, 64, 48).unwrap()
}

/// T3: two triangles sharing an edge cover every pixel centre of their union exactly once; the
/// covered count of a large triangle matches its area within its perimeter; a fronto-parallel
/// plane has the right depth.
#[test]
fn t3_rasteriser_partition_area_depth() {
    let c = camera();
    let p = vec![
        Pt3::new(-0.3, 0.0, -0.2),
        Pt3::new(0.25, 0.0, -0.15),
        Pt3::new(0.05, 0.0, 0.22),
        Pt3::new(-0.28, 0.0, 0.2),
    ];
    let both = rasterize(&c, &p, &[[0, 1, 2], [0, 2, 3]], &RasterOptions::default());
    let a = rasterize(&c, &p, &[[0, 1, 2]], &RasterOptions::default());
    let b = rasterize(&c, &p, &[[0, 2, 3]], &RasterOptions::default());
    for i in 0..both.face.len() {
        let (ia, ib) = (a.face[i] != NONE, b.face[i] != NONE);
        assert!(!(ia && ib), "pixel {i} covered twice");
        assert_eq!(both.face[i] != NONE, ia || ib, "pixel {i}: union mismatch");
    }
    // Area: pixel count vs the projected triangle's area, within its perimeter (in px).
    let q: Vec<_> = p.iter().map(|x| c.project(x).unwrap().0).collect();
    let area = 0.5 * ((q[1] - q[0]).perp(&(q[2] - q[0]))).abs();
    let per = (q[1] - q[0]).norm() + (q[2] - q[1]).norm() + (q[0] - q[2]).norm();
    let count = a.face.iter().filter(|&&f| f != NONE).count() as f64;
    assert!((count - area).abs() <= per, "count {count}, area {area}, perimeter {per}");
    // Depth of the fronto-parallel plane y = 0 seen from 1.2 m.
    for (i, &d) in both.depth.iter().enumerate() {
        if both.face[i] != NONE {
            assert!((d as f64 - 1.2).abs() < 1e-6, "depth {d}");
        }
    }
}

/// T4: the world position recovered from perspective-correct barycentrics lies on a slanted plane.
#[test]
fn t4_perspective_correct_positions() {
    let c = camera();
    let p = vec![Pt3::new(-0.3, -0.2, -0.2), Pt3::new(0.3, 0.3, -0.2), Pt3::new(0.0, 0.1, 0.25)];
    let n = (p[1] - p[0]).cross(&(p[2] - p[0])).normalize();
    let gb = rasterize(&c, &p, &[[0, 1, 2]], &RasterOptions::default());
    let mut checked = 0;
    for (i, &f) in gb.face.iter().enumerate() {
        if f == NONE {
            continue;
        }
        let b = gb.bary[i];
        let x = Pt3::from(p[0].coords * b[0] as f64 + p[1].coords * b[1] as f64 + p[2].coords * b[2] as f64);
        // f32 barycentrics: 1e-9 m is beyond their precision, so check the plane distance at
        // f32 resolution of the coordinates (|x| < 1 m → ~1e-7 m) and the pixel ray exactly.
        assert!((x - p[0]).dot(&n).abs() < 2e-7, "off-plane by {}", (x - p[0]).dot(&n));
        let (px, _) = c.project(&x).unwrap();
        let (u, v) = ((i % 64) as f64, (i / 64) as f64);
        assert!((px.x - u).abs() < 1e-4 && (px.y - v).abs() < 1e-4, "pixel ({u}, {v}) → {px:?}");
        checked += 1;
    }
    assert!(checked > 50);
}

/// T5: a plane perpendicular to the projector axis shows the predicted stripe period (via the
/// two homographies) within 1 %.
#[test]
fn t5_stripe_period_on_a_plane() {
    let rig = rig_spec(320, 240).build().unwrap().rig;
    let d = 1.15;
    let predicted = stripe_period_on_projector_plane(&rig, d).unwrap();
    let cp = rig.projector.camera.center().unwrap();
    let axis = rig.projector.camera.view_rotation().row(2).transpose();
    let o = cp + d * axis;
    let (e1, e2) = (Vec3::x(), axis.cross(&Vec3::x()).normalize());
    let s = 0.6;
    let corners = [o - s * e1 - s * e2, o + s * e1 - s * e2, o + s * e1 + s * e2, o - s * e1 + s * e2];
    let r = render_frame(
        &corners,
        &[[0, 1, 2], [0, 2, 3]],
        &rig,
        &RenderOptions { supersample: 4, shadows: false, ambient: 0.0, albedo: 1.0, background: 0.0 },
    );
    let (px, _) = rig.camera.project(&o).unwrap();
    // Zero crossings of the stripe signal along the image column through the point, around it.
    let x = px.x.round() as u32;
    let col: Vec<f64> = (0..240).map(|y| r.intensity.at(x, y) as f64).collect();
    let y0 = px.y.round() as i64;
    let win: Vec<usize> = ((y0 - 24).max(1) as usize..(y0 + 24).min(238) as usize).collect();
    let mean = win.iter().map(|&i| col[i]).sum::<f64>() / win.len() as f64;
    let mut crossings = Vec::new();
    for &i in &win {
        let (a, b) = (col[i] - mean, col[i + 1] - mean);
        if a * b < 0.0 {
            crossings.push(i as f64 + a / (a - b));
        }
    }
    assert!(crossings.len() >= 6, "{crossings:?}");
    let k = crossings.len() - 1;
    let measured = 2.0 * (crossings[k] - crossings[0]) / k as f64;
    assert!((measured / predicted - 1.0).abs() < 0.01, "measured {measured} px, predicted {predicted} px");
}

/// T10: a planar swatch facing the camera has an empty fold mask; a Gaussian fold is found
/// (≥ 80 % of its ridge pixels).
#[test]
fn t10_planar_has_no_folds_and_a_fold_is_found() {
    let rig = rig_spec(160, 120).build().unwrap().rig;
    let o = AngleOptions { stripe_period_img_px: 4.0, coeff_blur_px: 2.0, ..AngleOptions::default() };
    let n = 40;
    let grid = |bump: f64| -> (Vec<Pt3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (-0.25 + 0.5 * i as f64 / n as f64, -0.45 + 0.5 * j as f64 / n as f64);
                let y = -bump * (-(u * u) / (2.0 * 0.03f64.powi(2))).exp();
                p.push(Pt3::new(u, y, v));
            }
        }
        let mut f = Vec::new();
        for j in 0..n as u32 {
            for i in 0..n as u32 {
                let a = j * (n as u32 + 1) + i;
                f.push([a, a + 1, a + n as u32 + 2]);
                f.push([a, a + n as u32 + 2, a + n as u32 + 1]);
            }
        }
        (p, f)
    };
    let ropt = RenderOptions { shadows: false, ..RenderOptions::default() };
    let (p, f) = grid(0.0);
    let r = render_frame(&p, &f, &rig, &ropt);
    let a = angle_map(&r.intensity, &r.silhouette, &o);
    assert!(a.valid.count() > 1000);
    assert_eq!(a.fold_mask.count(), 0, "a planar swatch has no folds");
    let (p, f) = grid(0.04);
    let r = render_frame(&p, &f, &rig, &ropt);
    let a = angle_map(&r.intensity, &r.silhouette, &o);
    // Ridge: the image column of u = 0, over the valid rows.
    let (ridge, _) = rig.camera.project(&Pt3::new(0.0, -0.04, -0.2)).unwrap();
    let x = ridge.x.round() as u32;
    let rows: Vec<u32> = (0..120).filter(|&y| a.valid.at(x, y)).collect();
    let hit = rows.iter().filter(|&&y| (x - 1..=x + 1).any(|xx| a.fold_mask.at(xx, y))).count();
    assert!(rows.len() > 20 && hit as f64 >= 0.8 * rows.len() as f64, "{hit} of {} ridge rows", rows.len());
}

fn write_png(
    path: &std::path::Path,
    color: png::ColorType,
    depth: png::BitDepth,
    w: u32,
    h: u32,
    data: &[u8],
    palette: Option<Vec<u8>>,
) {
    let f = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w, h);
    enc.set_color(color);
    enc.set_depth(depth);
    if let Some(p) = palette {
        enc.set_palette(p);
    }
    enc.write_header().unwrap().write_image_data(data).unwrap();
}

/// T22: 8/16-bit gray, RGB, RGBA and palette PNGs read back to the same luminance (1/255); a
/// corrupt file is an `Io` error naming it.
#[test]
fn t22_png_io() {
    let dir = std::env::temp_dir().join(format!("cloth-fit-png-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (4u32, 2u32);
    let lum: Vec<f64> = (0..8).map(|i| i as f64 / 7.0).collect();
    let g8: Vec<u8> = lum.iter().map(|v| (v * 255.0).round() as u8).collect();
    write_png(&dir.join("f_0000.png"), png::ColorType::Grayscale, png::BitDepth::Eight, w, h, &g8, None);
    let g16: Vec<u8> = lum.iter().flat_map(|v| ((v * 65535.0).round() as u16).to_be_bytes()).collect();
    write_png(&dir.join("f_0001.png"), png::ColorType::Grayscale, png::BitDepth::Sixteen, w, h, &g16, None);
    let rgb: Vec<u8> = g8.iter().flat_map(|&v| [v, v, v]).collect();
    write_png(&dir.join("f_0002.png"), png::ColorType::Rgb, png::BitDepth::Eight, w, h, &rgb, None);
    let rgba: Vec<u8> = g8.iter().flat_map(|&v| [v, v, v, 255]).collect();
    write_png(&dir.join("f_0003.png"), png::ColorType::Rgba, png::BitDepth::Eight, w, h, &rgba, None);
    let pal: Vec<u8> = g8.iter().flat_map(|&v| [v, v, v]).collect();
    let idx: Vec<u8> = (0..8u8).collect();
    write_png(&dir.join("f_0004.png"), png::ColorType::Indexed, png::BitDepth::Eight, w, h, &idx, Some(pal));
    let frames = load_png_sequence(&dir.join("f_%04d.png").display().to_string(), 0, 5).unwrap();
    for f in &frames {
        for (a, b) in f.data.iter().zip(&lum) {
            assert!((*a as f64 - b).abs() <= 1.0 / 255.0, "{a} vs {b}");
        }
    }
    std::fs::write(dir.join("f_0005.png"), b"\x89PNG\r\n\x1a\ntruncated").unwrap();
    match load_png_sequence(&dir.join("f_%04d.png").display().to_string(), 0, 6) {
        Err(FitError::Io { path, .. }) => assert!(path.ends_with("f_0005.png"), "{path:?}"),
        other => panic!("expected an Io error naming the file, got {other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
    let _ = (ImageF32::new(1, 1, 0.0), Mask::new(1, 1, false));
}
