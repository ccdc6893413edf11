//! `Camera/Tonemap`: how an HDR image becomes an 8-bit PNG (hw5).
//!
//! | element | meaning | default |
//! |---|---|---|
//! | `TMO` | `Photographic` (hw5), or luster's `ACES` and `Filmic` | `Photographic` |
//! | `TMOOptions` | key value, then burn-out percentage (0 ≤ p < 100) | `0.18 0` |
//! | `Saturation` | exponent `s` of `(C / Y)^s` | `1` |
//! | `Gamma` | a positive number `g` (`C^(1/g)`), or `sRGB` for the sRGB curve | `2.2` |
//!
//! ```xml
//! <ImageName>output.exr</ImageName>
//! <Tonemap>
//!     <TMO>Photographic</TMO>
//!     <TMOOptions>0.18 1</TMOOptions>
//!     <Saturation>1.0</Saturation>
//!     <Gamma>2.2</Gamma>
//! </Tonemap>
//! ```
//!
//! A camera may have several (`"Tonemap": [ ... ]` in the 2025 JSON): each
//! writes its own PNG (names in [`luster_core::image::outputs`]). On a `.png`
//! `ImageName` a `Tonemap` is luster's way for a scene to ask for a
//! display-referred image instead of the course's clamp. The curves are in
//! [`luster_core::tonemap`].

use super::Warnings;
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::tonemap::{Gamma, Operator, Tonemap};

/// Reads every `Tonemap` child of a camera.
pub fn read_all(r: &Reader, camera: &Element, w: &mut Warnings) -> Result<Vec<Tonemap>, SceneError> {
    camera.children_named("Tonemap").map(|t| read(r, t, w)).collect()
}

fn read(r: &Reader, t: &Element, w: &mut Warnings) -> Result<Tonemap, SceneError> {
    w.unknown_children(t, &["TMO", "TMOOptions", "Saturation", "Gamma"]);
    let operator = match t.child("TMO") {
        Some(el) => Operator::parse(&el.text).ok_or_else(|| {
            r.err(
                el,
                format!(
                    "<TMO> names a tone-mapping operator luster does not know (expected {})",
                    Operator::NAMES
                ),
            )
        })?,
        None => Operator::Photographic,
    };
    let (mut key, mut burn_percent) = (0.18, 0.0);
    if let Some(el) = t.child("TMOOptions") {
        let v = r.floats(el).map_err(|_| {
            r.err(el, "<TMOOptions> must be numbers: the key value, then the burn-out percentage")
        })?;
        match v.as_slice() {
            [k] => key = *k,
            [k, b] => (key, burn_percent) = (*k, *b),
            _ => {
                return Err(r.err(
                    el,
                    format!(
                        "<TMOOptions> needs 1 or 2 numbers (key value, burn-out percentage), found {}",
                        v.len()
                    ),
                ))
            }
        }
        if key <= 0.0 {
            return Err(r.err(el, format!("<TMOOptions>: the key value must be positive, found {key}")));
        }
        if !(0.0..100.0).contains(&burn_percent) {
            return Err(r.err(
                el,
                format!("<TMOOptions>: the burn-out percentage must be at least 0 and below 100, found {burn_percent}"),
            ));
        }
    }
    let saturation = r.float_or(t, "Saturation", 1.0)?;
    if saturation < 0.0 {
        return Err(r.err(t, format!("<Saturation> must not be negative, found {saturation}")));
    }
    let gamma = match t.child("Gamma") {
        None => Gamma::Power(2.2),
        Some(el) if el.text.trim().eq_ignore_ascii_case("srgb") => Gamma::Srgb,
        Some(el) => match el.text.trim().parse::<f32>() {
            Ok(g) if g > 0.0 && g.is_finite() => Gamma::Power(g),
            _ => return Err(r.err(el, "<Gamma> must be a positive number or sRGB")),
        },
    };
    Ok(Tonemap { operator, key, burn_percent, saturation, gamma })
}
