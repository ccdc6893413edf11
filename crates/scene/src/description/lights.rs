//! Lights in the scene description: point, area, directional and spot
//! lights, environment maps, and the objects that emit (`LightMesh`,
//! `LightSphere`).

use crate::error::Loc;
use luster_core::math::Vec3;

/// An object that emits light: its index in [`Description::objects`](super::Description::objects) and
/// its radiance (`Radiance` of `LightMesh`/`LightSphere`).
#[derive(Clone, Debug)]
pub struct EmitterDesc {
    /// Index into [`Description::objects`](super::Description::objects).
    pub object: usize,
    /// RGB radiance leaving every point of its surface.
    pub radiance: Vec3,
    /// Where.
    pub loc: Loc,
}

/// A point light: intensity `I` gives irradiance `I / d²`.
#[derive(Clone, Debug)]
pub struct PointLightDesc {
    /// Position.
    pub position: Vec3,
    /// RGB intensity.
    pub intensity: Vec3,
    /// Where.
    pub loc: Loc,
}

/// A square area light of uniform radiance.
#[derive(Clone, Debug)]
pub struct AreaLightDesc {
    /// Centre.
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Edge length.
    pub size: f32,
    /// RGB radiance.
    pub radiance: Vec3,
    /// Where.
    pub loc: Loc,
}

/// A directional light: parallel rays of one radiance, no attenuation.
#[derive(Clone, Debug)]
pub struct DirectionalLightDesc {
    /// Unit direction the light travels in.
    pub direction: Vec3,
    /// RGB radiance.
    pub radiance: Vec3,
    /// Where.
    pub loc: Loc,
}

/// A spot light: a point light limited to a cone, with a smooth edge.
#[derive(Clone, Debug)]
pub struct SpotLightDesc {
    /// Position.
    pub position: Vec3,
    /// Unit direction of the cone's axis.
    pub direction: Vec3,
    /// RGB intensity (irradiance `I / d²` inside the fall-off cone).
    pub intensity: Vec3,
    /// Full opening angle of the lit cone, degrees.
    pub coverage_angle: f32,
    /// Full opening angle of the cone without fall-off, degrees (at most `coverage_angle`).
    pub falloff_angle: f32,
    /// Where.
    pub loc: Loc,
}

/// How an environment image wraps around the sphere of directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvMapping {
    /// Latitude-longitude (equirectangular), `type="latlong"`.
    LatLong,
    /// Debevec's angular map (light probe), `type="probe"`.
    Probe,
}

/// How the environment light picks directions for direct lighting.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvSampling {
    /// By the map's luminance (a 2D piecewise-constant distribution); the default.
    Importance,
    /// Uniformly over the hemisphere around the normal (hw5's scheme, `Sampler` `uniform`).
    Uniform,
    /// Cosine-weighted over the hemisphere around the normal (`Sampler` `cosine`).
    Cosine,
}

/// The environment light: an image of radiance on the sphere at infinity.
#[derive(Clone, Debug)]
pub struct EnvironmentLightDesc {
    /// Index into [`Description::images`](super::Description::images).
    pub image: usize,
    /// How the image maps to directions.
    pub mapping: EnvMapping,
    /// How directions are sampled.
    pub sampling: EnvSampling,
    /// Where.
    pub loc: Loc,
}
