//! The display transform: how a scene that is not a course scene turns its
//! linear film into an 8-bit PNG (the scene-level `<Display>` element, or
//! `--display` on the command line).
//!
//! | `Display` | 8-bit image | inputs |
//! |---|---|---|
//! | `course` (course scenes' default) | the course's clamp and truncation, no gamma ([`super::course_rgb8`]) | as written |
//! | `srgb` (OBJ models' default) | `x = C / 255`, clamped to [0, 1], sRGB-encoded, rounded | 8-bit colour textures sRGB-decoded |
//! | `aces` | Narkowicz's ACES fit of `0.6 x` per channel, then as `srgb` | as `srgb` |
//! | `filmic` | Hable's Uncharted 2 curve of `2 x` per channel, white 11.2, then as `srgb` | as `srgb` |
//!
//! The exposure is fixed, not keyed to the image: the film's 255 is linear
//! 1, so a Lambertian reflectance of 0.18 under an irradiance of 255 lands
//! on sRGB mid-grey (118 with `srgb`) whatever else is in the picture. The
//! curves act on each channel, so bright saturated colours run to white as on
//! film; `srgb` keeps every value below 1 exactly as the linear render has
//! it. Exact curves and sources are in docs/hdr.md.

use super::quantize::Quantizer;
use super::Gamma;
use super::{aces_fit, hable_filmic};
use crate::math::Vec3;
use rayon::prelude::*;

/// A scene's display transform.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Display {
    /// The course's 8-bit semantics: linear values clamped and truncated.
    #[default]
    Course,
    /// Linear workflow, the plain sRGB transfer curve with a clamp.
    Srgb,
    /// Linear workflow, Narkowicz's ACES fit.
    Aces,
    /// Linear workflow, Hable's filmic curve.
    Filmic,
}

/// Narkowicz's pre-exposure: his fit maps `0.6 x`, so mid-grey lands near
/// where `srgb` puts it instead of a stop brighter.
const ACES_EXPOSURE: f32 = 0.6;

impl Display {
    /// The names a scene or `--display` uses, for error messages.
    pub const NAMES: &'static str = "course, srgb, aces or filmic";

    /// The mode named `name` (without regard to case or surrounding space).
    pub fn parse(name: &str) -> Option<Display> {
        match name.trim().to_ascii_lowercase().as_str() {
            "course" => Some(Display::Course),
            "srgb" => Some(Display::Srgb),
            "aces" => Some(Display::Aces),
            "filmic" => Some(Display::Filmic),
            _ => None,
        }
    }

    /// The lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Display::Course => "course",
            Display::Srgb => "srgb",
            Display::Aces => "aces",
            Display::Filmic => "filmic",
        }
    }

    /// Whether inputs are display-encoded values to be made linear (8-bit
    /// colour textures) and outputs view-transformed: every mode but `course`.
    pub fn is_linear_workflow(self) -> bool {
        self != Display::Course
    }

    #[inline]
    fn curve(self, x: f32) -> f32 {
        match self {
            Display::Course | Display::Srgb => x,
            Display::Aces => aces_fit(ACES_EXPOSURE * x),
            Display::Filmic => hable_filmic(x),
        }
    }

    /// 8-bit RGB of `pixels` (linear, the film's units) through this
    /// transform, row-major.
    pub fn apply(self, pixels: &[Vec3]) -> Vec<u8> {
        if self == Display::Course {
            return super::course_rgb8(pixels);
        }
        let q = Quantizer::shared(Gamma::Srgb, true);
        let mut out = vec![0u8; 3 * pixels.len()];
        const ROWS: usize = 1024;
        out.par_chunks_mut(3 * ROWS).zip(pixels.par_chunks(ROWS)).for_each(|(out, px)| {
            for (o, &p) in out.chunks_exact_mut(3).zip(px) {
                for (b, c) in o.iter_mut().zip(p.to_array()) {
                    *b = q.code(self.curve(c * (1.0 / 255.0)));
                }
            }
        });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::buffer::linear_to_srgb;

    fn one(d: Display, c: f32) -> u8 {
        d.apply(&[Vec3::splat(c)])[0]
    }

    #[test]
    fn srgb_puts_mid_grey_on_the_encoded_value_and_rounds() {
        // 0.18 · 255 is 45.9: the course's clamp writes 45, the sRGB curve 118.
        assert_eq!(one(Display::Course, 0.18 * 255.0), 45);
        assert_eq!(one(Display::Srgb, 0.18 * 255.0), 118);
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            let want = (linear_to_srgb(x) * 255.0).round() as u8;
            let got = one(Display::Srgb, x * 255.0);
            assert!(got.abs_diff(want) <= 1, "{x}: {got} against {want}");
            if ((linear_to_srgb(x) * 255.0).fract() - 0.5).abs() > 1e-3 {
                assert_eq!(got, want, "{x}");
            }
        }
    }

    #[test]
    fn curves_roll_off_instead_of_clipping() {
        for d in [Display::Aces, Display::Filmic] {
            let (a, b) = (one(d, 2.0 * 255.0), one(d, 4.0 * 255.0));
            assert!(a < b && b < 255, "{d:?}: {a} {b}");
            let mid = one(d, 0.18 * 255.0);
            assert!((95..=125).contains(&mid), "{d:?} puts mid-grey at {mid}");
        }
        assert_eq!(one(Display::Srgb, 2.0 * 255.0), 255);
    }

    #[test]
    fn bad_values_are_black_and_names_round_trip() {
        for d in [Display::Srgb, Display::Aces, Display::Filmic] {
            assert_eq!(d.apply(&[Vec3::new(f32::NAN, -1.0, 0.0)]), [0, 0, 0]);
            assert_eq!(Display::parse(&format!(" {} ", d.name().to_uppercase())), Some(d));
        }
        assert_eq!(Display::parse("linear"), None);
    }
}
