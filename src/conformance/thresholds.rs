//! The bar each expected image must meet, and why.
//!
//! Single-sample scenes (hw1, hw2) are deterministic: our render should match
//! the course's to within rounding and the odd silhouette pixel, so the bar is
//! PSNR ≥ 40 dB on 8-bit RGB. Mean LDR-FLIP is a second guard against a
//! visible but low-energy difference: our hw1/hw2 renders score 0.0000–0.0020,
//! so its bar for these scenes is 0.01. Scenes that cannot meet it for a reason we
//! understand get their own bar here, with the reason next to it. Scenes of
//! homeworks whose features are not implemented yet are judged by the same
//! default and are expected to fail until they are.

use super::Case;
use crate::image::Comparison;

/// What an image must reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Threshold {
    /// Minimum PSNR in dB.
    pub min_psnr: f64,
    /// Maximum mean FLIP error.
    pub max_flip: f64,
    /// Why this bar (shown in reports).
    pub reason: &'static str,
}

impl Threshold {
    /// Whether a comparison meets the bar.
    pub fn accepts(&self, c: &Comparison) -> bool {
        self.psnr_ok(c) && self.flip_ok(c)
    }

    /// Whether the PSNR reaches the bar.
    pub fn psnr_ok(&self, c: &Comparison) -> bool {
        c.psnr >= self.min_psnr
    }

    /// Whether the mean FLIP error stays under the bar.
    pub fn flip_ok(&self, c: &Comparison) -> bool {
        c.flip <= self.max_flip
    }
}

/// The default bar of deterministic single-sample scenes.
pub const DEFAULT: Threshold = Threshold {
    min_psnr: 40.0,
    max_flip: 0.01,
    reason: "single-sample scene: PSNR ≥ 40 dB, mean FLIP ≤ 0.01",
};

/// Per-image exceptions: (homework, encoding or "*", image name, bar). None
/// is needed today; an entry must say why its scene cannot meet the default.
const EXCEPTIONS: &[(&str, &str, &str, Threshold)] = &[];

/// The bar for one camera's image of a case.
pub fn threshold(case: &Case, image_name: &str) -> Threshold {
    EXCEPTIONS
        .iter()
        .find(|(hw, enc, name, _)| {
            *hw == case.hw && (*enc == "*" || *enc == case.encoding.name()) && *name == image_name
        })
        .map(|e| e.3)
        .unwrap_or(DEFAULT)
}
