//! PNG round trips and filter invariants.

use geom_core::image::{
    convolve_separable, encode_png_gray16, encode_png_gray8, encode_png_mask, encode_png_rgb8, gaussian_blur, read_png,
    read_png_rgb, write_png_gray16, write_png_gray8, write_png_mask, write_png_rgb8, Border, ImageF32, ImageRgbF32,
    Mask,
};
use geom_core::rng::Rng;
use geom_core::Error;

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("geom_core_image_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

fn random_image(rng: &mut Rng, w: u32, h: u32) -> ImageF32 {
    ImageF32::from_data(w, h, (0..w * h).map(|_| rng.f64() as f32).collect()).expect("sizes match")
}

#[test]
fn gray8_round_trip_is_exact_on_the_8_bit_grid() {
    let mut rng = Rng::new(1);
    let img =
        ImageF32::from_data(13, 7, (0..91).map(|_| (rng.below(256) as f64 / 255.0) as f32).collect()).expect("sizes");
    let path = tmp("g8.png");
    write_png_gray8(&path, &img).expect("write");
    let back = read_png(&path).expect("read");
    assert_eq!((back.width, back.height), (13, 7));
    assert_eq!(back, img);
    // Arbitrary values come back within half a quantum; out-of-range values clamp.
    let mut img = random_image(&mut rng, 9, 4);
    img.data[0] = -3.0;
    img.data[1] = 7.0;
    write_png_gray8(&path, &img).expect("write");
    let back = read_png(&path).expect("read");
    assert_eq!((back.data[0], back.data[1]), (0.0, 1.0));
    for (a, b) in img.data.iter().zip(&back.data).skip(2) {
        assert!((a - b).abs() <= 0.5 / 255.0 + 1e-7);
    }
}

#[test]
fn gray16_round_trip() {
    let mut rng = Rng::new(2);
    let img = random_image(&mut rng, 17, 5);
    let path = tmp("g16.png");
    write_png_gray16(&path, &img, 65535.0).expect("write");
    let back = read_png(&path).expect("read");
    for (a, b) in img.data.iter().zip(&back.data) {
        assert!((a - b).abs() <= 0.5 / 65535.0 + 1e-7, "{a} vs {b}");
    }
    // Values on the 16-bit grid are exact.
    let grid = ImageF32::from_data(4, 1, vec![0.0, 1.0 / 65535.0, 0.5, 1.0]).expect("sizes");
    let grid_q: Vec<f32> = grid.data.iter().map(|&v| ((v as f64 * 65535.0).round() / 65535.0) as f32).collect();
    write_png_gray16(&path, &grid, 65535.0).expect("write");
    assert_eq!(read_png(&path).expect("read").data, grid_q);
}

/// The in-memory encoders produce exactly the bytes the file writers write.
#[test]
fn encoders_match_the_files() {
    let mut rng = Rng::new(4);
    let img = random_image(&mut rng, 11, 6);
    let rgb = ImageRgbF32::from_data(3, 2, (0..6).map(|i| [i as f32 / 6.0, 0.5, 1.0]).collect()).expect("sizes");
    let mut m = Mask::new(4, 2, false);
    m.set(2, 1, true);
    let (p8, p16, prgb, pm) = (tmp("e8.png"), tmp("e16.png"), tmp("ergb.png"), tmp("em.png"));
    write_png_gray8(&p8, &img).expect("write");
    write_png_gray16(&p16, &img, 1000.0).expect("write");
    write_png_rgb8(&prgb, &rgb).expect("write");
    write_png_mask(&pm, &m).expect("write");
    let read = |p: &std::path::Path| std::fs::read(p).expect("read back");
    assert_eq!(encode_png_gray8(&img).expect("encode"), read(&p8));
    assert_eq!(encode_png_gray16(&img, 1000.0).expect("encode"), read(&p16));
    assert_eq!(encode_png_rgb8(&rgb).expect("encode"), read(&prgb));
    assert_eq!(encode_png_mask(&m).expect("encode"), read(&pm));
    assert!(encode_png_gray8(&ImageF32::new(0, 3, 0.0)).is_err(), "empty images are errors");
}

#[test]
fn rgb8_and_mask_round_trip() {
    let mut rng = Rng::new(3);
    let data: Vec<[f32; 3]> = (0..6 * 5).map(|_| [0, 1, 2].map(|_| (rng.below(256) as f64 / 255.0) as f32)).collect();
    let img = ImageRgbF32::from_data(6, 5, data).expect("sizes");
    let path = tmp("rgb.png");
    write_png_rgb8(&path, &img).expect("write");
    assert_eq!(read_png_rgb(&path).expect("read"), img);
    // As luminance: Rec. 709 weights.
    let lum = read_png(&path).expect("read");
    let c = img.at(2, 3);
    let expect = 0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64;
    assert!((lum.at(2, 3) as f64 - expect).abs() < 1e-6);
    let mut m = Mask::new(5, 3, false);
    m.set(1, 2, true);
    m.set(4, 0, true);
    let mpath = tmp("mask.png");
    write_png_mask(&mpath, &m).expect("write");
    assert_eq!(read_png(&mpath).expect("read"), m.to_image());
}

#[test]
fn reading_bad_files_gives_errors_naming_the_file() {
    let path = tmp("not_a_png.png");
    std::fs::write(&path, b"definitely not a PNG").expect("write");
    match read_png(&path) {
        Err(Error::Image(msg)) => assert!(msg.contains("not_a_png.png"), "{msg}"),
        other => panic!("expected an image error, got {other:?}"),
    }
    assert!(matches!(read_png(tmp("missing.png")), Err(Error::Io(_))));
    assert!(write_png_gray8(tmp("empty.png"), &ImageF32::new(0, 3, 0.0)).is_err());
}

#[test]
fn blur_preserves_mean_with_wrap_and_constants() {
    let mut rng = Rng::new(4);
    let img = random_image(&mut rng, 40, 23);
    for sigma in [0.5, 1.7, 4.0] {
        let out = gaussian_blur(&img, sigma, Border::Wrap);
        // f32 kernel weights sum to 1 within ~1e-7, f32 storage: relative 1e-6.
        assert!((out.mean() - img.mean()).abs() < 1e-6 * img.mean(), "sigma {sigma}");
        // Smoothing lowers the variance.
        let var = |im: &ImageF32| {
            let m = im.mean();
            im.data.iter().map(|&v| (v as f64 - m).powi(2)).sum::<f64>()
        };
        assert!(var(&out) < var(&img));
    }
    let c = ImageF32::new(11, 9, 0.375);
    for b in [Border::Clamp, Border::Wrap] {
        let out = gaussian_blur(&c, 2.3, b);
        assert!(out.data.iter().all(|&v| (v - 0.375).abs() < 1e-6), "{b:?}");
    }
    // Zero border darkens the edges of a constant image but not its centre (radius 3 < 5).
    let out = gaussian_blur(&c, 1.0, Border::Zero);
    assert!(out.at(0, 0) < 0.375 && (out.at(5, 4) - 0.375).abs() < 1e-6);
}

#[test]
fn separable_equals_direct_2d_convolution() {
    let mut rng = Rng::new(5);
    let img = random_image(&mut rng, 12, 10);
    let kx = [0.1f32, 0.5, 0.2, 0.2];
    let ky = [0.3f32, 0.3, 0.4];
    for b in [Border::Clamp, Border::Wrap, Border::Zero] {
        let out = convolve_separable(&img, &kx, &ky, b);
        for y in 0..10i64 {
            for x in 0..12i64 {
                let mut acc = 0.0f64;
                for (j, &wy) in ky.iter().enumerate() {
                    for (i, &wx) in kx.iter().enumerate() {
                        acc += wx as f64 * wy as f64 * img.at_border(x + i as i64 - 2, y + j as i64 - 1, b) as f64;
                    }
                }
                assert!((out.at(x as u32, y as u32) as f64 - acc).abs() < 1e-6);
            }
        }
    }
}

/// Writes raw samples with the `png` crate directly (formats our writers do not produce).
fn write_raw(
    path: &std::path::Path,
    w: u32,
    h: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    palette: Option<Vec<u8>>,
    data: &[u8],
) {
    let file = std::fs::File::create(path).expect("create");
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(color);
    enc.set_depth(depth);
    if let Some(p) = palette {
        enc.set_palette(p);
    }
    let mut wr = enc.write_header().expect("header");
    wr.write_image_data(data).expect("data");
    wr.finish().expect("finish");
}

#[test]
fn reads_palette_low_bit_gray_alpha_and_16_bit_colour() {
    // 2-bit palette: indices 0..3 → black, red, white, mid-gray; 4 pixels in one byte.
    let path = tmp("palette.png");
    let pal = vec![0, 0, 0, 255, 0, 0, 255, 255, 255, 128, 128, 128];
    write_raw(&path, 4, 1, png::ColorType::Indexed, png::BitDepth::Two, Some(pal), &[0b00_01_10_11]);
    let img = read_png(&path).expect("read");
    let expect = [0.0, 0.2126, 1.0, 128.0 / 255.0];
    for (x, e) in expect.iter().enumerate() {
        assert!((img.at(x as u32, 0) - e).abs() < 1e-6, "pixel {x}: {} vs {e}", img.at(x as u32, 0));
    }
    assert_eq!(read_png_rgb(&path).expect("read").at(1, 0), [1.0, 0.0, 0.0]);
    // 1-bit gray: 0 → 0, 1 → 1.
    write_raw(&path, 3, 1, png::ColorType::Grayscale, png::BitDepth::One, None, &[0b1010_0000]);
    assert_eq!(read_png(&path).expect("read").data, vec![1.0, 0.0, 1.0]);
    // 8-bit gray + alpha: alpha ignored.
    write_raw(&path, 2, 1, png::ColorType::GrayscaleAlpha, png::BitDepth::Eight, None, &[51, 0, 204, 255]);
    assert_eq!(read_png(&path).expect("read").data, vec![0.2, 0.8]);
    // 16-bit RGBA, big-endian samples.
    let px: [u16; 4] = [65535, 0, 32768, 7];
    let bytes: Vec<u8> = px.iter().flat_map(|v| v.to_be_bytes()).collect();
    write_raw(&path, 1, 1, png::ColorType::Rgba, png::BitDepth::Sixteen, None, &bytes);
    let c = read_png_rgb(&path).expect("read").at(0, 0);
    assert_eq!(c, [1.0, 0.0, (32768.0f64 / 65535.0) as f32]);
}
