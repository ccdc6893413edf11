//! The numbers of one comparison as the report shows them: the metrics, and
//! which parts of the bar (see [`Bar`]) they met.

use crate::conformance::thresholds::{BlockZ, StatsPair};
use crate::conformance::Bar;
use crate::metrics::{Comparison, MetricSpace};
use serde::Serialize;

/// A comparison's numbers (the per-pixel maps are in the heatmap).
#[derive(Clone, Debug, Serialize)]
pub struct Metrics {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `display` (sRGB values) or `linear` (both images EXR/HDR).
    pub space: &'static str,
    /// PSNR in dB; `null` when infinite (identical images).
    pub psnr: Option<f64>,
    /// Mean SSIM on luma.
    pub ssim: f64,
    /// Mean LDR-FLIP error (Andersson et al. 2020).
    pub flip: f64,
    /// Pixels whose 8-bit codes differ.
    pub differing_pixels: usize,
    /// The same as a percentage of all pixels.
    pub differing_percent: f64,
    /// Inclusive bounding box `[x0, y0, x1, y1]` of the differing pixels.
    pub diff_bbox: Option<[u32; 4]>,
    /// Largest absolute channel difference.
    pub max_abs_diff: f32,
    /// Whether the PSNR part of the threshold was met.
    pub psnr_ok: bool,
    /// Whether the FLIP part of the threshold was met.
    pub flip_ok: bool,
    /// PSNR of the means of 8×8 blocks, when the threshold tests it.
    pub coarse_psnr: Option<f64>,
    /// Whether that part of the threshold was met (true when not tested).
    pub coarse_ok: bool,
    /// Statistical rule: mean luma of ours and of the expected image.
    pub mean_luma: Option<[f64; 2]>,
    /// Statistical rule: luma contrast (standard deviation) of ours and of the expected image.
    pub contrast: Option<[f64; 2]>,
    /// Whether the statistics agreed (true when not tested).
    pub stats_ok: bool,
    /// Noise-aware rule: the space the noise was judged in (`display` on the
    /// 8-bit images, `linear` against the course's `.exr`).
    pub noise_space: Option<&'static str>,
    /// Noise-aware rule: the block edge in pixels.
    pub block: Option<u32>,
    /// Noise-aware rule: mean z² of the block means (see
    /// `conformance::noise::block_z`).
    pub block_mean_z2: Option<f64>,
    /// Noise-aware rule: share of blocks with |z| > 5.
    pub block_outliers: Option<f64>,
    /// Noise-aware rule: blocks left out (showing a light, or clipped at white).
    pub left_out_blocks: Option<usize>,
    /// Noise-aware rule: our mean luminance minus the course's, in standard
    /// errors.
    pub luminance_z: Option<f64>,
    /// Noise-aware rule: mean luminance of ours and of the expected image.
    pub mean_luminance: Option<[f64; 2]>,
    /// Whether the z-scores met the bar (true when not tested).
    pub z_ok: bool,
}

pub(super) fn metrics(
    c: &Comparison,
    t: &Bar,
    coarse_psnr: Option<f64>,
    stats: Option<&StatsPair>,
    z: Option<&BlockZ>,
) -> Metrics {
    Metrics {
        width: c.width,
        height: c.height,
        space: match c.space {
            MetricSpace::Display => "display",
            MetricSpace::Linear => "linear",
        },
        psnr: c.psnr.is_finite().then_some(c.psnr),
        ssim: c.ssim,
        flip: c.flip,
        differing_pixels: c.differing_pixels,
        differing_percent: 100.0 * c.differing_fraction(),
        diff_bbox: c.diff_bbox.map(|(a, b, x, y)| [a, b, x, y]),
        max_abs_diff: c.max_abs_diff,
        psnr_ok: t.psnr_ok(c),
        flip_ok: t.flip_ok(c),
        coarse_psnr: coarse_psnr.filter(|p| p.is_finite()),
        coarse_ok: t.coarse_ok(coarse_psnr),
        mean_luma: stats.map(|s| [s.ours.mean, s.reference.mean]),
        contrast: stats.map(|s| [s.ours.contrast, s.reference.contrast]),
        stats_ok: t.stats_ok(stats),
        noise_space: z.map(|z| z.space.name()),
        block: z.map(|z| z.block),
        block_mean_z2: z.map(|z| z.mean_z2),
        block_outliers: z.map(|z| z.outliers),
        left_out_blocks: z.map(|z| z.left_out),
        luminance_z: z.map(|z| z.luminance_z),
        mean_luminance: z.map(|z| z.mean_luminance),
        z_ok: t.z_ok(z),
    }
}
