//! Materials, lights and the Fresnel equations.

pub mod fresnel;
pub mod material;

pub use material::Material;

use crate::math::{orthonormal_basis, Vec3};
use crate::scene::description::AreaLightDesc;

/// A point light, intensity `I`, irradiance `I / d²`.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// RGB intensity.
    pub intensity: Vec3,
}

/// A square area light of uniform radiance, emitting from both faces.
#[derive(Clone, Copy, Debug)]
pub struct AreaLight {
    /// Centre.
    pub center: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// The square's edge vectors (length `size`, perpendicular to the normal).
    pub edge_u: Vec3,
    /// See `edge_u`.
    pub edge_v: Vec3,
    /// Area.
    pub area: f32,
    /// RGB radiance.
    pub radiance: Vec3,
}

impl AreaLight {
    /// From the description.
    pub fn from_desc(d: &AreaLightDesc) -> AreaLight {
        let (u, v) = orthonormal_basis(d.normal);
        AreaLight {
            center: d.position,
            normal: d.normal,
            edge_u: u * d.size,
            edge_v: v * d.size,
            area: d.size * d.size,
            radiance: d.radiance,
        }
    }

    /// The point of the square at `(a, b)` in `[0, 1)²`.
    #[inline]
    pub fn point(&self, (a, b): (f32, f32)) -> Vec3 {
        self.center + self.edge_u * (a - 0.5) + self.edge_v * (b - 0.5)
    }
}
