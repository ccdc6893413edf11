//! `luster compare`: how far a test image is from a reference image.
//!
//! Prints PSNR, SSIM, the mean LDR-FLIP error (Andersson et al., "FLIP: A
//! Difference Evaluator for Alternating Images", HPG 2020), how many pixels
//! differ and where, the largest channel difference, and the space the
//! numbers were computed in; optionally writes the FLIP heatmap. The metrics
//! are the library's ([`luster::metrics::compare`]), the same the conformance
//! suite judges by.
//!
//! Exit codes: 0 when the images compared (and met `--max-error` /
//! `--min-psnr` when given), 1 when a given bound was not met, 2 when an
//! image could not be read, the sizes differ, or the heatmap could not be
//! written.

use luster::image::{Encoding, Rgb32Image};
use luster::metrics::{
    comparison_heatmap, write_heatmap, CompareOptions, Comparison, HeatmapSource, MetricSpace,
};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// What `luster compare` was asked.
pub struct Args {
    /// The reference image.
    pub reference: PathBuf,
    /// The test image.
    pub test: PathBuf,
    /// Where to write the FLIP heatmap.
    pub heatmap: Option<PathBuf>,
    /// Largest acceptable mean LDR-FLIP.
    pub max_error: Option<f64>,
    /// Smallest acceptable PSNR in dB.
    pub min_psnr: Option<f64>,
    /// Per-channel 8-bit difference still counted as equal.
    pub tolerance: u8,
    /// Exposure in stops for EXR/HDR images.
    pub exposure: f32,
}

/// Compares, prints, and returns the exit code.
pub fn run(args: &Args) -> ExitCode {
    let fail = |msg: String| {
        super::report("error", &msg);
        ExitCode::from(2)
    };
    let (reference, test) =
        rayon::join(|| Rgb32Image::load(&args.reference), || Rgb32Image::load(&args.test));
    let (reference, test) = match (reference, test) {
        (Ok(r), Ok(t)) => (r, t),
        (Err(e), _) | (_, Err(e)) => return fail(e.to_string()),
    };
    let opts =
        CompareOptions { tolerance: args.tolerance, exposure: args.exposure, ..CompareOptions::default() };
    let c = match luster::metrics::compare(&reference, &test, &opts) {
        Ok(c) => c,
        Err(e) => {
            return fail(format!("{} and {}: {e}", args.reference.display(), args.test.display()));
        }
    };
    print_comparison(args, &reference, &test, &c);
    if c.space == MetricSpace::Linear {
        if let Ok(rel) = luster::metrics::relative_error(&reference, &test) {
            say!("{:<10} {:.4}% (Σ|t − r| / Σ|r|, linear light)", "rel. MAE", 100.0 * rel.mae);
            say!("{:<10} {:.6} (mean (t − r)² / (r² + 0.01))", "rel. MSE", rel.mse);
        }
    }
    let flip_name = if c.space == MetricSpace::Linear { "HDR-FLIP" } else { "LDR-FLIP" };
    if let Some(path) = &args.heatmap {
        match comparison_heatmap(&c, HeatmapSource::Flip).and_then(|h| write_heatmap(&h, path)) {
            Ok(()) => say!("{:<10} {} ({flip_name} per pixel, magma colour map)", "heatmap", path.display()),
            Err(e) => return fail(e.to_string()),
        }
    }
    let mut unmet = Vec::new();
    if let Some(max) = args.max_error {
        if c.flip > max || c.flip.is_nan() {
            unmet.push(format!("mean {flip_name} {:.4} is above --max-error {max}", c.flip));
        }
    }
    if let Some(min) = args.min_psnr {
        if c.psnr < min || c.psnr.is_nan() {
            unmet.push(format!("PSNR {:.2} dB is below --min-psnr {min}", c.psnr));
        }
    }
    if unmet.is_empty() {
        if args.max_error.is_some() || args.min_psnr.is_some() {
            say!("{:<10} met", "bounds");
        }
        ExitCode::SUCCESS
    } else {
        for u in &unmet {
            say!("{:<10} NOT MET: {u}", "bounds");
        }
        ExitCode::from(1)
    }
}

fn encoding(e: Encoding) -> &'static str {
    match e {
        Encoding::Srgb => "sRGB",
        Encoding::Linear => "linear",
    }
}

fn describe(path: &Path, img: &Rgb32Image) -> String {
    format!("{}  ({}×{}, {})", path.display(), img.width, img.height, encoding(img.encoding))
}

fn print_comparison(args: &Args, reference: &Rgb32Image, test: &Rgb32Image, c: &Comparison) {
    say!("{:<10} {}", "reference", describe(&args.reference, reference));
    say!("{:<10} {}", "test", describe(&args.test, test));
    let space = match c.space {
        MetricSpace::Display => "display values (sRGB-encoded, 0 to 1)".to_string(),
        MetricSpace::Linear => {
            format!(
                "linear light (both EXR/HDR; HDR-FLIP; SSIM after {:+} stops and clamping)",
                args.exposure
            )
        }
    };
    say!("{:<10} {space}", "space");
    if c.psnr.is_infinite() {
        say!("{:<10} inf dB (identical)", "PSNR");
    } else {
        say!("{:<10} {:.2} dB", "PSNR", c.psnr);
    }
    say!("{:<10} {:.4}", "SSIM", c.ssim);
    let flip_name = if c.space == MetricSpace::Linear { "HDR-FLIP" } else { "LDR-FLIP" };
    say!("{:<10} {:.4} (mean {flip_name}, 0 = no visible difference)", "FLIP", c.flip);
    let total = u64::from(c.width) * u64::from(c.height);
    say!(
        "{:<10} {} of {} pixels ({:.3}%) with an 8-bit channel differing by more than {}",
        "differing",
        c.differing_pixels,
        total,
        100.0 * c.differing_fraction(),
        args.tolerance
    );
    match c.diff_bbox {
        Some((x0, y0, x1, y1)) => {
            say!("{:<10} x {x0}..={x1}, y {y0}..={y1} ({}×{} pixels)", "bbox", x1 - x0 + 1, y1 - y0 + 1)
        }
        None => say!("{:<10} none", "bbox"),
    }
    say!("{:<10} {:.4} (largest absolute channel difference)", "max |Δ|", c.max_abs_diff);
}
