//! Each light's emitted power, which the light tree ([`super::tree`]) ranks
//! lights by, and [`LightPick`], a choice by power alone (pbrt's "power
//! light sampler"), the baseline the tree's tests compare against.
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
//! only luster's `MIS` mode, through the tree, uses this table. Where the
//! powers cannot rank the lights (all zero, or one infinite) [`LightPick`]'s
//! choice is uniform.

use super::{Light, ShadedShape};
use luster_core::math::Vec3;
use std::f32::consts::PI;

/// The probabilities of choosing each light, and their running sums.
#[derive(Clone, Debug, Default)]
pub struct LightPick {
    pmf: Vec<f32>,
    cdf: Vec<f32>,
    /// The chance of the environment light (0 without one).
    environment: f32,
}

impl LightPick {
    /// Every one of `n` lights equally likely.
    pub fn uniform(n: usize) -> LightPick {
        LightPick::from_weights(&vec![1.0; n])
    }

    /// Lights chosen by power in a scene whose bounds have radius `radius`.
    pub fn by_power(lights: &[Light], radius: f32) -> LightPick {
        let powers: Vec<f32> = lights.iter().map(|l| power(l, radius)).collect();
        let mut pick = LightPick::from_weights(&powers);
        let env = lights.iter().position(|l| matches!(l, Light::Environment(_)));
        pick.environment = env.map_or(0.0, |i| pick.pmf[i]);
        pick
    }

    /// Probabilities proportional to `w` (uniform where they cannot be).
    pub fn from_weights(w: &[f32]) -> LightPick {
        let total: f64 = w.iter().map(|&x| f64::from(x.max(0.0))).sum();
        let usable = total > 0.0 && total.is_finite() && w.iter().all(|x| x.is_finite());
        let pmf: Vec<f32> = match usable {
            true => w.iter().map(|&x| (f64::from(x.max(0.0)) / total) as f32).collect(),
            false => vec![1.0 / w.len().max(1) as f32; w.len()],
        };
        let mut sum = 0.0f32;
        let mut cdf: Vec<f32> = pmf
            .iter()
            .map(|p| {
                sum += p;
                sum
            })
            .collect();
        // The last light with a chance closes the sums at exactly 1, so a
        // draw just below 1 never falls past it.
        if let Some(last) = pmf.iter().rposition(|&p| p > 0.0) {
            cdf[last..].iter_mut().for_each(|c| *c = 1.0);
        }
        LightPick { pmf, cdf, environment: 0.0 }
    }

    /// The light for a uniform `u` in [0, 1) and its probability.
    #[inline]
    pub fn choose(&self, u: f32) -> (usize, f32) {
        let n = self.cdf.len();
        let i = self.cdf.partition_point(|&c| c <= u).min(n.saturating_sub(1));
        (i, self.pmf.get(i).copied().unwrap_or(0.0))
    }

    /// The probability of choosing light `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// The probability of choosing the environment light.
    #[inline]
    pub fn environment_pmf(&self) -> f32 {
        self.environment
    }

    /// How many lights there are to choose from.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }
}

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
    fn pick_probabilities_follow_power_and_match_the_draws() {
        // Power π·L·A: π·1·4 = 4π and π·3·1 = 3π; a point light of
        // intensity 0.75 gives 4π·0.75 = 3π. So 4:3:3 of 10.
        let point = Light::Point(PointLight { position: Vec3::ONE, intensity: Vec3::splat(0.75) });
        let lights = [square(2.0, 1.0), square(1.0, 3.0), point];
        let pick = LightPick::by_power(&lights, 10.0);
        let want = [0.4, 0.3, 0.3];
        for (i, w) in want.iter().enumerate() {
            assert!((pick.pmf(i) - w).abs() < 1e-6, "light {i}: {} against {w}", pick.pmf(i));
        }
        // The draws agree with the pmf: 30 000 stratified uniforms land on
        // each light in proportion, and `choose` reports the same pmf.
        let n = 30_000;
        let mut count = [0usize; 3];
        for k in 0..n {
            let (i, p) = pick.choose((k as f32 + 0.5) / n as f32);
            assert_eq!(p, pick.pmf(i));
            count[i] += 1;
        }
        for (i, w) in want.iter().enumerate() {
            assert!((count[i] as f32 / n as f32 - w).abs() < 1e-3, "light {i}: {count:?}");
        }
        // The largest uniform below 1 still finds the last light.
        assert_eq!(pick.choose(1.0 - f32::EPSILON / 2.0).0, 2);
    }

    #[test]
    fn unusable_powers_give_a_uniform_choice_and_dark_lights_none() {
        let pick = LightPick::from_weights(&[0.0, 0.0]);
        assert_eq!((pick.pmf(0), pick.pmf(1)), (0.5, 0.5));
        let pick = LightPick::from_weights(&[1.0, f32::INFINITY, 2.0]);
        assert!((0..3).all(|i| (pick.pmf(i) - 1.0 / 3.0).abs() < 1e-7));
        // A black light is never chosen, even by the largest draw.
        let pick = LightPick::from_weights(&[1.0, 3.0, 0.0]);
        assert_eq!(pick.pmf(2), 0.0);
        assert_eq!(pick.choose(1.0 - f32::EPSILON / 2.0).0, 1);
        assert_eq!(pick.choose(0.2), (0, 0.25));
        assert!(LightPick::uniform(0).is_empty());
    }
}
