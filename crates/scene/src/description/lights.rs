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
    /// Degrees the map is turned about `+y`, counter-clockwise seen from
    /// above, from hw5's orientation (docs/environment-light.md); 0 for the
    /// course's `SphericalDirectionalLight`.
    pub rotation: f32,
    /// Factor on the image's values: 1 for the course's light (its values
    /// are radiance as they are), `255 × --env-strength` for `--env` (whose
    /// 1.0 is display white).
    pub strength: f32,
    /// Where.
    pub loc: Loc,
}

/// The lighting a model scene adds around a model (`luster render
/// model.obj`): the lights an HDRI (`--env`, [`crate::hdri`]) replaces.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Studio {
    /// Indices into [`Description::point_lights`](super::Description::point_lights): the key and fill lights.
    pub point_lights: Vec<usize>,
    /// Whether [`Description::ambient_light`](super::Description::ambient_light) is the studio's.
    pub ambient: bool,
    /// Indices into [`Description::materials`](super::Description::materials):
    /// the model's course materials, whose diffuse term (without the course's
    /// missing `1/π`) is tuned to the studio lights. Under an HDRI they take
    /// the normalized Blinn-Phong, so that a reflectance is an albedo as in
    /// other renderers.
    pub materials: Vec<usize>,
    /// Index into [`Description::objects`](super::Description::objects) of
    /// a ground the studio added that an HDRI takes away (a glTF file's:
    /// it is rendered as Blender imports it, on the HDRI alone); always the
    /// last object.
    pub ground: Option<usize>,
}
