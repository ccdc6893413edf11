//! Colour-mapped error heatmaps.
//!
//! Errors in [0, 1] are shown with the *magma* colour map, as in the FLIP
//! paper's figures and tools (Andersson et al., HPG 2020): black–purple for
//! small errors through orange to pale yellow for the largest. Magma is one of
//! the perceptually uniform sequential maps designed by Stéfan van der Walt and
//! Nathaniel Smith for matplotlib (<https://bids.github.io/colormap/>, CC0).
//!
//! The map is stored as 33 knots (every 8th entry of the 256-entry table, plus
//! the last, rounded to 8 bits) and interpolated linearly; this reproduces the
//! full table to within 1.6/255 per channel.
//!
//! | source | value mapped to [0, 1] |
//! |---|---|
//! | [`HeatmapSource::Flip`] | the per-pixel LDR-FLIP error, already in [0, 1] |
//! | [`HeatmapSource::AbsDiff`] | the largest absolute channel difference divided by `scale` (`None`: by the largest one in the image) |

use std::path::Path;

use image::{Rgb, RgbImage};

use super::compare::Comparison;
use luster_core::image::error::ImageError;

/// Magma at t = 0, 8/255, 16/255, …, 248/255, 1 (8-bit sRGB).
const MAGMA_KNOTS: [[u8; 3]; 33] = [
    [0, 0, 4],
    [3, 3, 18],
    [10, 8, 34],
    [19, 13, 52],
    [29, 17, 71],
    [41, 17, 90],
    [54, 16, 107],
    [68, 15, 118],
    [81, 18, 124],
    [93, 23, 127],
    [106, 28, 129],
    [118, 33, 129],
    [131, 38, 129],
    [144, 42, 129],
    [156, 46, 127],
    [170, 51, 125],
    [183, 55, 121],
    [196, 60, 117],
    [208, 65, 111],
    [220, 72, 105],
    [231, 82, 99],
    [239, 93, 94],
    [245, 107, 92],
    [249, 121, 93],
    [252, 137, 97],
    [253, 152, 105],
    [254, 167, 114],
    [254, 182, 124],
    [254, 196, 136],
    [254, 211, 149],
    [253, 226, 163],
    [252, 240, 178],
    [252, 253, 191],
];

/// The magma colour for `t` ∈ [0, 1] (clamped; NaN maps to 0).
pub fn magma(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    // Position in the 256-entry table; knot k sits at entry 8k, the last at 255.
    let pos = t * 255.0;
    let k = ((pos / 8.0) as usize).min(31);
    let (a, b) = (8.0 * k as f32, if k == 31 { 255.0 } else { 8.0 * (k + 1) as f32 });
    let f = (pos - a) / (b - a);
    let (p, q) = (MAGMA_KNOTS[k], MAGMA_KNOTS[k + 1]);
    // Each channel interpolates between two u8 values, so it stays in [0, 255].
    [0, 1, 2].map(|c| (f32::from(p[c]) + f * (f32::from(q[c]) - f32::from(p[c]))).round() as u8)
}

/// What a heatmap shows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HeatmapSource {
    /// The LDR-FLIP error map.
    Flip,
    /// The absolute difference map, divided by `scale` (or by its maximum when `None`).
    AbsDiff {
        /// The difference shown at full brightness.
        scale: Option<f32>,
    },
}

/// Colour-maps per-pixel values in [0, 1] to an 8-bit image.
///
/// Fails if `values` does not hold `width * height` entries.
pub fn heatmap(values: &[f32], width: u32, height: u32) -> Result<RgbImage, ImageError> {
    let expected = width as usize * height as usize;
    if values.len() != expected {
        return Err(ImageError::BufferSize { width, height, len: values.len(), expected });
    }
    let mut out = RgbImage::new(width, height);
    for (dst, &v) in out.pixels_mut().zip(values) {
        *dst = Rgb(magma(v));
    }
    Ok(out)
}

/// The heatmap of a comparison.
pub fn comparison_heatmap(comparison: &Comparison, source: HeatmapSource) -> Result<RgbImage, ImageError> {
    match source {
        HeatmapSource::Flip => heatmap(&comparison.flip_map, comparison.width, comparison.height),
        HeatmapSource::AbsDiff { scale } => {
            let scale = scale.unwrap_or(comparison.max_abs_diff);
            let scaled: Vec<f32> = if scale > 0.0 && scale.is_finite() {
                comparison.diff_map.iter().map(|d| d / scale).collect()
            } else {
                vec![0.0; comparison.diff_map.len()]
            };
            heatmap(&scaled, comparison.width, comparison.height)
        }
    }
}

/// Writes a heatmap; the format follows the extension (PNG recommended).
pub fn write_heatmap(image: &RgbImage, path: impl AsRef<Path>) -> Result<(), ImageError> {
    let path = path.as_ref();
    image.save(path).map_err(|e| ImageError::Write { path: path.to_path_buf(), detail: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magma_end_points_and_monotone_lightness() {
        assert_eq!(magma(0.0), [0, 0, 4]);
        assert_eq!(magma(1.0), [252, 253, 191]);
        assert_eq!(magma(-3.0), magma(0.0));
        assert_eq!(magma(f32::NAN), magma(0.0));
        assert_eq!(magma(128.0 / 255.0), [183, 55, 121]);
        // Magma's lightness grows monotonically; a luma proxy must not fall.
        let mut last = -1.0;
        for i in 0..=255 {
            let [r, g, b] = magma(i as f32 / 255.0);
            let y = 0.2126 * f32::from(r) + 0.7152 * f32::from(g) + 0.0722 * f32::from(b);
            assert!(y >= last - 0.5, "entry {i}");
            last = y;
        }
    }

    #[test]
    fn heatmap_checks_size_and_writes() {
        assert!(heatmap(&[0.0; 5], 2, 2).is_err());
        let img = heatmap(&[0.0, 0.25, 0.5, 1.0], 2, 2).unwrap();
        assert_eq!(img.get_pixel(1, 1).0, [252, 253, 191]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("heat.png");
        write_heatmap(&img, &path).unwrap();
        assert_eq!(image::open(&path).unwrap().to_rgb8(), img);
        let bad = dir.path().join("no_such_dir").join("heat.png");
        let err = write_heatmap(&img, &bad).unwrap_err();
        assert!(err.to_string().contains("heat.png"));
    }
}
