//! Render-side materials: the course's Blinn-Phong surface or a BRDF, with an
//! optional perfectly specular part (mirror, dielectric or conductor). How a
//! material scatters is [`crate::bsdf`]'s: [`crate::bsdf::Bsdf`] views one at a
//! shading point.

use crate::bsdf::{Brdf, Specular};
use luster_core::math::Vec3;
use luster_scene::description::{MaterialDesc, MaterialKind};

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
    /// Whether a shader's closure replaces the fields above but the
    /// emission: its lobes travel beside the material (in the path state),
    /// flattened at the shading point.
    pub closure: bool,
    /// Facts the path tracer asks at every vertex, worked out from the
    /// fields above by [`from_desc`](Self::from_desc) and
    /// [`refresh`](Self::refresh): a material changed after either (a
    /// texture map's copy) calls `refresh` again.
    pub traits: Traits,
}

/// What a [`Material`]'s colours and model imply, tested per path vertex:
/// an integer's worth of flags instead of several `Vec3` comparisons each
/// time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Traits {
    /// Some diffuse or specular colour above zero: light samples and
    /// bounces are taken there.
    pub reflects: bool,
    /// The emission is not zero.
    pub emits: bool,
    /// A Phong-family BRDF without specular colour: its value, the same for
    /// every pair of directions above the surface (see
    /// [`PhongFamily::diffuse_value`](crate::bsdf::PhongFamily::diffuse_value)).
    pub phong_diffuse: Option<Vec3>,
    /// That BRDF's sampler always takes the diffuse part
    /// ([`Brdf::diffuse_only`]).
    pub diffuse_only: bool,
}

impl Traits {
    /// The traits of `m`'s current fields.
    pub fn of(m: &Material) -> Traits {
        let phong_diffuse = match &m.brdf {
            Some(Brdf::Phong(b)) if m.specular == Vec3::ZERO => Some(b.diffuse_value(m.diffuse, m.specular)),
            _ => None,
        };
        Traits {
            reflects: m.closure || m.diffuse.max_element() > 0.0 || m.specular.max_element() > 0.0,
            emits: m.emission != Vec3::ZERO,
            phong_diffuse,
            diffuse_only: m.brdf.as_ref().is_some_and(|b| b.diffuse_only(m.diffuse, m.specular).is_some()),
        }
    }
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
            closure: false,
            traits: Traits::default(),
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
        let mut m = Material {
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
            closure: false,
            traits: Traits::default(),
        };
        m.refresh();
        m
    }

    /// Works out [`traits`](Self::traits) again after the fields changed.
    #[inline]
    pub fn refresh(&mut self) {
        self.traits = Traits::of(self);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Lobe, PhongFamily, Variant};

    /// The traits follow the fields they are worked out from, and a changed
    /// material has them again after `refresh`.
    #[test]
    fn traits_follow_the_fields() {
        let phong =
            Brdf::Phong(PhongFamily { lobe: Lobe::Phong, variant: Variant::Normalized, exponent: 10.0 });
        let mut m = Material { diffuse: Vec3::splat(0.5), brdf: Some(phong), ..Material::default() };
        m.refresh();
        let want = Vec3::splat(0.5) * std::f32::consts::FRAC_1_PI;
        assert_eq!(
            m.traits,
            Traits { reflects: true, emits: false, phong_diffuse: Some(want), diffuse_only: true }
        );
        m.specular = Vec3::new(0.0, 0.1, 0.0);
        m.emission = Vec3::X;
        m.refresh();
        assert_eq!(
            m.traits,
            Traits { reflects: true, emits: true, phong_diffuse: None, diffuse_only: false }
        );
        m.diffuse = Vec3::ZERO;
        m.specular = Vec3::ZERO;
        m.refresh();
        assert!(!m.traits.reflects && m.traits.phong_diffuse.is_some() && !m.traits.diffuse_only);
        assert_eq!(Material::default().traits, Traits::default());
    }
}
