//! PNG reading and writing through the `png` crate.

use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::Path;

use super::buffers::{luminance, ImageF32, ImageRgbF32, Mask};
use crate::error::{Error, Result};

fn image_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Image(format!("{}: {e}", path.display()))
}

/// Quantises `v ∈ [0, 1]` to `0..=max` (round to nearest; clamped; NaN → 0).
#[inline]
fn quantize(v: f32, max: f64) -> u32 {
    if v.is_nan() {
        return 0;
    }
    (v as f64 * max).round().clamp(0.0, max) as u32
}

/// Encodes samples as PNG into `w`; `what` names the destination in errors.
fn encode_into(
    w: impl Write,
    what: &Path,
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    bytes: &[u8],
) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::Image(format!("{}: cannot write an empty {width}×{height} PNG", what.display())));
    }
    let mut enc = png::Encoder::new(w, width, height);
    enc.set_color(color);
    enc.set_depth(depth);
    let mut writer = enc.write_header().map_err(|e| image_err(what, e))?;
    writer.write_image_data(bytes).map_err(|e| image_err(what, e))?;
    writer.finish().map_err(|e| image_err(what, e))
}

fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    color: png::ColorType,
    depth: png::BitDepth,
    bytes: &[u8],
) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::Image(format!("{}: cannot write an empty {width}×{height} PNG", path.display())));
    }
    let file = File::create(path)?;
    encode_into(BufWriter::new(file), path, width, height, color, depth, bytes)
}

/// The PNG file bytes (the same bytes the `write_png_*` functions write).
fn encode_png(width: u32, height: u32, color: png::ColorType, depth: png::BitDepth, bytes: &[u8]) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    encode_into(&mut out, Path::new("<in-memory PNG>"), width, height, color, depth, bytes)?;
    Ok(out)
}

fn gray8_samples(img: &ImageF32) -> Vec<u8> {
    img.data.iter().map(|&v| quantize(v, 255.0) as u8).collect()
}

fn gray16_samples(img: &ImageF32, scale: f64) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(img.data.len() * 2);
    for &v in &img.data {
        let q = if v.is_nan() { 0 } else { (v as f64 * scale).round().clamp(0.0, 65535.0) as u16 };
        bytes.extend_from_slice(&q.to_be_bytes());
    }
    bytes
}

/// [`write_png_gray8`] into memory: the PNG file's bytes (for a `Recorder::file`).
pub fn encode_png_gray8(img: &ImageF32) -> Result<Vec<u8>> {
    encode_png(img.width, img.height, png::ColorType::Grayscale, png::BitDepth::Eight, &gray8_samples(img))
}

/// [`write_png_gray16`] into memory: the PNG file's bytes.
pub fn encode_png_gray16(img: &ImageF32, scale: f64) -> Result<Vec<u8>> {
    let s = gray16_samples(img, scale);
    encode_png(img.width, img.height, png::ColorType::Grayscale, png::BitDepth::Sixteen, &s)
}

/// [`write_png_rgb8`] into memory: the PNG file's bytes.
pub fn encode_png_rgb8(img: &ImageRgbF32) -> Result<Vec<u8>> {
    let bytes: Vec<u8> = img.data.iter().flat_map(|c| c.map(|v| quantize(v, 255.0) as u8)).collect();
    encode_png(img.width, img.height, png::ColorType::Rgb, png::BitDepth::Eight, &bytes)
}

/// [`write_png_mask`] into memory: the PNG file's bytes.
pub fn encode_png_mask(m: &Mask) -> Result<Vec<u8>> {
    let bytes: Vec<u8> = m.data.iter().map(|&b| if b { 255 } else { 0 }).collect();
    encode_png(m.width, m.height, png::ColorType::Grayscale, png::BitDepth::Eight, &bytes)
}

/// Writes an 8-bit grayscale PNG: each value `v ∈ [0, 1]` becomes `round(255 v)` (clamped,
/// NaN → 0).
pub fn write_png_gray8(path: impl AsRef<Path>, img: &ImageF32) -> Result<()> {
    let bytes = gray8_samples(img);
    write_png(path.as_ref(), img.width, img.height, png::ColorType::Grayscale, png::BitDepth::Eight, &bytes)
}

/// Encodes an image as an 8-bit grayscale PNG in memory (the bytes [`write_png_gray8`] writes),
/// for outputs handed to a [`crate::record::Recorder`] as files: [`encode_png_gray8`] (the name
/// flip-tet's experiments use).
pub fn png_gray8_bytes(img: &ImageF32) -> Result<Vec<u8>> {
    encode_png_gray8(img)
}

/// Writes a 16-bit grayscale PNG: each value `v` becomes `round(v · scale)` clamped to
/// `0..=65535` (NaN → 0). Use `scale = 65535` for `[0, 1]` data (then [`read_png`] returns `v` to
/// within `1/131070`), or e.g. `scale = 1000` to store depths in millimetres.
pub fn write_png_gray16(path: impl AsRef<Path>, img: &ImageF32, scale: f64) -> Result<()> {
    let bytes = gray16_samples(img, scale);
    write_png(path.as_ref(), img.width, img.height, png::ColorType::Grayscale, png::BitDepth::Sixteen, &bytes)
}

/// Writes an 8-bit RGB PNG: each channel `c ∈ [0, 1]` becomes `round(255 c)` (clamped, NaN → 0).
pub fn write_png_rgb8(path: impl AsRef<Path>, img: &ImageRgbF32) -> Result<()> {
    let bytes: Vec<u8> = img.data.iter().flat_map(|c| c.map(|v| quantize(v, 255.0) as u8)).collect();
    write_png(path.as_ref(), img.width, img.height, png::ColorType::Rgb, png::BitDepth::Eight, &bytes)
}

/// Writes a mask as an 8-bit grayscale PNG (set = 255, clear = 0).
pub fn write_png_mask(path: impl AsRef<Path>, m: &Mask) -> Result<()> {
    let bytes: Vec<u8> = m.data.iter().map(|&b| if b { 255 } else { 0 }).collect();
    write_png(path.as_ref(), m.width, m.height, png::ColorType::Grayscale, png::BitDepth::Eight, &bytes)
}

/// A decoded PNG as normalised RGB pixels (alpha dropped).
fn decode(path: &Path) -> Result<ImageRgbF32> {
    let file = File::open(path)?;
    let mut dec = png::Decoder::new(BufReader::new(file));
    // Palette → RGB, gray below 8 bits → 8 bits (scaled), tRNS → alpha.
    dec.set_transformations(png::Transformations::EXPAND);
    let mut reader = dec.read_info().map_err(|e| image_err(path, e))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| Error::Image(format!("{}: image too large to decode", path.display())))?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(|e| image_err(path, e))?;
    let (w, h) = (info.width, info.height);
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => {
            return Err(Error::Image(format!("{}: palette was not expanded", path.display())));
        }
    };
    let (bytes_per_sample, max) = match info.bit_depth {
        png::BitDepth::Eight => (1, 255.0f64),
        png::BitDepth::Sixteen => (2, 65535.0f64),
        d => return Err(Error::Image(format!("{}: unexpected bit depth {d:?} after expansion", path.display()))),
    };
    let sample = |row: &[u8], s: usize| -> f32 {
        let v =
            if bytes_per_sample == 1 { row[s] as f64 } else { u16::from_be_bytes([row[2 * s], row[2 * s + 1]]) as f64 };
        (v / max) as f32
    };
    let mut data = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h as usize {
        let row = &buf[y * info.line_size..(y + 1) * info.line_size];
        for x in 0..w as usize {
            let s = x * channels;
            data.push(match channels {
                1 | 2 => [sample(row, s); 3],
                _ => [sample(row, s), sample(row, s + 1), sample(row, s + 2)],
            });
        }
    }
    ImageRgbF32::from_data(w, h, data)
}

/// Reads a PNG as luminance in `[0, 1]`: 1/2/4/8/16-bit gray directly (divided by `2^bits − 1`),
/// RGB(A) and palette images through Rec. 709 weights `0.2126 R + 0.7152 G + 0.0722 B` on the
/// stored values (no gamma decoding); alpha is ignored. Errors name the file.
pub fn read_png(path: impl AsRef<Path>) -> Result<ImageF32> {
    let path = path.as_ref();
    let rgb = decode(path)?;
    // Gray images decode to equal channels, whose luminance would round; keep them exact.
    let data = rgb.data.iter().map(|&c| if c[0] == c[1] && c[1] == c[2] { c[0] } else { luminance(c) }).collect();
    ImageF32::from_data(rgb.width, rgb.height, data)
}

/// Reads a PNG as RGB in `[0, 1]` (gray replicated into the three channels, palette expanded,
/// alpha ignored).
pub fn read_png_rgb(path: impl AsRef<Path>) -> Result<ImageRgbF32> {
    decode(path.as_ref())
}
