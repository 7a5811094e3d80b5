//! Images (GEOM-CORE.md §3.14): single-channel [`ImageF32`], colour [`ImageRgbF32`] and binary
//! [`Mask`] buffers, PNG reading and writing (the `png` crate), animated PNG ([`write_apng`]),
//! Gaussian blur and separable convolution.
//!
//! Conventions: row-major storage, `data[y · width + x]`; pixel `(0, 0)` is the top-left pixel
//! and its centre has continuous coordinates `(0.0, 0.0)` (the OpenCV convention shared with
//! [`crate::raster`]); `x` grows to the right, `y` downwards. Intensities are `f32`, normally in
//! `[0, 1]` for display.

mod apng;
mod buffers;
mod filter;
mod png_io;

pub use apng::{encode_apng, write_apng};
pub use buffers::{Border, ImageF32, ImageRgbF32, Mask};
pub use filter::{convolve_separable, gaussian_blur, gaussian_kernel};
pub use png_io::{
    encode_png_gray16, encode_png_gray8, encode_png_mask, encode_png_rgb8, png_gray8_bytes, read_png, read_png_rgb,
    write_png_gray16, write_png_gray8, write_png_mask, write_png_rgb8,
};
