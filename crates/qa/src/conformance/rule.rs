//! What a bar is: the [`Rule`] an image is judged by (with its reason, a
//! [`Threshold`]), and the numbers ([`Bar`]) the rule sets once applied.
//! Which image gets which rule, and why, is in [`thresholds`](super::thresholds).

use super::measures::{StatsPair, COARSE};
use super::noise::{BlockZ, Space, REF_NOISE_PER_SAMPLE, Z_OUTLIER};
use crate::metrics::Comparison;

/// A rule for what an image must reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rule {
    /// Fixed numbers, for deterministic images.
    Fixed {
        /// Minimum PSNR in dB.
        min_psnr: f64,
        /// Maximum mean FLIP error.
        max_flip: f64,
    },
    /// Per-block z-scores against the noise of two of our renders.
    NoiseAware {
        /// Whatever the noise, PSNR must reach this.
        floor_psnr: f64,
        /// Whatever the noise, FLIP must stay under this.
        ceiling_flip: f64,
        /// Largest mean z² over blocks and channels.
        max_mean_z2: f64,
        /// Largest share of blocks and channels with |z| > [`Z_OUTLIER`].
        max_outliers: f64,
        /// Largest |offset| of the mean luminance in standard errors.
        max_luminance_z: f64,
    },
    /// By image statistics, for patterns that cannot match pixel for pixel.
    Statistical {
        /// Maximum mean FLIP error.
        max_flip: f64,
        /// Largest difference of the mean luma (0–1).
        max_mean_diff: f64,
        /// Largest relative difference of the luma's standard deviation.
        max_contrast_diff: f64,
    },
}

/// The rule an image is judged by, with the reason (shown in reports).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Threshold {
    /// The rule.
    pub rule: Rule,
    /// Why this rule (shown in reports).
    pub reason: &'static str,
}

/// The numbers an image must reach once the rule is applied (for a
/// noise-aware rule, to the pair of our renders).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bar {
    /// Minimum PSNR in dB.
    pub min_psnr: f64,
    /// Maximum mean FLIP error.
    pub max_flip: f64,
    /// Minimum PSNR of the block means (see [`COARSE`]); −∞ when not tested.
    pub min_coarse_psnr: f64,
    /// Largest difference of mean luma; ∞ when not tested.
    pub max_mean_diff: f64,
    /// Largest relative difference of luma contrast; ∞ when not tested.
    pub max_contrast_diff: f64,
    /// Largest mean block z²; ∞ when not tested.
    pub max_mean_z2: f64,
    /// Largest share of outlier blocks; ∞ when not tested.
    pub max_outliers: f64,
    /// Largest |offset| of the mean luminance in standard errors; ∞ when not
    /// tested.
    pub max_luminance_z: f64,
}

impl Bar {
    /// Whether a comparison (and, when tested, the PSNR of its block means)
    /// meets the bar.
    pub fn accepts(
        &self,
        c: &Comparison,
        coarse_psnr: Option<f64>,
        stats: Option<&StatsPair>,
        z: Option<&BlockZ>,
    ) -> bool {
        self.psnr_ok(c)
            && self.flip_ok(c)
            && self.coarse_ok(coarse_psnr)
            && self.stats_ok(stats)
            && self.z_ok(z)
    }

    /// Whether the bar tests block z-scores.
    pub fn tests_z(&self) -> bool {
        self.max_mean_z2 < f64::INFINITY || self.max_outliers < f64::INFINITY
    }

    /// Whether the block z-scores are within the bar (true when not tested;
    /// false when tested without them).
    pub fn z_ok(&self, z: Option<&BlockZ>) -> bool {
        !self.tests_z()
            || z.is_some_and(|z| {
                z.mean_z2 <= self.max_mean_z2
                    && z.outliers <= self.max_outliers
                    && z.luminance_z.abs() <= self.max_luminance_z
            })
    }

    /// Whether the bar compares image statistics.
    pub fn tests_stats(&self) -> bool {
        self.max_mean_diff < f64::INFINITY || self.max_contrast_diff < f64::INFINITY
    }

    /// Whether mean and contrast agree well enough (true when not tested;
    /// false when tested without statistics).
    pub fn stats_ok(&self, stats: Option<&StatsPair>) -> bool {
        !self.tests_stats()
            || stats.is_some_and(|s| {
                s.mean_diff() <= self.max_mean_diff && s.contrast_diff() <= self.max_contrast_diff
            })
    }

    /// Whether the bar tests block means at all.
    pub fn tests_coarse(&self) -> bool {
        self.min_coarse_psnr > f64::NEG_INFINITY
    }

    /// Whether the PSNR of the block means reaches the bar (true when the
    /// bar does not test them; false when it does and there is no value).
    pub fn coarse_ok(&self, coarse_psnr: Option<f64>) -> bool {
        !self.tests_coarse() || coarse_psnr.is_some_and(|p| p >= self.min_coarse_psnr)
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

impl std::fmt::Display for Rule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Rule::Fixed { min_psnr, max_flip } => write!(f, "fixed: PSNR ≥ {min_psnr} dB, FLIP ≤ {max_flip}"),
            Rule::Statistical { max_flip, max_mean_diff, max_contrast_diff } => write!(
                f,
                "statistical: mean luma within {max_mean_diff}, luma contrast within {:.0}%, FLIP ≤ {max_flip}",
                max_contrast_diff * 100.0
            ),
            Rule::NoiseAware { floor_psnr, ceiling_flip, max_mean_z2, max_outliers, max_luminance_z } => write!(
                f,
                "noise-aware: block means against the reference's, in units of the noise our render \
                 with the next seed measures at the same count (widened by the reference's: measured \
                 from the course's two years' renders where they agree, else scaled from ours by \
                 {REF_NOISE_PER_SAMPLE} × our spp / its spp): mean z² ≤ {max_mean_z2}, \
                 at most {:.1}% of blocks with |z| > {Z_OUTLIER}, mean luminance within \
                 {max_luminance_z} standard errors; on 8-bit images {COARSE}×{COARSE} blocks (those clipped \
                 at white in the reference left out) and PSNR ≥ {floor_psnr} dB, FLIP ≤ {ceiling_flip} \
                 whatever the noise; against the course's .exr {}×{} blocks of linear radiance (those \
                 showing a light left out)",
                max_outliers * 100.0,
                super::noise::LINEAR_BLOCK,
                super::noise::LINEAR_BLOCK
            ),
        }
    }
}

impl Threshold {
    /// The reason and the rule in words, for reports.
    pub fn describe(&self) -> String {
        format!("{}; {}", self.reason, self.rule)
    }

    /// Whether judging needs a second render with another seed.
    pub fn needs_pair(&self) -> bool {
        matches!(self.rule, Rule::NoiseAware { .. })
    }

    /// The numbers an image must reach under this rule, judged on 8-bit
    /// display values.
    pub fn bar(&self) -> Bar {
        self.bar_in(Space::Display)
    }

    /// The numbers an image must reach under this rule when judged in
    /// `space`: a noise-aware rule keeps its PSNR and FLIP floor only on
    /// display values (see the module documentation).
    pub fn bar_in(&self, space: Space) -> Bar {
        match self.rule {
            Rule::Fixed { min_psnr, max_flip } => Bar { min_psnr, max_flip, ..UNTESTED },
            Rule::Statistical { max_flip, max_mean_diff, max_contrast_diff } => {
                Bar { min_psnr: f64::NEG_INFINITY, max_flip, max_mean_diff, max_contrast_diff, ..UNTESTED }
            }
            Rule::NoiseAware { floor_psnr, ceiling_flip, max_mean_z2, max_outliers, max_luminance_z } => {
                let z = Bar { max_mean_z2, max_outliers, max_luminance_z, ..UNTESTED };
                match space {
                    Space::Display => Bar { min_psnr: floor_psnr, max_flip: ceiling_flip, ..z },
                    Space::Linear => z,
                }
            }
        }
    }
}

/// A bar that tests nothing beyond what a rule sets.
pub(super) const UNTESTED: Bar = Bar {
    min_psnr: f64::NEG_INFINITY,
    max_flip: f64::INFINITY,
    min_coarse_psnr: f64::NEG_INFINITY,
    max_mean_diff: f64::INFINITY,
    max_contrast_diff: f64::INFINITY,
    max_mean_z2: f64::INFINITY,
    max_outliers: f64::INFINITY,
    max_luminance_z: f64::INFINITY,
};
