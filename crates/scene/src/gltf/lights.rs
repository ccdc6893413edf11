//! `KHR_lights_punctual`: point, spot and directional lights placed by their
//! nodes (a light shines down its node's −Z), in the photometric units the
//! extension uses, converted as Blender's glTF importer does in its default
//! ("Standard") lighting mode, so that a file renders as bright in luster
//! as in Cycles.
//!
//! | glTF | luster |
//! |---|---|
//! | point, `intensity` in candela | point light, intensity `255 · cd / 683` per colour channel × `color` |
//! | spot, `intensity` in candela | spot light, intensity as a point light's |
//! | spot `innerConeAngle`, `outerConeAngle` (radians, from the axis) | fall-off angle `2 · inner`, coverage angle `2 · outer` (degrees, full) |
//! | directional, `intensity` in lux | directional light, radiance `255 · lux / 683` × `color` |
//! | `range` | ignored, with a warning: luster's lights fall off with the square of the distance to any distance |
//!
//! Blender turns candela into watts as `W = cd · 4π / 683` and lux into its
//! sun's `W/m² = lux / 683`; Cycles' lights of that power give an
//! irradiance of `cd / 683 / d²` and `lux / 683`, and a diffuse surface
//! (which divides by π, as luster's closures do) shows that as a fraction of
//! white. luster's film has 255 = white, hence the factor 255.
//!
//! Between the cones a glTF viewer's intensity falls as the square of
//! `(cos α − cos outer) / (cos inner − cos outer)`; luster's spot falls as its
//! fourth power (the course's spot light), a slightly softer edge.

use super::nodes::Placed;
use super::Notes;
use crate::description::{DirectionalLightDesc, PointLightDesc, SpotLightDesc};
use crate::error::Loc;
use gltf::khr_lights_punctual::Kind;
use luster_core::math::Vec3;

/// Film units (255 = white) per watt, as Blender's importer converts the
/// extension's candela and lux (683 lumens per watt).
pub const PER_LUMEN: f32 = 255.0 / 683.0;

/// The lights of a scene.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    /// Point lights.
    pub point: Vec<PointLightDesc>,
    /// Spot lights.
    pub spot: Vec<SpotLightDesc>,
    /// Directional lights.
    pub directional: Vec<DirectionalLightDesc>,
}

impl Lights {
    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.point.is_empty() && self.spot.is_empty() && self.directional.is_empty()
    }
}

/// The lights the drawn nodes carry.
pub fn lights(doc: &gltf::Document, placed: &[Placed], notes: &mut Notes) -> Lights {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut out = Lights::default();
    for p in placed {
        let Some(light) = nodes[p.node].light() else { continue };
        let name = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
        let loc = Loc { line: None, path: format!("nodes[{}]", p.node) };
        let colour = Vec3::from(light.color()) * light.intensity();
        if !colour.is_finite() || colour.min_element() < 0.0 {
            notes.warn(
                &name,
                "the light's colour × intensity is negative or not finite; the light is left out",
            );
            continue;
        }
        if light.range().is_some() {
            notes.warn(&name, "range is ignored: luster's lights reach any distance, falling off as 1/d²");
        }
        let position = p.world.point(Vec3::ZERO);
        let direction = p.world.vector(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
        match light.kind() {
            Kind::Point => out.point.push(PointLightDesc { position, intensity: colour * PER_LUMEN, loc }),
            Kind::Directional => {
                out.directional.push(DirectionalLightDesc { direction, radiance: colour * PER_LUMEN, loc })
            }
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let outer = outer_cone_angle.clamp(1e-4, std::f32::consts::FRAC_PI_2);
                let inner = inner_cone_angle.clamp(0.0, outer);
                out.spot.push(SpotLightDesc {
                    position,
                    direction,
                    intensity: colour * PER_LUMEN,
                    coverage_angle: 2.0 * outer.to_degrees(),
                    falloff_angle: 2.0 * inner.to_degrees(),
                    loc,
                })
            }
        }
    }
    out
}
