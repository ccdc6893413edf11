//! Known-answer tests for [`compare`](super::compare).

use super::*;

/// xorshift64* — a tiny deterministic generator for test noise.
struct XorShift(u64);

impl XorShift {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// Standard normal by Box–Muller.
    fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

fn flat(w: u32, h: u32, v: f32) -> Rgb32Image {
    Rgb32Image::from_fn(w, h, Encoding::Srgb, |_, _| [v; 3])
}

/// A smooth, structured test picture (gradients and a disc), values in [0.1, 0.9].
fn picture(w: u32, h: u32) -> Rgb32Image {
    Rgb32Image::from_fn(w, h, Encoding::Srgb, |x, y| {
        let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
        let disc = if (u - 0.5).powi(2) + (v - 0.5).powi(2) < 0.09 { 0.3 } else { 0.0 };
        [0.1 + 0.6 * u + disc * 0.5, 0.1 + 0.6 * v, 0.5 + disc - 0.2 * u]
    })
}

fn noisy(base: &Rgb32Image, sigma: f64, seed: u64) -> Rgb32Image {
    let mut rng = XorShift(seed);
    let mut out = base.clone();
    for p in &mut out.pixels {
        for c in p.iter_mut() {
            *c += (sigma * rng.gaussian()) as f32;
        }
    }
    out
}

fn opts() -> CompareOptions {
    CompareOptions::default()
}

#[test]
fn identical_images() {
    let a = picture(64, 48);
    let c = compare(&a, &a, &opts()).unwrap();
    assert_eq!(c.psnr, f64::INFINITY);
    assert_eq!(c.mse, 0.0);
    assert_eq!(c.ssim, 1.0);
    assert_eq!(c.flip, 0.0);
    assert!(c.flip_map.iter().all(|v| *v == 0.0));
    assert_eq!(c.differing_pixels, 0);
    assert_eq!(c.diff_bbox, None);
    assert_eq!(c.max_abs_diff, 0.0);
    assert_eq!(c.space, MetricSpace::Display);
}

#[test]
fn one_changed_pixel() {
    let (w, h) = (40u32, 30u32);
    let a = flat(w, h, 0.5);
    let mut b = a.clone();
    let d = 0.25f32;
    *b.get_mut(17, 9).unwrap() = [0.5 + d; 3];
    let c = compare(&a, &b, &opts()).unwrap();
    assert_eq!(c.differing_pixels, 1);
    assert_eq!(c.diff_bbox, Some((17, 9, 17, 9)));
    assert_eq!(c.max_abs_diff, d);
    // MSE = 3d² / (3N): PSNR = 10·log10(N / d²).
    let n = f64::from(w * h);
    let expected = 10.0 * (n / f64::from(d * d)).log10();
    assert!((c.psnr - expected).abs() < 1e-9, "{} vs {expected}", c.psnr);
    assert!(c.ssim < 1.0);
    assert!(c.flip > 0.0);
    // FLIP is local: far from the change the error is zero; at the pixel the
    // CSF blurs a lone pixel, so the error is clearly visible but not maximal.
    assert_eq!(c.flip_map[0], 0.0);
    let at = c.flip_map[9 * w as usize + 17];
    assert!(at > 0.1, "{at}");
    assert!(c.flip_map.iter().all(|v| *v <= at));
}

#[test]
fn bbox_spans_scattered_changes_and_tolerance() {
    let a = flat(20, 20, 0.5);
    let mut b = a.clone();
    *b.get_mut(2, 15).unwrap() = [0.5, 0.5 + 3.0 / 255.0, 0.5];
    *b.get_mut(11, 4).unwrap() = [0.5 + 1.0 / 255.0, 0.5, 0.5];
    let c = compare(&a, &b, &opts()).unwrap();
    assert_eq!(c.differing_pixels, 2);
    assert_eq!(c.diff_bbox, Some((2, 4, 11, 15)));
    let tolerant = CompareOptions { tolerance: 1, ..opts() };
    let c = compare(&a, &b, &tolerant).unwrap();
    assert_eq!(c.differing_pixels, 1);
    assert_eq!(c.diff_bbox, Some((2, 15, 2, 15)));
    // A change below half an 8-bit step is not a difference.
    let mut e = a.clone();
    e.pixels[0] = [0.5 + 0.4 / 255.0; 3];
    let c = compare(&a, &e, &opts()).unwrap();
    assert_eq!(c.differing_pixels, 0);
    assert!(c.mse > 0.0);
}

#[test]
fn constant_offset() {
    let base = flat(32, 32, 0.3);
    for offset in [0.01f32, 0.05, 0.2] {
        let shifted = flat(32, 32, 0.3 + offset);
        let c = compare(&base, &shifted, &opts()).unwrap();
        let o = f64::from(offset);
        assert!((c.mse - o * o).abs() < 1e-6 * o * o + 1e-9, "{}", c.mse);
        assert!((c.psnr + 20.0 * o.log10()).abs() < 1e-3, "{}", c.psnr);
        assert_eq!(c.differing_pixels, 32 * 32);
        assert_eq!(c.diff_bbox, Some((0, 0, 31, 31)));
    }
}

#[test]
fn gaussian_noise_psnr_and_monotone_ssim() {
    let base = flat(256, 256, 0.5);
    let mut last_ssim = 1.0;
    let mut last_flip = 0.0;
    for (i, sigma) in [0.005, 0.01, 0.02, 0.05, 0.1].into_iter().enumerate() {
        let test = noisy(&base, sigma, 0x9E37_79B9_7F4A_7C15 + i as u64);
        let c = compare(&base, &test, &opts()).unwrap();
        let expected = -20.0 * sigma.log10();
        assert!((c.psnr - expected).abs() < 0.2, "σ = {sigma}: PSNR {} vs {expected}", c.psnr);
        assert!(c.ssim < last_ssim, "σ = {sigma}: SSIM {} !< {last_ssim}", c.ssim);
        assert!(c.flip > last_flip, "σ = {sigma}: FLIP {} !> {last_flip}", c.flip);
        last_ssim = c.ssim;
        last_flip = c.flip;
    }
}

#[test]
fn ssim_falls_with_noise_on_a_picture() {
    let base = picture(96, 96);
    let values: Vec<f64> = [0.0, 0.01, 0.03, 0.1]
        .iter()
        .map(|&s| compare(&base, &noisy(&base, s, 7), &opts()).unwrap().ssim)
        .collect();
    assert_eq!(values[0], 1.0);
    assert!(values.windows(2).all(|w| w[1] < w[0]), "{values:?}");
}

#[test]
fn flip_black_vs_white_and_tiny_noise() {
    let black = flat(48, 48, 0.0);
    let white = flat(48, 48, 1.0);
    let c = compare(&black, &white, &opts()).unwrap();
    // HyAB = 100, 100^0.7 = 25.1 above the knee 0.4·cmax: ≈ 0.967 everywhere.
    assert!(c.flip > 0.95 && c.flip <= 1.0, "{}", c.flip);
    assert_eq!(c.psnr, 0.0);

    let base = picture(64, 64);
    let c = compare(&base, &noisy(&base, 0.002, 3), &opts()).unwrap();
    assert!(c.flip < 0.05, "{}", c.flip);
    assert!(c.flip > 0.0);
}

#[test]
fn size_mismatch_names_both_sizes() {
    let err = compare(&flat(800, 600, 0.0), &flat(640, 480, 0.0), &opts()).unwrap_err();
    assert!(matches!(err, ImageError::SizeMismatch { .. }));
    let msg = err.to_string();
    assert!(msg.contains("800×600") && msg.contains("640×480"), "{msg}");
}

#[test]
fn malformed_buffers_and_empty_images_are_errors() {
    let mut bad = flat(4, 4, 0.0);
    bad.pixels.pop();
    assert!(matches!(compare(&bad, &flat(4, 4, 0.0), &opts()), Err(ImageError::BufferSize { .. })));
    assert!(matches!(compare(&flat(0, 3, 0.0), &flat(0, 3, 0.0), &opts()), Err(ImageError::Empty { .. })));
}

#[test]
fn linear_images_compare_in_linear_light() {
    let a = Rgb32Image::from_fn(16, 16, Encoding::Linear, |_, _| [2.0, 0.5, 0.1]);
    let b = Rgb32Image::from_fn(16, 16, Encoding::Linear, |_, _| [2.1, 0.5, 0.1]);
    let c = compare(&a, &b, &opts()).unwrap();
    assert_eq!(c.space, MetricSpace::Linear);
    // Only red differs, by 0.1: MSE = 0.01 / 3.
    assert!((c.mse - 0.01 / 3.0).abs() < 1e-7);
    assert!((c.max_abs_diff - 0.1).abs() < 1e-6);
    // Red is clipped at exposure 0, so the 8-bit counts see nothing…
    assert_eq!(c.differing_pixels, 0);
    // …but HDR-FLIP sweeps exposures and does.
    assert!(c.flip > 0.0);
    let darker = CompareOptions { exposure: -2.0, ..opts() };
    let d = compare(&a, &b, &darker).unwrap();
    assert_eq!(d.differing_pixels, 256);
    assert_eq!(d.flip, c.flip, "HDR-FLIP does not depend on the display exposure");

    // Mixed encodings compare display values.
    let srgb = flat(16, 16, 0.5);
    let lin = Rgb32Image::from_fn(16, 16, Encoding::Linear, |_, _| {
        [luster_core::image::buffer::srgb_to_linear(0.5); 3]
    });
    let c = compare(&srgb, &lin, &opts()).unwrap();
    assert_eq!(c.space, MetricSpace::Display);
    assert!(c.max_abs_diff < 1e-6);
    assert_eq!(c.differing_pixels, 0);
}

#[test]
fn non_finite_samples_do_not_poison_metrics() {
    let a = Rgb32Image::from_fn(12, 12, Encoding::Linear, |_, _| [0.5; 3]);
    let mut b = a.clone();
    b.pixels[5] = [f32::NAN, f32::INFINITY, 0.5];
    let c = compare(&a, &b, &opts()).unwrap();
    assert!(c.mse.is_finite() && c.psnr.is_finite());
    assert!(c.ssim.is_finite() && c.flip.is_finite());
    assert_eq!(c.differing_pixels, 1);
}

#[test]
fn relative_error_is_scale_free_and_zero_for_equal_images() {
    let r = Rgb32Image::from_fn(4, 4, Encoding::Linear, |x, y| [x as f32 * 100.0, y as f32, 0.5]);
    assert_eq!(relative_error(&r, &r).unwrap().mae, 0.0);
    let t = Rgb32Image::from_fn(4, 4, Encoding::Linear, |x, y| [x as f32 * 101.0, y as f32 * 1.01, 0.505]);
    let e = relative_error(&r, &t).unwrap();
    assert!((e.mae - 0.01).abs() < 1e-6, "{}", e.mae);
    let small = Rgb32Image::new(2, 2, Encoding::Linear);
    assert!(relative_error(&r, &small).is_err());
}
