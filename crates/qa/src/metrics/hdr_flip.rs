//! HDR-FLIP (Andersson et al., "Visualizing Errors in Rendered High Dynamic
//! Range Images", Eurographics 2021 short paper): LDR-FLIP swept over the
//! exposures a viewer might choose, keeping each pixel's largest error.
//!
//! Both images are linear RGB (EXR/HDR). The exposure range comes from the
//! reference alone: the first exposure maps its largest luminance, the last
//! its median luminance, to 0.85 after the tone mapper; the count is the
//! number of whole stops between them, at least 2, evenly spaced. At each
//! exposure `e` both images are scaled by `2^e`, tone mapped by the paper's
//! ACES fit (Narkowicz's curve with its input scaled by 0.6), clamped to
//! [0, 1] and compared by [`ldr_flip_map`]. These are the defaults of NVIDIA's
//! reference implementation (`flip-evaluator`, which `tests/flip_reference.rs`
//! checks this against).

use super::flip::ldr_flip_map;
use rayon::prelude::*;

/// The tone mapper's rational curve `(x (a x + b) + c) / (x (d x + e) + f)`:
/// ACES as fitted by Narkowicz, with the input scaled by 0.6 (as FLIP does).
const ACES: [f32; 6] = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14];

/// The tone-mapped value both ends of the exposure range aim at.
const TARGET: f32 = 0.85;

fn tone_map(x: f32) -> f32 {
    let [a, b, c, d, e, f] = ACES.map(f64::from);
    // In f64 so that x² cannot overflow for any finite f32.
    let x = if x.is_finite() { f64::from(x.max(0.0)) } else { 0.0 };
    ((x * (a * x + b) + c) / (x * (d * x + e) + f)).clamp(0.0, 1.0) as f32
}

/// The input the tone mapper maps to [`TARGET`].
fn input_for_target() -> f32 {
    let [a0, b0, c0, d, e, f] = ACES;
    let (a, b, c) = (a0 - TARGET * d, b0 - TARGET * e, c0 - TARGET * f);
    (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)
}

/// Luminance Y of linear sRGB primaries (the sRGB-to-XYZ matrix's middle row).
fn luminance(p: [f32; 3]) -> f32 {
    0.212_672_9 * p[0] + 0.715_152_2 * p[1] + 0.072_175 * p[2]
}

/// The first and last exposure (in stops) for `reference`, and their count.
pub fn exposure_range(reference: &[[f32; 3]]) -> (f32, f32, usize) {
    let mut y: Vec<f32> =
        reference.iter().map(|&p| luminance(p)).map(|v| if v.is_finite() { v } else { 0.0 }).collect();
    let y_max = y.iter().copied().fold(0.0f32, f32::max);
    if y.is_empty() || y_max <= 0.0 {
        return (0.0, 0.0, 2);
    }
    y.sort_unstable_by(f32::total_cmp);
    let n = y.len();
    // The median as numpy's 50th percentile takes it: the mean of the two
    // middle values for an even count.
    let median = if n % 2 == 1 { y[n / 2] } else { 0.5 * (y[n / 2 - 1] + y[n / 2]) };
    let x = input_for_target();
    let start = (x / y_max).log2();
    let stop = if median > 0.0 { (x / median).log2() } else { start };
    let count = ((stop - start).ceil().max(2.0)) as usize;
    (start, stop, count)
}

/// The per-pixel HDR-FLIP error between two linear-RGB images, row-major with
/// `width` pixels per row (same length), for an observer at `ppd` pixels per
/// degree.
pub fn hdr_flip_map(reference: &[[f32; 3]], test: &[[f32; 3]], width: usize, ppd: f32) -> Vec<f32> {
    debug_assert_eq!(reference.len(), test.len());
    if reference.is_empty() || width == 0 {
        return Vec::new();
    }
    let (start, stop, count) = exposure_range(reference);
    let step = (stop - start) / (count - 1).max(1) as f32;
    let exposed = |img: &[[f32; 3]], e: f32| -> Vec<[f32; 3]> {
        let k = e.exp2();
        img.par_iter().map(|p| p.map(|c| tone_map(k * c))).collect()
    };
    let mut out = vec![0.0f32; reference.len()];
    for i in 0..count {
        let e = start + i as f32 * step;
        let map = ldr_flip_map(&exposed(reference, e), &exposed(test, e), width, ppd);
        out.par_iter_mut().zip(map).for_each(|(o, m)| *o = o.max(m));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tone_mapper_reaches_its_target_at_the_computed_input() {
        let x = input_for_target();
        assert!((tone_map(x) - TARGET).abs() < 1e-5, "{x} maps to {}", tone_map(x));
        assert_eq!(tone_map(0.0), 0.0);
        assert_eq!(tone_map(f32::NAN), 0.0);
        assert_eq!(tone_map(1e30), 1.0);
    }

    #[test]
    fn exposures_span_the_references_maximum_to_its_median() {
        // Luminances 1 (three pixels) and 16: median 1, maximum 16, so the
        // range is exactly 4 stops wide and holds 4 exposures.
        let grey = |v: f32| [v, v, v];
        let (start, stop, count) = exposure_range(&[grey(1.0), grey(16.0), grey(1.0), grey(1.0)]);
        assert!((stop - start - 4.0).abs() < 1e-4, "{start} .. {stop}");
        assert!((stop - input_for_target().log2()).abs() < 1e-4);
        assert_eq!(count, 4);
        // A black reference: one degenerate range, never NaN.
        assert_eq!(exposure_range(&[grey(0.0); 4]), (0.0, 0.0, 2));
    }

    #[test]
    fn identical_images_have_no_error_and_a_bright_change_shows() {
        let w = 16;
        let a: Vec<[f32; 3]> = (0..w * w).map(|i| [0.2 + (i % 7) as f32 * 0.1; 3]).collect();
        assert!(hdr_flip_map(&a, &a, w, 67.0).iter().all(|&e| e == 0.0));
        // A highlight 50x brighter: clamped away by LDR-FLIP at exposure 0,
        // seen by HDR-FLIP at the darker exposures.
        let mut b = a.clone();
        b[100] = [40.0; 3];
        let mut a2 = a.clone();
        a2[100] = [2.0; 3];
        let ldr = ldr_flip_map(
            &a2.iter().map(|p| p.map(|c| c.min(1.0))).collect::<Vec<_>>(),
            &b.iter().map(|p| p.map(|c| c.min(1.0))).collect::<Vec<_>>(),
            w,
            67.0,
        );
        let hdr = hdr_flip_map(&a2, &b, w, 67.0);
        assert_eq!(ldr[100], 0.0);
        assert!(hdr[100] > 0.05, "{}", hdr[100]);
    }
}
