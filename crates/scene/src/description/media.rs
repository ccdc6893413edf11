//! Homogeneous media that fill objects' interiors (`<Media>`, `<Interior>`).

use crate::error::Loc;
use luster_core::math::Vec3;

/// A homogeneous medium: the same coefficients everywhere it is.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumDesc {
    /// Its id, as objects name it.
    pub id: String,
    /// Absorption coefficient per unit length (σa).
    pub absorption: Vec3,
    /// Scattering coefficient per unit length (σs).
    pub scattering: Vec3,
    /// Emitted radiance per unit length.
    pub emission: Vec3,
    /// Henyey–Greenstein asymmetry, −0.99 to 0.99.
    pub anisotropy: f32,
    /// Where.
    pub loc: Loc,
}

/// An object whose inside is filled by a medium.
#[derive(Clone, Debug, PartialEq)]
pub struct InteriorDesc {
    /// Index into [`Description::objects`](super::Description::objects).
    pub object: usize,
    /// Index into [`Description::media`](super::Description::media).
    pub medium: usize,
}
