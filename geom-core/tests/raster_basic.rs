//! Rasteriser: fill rule, coverage counts, depth, perspective-correct barycentrics, clipping,
//! empty input, and the PNG views.

use geom_core::image::read_png;
use geom_core::math::{Mat3, Pt2, Pt3, Vec3};
use geom_core::query::orient2d;
use geom_core::raster::{lambert_preview, rasterize, rasterize_uv, render_views, Camera, GBuffer, RasterOptions};
use geom_core::rng::Rng;
use geom_core::NONE;

/// A camera looking down −z from (0, 0, 4) with focal length 64 px and principal point
/// (32, 32) on a 64×64 image: the world point (x, y, 0) lands exactly on pixel
/// (32 + 16 x, 32 − 16 y), so test geometry can sit exactly on pixel centres.
fn exact_camera() -> Camera {
    let k = Mat3::new(64.0, 0.0, 32.0, 0.0, 64.0, 32.0, 0.0, 0.0, 1.0);
    let r = Mat3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
    Camera::from_krt(&k, &r, &Vec3::new(0.0, 0.0, 4.0), 64, 64)
}

/// World point on z = 0 that projects to pixel `(u, v)` of [`exact_camera`].
fn at_pixel(u: f64, v: f64) -> Pt3 {
    Pt3::new((u - 32.0) / 16.0, (32.0 - v) / 16.0, 0.0)
}

fn covered(gb: &GBuffer) -> Vec<bool> {
    gb.face.iter().map(|&f| f != NONE).collect()
}

fn count(v: &[bool]) -> usize {
    v.iter().filter(|&&b| b).count()
}

/// Rasterises the two triangles separately and checks they never share a sample; returns
/// their union.
fn union_of_disjoint(c: &Camera, p: &[Pt3], f0: [u32; 3], f1: [u32; 3], o: &RasterOptions) -> Vec<bool> {
    let a = covered(&rasterize(c, p, &[f0], o));
    let b = covered(&rasterize(c, p, &[f1], o));
    assert!(a.iter().zip(&b).all(|(x, y)| !(*x && *y)), "a sample is covered twice");
    a.iter().zip(&b).map(|(x, y)| *x || *y).collect()
}

#[test]
fn quad_on_pixel_centres_covers_exactly_its_area() {
    let c = exact_camera();
    // Square with corners on pixel centres (16, 16) … (48, 48): the top-left rule keeps the
    // left and top edges, drops the right and bottom ones: exactly 32 × 32 pixels.
    let p = vec![at_pixel(16.0, 16.0), at_pixel(48.0, 16.0), at_pixel(48.0, 48.0), at_pixel(16.0, 48.0)];
    let o = RasterOptions::default();
    for (f0, f1) in [([0, 1, 2], [0, 2, 3]), ([1, 2, 3], [1, 3, 0]), ([0, 2, 1], [0, 3, 2])] {
        let u = union_of_disjoint(&c, &p, f0, f1, &o);
        assert_eq!(count(&u), 32 * 32);
        for y in 0..64 {
            for x in 0..64 {
                assert_eq!(u[y * 64 + x], (16..48).contains(&x) && (16..48).contains(&y), "pixel ({x}, {y})");
            }
        }
        let both = rasterize(&c, &p, &[f0, f1], &o);
        assert_eq!(count(&covered(&both)), 32 * 32);
    }
    // 4×4 supersampling: coverage sums to the area in pixels, half-covered border pixels.
    let o4 = RasterOptions { supersample: 4, ..o };
    let gb = rasterize(&c, &p, &[[0, 1, 2], [0, 2, 3]], &o4);
    let cov = gb.coverage();
    assert_eq!(cov.data.iter().map(|&v| v as f64).sum::<f64>(), 1024.0);
    assert_eq!(cov.at(16, 30), 0.5);
    assert_eq!(cov.at(16, 16), 0.25);
    assert_eq!(cov.at(20, 20), 1.0);
}

#[test]
fn shared_edges_partition_samples_for_random_quads_and_fans() {
    let c = exact_camera();
    let mut rng = Rng::new(8);
    let o = RasterOptions { supersample: 2, ..RasterOptions::default() };
    for case in 0..60 {
        // Random convex quad around (32, 32); every other case snaps corners to the sample grid.
        let snap = case % 2 == 0;
        let mut corners = Vec::new();
        for k in 0..4 {
            let ang = (k as f64 + rng.range(-0.3, 0.3)) * std::f64::consts::FRAC_PI_2;
            let r = rng.range(6.0, 25.0);
            let (mut u, mut v) = (32.0 + r * ang.cos(), 32.0 + r * ang.sin());
            if snap {
                (u, v) = ((u * 2.0).round() / 2.0 + 0.25, (v * 2.0).round() / 2.0 + 0.25);
            }
            corners.push(Pt2::new(u, v));
        }
        let convex = (0..4).all(|i| orient2d(&corners[i], &corners[(i + 1) % 4], &corners[(i + 2) % 4]) > 0.0);
        if !convex {
            continue;
        }
        let p: Vec<Pt3> = corners.iter().map(|q| at_pixel(q.x, q.y)).collect();
        let d1 = union_of_disjoint(&c, &p, [0, 1, 2], [0, 2, 3], &o);
        let d2 = union_of_disjoint(&c, &p, [1, 2, 3], [1, 3, 0], &o);
        assert_eq!(d1, d2, "case {case}: coverage depends on the diagonal");
        if !snap {
            // No sample on an edge (generic corners): coverage = samples strictly inside.
            let mut inside = 0;
            for sy in 0..128 {
                for sx in 0..128 {
                    let s = Pt2::new((sx as f64 + 0.5) / 2.0 - 0.5, (sy as f64 + 0.5) / 2.0 - 0.5);
                    if (0..4).all(|i| orient2d(&corners[i], &corners[(i + 1) % 4], &s) > 0.0) {
                        inside += 1;
                    }
                }
            }
            assert_eq!(count(&d1), inside, "case {case}");
        }
    }
    // A fan of 12 triangles around a pixel centre: every sample at most once, the centre once.
    let centre = at_pixel(30.0, 31.0);
    let mut p = vec![centre];
    for k in 0..12 {
        let a = k as f64 / 12.0 * std::f64::consts::TAU;
        p.push(at_pixel(30.0 + 10.0 * a.cos(), 31.0 + 10.0 * a.sin()));
    }
    let o1 = RasterOptions::default();
    let mut hits = vec![0u32; 64 * 64];
    for k in 0..12u32 {
        let gb = rasterize(&c, &p, &[[0, 1 + k, 1 + (k + 1) % 12]], &o1);
        for (h, f) in hits.iter_mut().zip(&gb.face) {
            *h += (*f != NONE) as u32;
        }
    }
    assert!(hits.iter().all(|&h| h <= 1));
    assert_eq!(hits[31 * 64 + 30], 1);
}

#[test]
fn depth_and_barycentrics_are_perspective_correct() {
    let c = Camera::look_at(&Pt3::new(0.3, 0.4, 3.0), &Pt3::origin(), &Vec3::y(), 50.0, 80, 60).expect("camera");
    // A tilted triangle.
    let p = vec![Pt3::new(-1.0, -0.8, -0.5), Pt3::new(1.2, -0.6, 0.4), Pt3::new(0.1, 1.0, -0.2)];
    let gb = rasterize(&c, &p, &[[0, 1, 2]], &RasterOptions::default());
    let n = (p[1] - p[0]).cross(&(p[2] - p[0]));
    let eye = c.center().expect("finite camera");
    let r = c.view_rotation();
    let mut checked = 0;
    for y in 0..60u32 {
        for x in 0..80u32 {
            let s = (y * 80 + x) as usize;
            if gb.face[s] == NONE {
                continue;
            }
            // Ray through the pixel centre, intersected with the plane: the exact depth.
            let kinv = c.p.fixed_view::<3, 3>(0, 0).into_owned().try_inverse().expect("invertible");
            let dir = kinv * Vec3::new(x as f64, y as f64, 1.0);
            let t = n.dot(&(p[0] - eye)) / n.dot(&dir);
            let hit = eye + dir * t;
            let w = (r * (hit - eye)).z;
            // f32 depth storage: relative 1e-6.
            assert!((gb.depth[s] as f64 - w).abs() < 1e-6 * w, "depth {} vs {w}", gb.depth[s]);
            let b = gb.bary[s];
            let q = p[0].coords * b[0] as f64 + p[1].coords * b[1] as f64 + p[2].coords * b[2] as f64;
            // f32 barycentrics: about 1e-7 relative on O(1) coordinates.
            assert!((q - hit.coords).norm() < 1e-6, "bary point off by {}", (q - hit.coords).norm());
            checked += 1;
        }
    }
    assert!(checked > 300, "{checked}");
    let d = gb.depth();
    assert_eq!(d.at(0, 0), 0.0);
}

#[test]
fn near_plane_clipping_and_culling() {
    let c = exact_camera(); // at z = 4 looking down −z
    let o = RasterOptions::default();
    // Entirely behind the camera.
    let behind = vec![Pt3::new(-1.0, -1.0, 5.0), Pt3::new(1.0, -1.0, 6.0), Pt3::new(0.0, 1.0, 7.0)];
    assert_eq!(count(&covered(&rasterize(&c, &behind, &[[0, 1, 2]], &o))), 0);
    // Crossing the camera plane (one corner behind): clipped, partly visible.
    let crossing = vec![Pt3::new(-1.0, -1.0, 0.0), Pt3::new(1.0, -1.0, 0.0), Pt3::new(0.0, 1.0, 6.0)];
    let gb = rasterize(&c, &crossing, &[[0, 1, 2]], &o);
    assert!(count(&covered(&gb)) > 0);
    assert!(gb.depth.iter().filter(|d| d.is_finite()).all(|&d| d as f64 >= o.near_w * (1.0 - 1e-6)));
    let on_eye = vec![Pt3::new(0.0, 0.0, 4.0), Pt3::new(1.0, 0.0, 4.0), Pt3::new(0.0, 1.0, 4.0)];
    assert_eq!(count(&covered(&rasterize(&c, &on_eye, &[[0, 1, 2]], &o))), 0);
    // Non-finite corners and out-of-range indices are skipped, not a panic.
    let bad = vec![Pt3::new(f64::NAN, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0)];
    assert_eq!(count(&covered(&rasterize(&c, &bad, &[[0, 1, 2], [0, 1, 7]], &o))), 0);
    // Culling: counter-clockwise seen from the camera (+z side) is the front.
    let p = vec![at_pixel(10.0, 10.0), at_pixel(50.0, 10.0), at_pixel(10.0, 50.0)];
    let cull = RasterOptions { cull_back: true, ..o };
    let front = count(&covered(&rasterize(&c, &p, &[[0, 2, 1]], &cull)));
    let back = count(&covered(&rasterize(&c, &p, &[[0, 1, 2]], &cull)));
    let two_sided = count(&covered(&rasterize(&c, &p, &[[0, 1, 2]], &o)));
    assert!(front > 0 && back == 0 && two_sided == front);
}

#[test]
fn empty_mesh_gives_background() {
    let c = exact_camera();
    let o = RasterOptions { supersample: 3, ..RasterOptions::default() };
    let gb = rasterize(&c, &[], &[], &o);
    assert_eq!(gb.depth.len(), 64 * 64 * 9);
    assert!(gb.face.iter().all(|&f| f == NONE) && gb.depth.iter().all(|d| d.is_infinite()));
    assert!(gb.resolve(|_, _| 1.0, 0.25).data.iter().all(|&v| v == 0.25));
    assert!(gb.depth().data.iter().all(|&v| v == 0.0));
    assert_eq!(gb.silhouette(0.0).count(), 0);
    let img = lambert_preview(&c, &[], &[], &Vec3::z(), &o);
    assert!(img.data.iter().all(|&v| v == 0.0));
}

#[test]
fn nearest_surface_wins_and_lambert_shades() {
    let c = exact_camera();
    let mut p = vec![at_pixel(10.0, 10.0), at_pixel(50.0, 10.0), at_pixel(10.0, 50.0)];
    // The same triangle 1 m closer to the camera (z = 1), listed second.
    p.extend(p.clone().iter().map(|q| Pt3::new(q.x, q.y, 1.0)));
    let faces = [[0, 2, 1], [3, 5, 4]];
    let gb = rasterize(&c, &p, &faces, &RasterOptions::default());
    let s = 20 * 64 + 20;
    assert_eq!(gb.face[s], 1);
    assert_eq!(gb.depth[s], 3.0);
    // Light along the normal: full brightness; at 60°: AMBIENT + (1 − AMBIENT)/2.
    let img = lambert_preview(&c, &p, &faces, &Vec3::z(), &RasterOptions::default());
    assert!((img.at(20, 20) - 1.0).abs() < 1e-6);
    let l = Vec3::new(3f64.sqrt() / 2.0, 0.0, 0.5);
    let img = lambert_preview(&c, &p, &faces, &l, &RasterOptions::default());
    let expect = geom_core::raster::AMBIENT + (1.0 - geom_core::raster::AMBIENT) * 0.5;
    assert!((img.at(20, 20) - expect).abs() < 1e-6);
}

#[test]
fn texture_space_rasterisation() {
    // Lower-left half of a 16×8 image in pixel coordinates, edges on the image border.
    let tris = [[Pt2::new(-0.5, -0.5), Pt2::new(-0.5, 7.5), Pt2::new(15.5, 7.5)]];
    let gb = rasterize_uv(16, 8, &tris, 1);
    for y in 0..8 {
        for x in 0..16 {
            // Inside iff the pixel centre is strictly below the diagonal y = x / 2 (none lie on it:
            // the diagonal passes through y + ½ = (x + ½) / 2, never at integer x, y).
            let inside = (y as f64 + 0.5) > (x as f64 + 0.5) / 2.0;
            assert_eq!(gb.face[y * 16 + x] == 0, inside, "({x}, {y})");
        }
    }
    let s = 5 * 16 + 2;
    let b = gb.bary[s];
    let q = tris[0][0].coords * b[0] as f64 + tris[0][1].coords * b[1] as f64 + tris[0][2].coords * b[2] as f64;
    assert!((q - Pt2::new(2.0, 5.0).coords).norm() < 1e-5);
}

#[test]
fn render_views_writes_four_pngs() {
    let c = Camera::look_at(&Pt3::new(1.0, 1.5, 3.0), &Pt3::origin(), &Vec3::y(), 45.0, 48, 32).expect("camera");
    // A tetrahedron.
    let p = vec![Pt3::new(0.0, 0.0, 0.0), Pt3::new(1.0, 0.0, 0.0), Pt3::new(0.0, 1.0, 0.0), Pt3::new(0.0, 0.0, 1.0)];
    let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let dir = std::env::temp_dir().join(format!("geom_core_views_{}", std::process::id()));
    let v = render_views(&c, &p, &faces, &Vec3::new(1.0, 2.0, 3.0), &RasterOptions::default(), &dir, "tet")
        .expect("rendered");
    for path in [&v.depth, &v.normal, &v.silhouette, &v.shaded] {
        let img = read_png(path).expect("readable");
        assert_eq!((img.width, img.height), (48, 32));
        assert!(img.data.iter().any(|&x| x > 0.0), "{} is blank", path.display());
    }
    assert!(v.depth_max > 2.0 && v.depth_max < 5.0);
}
