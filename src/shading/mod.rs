//! Materials, lights and the Fresnel equations.

pub mod fresnel;
pub mod material;

pub use material::Material;

use crate::math::Vec3;

/// A point light, intensity `I`, irradiance `I / d²`.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// RGB intensity.
    pub intensity: Vec3,
}
