//! Animated PNG (APNG): colour frames as one looping animation that every current browser plays
//! in an `<img>`, written with the `png` crate already used for stills.
//!
//! Frames are stored palette-indexed (one byte per pixel, a third of RGB): a fixed 6 × 7 × 6
//! colour cube (252 colours; green, to which the eye is most sensitive, gets the seventh level)
//! with 4 × 4 ordered (Bayer) dithering, so smooth shading does not band. Fixed palette and
//! dither make the output deterministic and independent of the frame content.

use std::io::Write;
use std::path::Path;

use super::buffers::ImageRgbF32;
use crate::error::{Error, Result};

const LEVELS: [usize; 3] = [6, 7, 6];

/// 4 × 4 Bayer matrix, values in `[0, 16)`.
const BAYER: [[u8; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

fn palette() -> Vec<u8> {
    let mut p = Vec::with_capacity(3 * 252);
    for r in 0..LEVELS[0] {
        for g in 0..LEVELS[1] {
            for b in 0..LEVELS[2] {
                for (v, n) in [(r, LEVELS[0]), (g, LEVELS[1]), (b, LEVELS[2])] {
                    p.push((v as f64 * 255.0 / (n - 1) as f64).round() as u8);
                }
            }
        }
    }
    p
}

/// Palette index of colour `c` (each channel in `[0, 1]`, NaN → 0) at pixel `(x, y)`.
#[inline]
fn index(c: [f32; 3], x: usize, y: usize) -> u8 {
    let t = (BAYER[y & 3][x & 3] as f32 + 0.5) / 16.0;
    let q = |v: f32, n: usize| -> usize {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        let s = v * (n - 1) as f32;
        let base = s.floor();
        let up = (s - base) > t;
        (base as usize + up as usize).min(n - 1)
    };
    let (r, g, b) = (q(c[0], LEVELS[0]), q(c[1], LEVELS[1]), q(c[2], LEVELS[2]));
    ((r * LEVELS[1] + g) * LEVELS[2] + b) as u8
}

fn indexed(img: &ImageRgbF32) -> Vec<u8> {
    let w = img.width as usize;
    img.data.iter().enumerate().map(|(i, &c)| index(c, i % w, i / w)).collect()
}

/// The APNG bytes of `frames` (all the same size, at least one), played at `fps` frames per
/// second and looping forever.
///
/// Errors (`Image`): no frames, frames of different or zero size, `fps` not > 0, an encoder
/// failure.
pub fn encode_apng(frames: &[ImageRgbF32], fps: f64) -> Result<Vec<u8>> {
    let first = frames.first().ok_or_else(|| Error::Image("APNG: no frames".into()))?;
    let (w, h) = (first.width, first.height);
    if w == 0 || h == 0 || frames.iter().any(|f| f.width != w || f.height != h) {
        return Err(Error::Image(format!("APNG: frames must share one non-zero size (first {w}×{h})")));
    }
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(Error::Image(format!("APNG: fps must be > 0, got {fps}")));
    }
    let err = |e: png::EncodingError| Error::Image(format!("APNG: {e}"));
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, w, h);
        enc.set_color(png::ColorType::Indexed);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_palette(palette());
        enc.set_compression(png::Compression::High);
        enc.set_animated(frames.len() as u32, 0).map_err(err)?;
        // Delay in milliseconds (1 ms resolution, at least 10 ms as browsers clamp shorter ones).
        let ms = (1000.0 / fps).round().clamp(10.0, 65535.0) as u16;
        enc.set_frame_delay(ms, 1000).map_err(err)?;
        let mut wr = enc.write_header().map_err(err)?;
        for f in frames {
            wr.write_image_data(&indexed(f)).map_err(err)?;
        }
        wr.finish().map_err(err)?;
    }
    Ok(out)
}

/// Writes [`encode_apng`] to `path`; errors name the file.
pub fn write_apng(path: impl AsRef<Path>, frames: &[ImageRgbF32], fps: f64) -> Result<()> {
    let path = path.as_ref();
    let bytes = encode_apng(frames, fps)?;
    let mut f = std::fs::File::create(path)
        .map_err(|e| Error::Io(std::io::Error::new(e.kind(), format!("cannot create {}: {e}", path.display()))))?;
    f.write_all(&bytes)
        .map_err(|e| Error::Io(std::io::Error::new(e.kind(), format!("cannot write {}: {e}", path.display()))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_round_trip_through_the_decoder() {
        let mk = |v: f32| ImageRgbF32::new(8, 5, [v, 0.5, 1.0 - v]);
        let frames = [mk(0.0), mk(0.5), mk(1.0)];
        let bytes = encode_apng(&frames, 12.0).unwrap();
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let reader = dec.read_info().unwrap();
        let info = reader.info();
        assert_eq!((info.width, info.height), (8, 5));
        let anim = info.animation_control().expect("animated");
        assert_eq!((anim.num_frames, anim.num_plays), (3, 0));
        assert_eq!(info.frame_control().map(|f| (f.delay_num, f.delay_den)), Some((83, 1000)));
    }

    #[test]
    fn pure_colours_are_exact_and_bad_input_is_an_error() {
        let pal = palette();
        for c in [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [1.0, 0.0, 0.0]] {
            let i = index(c, 1, 2) as usize;
            let got: Vec<f32> = pal[3 * i..3 * i + 3].iter().map(|&v| v as f32 / 255.0).collect();
            assert_eq!(got, c.to_vec());
        }
        assert!(encode_apng(&[], 10.0).is_err());
        assert!(encode_apng(&[ImageRgbF32::new(2, 2, [0.0; 3]), ImageRgbF32::new(3, 2, [0.0; 3])], 10.0).is_err());
        assert!(encode_apng(&[ImageRgbF32::new(2, 2, [0.0; 3])], 0.0).is_err());
    }
}
