//! Separable filtering of single-channel float planes.
//!
//! Every filter the metrics need is separable, or a sum of separable terms:
//! SSIM's Gaussian window, FLIP's contrast-sensitivity Gaussians (the
//! blue–yellow one is a sum of two), and FLIP's edge and point detectors
//! (a derivative of a Gaussian in one axis times a Gaussian in the other). A
//! `(2r+1)²` 2-D filter thus costs two 1-D passes of `2r+1` taps.
//!
//! Borders are handled by clamping to the edge (replicating the outermost
//! pixel), as the FLIP reference implementation does (OpenCV
//! `BORDER_REPLICATE`). The passes compute a correlation
//! `out[x] = Σ k[i] · in[x + i − r]`; for the symmetric kernels this equals a
//! convolution, and for the antisymmetric edge kernel only the magnitude of
//! the response is used. Rows are distributed over rayon's pool.

use std::ops::{AddAssign, Mul};

use rayon::prelude::*;

/// A sample type the filters work on: `f32` (FLIP) or `f64` (SSIM, whose
/// variances `E[x²] − μ²` would lose digits to cancellation in `f32`).
pub(crate) trait Sample: Copy + Send + Sync + Default + Mul<Output = Self> + AddAssign {}
impl Sample for f32 {}
impl Sample for f64 {}

/// Filters each row of a `width × height` plane with the odd-length kernel `k`.
pub(crate) fn filter_rows<T: Sample>(src: &[T], width: usize, k: &[T]) -> Vec<T> {
    let r = k.len() / 2;
    let mut out = vec![T::default(); src.len()];
    if width == 0 {
        return out;
    }
    out.par_chunks_mut(width).zip(src.par_chunks(width)).for_each(|(dst, row)| {
        // Pad the row by replicating its end pixels, then run the kernel
        // without any bounds logic in the inner loop.
        let mut padded = Vec::with_capacity(width + 2 * r);
        padded.extend(std::iter::repeat_n(row[0], r));
        padded.extend_from_slice(row);
        padded.extend(std::iter::repeat_n(row[width - 1], r));
        // Tap-outer order: each tap is a multiply-add over the whole row,
        // which vectorises (a per-pixel dot product would be a reduction
        // the compiler may not reorder).
        for (i, &w) in k.iter().enumerate() {
            for (d, s) in dst.iter_mut().zip(&padded[i..i + width]) {
                *d += w * *s;
            }
        }
    });
    out
}

/// Filters each column of a `width × height` plane with the odd-length kernel `k`.
pub(crate) fn filter_cols<T: Sample>(src: &[T], width: usize, k: &[T]) -> Vec<T> {
    let r = k.len() / 2;
    let mut out = vec![T::default(); src.len()];
    if width == 0 {
        return out;
    }
    let height = src.len() / width;
    out.par_chunks_mut(width).enumerate().for_each(|(y, dst)| {
        // Accumulate whole source rows: contiguous, and vectorises well.
        for (i, &w) in k.iter().enumerate() {
            let sy = (y + i).saturating_sub(r).min(height - 1);
            let row = &src[sy * width..(sy + 1) * width];
            for (d, s) in dst.iter_mut().zip(row) {
                *d += w * *s;
            }
        }
    });
    out
}

/// Filters a plane with the separable kernel `kx(x) · ky(y)`.
pub(crate) fn filter_separable<T: Sample>(src: &[T], width: usize, kx: &[T], ky: &[T]) -> Vec<T> {
    filter_cols(&filter_rows(src, width, kx), width, ky)
}

/// A 1-D Gaussian `exp(−x² / (2σ²))` sampled at `x = −r..=r`, normalised to sum 1.
pub(crate) fn gaussian_kernel(sigma: f64, r: usize) -> Vec<f64> {
    let k: Vec<f64> =
        (-(r as i64)..=r as i64).map(|x| (-((x * x) as f64) / (2.0 * sigma * sigma)).exp()).collect();
    let sum: f64 = k.iter().sum();
    k.into_iter().map(|w| w / sum).collect()
}

/// Scales a kernel so its weights sum to 1.
pub(crate) fn normalize(mut k: Vec<f32>) -> Vec<f32> {
    let sum: f32 = k.iter().sum();
    if sum != 0.0 {
        k.iter_mut().for_each(|w| *w /= sum);
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct 2-D correlation with clamp-to-edge, for checking the separable passes.
    fn direct(src: &[f32], w: usize, h: usize, kx: &[f32], ky: &[f32]) -> Vec<f32> {
        let (rx, ry) = (kx.len() / 2, ky.len() / 2);
        let mut out = vec![0.0; src.len()];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for (j, wy) in ky.iter().enumerate() {
                    let sy = (y + j).saturating_sub(ry).min(h - 1);
                    for (i, wx) in kx.iter().enumerate() {
                        let sx = (x + i).saturating_sub(rx).min(w - 1);
                        s += wx * wy * src[sy * w + sx];
                    }
                }
                out[y * w + x] = s;
            }
        }
        out
    }

    #[test]
    fn separable_matches_direct_2d() {
        let (w, h) = (13, 7);
        let src: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 11) as f32).collect();
        let kx = [0.1, -0.5, 0.2, 0.7, 0.3];
        let ky = [0.25, 0.5, 0.25];
        let a = filter_separable(&src, w, &kx, &ky);
        let b = direct(&src, w, h, &kx, &ky);
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).abs() < 1e-4, "{p} vs {q}");
        }
    }

    #[test]
    fn kernel_wider_than_image() {
        let src = vec![1.0, 2.0, 3.0];
        let k: Vec<f32> = gaussian_kernel(2.0, 5).iter().map(|&w| w as f32).collect();
        let a = filter_separable(&src, 3, &k, &k);
        let b = direct(&src, 3, 1, &k, &k);
        for (p, q) in a.iter().zip(&b) {
            assert!((p - q).abs() < 1e-5);
        }
    }

    #[test]
    fn constant_plane_is_preserved() {
        let src = vec![0.5f64; 40 * 30];
        let k = gaussian_kernel(1.5, 5);
        assert!(filter_separable(&src, 40, &k, &k).iter().all(|v| (v - 0.5).abs() < 1e-12));
    }
}
