//! `luster tonemap`: tone-map an HDR image (OpenEXR or Radiance HDR) to an
//! 8-bit PNG or JPEG without rendering, with the same operators, saturation
//! and gamma a camera's `Tonemap` element gives (`luster::tonemap`).
//!
//! Exit codes: 0 written; 2 the input could not be read or is not HDR, an
//! option is out of range, or the output could not be written.

use luster::image::{Encoding, Rgb32Image};
use luster::math::Vec3;
use luster::tonemap::{Gamma, Operator, Tonemap};
use std::path::PathBuf;
use std::process::ExitCode;

/// What `luster tonemap` was asked.
pub struct Args {
    /// The HDR image.
    pub input: PathBuf,
    /// The 8-bit image to write.
    pub output: PathBuf,
    /// Operator name.
    pub tmo: String,
    /// Key value.
    pub key: f32,
    /// Burn-out percentage.
    pub burn: f32,
    /// Saturation exponent.
    pub saturation: f32,
    /// A number, or `sRGB`.
    pub gamma: String,
}

/// Tone-maps, writes, and returns the exit code.
pub fn run(a: &Args) -> ExitCode {
    match tonemap(a) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            super::report("error", &msg);
            ExitCode::from(2)
        }
    }
}

fn tonemap(a: &Args) -> Result<(), String> {
    let t = settings(a)?;
    let img = Rgb32Image::load(&a.input).map_err(|e| e.to_string())?;
    if img.encoding != Encoding::Linear {
        return Err(format!("{}: is not an HDR image (expected .exr or .hdr)", a.input.display()));
    }
    let px: Vec<Vec3> = img.pixels.iter().map(|&p| Vec3::from_array(p)).collect();
    luster::image::output::write_rgb8(&a.output, img.width, img.height, &t.apply(&px))
        .map_err(|e| e.to_string())
}

fn settings(a: &Args) -> Result<Tonemap, String> {
    let operator = Operator::parse(&a.tmo)
        .ok_or_else(|| format!("--tmo: \"{}\" is not an operator (expected {})", a.tmo, Operator::NAMES))?;
    if !(a.key > 0.0 && a.key.is_finite()) {
        return Err(format!("--key must be a positive number, found {}", a.key));
    }
    if !(0.0..100.0).contains(&a.burn) {
        return Err(format!("--burn must be at least 0 and below 100, found {}", a.burn));
    }
    if !(a.saturation >= 0.0 && a.saturation.is_finite()) {
        return Err(format!("--saturation must not be negative, found {}", a.saturation));
    }
    let gamma = if a.gamma.trim().eq_ignore_ascii_case("srgb") {
        Gamma::Srgb
    } else {
        match a.gamma.trim().parse::<f32>() {
            Ok(g) if g > 0.0 && g.is_finite() => Gamma::Power(g),
            _ => return Err(format!("--gamma: \"{}\" is not a positive number or sRGB", a.gamma)),
        }
    };
    Ok(Tonemap { operator, key: a.key, burn_percent: a.burn, saturation: a.saturation, gamma })
}
