//! Each light's emitted power, which the light tree ([`super::tree`]) ranks
//! lights by.
//!
//! Power by light, with `L` the radiance (mean of its RGB components), `I`
//! the intensity, `A` the area and `r` the radius of the scene's bounds:
//!
//! | light | power |
//! |---|---|
//! | point | `4π I` |
//! | spot | `2π I (1 − (cos θfalloff + cos θcoverage) / 2)` |
//! | directional | `π r² L` |
//! | square area, mesh | `π L A` (one face's worth: the course's light meshes are closed boxes, whose inner faces light nothing) |
//! | sphere (outward) | `π L 4π R²` |
//! | environment | `4π² r² L̄`, `L̄` its mean over the sphere |
//! | emissive shader | as its shape, with the largest emission the probes found |
//!
//! The course's variants sample every light at every hit and never pick;
//! only luster's `MIS` mode, through the tree, uses this table.

use super::{Light, ShadedShape};
use luster_core::math::Vec3;
use std::f32::consts::PI;

/// The mean of the RGB components.
fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// The light's emitted power (see the module doc), up to a factor shared by
/// every light.
pub fn power(light: &Light, radius: f32) -> f32 {
    let sphere = |r: f32, l: f32| PI * l * 4.0 * PI * r * r;
    match light {
        Light::Point(l) => 4.0 * PI * mean(l.intensity),
        Light::Spot(l) => 2.0 * PI * mean(l.intensity) * (1.0 - 0.5 * (l.cos_falloff + l.cos_coverage)),
        Light::Directional { radiance, .. } => PI * radius * radius * mean(*radiance),
        Light::Area(l) => PI * mean(l.radiance) * l.area,
        Light::Mesh(l) => PI * mean(l.radiance) * l.area(),
        Light::Sphere(l) => sphere(l.radius, mean(l.radiance)),
        Light::Environment(e) => 4.0 * PI * PI * radius * radius * mean(e.mean_radiance()),
        Light::Shaded(l) => match &l.shape {
            ShadedShape::Mesh(m) => PI * l.probed_max * m.area(),
            ShadedShape::Sphere(s) => sphere(s.radius, l.probed_max),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{LightMesh, PointLight};
    use luster_core::math::Transform;

    fn square(size: f32, radiance: f32) -> Light {
        let (a, b, c, d) =
            (Vec3::ZERO, Vec3::new(size, 0.0, 0.0), Vec3::new(size, 0.0, size), Vec3::new(0.0, 0.0, size));
        let m =
            LightMesh::new([[a, b, c], [a, c, d]].into_iter(), &Transform::IDENTITY, Vec3::splat(radiance));
        Light::Mesh(std::sync::Arc::new(m.expect("the square has area")))
    }

    #[test]
    fn powers_follow_the_table() {
        // Power π·L·A: π·1·4 = 4π and π·3·1 = 3π; a point light of
        // intensity 0.75 gives 4π·0.75 = 3π. So 4:3:3 of 10.
        let point = Light::Point(PointLight { position: Vec3::ONE, intensity: Vec3::splat(0.75) });
        let lights = [square(2.0, 1.0), square(1.0, 3.0), point];
        let powers: Vec<f32> = lights.iter().map(|l| power(l, 10.0)).collect();
        let total: f32 = powers.iter().sum();
        let want = [0.4, 0.3, 0.3];
        for (i, w) in want.iter().enumerate() {
            assert!((powers[i] / total - w).abs() < 1e-6, "light {i}: {} against {w}", powers[i] / total);
        }
    }
}
