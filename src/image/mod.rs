//! Reading, writing and comparing images.
//!
//! - [`buffer`]: [`Rgb32Image`], a float RGB image loaded from PNG, JPEG,
//!   OpenEXR or Radiance HDR, remembering whether its values are sRGB-encoded
//!   or linear.
//! - [`compare`](mod@compare): PSNR/MSE, SSIM (Wang et al. 2004), LDR-FLIP
//!   (Andersson et al. 2020) and pixel-exact statistics between a reference and
//!   a test image — the core of `luster compare` and the golden-image tests.
//! - [`flip`], [`hdr_flip`], [`ssim`](mod@ssim): the perceptual metrics.
//! - [`heatmap`](mod@heatmap): magma-coloured error maps for people to look at.
//! - [`error`]: [`ImageError`], one sentence naming the file and the problem.

pub mod buffer;
pub mod compare;
pub mod error;
mod filter;
pub mod flip;
pub mod hdr_flip;
pub mod heatmap;
pub mod output;
pub mod png_writer;
pub mod ssim;

pub use buffer::{Encoding, Rgb32Image};
pub use compare::{compare, relative_error, CompareOptions, Comparison, MetricSpace, RelativeError};
pub use error::ImageError;
pub use heatmap::{comparison_heatmap, heatmap, magma, write_heatmap, HeatmapSource};
