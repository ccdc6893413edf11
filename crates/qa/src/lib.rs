//! luster-qa: how luster checks itself — the conformance suite over the
//! course's scenes, its HTML/JSON report, the image metrics (PSNR, SSIM,
//! LDR- and HDR-FLIP, heatmaps), and the entry points of the fuzz targets.
#![warn(missing_docs)]

pub mod conformance;
pub mod fuzzing;
pub mod metrics;
pub mod report;
