//! Render-side materials: the course's Blinn-Phong surface with an optional
//! perfect-specular part (mirror, dielectric or conductor).

use crate::bsdf::Brdf;
use crate::math::Vec3;
use crate::scene::description::{MaterialDesc, MaterialKind};

/// The specular part of a material beyond Blinn-Phong.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specular {
    /// None.
    None,
    /// Perfect reflection weighted by the mirror reflectance.
    Mirror,
    /// Fresnel-weighted reflection and refraction, Beer absorption inside.
    Dielectric {
        /// Index of refraction.
        ior: f32,
        /// Absorption per unit distance travelled inside.
        absorption: Vec3,
    },
    /// Reflection weighted by the mirror reflectance and the conductor Fresnel term.
    Conductor {
        /// Real part of the index.
        n: f32,
        /// Imaginary part of the index.
        k: f32,
    },
}

/// A material.
#[derive(Clone, Copy, Debug)]
pub struct Material {
    /// Ambient reflectance.
    pub ambient: Vec3,
    /// Diffuse reflectance.
    pub diffuse: Vec3,
    /// Specular reflectance.
    pub specular: Vec3,
    /// Blinn-Phong exponent.
    pub phong: f32,
    /// Mirror reflectance.
    pub mirror: Vec3,
    /// The perfect-specular part.
    pub kind: Specular,
    /// Glossy spread of mirror and conductor reflections (0: perfect).
    pub roughness: f32,
    /// A reflection model replacing Blinn-Phong in direct lighting.
    pub brdf: Option<Brdf>,
    /// Radiance the surface emits, from a shader's `emission(s)` (the scene's
    /// own materials emit nothing; object lights carry their radiance
    /// separately, as lights).
    pub emission: Vec3,
}

impl Default for Material {
    /// A black, non-reflective surface.
    fn default() -> Material {
        Material {
            ambient: Vec3::ZERO,
            diffuse: Vec3::ZERO,
            specular: Vec3::ZERO,
            phong: 1.0,
            mirror: Vec3::ZERO,
            kind: Specular::None,
            roughness: 0.0,
            brdf: None,
            emission: Vec3::ZERO,
        }
    }
}

impl Material {
    /// From the description.
    pub fn from_desc(d: &MaterialDesc) -> Material {
        let kind = match d.kind {
            MaterialKind::Plain => Specular::None,
            MaterialKind::Mirror => Specular::Mirror,
            MaterialKind::Dielectric => {
                Specular::Dielectric { ior: d.refraction_index, absorption: d.absorption_coefficient }
            }
            MaterialKind::Conductor => Specular::Conductor { n: d.refraction_index, k: d.absorption_index },
        };
        Material {
            ambient: d.ambient,
            diffuse: d.diffuse,
            specular: d.specular,
            phong: d.phong_exponent,
            mirror: d.mirror,
            kind,
            roughness: d.roughness,
            brdf: d
                .brdf
                .as_ref()
                .map(|b| Brdf::from_desc(b, d.phong_exponent, d.refraction_index, d.absorption_index)),
            emission: Vec3::ZERO,
        }
    }
}
