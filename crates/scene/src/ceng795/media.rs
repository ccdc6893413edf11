//! `<Media>`: homogeneous media (a luster extension) that fill objects named
//! by their `<Interior>`, for the path tracer.
//!
//! ```xml
//! <Media>
//!     <Medium id="milk">
//!         <Absorption>0.002 0.004 0.01</Absorption>
//!         <Scattering>4 4.2 4.5</Scattering>
//!         <Anisotropy>0.7</Anisotropy>
//!     </Medium>
//! </Media>
//! <Objects>
//!     <Mesh id="glass"><Material>glass</Material><Interior>milk</Interior>…</Mesh>
//! </Objects>
//! ```
//!
//! | element | reads | default |
//! |---|---|---|
//! | `Absorption`, `Scattering` | σa, σs per unit length | 1 1 1, 0 0 0 |
//! | `Emission` | emitted radiance per unit length | 0 0 0 |
//! | `Anisotropy` | Henyey–Greenstein g, −0.99 to 0.99 | 0 |

use super::Warnings;
use crate::description::MediumDesc;
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::Vec3;

/// Reads every `Medium` of a `Media` element.
pub fn read_all(r: &Reader, el: &Element, w: &mut Warnings) -> Result<Vec<MediumDesc>, SceneError> {
    w.unknown_children(el, &["Medium"]);
    let mut out: Vec<MediumDesc> = Vec::new();
    for m in el.children.iter().filter(|c| c.name == "Medium") {
        w.unknown_children(m, &["Absorption", "Scattering", "Emission", "Anisotropy"]);
        let id = m.attr("id").unwrap_or("").trim().to_string();
        if id.is_empty() {
            return Err(r.err(m, "<Medium> has no id"));
        }
        if out.iter().any(|o| o.id == id) {
            return Err(r.err(m, format!("medium \"{id}\" is defined twice")));
        }
        let c = coefficients(r, m)?;
        out.push(MediumDesc {
            id,
            absorption: c.absorption,
            scattering: c.scattering,
            emission: c.emission,
            anisotropy: c.anisotropy,
            loc: m.loc.clone(),
        });
    }
    Ok(out)
}

/// A medium's coefficients, as `<Medium>` and `<Volume>` give them.
pub(super) struct Coefficients {
    pub absorption: Vec3,
    pub scattering: Vec3,
    pub emission: Vec3,
    pub anisotropy: f32,
}

/// Reads `Absorption`, `Scattering`, `Emission` (finite, none negative) and
/// `Anisotropy` (−0.99 to 0.99) of `el`, with their defaults.
pub(super) fn coefficients(r: &Reader, el: &Element) -> Result<Coefficients, SceneError> {
    let non_negative = |name: &str, default: Vec3| -> Result<Vec3, SceneError> {
        let c = r.vec3_or(el, name, default)?;
        if c.min_element() < 0.0 || !c.is_finite() {
            return Err(r.err(el.child(name).unwrap_or(el), format!("<{name}> must be finite and ≥ 0")));
        }
        Ok(c)
    };
    let anisotropy = r.float_or(el, "Anisotropy", 0.0)?;
    if !(-0.99..=0.99).contains(&anisotropy) {
        return Err(r.err(
            el.child("Anisotropy").unwrap_or(el),
            format!("<Anisotropy> must lie between -0.99 and 0.99, found {anisotropy}"),
        ));
    }
    Ok(Coefficients {
        absorption: non_negative("Absorption", Vec3::ONE)?,
        scattering: non_negative("Scattering", Vec3::ZERO)?,
        emission: non_negative("Emission", Vec3::ZERO)?,
        anisotropy,
    })
}
