//! Image buffers and border handling.

use crate::error::{Error, Result};

/// How a filter or sampler reads pixels outside the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Border {
    /// Repeat the nearest edge pixel.
    Clamp,
    /// Periodic: `x` outside `[0, width)` wraps around (a torus; preserves sums under filtering).
    Wrap,
    /// Read zero outside.
    Zero,
}

impl Border {
    /// Maps an integer coordinate to an index in `[0, n)`, or `None` (read zero) for
    /// [`Border::Zero`] outside. `n` must be positive.
    #[inline]
    pub fn index(self, i: i64, n: u32) -> Option<usize> {
        let n = n as i64;
        if (0..n).contains(&i) {
            return Some(i as usize);
        }
        match self {
            Border::Clamp => Some(i.clamp(0, n - 1) as usize),
            Border::Wrap => Some(i.rem_euclid(n) as usize),
            Border::Zero => None,
        }
    }
}

fn check_len(what: &'static str, width: u32, height: u32, len: usize) -> Result<()> {
    let expected = width as usize * height as usize;
    if len != expected {
        return Err(Error::DimensionMismatch { what, expected, got: len });
    }
    Ok(())
}

/// A single-channel `f32` image (intensity, depth, coverage …), row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageF32 {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` values, `data[y · width + x]`.
    pub data: Vec<f32>,
}

impl ImageF32 {
    /// A `width × height` image filled with `v`.
    pub fn new(width: u32, height: u32, v: f32) -> Self {
        Self { width, height, data: vec![v; width as usize * height as usize] }
    }

    /// An image from row-major data; `Err(DimensionMismatch)` if the length is not
    /// `width · height`.
    pub fn from_data(width: u32, height: u32, data: Vec<f32>) -> Result<Self> {
        check_len("ImageF32 data", width, height, data.len())?;
        Ok(Self { width, height, data })
    }

    /// Linear index of pixel `(x, y)`.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Value of pixel `(x, y)`. Panics if out of range.
    #[inline]
    pub fn at(&self, x: u32, y: u32) -> f32 {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        self.data[self.index(x, y)]
    }

    /// Sets pixel `(x, y)`. Panics if out of range.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: f32) {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        let i = self.index(x, y);
        self.data[i] = v;
    }

    /// Reads pixel `(x, y)` given as signed integers, applying the border rule.
    #[inline]
    pub fn at_border(&self, x: i64, y: i64, b: Border) -> f32 {
        if self.width == 0 || self.height == 0 {
            return 0.0;
        }
        match (b.index(x, self.width), b.index(y, self.height)) {
            (Some(i), Some(j)) => self.data[j * self.width as usize + i],
            _ => 0.0,
        }
    }

    /// Bilinear interpolation at continuous coordinates `(x, y)` (pixel centres at integers),
    /// reading outside pixels by the border rule `b`. Exact at pixel centres; non-finite
    /// coordinates give 0.
    pub fn sample_bilinear(&self, x: f64, y: f64, b: Border) -> f32 {
        if !(x.is_finite() && y.is_finite()) {
            return 0.0;
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (i, j) = (x0 as i64, y0 as i64);
        let v = |di: i64, dj: i64| self.at_border(i + di, j + dj, b) as f64;
        let top = v(0, 0) * (1.0 - fx) + v(1, 0) * fx;
        let bottom = v(0, 1) * (1.0 - fx) + v(1, 1) * fx;
        (top * (1.0 - fy) + bottom * fy) as f32
    }

    /// Arithmetic mean of all pixels (f64 accumulation), 0 for an empty image.
    pub fn mean(&self) -> f64 {
        if self.data.is_empty() {
            return 0.0;
        }
        self.data.iter().map(|&v| v as f64).sum::<f64>() / self.data.len() as f64
    }

    /// Smallest and largest finite values, `None` if there is none.
    pub fn finite_range(&self) -> Option<(f32, f32)> {
        let mut r: Option<(f32, f32)> = None;
        for &v in self.data.iter().filter(|v| v.is_finite()) {
            r = Some(r.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
        }
        r
    }
}

/// An RGB `f32` image, row-major, channels normally in `[0, 1]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageRgbF32 {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` pixels, `data[y · width + x] = [r, g, b]`.
    pub data: Vec<[f32; 3]>,
}

impl ImageRgbF32 {
    /// A `width × height` image filled with `v`.
    pub fn new(width: u32, height: u32, v: [f32; 3]) -> Self {
        Self { width, height, data: vec![v; width as usize * height as usize] }
    }

    /// An image from row-major data; `Err(DimensionMismatch)` on a wrong length.
    pub fn from_data(width: u32, height: u32, data: Vec<[f32; 3]>) -> Result<Self> {
        check_len("ImageRgbF32 data", width, height, data.len())?;
        Ok(Self { width, height, data })
    }

    /// Pixel `(x, y)`. Panics if out of range.
    #[inline]
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        self.data[y as usize * self.width as usize + x as usize]
    }

    /// Sets pixel `(x, y)`. Panics if out of range.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: [f32; 3]) {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        self.data[y as usize * self.width as usize + x as usize] = v;
    }

    /// Rec. 709 luminance `0.2126 R + 0.7152 G + 0.0722 B` per pixel (on the stored values, no
    /// gamma decoding).
    pub fn luminance(&self) -> ImageF32 {
        ImageF32 { width: self.width, height: self.height, data: self.data.iter().map(|&c| luminance(c)).collect() }
    }
}

/// Rec. 709 luma weights applied to the stored (not linearised) values.
#[inline]
pub(crate) fn luminance(c: [f32; 3]) -> f32 {
    (0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64) as f32
}

/// A binary image (silhouettes, regions of interest), row-major.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` flags, `data[y · width + x]`.
    pub data: Vec<bool>,
}

impl Mask {
    /// A `width × height` mask filled with `v`.
    pub fn new(width: u32, height: u32, v: bool) -> Self {
        Self { width, height, data: vec![v; width as usize * height as usize] }
    }

    /// A mask from row-major data; `Err(DimensionMismatch)` on a wrong length.
    pub fn from_data(width: u32, height: u32, data: Vec<bool>) -> Result<Self> {
        check_len("Mask data", width, height, data.len())?;
        Ok(Self { width, height, data })
    }

    /// Flag of pixel `(x, y)`. Panics if out of range.
    #[inline]
    pub fn at(&self, x: u32, y: u32) -> bool {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        self.data[y as usize * self.width as usize + x as usize]
    }

    /// Sets pixel `(x, y)`. Panics if out of range.
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: bool) {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        self.data[y as usize * self.width as usize + x as usize] = v;
    }

    /// Number of set pixels.
    pub fn count(&self) -> usize {
        self.data.iter().filter(|&&b| b).count()
    }

    /// The mask as a 0/1 image.
    pub fn to_image(&self) -> ImageF32 {
        ImageF32 {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn border_indices() {
        assert_eq!(Border::Clamp.index(-3, 5), Some(0));
        assert_eq!(Border::Clamp.index(7, 5), Some(4));
        assert_eq!(Border::Wrap.index(-1, 5), Some(4));
        assert_eq!(Border::Wrap.index(11, 5), Some(1));
        assert_eq!(Border::Zero.index(5, 5), None);
        assert_eq!(Border::Zero.index(2, 5), Some(2));
    }

    #[test]
    fn bilinear_is_exact_at_centres_and_linear_between() {
        let mut img = ImageF32::new(3, 2, 0.0);
        for y in 0..2 {
            for x in 0..3 {
                img.set(x, y, (x + 10 * y) as f32);
            }
        }
        assert_eq!(img.sample_bilinear(2.0, 1.0, Border::Clamp), 12.0);
        assert_eq!(img.sample_bilinear(0.5, 0.5, Border::Clamp), 5.5);
        assert_eq!(img.sample_bilinear(-1.0, 0.0, Border::Clamp), 0.0);
        assert_eq!(img.sample_bilinear(-1.0, 0.0, Border::Wrap), 2.0);
        assert_eq!(img.sample_bilinear(2.5, 0.0, Border::Zero), 1.0);
    }

    #[test]
    fn wrong_lengths_are_errors() {
        assert!(matches!(
            ImageF32::from_data(2, 2, vec![0.0; 3]),
            Err(Error::DimensionMismatch { expected: 4, got: 3, .. })
        ));
        assert!(Mask::from_data(1, 2, vec![true, false]).is_ok());
    }
}
