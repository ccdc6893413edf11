//! The render passes and adaptive sampling options of `luster render`:
//! `--aov`, `--noise-threshold`, `--min-spp` (docs/passes.md).

use luster::film::adaptive::Adaptive;
use luster::film::Passes;

/// The options, flattened into `luster render`'s.
#[derive(clap::Args)]
#[command(next_help_heading = "Passes and adaptive sampling")]
pub(super) struct PassArgs {
    /// Render passes to write beside each image as layers of one EXR,
    /// <stem>.aov.exr, comma-separated: albedo, normal, emission, depth,
    /// position, object_id, samples (the samples-per-pixel heat map), or all.
    #[arg(long, value_name = "LIST", value_parser = parse_passes)]
    aov: Option<Passes>,
    /// Adaptive sampling: a pixel stops once its estimated relative error
    /// (Cycles' two-half estimate) is below T (0.01 is Cycles' default; 0
    /// turns off a camera's <NoiseThreshold>). --spp or the camera's
    /// NumSamples is the most a pixel takes.
    #[arg(long, value_name = "T", value_parser = parse_threshold)]
    noise_threshold: Option<f32>,
    /// With adaptive sampling: samples every pixel takes before it may stop
    /// (default: Cycles' max(4, 16 / T^0.3), 64 at T = 0.01).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=1_048_576))]
    min_spp: Option<u32>,
}

impl PassArgs {
    /// The passes asked for.
    pub(super) fn passes(&self) -> Passes {
        self.aov.unwrap_or_default()
    }

    /// The adaptive sampling asked for.
    pub(super) fn adaptive(&self) -> Adaptive {
        Adaptive { threshold: self.noise_threshold, min_spp: self.min_spp }
    }
}

/// An `--aov` list.
fn parse_passes(s: &str) -> Result<Passes, String> {
    Passes::parse(s)
}

/// A `--noise-threshold`: 0 to 1.
fn parse_threshold(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(t) if (0.0..=1.0).contains(&t) => Ok(t),
        _ => Err(format!(
            "\"{}\" is not a noise threshold (expected a number from 0 to 1, e.g. 0.01)",
            luster::text::shown(s, false)
        )),
    }
}
