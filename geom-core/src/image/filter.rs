//! Separable filtering: [`convolve_separable`] and [`gaussian_blur`].

use rayon::prelude::*;

use super::buffers::{Border, ImageF32};

/// Normalised 1-D Gaussian kernel of standard deviation `sigma_px` (pixels) and radius
/// `⌈3σ⌉` (length `2⌈3σ⌉ + 1`), weights `exp(−i²/2σ²)` divided by their sum. A non-positive or
/// non-finite `sigma_px` gives the identity kernel `[1]`.
pub fn gaussian_kernel(sigma_px: f64) -> Vec<f32> {
    if !(sigma_px.is_finite() && sigma_px > 0.0) {
        return vec![1.0];
    }
    let r = (3.0 * sigma_px).ceil() as i64;
    let w: Vec<f64> = (-r..=r).map(|i| (-((i * i) as f64) / (2.0 * sigma_px * sigma_px)).exp()).collect();
    let s: f64 = w.iter().sum();
    w.iter().map(|&v| (v / s) as f32).collect()
}

/// Gaussian blur of standard deviation `sigma_px` pixels: [`convolve_separable`] with
/// [`gaussian_kernel`] along x and y. With [`Border::Wrap`] the image mean is preserved (up to
/// f32 rounding of the weights); a constant image stays constant with [`Border::Clamp`] and
/// [`Border::Wrap`].
pub fn gaussian_blur(img: &ImageF32, sigma_px: f64, b: Border) -> ImageF32 {
    let k = gaussian_kernel(sigma_px);
    convolve_separable(img, &k, &k, b)
}

/// Separable convolution (correlation form): first along x,
/// `t(x, y) = Σ_k kx[k] · img(x + k − ⌊len_x/2⌋, y)`, then along y with `ky` likewise; pixels
/// outside the image are read by the border rule `b`. Odd-length kernels are centred; for even
/// lengths the centre is the element `len/2`. An empty kernel is the zero kernel (the result is
/// all zeros). Sums are accumulated in f64; rows run in parallel with a deterministic result.
pub fn convolve_separable(img: &ImageF32, kx: &[f32], ky: &[f32], b: Border) -> ImageF32 {
    let (w, h) = (img.width as usize, img.height as usize);
    if w == 0 || h == 0 {
        return img.clone();
    }
    let cx = (kx.len() / 2) as i64;
    let cy = (ky.len() / 2) as i64;
    let mut tmp = vec![0.0f64; w * h];
    tmp.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let src = &img.data[y * w..(y + 1) * w];
        for (x, out) in row.iter_mut().enumerate() {
            let mut acc = 0.0f64;
            for (k, &wk) in kx.iter().enumerate() {
                if let Some(i) = b.index(x as i64 + k as i64 - cx, img.width) {
                    acc += wk as f64 * src[i] as f64;
                }
            }
            *out = acc;
        }
    });
    let mut out = ImageF32::new(img.width, img.height, 0.0);
    out.data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let mut acc = 0.0f64;
            for (k, &wk) in ky.iter().enumerate() {
                if let Some(j) = b.index(y as i64 + k as i64 - cy, img.height) {
                    acc += wk as f64 * tmp[j * w + x];
                }
            }
            *o = acc as f32;
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_is_normalised_with_radius_three_sigma() {
        let k = gaussian_kernel(1.2);
        assert_eq!(k.len(), 2 * 4 + 1);
        let s: f64 = k.iter().map(|&v| v as f64).sum();
        assert!((s - 1.0).abs() < 1e-6);
        assert_eq!(gaussian_kernel(0.0), vec![1.0]);
    }

    #[test]
    fn delta_spreads_into_the_kernel() {
        let mut img = ImageF32::new(7, 5, 0.0);
        img.set(3, 2, 1.0);
        let out = convolve_separable(&img, &[0.25, 0.5, 0.25], &[1.0], Border::Zero);
        assert_eq!(&out.data[2 * 7..3 * 7], &[0.0, 0.0, 0.25, 0.5, 0.25, 0.0, 0.0]);
        let out = convolve_separable(&img, &[], &[1.0], Border::Zero);
        assert!(out.data.iter().all(|&v| v == 0.0));
    }
}
