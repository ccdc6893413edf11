//! Mean structural similarity (SSIM) on luma.
//!
//! > Z. Wang, A. C. Bovik, H. R. Sheikh and E. P. Simoncelli, "Image Quality
//! > Assessment: From Error Visibility to Structural Similarity",
//! > *IEEE Trans. Image Processing* 13(4), 600–612, 2004.
//!
//! For each pixel, local means `μ`, variances `σ²` and covariance `σxy` are
//! taken under an 11×11 circular-symmetric Gaussian window of standard
//! deviation 1.5 (the paper's choice, normalised to unit sum), and
//!
//! ```text
//! SSIM = (2·μx·μy + C1)(2·σxy + C2) / ((μx² + μy² + C1)(σx² + σy² + C2))
//! C1 = (K1·L)², C2 = (K2·L)², K1 = 0.01, K2 = 0.03, L = 1
//! ```
//!
//! The reported value is the mean over the pixels whose whole window lies
//! inside the image (the reference MATLAB code's `'valid'` filtering). Images
//! smaller than the window in either direction use every pixel, with the
//! window clamped to the edge. The paper's optional down-sampling of large
//! images is not applied.
//!
//! SSIM is defined on one channel; we use the luma `Y' = 0.299 R' + 0.587 G'
//! + 0.114 B'` of the display-encoded values (ITU-R BT.601 weights, as
//! MATLAB's `rgb2gray`, which the reference implementation is run on).

use rayon::prelude::*;

use super::filter::{filter_separable, gaussian_kernel};

/// `K1` of the paper.
const K1: f64 = 0.01;
/// `K2` of the paper.
const K2: f64 = 0.03;
/// Dynamic range of the values: display values in [0, 1].
const L: f64 = 1.0;
/// Standard deviation of the Gaussian window, in pixels.
const WINDOW_SIGMA: f32 = 1.5;
/// Window radius: 11×11 taps.
const WINDOW_RADIUS: usize = 5;

/// BT.601 luma of a display-encoded RGB value.
pub fn luma(p: [f32; 3]) -> f32 {
    0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]
}

/// Mean SSIM of two luma planes of the same size (`width` pixels per row).
///
/// The moments are filtered in `f64`: in `f32` the cancellation in
/// `E[x²] − μ²` leaves errors of ~1e-7, visible against `C2` ≈ 1e-3.
pub fn mean_ssim(x: &[f32], y: &[f32], width: usize) -> f64 {
    debug_assert_eq!(x.len(), y.len());
    if x.is_empty() || width == 0 {
        return 1.0;
    }
    let height = x.len() / width;
    let k: Vec<f64> = gaussian_kernel(f64::from(WINDOW_SIGMA), WINDOW_RADIUS);
    let blur = |p: &[f64]| filter_separable(p, width, &k, &k);

    let x: Vec<f64> = x.par_iter().map(|&v| f64::from(v)).collect();
    let y: Vec<f64> = y.par_iter().map(|&v| f64::from(v)).collect();
    let (x, y) = (&x[..], &y[..]);
    let xx: Vec<f64> = x.par_iter().map(|v| v * v).collect();
    let yy: Vec<f64> = y.par_iter().map(|v| v * v).collect();
    let xy: Vec<f64> = x.par_iter().zip(y).map(|(a, b)| a * b).collect();
    let ((mu_x, mu_y), (e_xx, (e_yy, e_xy))) = rayon::join(
        || rayon::join(|| blur(x), || blur(y)),
        || rayon::join(|| blur(&xx), || rayon::join(|| blur(&yy), || blur(&xy))),
    );

    let c1 = (K1 * L).powi(2);
    let c2 = (K2 * L).powi(2);
    let window = 2 * WINDOW_RADIUS + 1;
    let (x0, x1, y0, y1) = if width >= window && height >= window {
        (WINDOW_RADIUS, width - WINDOW_RADIUS, WINDOW_RADIUS, height - WINDOW_RADIUS)
    } else {
        (0, width, 0, height)
    };
    let sum: f64 = (y0..y1)
        .into_par_iter()
        .map(|row| {
            let mut s = 0.0;
            for col in x0..x1 {
                let i = row * width + col;
                let (mx, my) = (mu_x[i], mu_y[i]);
                let sxx = e_xx[i] - mx * mx;
                let syy = e_yy[i] - my * my;
                let sxy = e_xy[i] - mx * my;
                s +=
                    ((2.0 * mx * my + c1) * (2.0 * sxy + c2)) / ((mx * mx + my * my + c1) * (sxx + syy + c2));
            }
            s
        })
        .sum();
    sum / ((x1 - x0) * (y1 - y0)) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_planes_give_one() {
        let p: Vec<f32> = (0..30 * 20).map(|i| ((i * 7) % 13) as f32 / 13.0).collect();
        assert_eq!(mean_ssim(&p, &p, 30), 1.0);
        assert_eq!(mean_ssim(&p[..12], &p[..12], 4), 1.0);
    }

    #[test]
    fn constant_planes_follow_the_luminance_term() {
        // With no structure, SSIM reduces to (2ab + C1) / (a² + b² + C1).
        let (a, b) = (0.3f32, 0.5f32);
        let x = vec![a; 16 * 16];
        let y = vec![b; 16 * 16];
        let (a, b) = (f64::from(a), f64::from(b));
        let c1 = (K1 * L).powi(2);
        let expected = (2.0 * a * b + c1) / (a * a + b * b + c1);
        let got = mean_ssim(&x, &y, 16);
        assert!((got - expected).abs() < 1e-5, "{got} vs {expected}");
    }

    #[test]
    fn inverted_structure_is_negative() {
        let x: Vec<f32> = (0..32 * 32).map(|i| if (i / 32 + i % 32) % 2 == 0 { 0.2 } else { 0.8 }).collect();
        let y: Vec<f32> = x.iter().map(|v| 1.0 - v).collect();
        assert!(mean_ssim(&x, &y, 32) < 0.0);
    }
}
