//! Comparing a test image against a reference: PSNR, SSIM, LDR-FLIP and
//! pixel-exact statistics.
//!
//! This is the core of `luster compare` and of the golden-image tests that
//! check our renders against the course's expected images.
//!
//! # Which values each metric sees
//! | metric | both images sRGB (PNG/JPEG) | both linear (EXR/HDR) | mixed |
//! |---|---|---|---|
//! | `mse`, `psnr`, `max_abs_diff`, `diff_map` | stored display values | linear values, unclamped | display values |
//! | `ssim` | luma of display values | luma of display values | same |
//! | `flip`, `flip_map` | LDR-FLIP on display values | HDR-FLIP on linear values | LDR-FLIP on display values |
//! | `differing_pixels`, `diff_bbox` | 8-bit codes of display values | 8-bit codes of display values | same |
//!
//! "Display values" of a linear image are `srgb(clamp(2^exposure · v))` with
//! [`CompareOptions::exposure`]; of an sRGB image, the stored values clamped to
//! [0, 1]. PSNR on two linear images therefore measures error in linear light
//! with peak 1, and can be negative where the images are brighter than 1.
//! FLIP on two linear images is HDR-FLIP ([`super::hdr_flip`]: LDR-FLIP swept
//! over the exposures the reference's luminance range calls for, through a
//! tone mapper), so highlights above 1 are compared too; it does not depend on
//! [`CompareOptions::exposure`].
//!
//! For two linear images, [`relative_error`] gives the HDR measures that do
//! not depend on exposure: the relative mean absolute error
//! `Σ|t − r| / Σ|r|` (over all channels of all pixels) and the relative MSE
//! `mean((t − r)² / (r² + 0.01))` (Rousselle et al. 2011).
//!
//! PSNR is `10·log10(1 / MSE)` over all three channels of all pixels, i.e. the
//! usual 8-bit PSNR with values scaled to [0, 1]; it is `+∞` when MSE is 0.
//! Non-finite samples count as 0.

use rayon::prelude::*;

use super::flip::{ldr_flip_map, DEFAULT_PIXELS_PER_DEGREE};
use super::hdr_flip::hdr_flip_map;
use super::ssim::{luma, mean_ssim};
use luster_core::image::buffer::{quantize8, srgb_to_linear, Encoding, Rgb32Image};
use luster_core::image::error::ImageError;

/// Settings of a comparison.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareOptions {
    /// Pixels per degree of visual angle of the FLIP observer
    /// (default 67.0, the FLIP paper's setup).
    pub pixels_per_degree: f32,
    /// A pixel counts as differing when some channel's 8-bit code differs by
    /// more than this (default 0: any difference after rounding to 8 bits).
    pub tolerance: u8,
    /// Exposure in stops applied to linear (EXR/HDR) images before they are
    /// clamped and sRGB-encoded for the display-referred metrics (default 0).
    pub exposure: f32,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self { pixels_per_degree: DEFAULT_PIXELS_PER_DEGREE, tolerance: 0, exposure: 0.0 }
    }
}

/// The values MSE and PSNR were computed on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetricSpace {
    /// Display-referred (sRGB-encoded) values in [0, 1].
    Display,
    /// Linear light (both inputs were EXR/HDR).
    Linear,
}

/// The result of [`compare`].
#[derive(Debug, Clone, PartialEq)]
pub struct Comparison {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The space of `mse`, `psnr`, `max_abs_diff` and `diff_map`.
    pub space: MetricSpace,
    /// Mean squared error over all channels of all pixels.
    pub mse: f64,
    /// Peak signal-to-noise ratio in dB with peak 1; `+∞` for identical images.
    pub psnr: f64,
    /// Mean SSIM on luma (1 for identical images).
    pub ssim: f64,
    /// Mean FLIP error in [0, 1] (0 for identical images): HDR-FLIP when
    /// `space` is [`MetricSpace::Linear`], LDR-FLIP otherwise.
    pub flip: f64,
    /// Per-pixel FLIP error, row-major.
    pub flip_map: Vec<f32>,
    /// Per-pixel largest absolute channel difference, row-major.
    pub diff_map: Vec<f32>,
    /// Number of pixels whose 8-bit codes differ by more than the tolerance.
    pub differing_pixels: usize,
    /// Inclusive bounding box `(x0, y0, x1, y1)` of the differing pixels.
    pub diff_bbox: Option<(u32, u32, u32, u32)>,
    /// Largest absolute difference of any channel of any pixel.
    pub max_abs_diff: f32,
}

impl Comparison {
    /// Fraction of pixels that differ (0 to 1).
    pub fn differing_fraction(&self) -> f64 {
        let n = self.width as usize * self.height as usize;
        if n == 0 {
            0.0
        } else {
            self.differing_pixels as f64 / n as f64
        }
    }
}

/// Per-row partial results of the pixel statistics.
#[derive(Clone, Copy)]
struct Stats {
    sum_sq: f64,
    max_abs: f32,
    differing: usize,
    bbox: Option<(u32, u32, u32, u32)>,
}

impl Stats {
    const EMPTY: Stats = Stats { sum_sq: 0.0, max_abs: 0.0, differing: 0, bbox: None };

    fn merge(self, other: Stats) -> Stats {
        let bbox = match (self.bbox, other.bbox) {
            (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.min(b.1), a.2.max(b.2), a.3.max(b.3))),
            (a, b) => a.or(b),
        };
        Stats {
            sum_sq: self.sum_sq + other.sum_sq,
            max_abs: self.max_abs.max(other.max_abs),
            differing: self.differing + other.differing,
            bbox,
        }
    }
}

fn finite_or_zero(c: f32) -> f32 {
    if c.is_finite() {
        c
    } else {
        0.0
    }
}

/// Refuses a pair that cannot be compared: a buffer that does not match its
/// stated size, two sizes, or no pixels.
fn check_pair(reference: &Rgb32Image, test: &Rgb32Image) -> Result<(), ImageError> {
    reference.check_len()?;
    test.check_len()?;
    if (reference.width, reference.height) != (test.width, test.height) {
        return Err(ImageError::SizeMismatch {
            reference: (reference.width, reference.height),
            test: (test.width, test.height),
        });
    }
    if reference.is_empty() {
        return Err(ImageError::Empty { width: reference.width, height: reference.height });
    }
    Ok(())
}

/// Compares `test` against `reference`.
///
/// Fails when the sizes differ (the error names both), when a pixel buffer
/// does not match its stated size, or when the images have no pixels.
pub fn compare(
    reference: &Rgb32Image,
    test: &Rgb32Image,
    opts: &CompareOptions,
) -> Result<Comparison, ImageError> {
    check_pair(reference, test)?;
    let width = reference.width as usize;

    let (ref_display, test_display) =
        rayon::join(|| reference.to_display(opts.exposure), || test.to_display(opts.exposure));
    let space = if reference.encoding == Encoding::Linear && test.encoding == Encoding::Linear {
        MetricSpace::Linear
    } else {
        MetricSpace::Display
    };
    let (ref_metric, test_metric): (&[[f32; 3]], &[[f32; 3]]) = match space {
        MetricSpace::Linear => (&reference.pixels, &test.pixels),
        MetricSpace::Display => (&ref_display, &test_display),
    };

    // Pixel statistics: squared error, largest difference, 8-bit differences.
    let diff_map: Vec<f32> = ref_metric
        .par_iter()
        .zip(test_metric)
        .map(|(a, b)| (0..3).map(|c| (finite_or_zero(a[c]) - finite_or_zero(b[c])).abs()).fold(0.0, f32::max))
        .collect();
    let tolerance = opts.tolerance;
    let stats = (0..reference.height)
        .into_par_iter()
        .map(|y| {
            let start = y as usize * width;
            let mut s = Stats::EMPTY;
            for x in 0..width {
                let i = start + x;
                let (a, b) = (ref_metric[i], test_metric[i]);
                for c in 0..3 {
                    let d = f64::from(finite_or_zero(a[c])) - f64::from(finite_or_zero(b[c]));
                    s.sum_sq += d * d;
                }
                s.max_abs = s.max_abs.max(diff_map[i]);
                let (qa, qb) = (ref_display[i].map(quantize8), test_display[i].map(quantize8));
                if (0..3).any(|c| qa[c].abs_diff(qb[c]) > tolerance) {
                    s.differing += 1;
                    let x = x as u32;
                    s.bbox = Some(match s.bbox {
                        None => (x, y, x, y),
                        Some((x0, y0, x1, y1)) => (x0.min(x), y0, x1.max(x), y1),
                    });
                }
            }
            s
        })
        .reduce(|| Stats::EMPTY, Stats::merge);
    let mse = stats.sum_sq / (3 * reference.len()) as f64;
    let psnr = if mse == 0.0 { f64::INFINITY } else { -10.0 * mse.log10() };

    // SSIM on display luma; LDR-FLIP on display values decoded to linear,
    // HDR-FLIP on two linear images.
    let (ssim, flip_map) = rayon::join(
        || {
            let lx: Vec<f32> = ref_display.iter().map(|p| luma(*p)).collect();
            let ly: Vec<f32> = test_display.iter().map(|p| luma(*p)).collect();
            mean_ssim(&lx, &ly, width)
        },
        || match space {
            MetricSpace::Linear => {
                hdr_flip_map(&reference.pixels, &test.pixels, width, opts.pixels_per_degree)
            }
            MetricSpace::Display => {
                let lin = |d: &[[f32; 3]]| -> Vec<[f32; 3]> {
                    d.par_iter().map(|p| p.map(srgb_to_linear)).collect()
                };
                ldr_flip_map(&lin(&ref_display), &lin(&test_display), width, opts.pixels_per_degree)
            }
        },
    );
    let flip = flip_map.iter().map(|&v| f64::from(v)).sum::<f64>() / flip_map.len() as f64;

    Ok(Comparison {
        width: reference.width,
        height: reference.height,
        space,
        mse,
        psnr,
        ssim,
        flip,
        flip_map,
        diff_map,
        differing_pixels: stats.differing,
        diff_bbox: stats.bbox,
        max_abs_diff: stats.max_abs,
    })
}

/// Exposure-independent errors of a linear test image against a linear
/// reference (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelativeError {
    /// `Σ|t − r| / Σ|r|`: 0.01 is "1% relative mean absolute error".
    pub mae: f64,
    /// `mean((t − r)² / (r² + 0.01))`.
    pub mse: f64,
}

/// [`RelativeError`] of `test` against `reference`; the sizes must match.
/// Non-finite samples count as 0. A black reference gives an infinite
/// relative MAE unless the test is black too (then 0).
pub fn relative_error(reference: &Rgb32Image, test: &Rgb32Image) -> Result<RelativeError, ImageError> {
    check_pair(reference, test)?;
    let (abs, refsum, rel_sq) = reference
        .pixels
        .par_iter()
        .zip(&test.pixels)
        .map(|(r, t)| {
            let mut acc = (0.0f64, 0.0f64, 0.0f64);
            for c in 0..3 {
                let (r, t) = (f64::from(finite_or_zero(r[c])), f64::from(finite_or_zero(t[c])));
                let d = t - r;
                acc.0 += d.abs();
                acc.1 += r.abs();
                acc.2 += d * d / (r * r + 0.01);
            }
            acc
        })
        .reduce(|| (0.0, 0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
    let mae = if abs == 0.0 { 0.0 } else { abs / refsum };
    Ok(RelativeError { mae, mse: rel_sq / (3 * reference.len()) as f64 })
}

#[cfg(test)]
mod tests;
