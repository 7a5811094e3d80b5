//! PNG encoding into memory, for artefacts handed to a `Recorder` (which takes bytes, not
//! paths). Same quantisation as geom-core's PNG writers: round(255·v), clamped, NaN → 0.

use geom_core::image::{ImageF32, ImageRgbF32, Mask};

fn encode(width: u32, height: u32, color: png::ColorType, depth: png::BitDepth, data: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width.max(1), height.max(1));
        enc.set_color(color);
        enc.set_depth(depth);
        // Writing into a Vec cannot fail for a consistent header and data length.
        let mut w = enc.write_header().expect("PNG header into memory");
        w.write_image_data(data).expect("PNG data into memory (length matches the header)");
    }
    out
}

fn q8(v: f32) -> u8 {
    if v.is_nan() {
        0
    } else {
        (v as f64 * 255.0).round().clamp(0.0, 255.0) as u8
    }
}

/// 8-bit grayscale PNG of an image in [0, 1].
pub fn gray8(img: &ImageF32) -> Vec<u8> {
    let d: Vec<u8> = img.data.iter().map(|&v| q8(v)).collect();
    encode(img.width, img.height, png::ColorType::Grayscale, png::BitDepth::Eight, &d)
}

/// 16-bit grayscale PNG of `round(v·scale)` (e.g. depth in millimetres with scale 1000).
pub fn gray16(img: &ImageF32, scale: f64) -> Vec<u8> {
    let mut d = Vec::with_capacity(2 * img.data.len());
    for &v in &img.data {
        let q = if v.is_nan() { 0 } else { (v as f64 * scale).round().clamp(0.0, 65535.0) as u16 };
        d.extend_from_slice(&q.to_be_bytes());
    }
    encode(img.width, img.height, png::ColorType::Grayscale, png::BitDepth::Sixteen, &d)
}

/// 8-bit RGB PNG of an image with channels in [0, 1].
pub fn rgb8(img: &ImageRgbF32) -> Vec<u8> {
    let d: Vec<u8> = img.data.iter().flat_map(|c| c.map(q8)).collect();
    encode(img.width, img.height, png::ColorType::Rgb, png::BitDepth::Eight, &d)
}

/// A mask as 0/255 grayscale.
pub fn mask(m: &Mask) -> Vec<u8> {
    let d: Vec<u8> = m.data.iter().map(|&b| if b { 255 } else { 0 }).collect();
    encode(m.width, m.height, png::ColorType::Grayscale, png::BitDepth::Eight, &d)
}
