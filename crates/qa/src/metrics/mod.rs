//! Comparing images: the metrics of `luster compare`, the conformance suite
//! and the golden-image tests.
//!
//! - [`compare`](mod@compare): PSNR/MSE, SSIM (Wang et al. 2004), LDR-FLIP
//!   (Andersson et al. 2020) and pixel-exact statistics between a reference and
//!   a test image — the core of `luster compare` and the golden-image tests.
//! - [`flip`], [`hdr_flip`], [`ssim`](mod@ssim): the perceptual metrics.
//! - [`heatmap`](mod@heatmap): magma-coloured error maps for people to look at.

pub mod compare;
mod filter;
pub mod flip;
pub mod hdr_flip;
pub mod heatmap;
pub mod ssim;

pub use compare::{compare, relative_error, CompareOptions, Comparison, MetricSpace, RelativeError};
pub use heatmap::{comparison_heatmap, heatmap, magma, write_heatmap, HeatmapSource};
