//! The scene description: plain data read from a scene file, every item with
//! the location it came from. It knows nothing of rendering and nothing of XML
//! or JSON; `render::Scene::build` turns it into something to trace.

use super::error::{Loc, Warning};
use luster_core::math::{Vec2, Vec3};
use std::path::PathBuf;

mod lights;
mod materials;
mod media;
mod objects;
mod textures;
mod volumes;

pub use lights::*;
pub use materials::*;
pub use media::*;
pub use objects::*;
pub use textures::*;
pub use volumes::*;

impl Description {
    /// The folders shaders' `require` searches: the scene's folder, its
    /// `<ShaderLibrary>` folders, then `--shader-lib`'s.
    pub fn module_search_path(&self) -> Vec<PathBuf> {
        let mut dirs = vec![self.base_dir.clone()];
        dirs.extend(self.shader_libraries.iter().cloned());
        luster_shading::shader::search_path(&dirs)
    }
}

/// A whole scene as the file describes it.
#[derive(Clone, Debug)]
pub struct Description {
    /// The scene file.
    pub file: PathBuf,
    /// Folder that relative asset paths (PLY files) are resolved against.
    pub base_dir: PathBuf,
    /// Folders shaders' `require` searches after `base_dir`
    /// (`<ShaderLibrary>`, relative to the scene file), in order.
    pub shader_libraries: Vec<PathBuf>,
    /// Reflection/refraction bounces allowed after the camera ray.
    pub max_recursion_depth: u32,
    /// Colour of rays that hit nothing.
    pub background: Vec3,
    /// Offset of secondary ray origins along the normal, where the scene
    /// sets one; `None` offsets each ray by the size of its hit point's
    /// coordinates (scale-independent).
    pub shadow_ray_epsilon: Option<f32>,
    /// Tolerance of intersection tests.
    pub intersection_test_epsilon: f32,
    /// One image per camera.
    pub cameras: Vec<CameraDesc>,
    /// Ambient radiance.
    pub ambient_light: Vec3,
    /// Point lights.
    pub point_lights: Vec<PointLightDesc>,
    /// Square area lights.
    pub area_lights: Vec<AreaLightDesc>,
    /// Directional lights (hw5).
    pub directional_lights: Vec<DirectionalLightDesc>,
    /// Spot lights (hw5).
    pub spot_lights: Vec<SpotLightDesc>,
    /// The environment light (`SphericalDirectionalLight`, hw5), if any.
    pub environment_light: Option<EnvironmentLightDesc>,
    /// The lights and materials a model scene adds around a model, which an
    /// HDRI replaces; `None` in scene files.
    pub studio: Option<Studio>,
    /// Objects that emit light (`LightMesh`, `LightSphere`, hw7).
    pub emitters: Vec<EmitterDesc>,
    /// Materials, referenced by index from objects.
    pub materials: Vec<MaterialDesc>,
    /// Shared vertex positions (the course's 1-based `VertexData`).
    pub vertices: Vec<Vec3>,
    /// Shared texture coordinates (the course's 1-based `TexCoordData`).
    pub tex_coords: Vec<Vec2>,
    /// Image files, referenced by index from image texture maps.
    pub images: Vec<ImageDesc>,
    /// Texture maps, referenced by index from objects.
    pub texture_maps: Vec<TextureMapDesc>,
    /// The texture map that replaces the background colour, if any.
    pub background_texture: Option<usize>,
    /// Objects in file order; instances refer to earlier or later ones by index.
    pub objects: Vec<ObjectDesc>,
    /// Participating media and hypertextures (`Volumes`, a luster extension).
    pub volumes: Vec<VolumeDesc>,
    /// Homogeneous media that objects' interiors name (`<Media>`).
    pub media: Vec<MediumDesc>,
    /// Which objects are filled by which medium (`<Interior>`).
    pub interiors: Vec<InteriorDesc>,
    /// The display transform of the 8-bit images (`Display`, a luster
    /// extension; `course` unless the scene opts in, `srgb` for OBJ models).
    pub display: luster_core::tonemap::Display,
    /// What the loader accepted but did not use or had to correct.
    pub warnings: Vec<Warning>,
}

/// How the camera's image plane is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// `Gaze` + `NearPlane` (left, right, bottom, top) at `NearDistance`.
    Plane {
        /// Viewing direction.
        gaze: Vec3,
        /// left, right, bottom, top.
        near_plane: [f32; 4],
    },
    /// `type="lookAt"`: `GazePoint` and a vertical field of view in degrees; the
    /// horizontal extent follows from the image's aspect ratio.
    LookAt {
        /// The point looked at.
        gaze_point: Vec3,
        /// Vertical field of view, degrees.
        fov_y: f32,
    },
}

/// A camera and the image it makes.
#[derive(Clone, Debug)]
pub struct CameraDesc {
    /// The camera's id.
    pub id: String,
    /// Eye position.
    pub position: Vec3,
    /// Up vector (need not be perpendicular to the gaze).
    pub up: Vec3,
    /// Image plane.
    pub projection: Projection,
    /// Distance from the eye to the image plane.
    pub near_distance: f32,
    /// Width and height in pixels.
    pub resolution: (u32, u32),
    /// Output file name.
    pub image_name: String,
    /// Tone mappings of the image (`Tonemap` elements), in order; none for
    /// the course's plain 8-bit images.
    pub tonemaps: Vec<luster_core::tonemap::Tonemap>,
    /// Samples per pixel requested by the scene.
    pub num_samples: u32,
    /// Adaptive sampling's noise threshold (`NoiseThreshold`; `None`: off).
    pub noise_threshold: Option<f32>,
    /// Edge of the square lens (0: a pinhole).
    pub aperture_size: f32,
    /// Distance along the gaze of the plane in focus.
    pub focus_distance: f32,
    /// How this camera's image is rendered (`Renderer`, `RendererParams`).
    pub renderer: RendererDesc,
    /// Where.
    pub loc: Loc,
}

/// The integrator a camera asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RendererDesc {
    /// The course's recursive ray tracer with direct lighting (no `<Renderer>`).
    #[default]
    Whitted,
    /// `<Renderer>PathTracing</Renderer>` with the course's `<RendererParams>`.
    PathTracing(PathParamsDesc),
}

/// The course's path-tracing switches, or luster's own MIS path tracer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathParamsDesc {
    /// `NextEventEstimation`: sample the lights at every bounce.
    pub next_event: bool,
    /// `ImportanceSampling`: cosine-weighted bounces instead of uniform ones.
    pub importance: bool,
    /// `RussianRoulette`: end paths by their throughput instead of the depth.
    pub russian_roulette: bool,
    /// luster's `MIS` word: light and BSDF samples combined by the power
    /// heuristic, bounces drawn from the BSDF, the environment light hit and
    /// sampled (see docs/path-tracing.md). The course's words are then unused.
    pub mis: bool,
    /// With `MIS`: how many lights a hit samples (`AllLights`, `OneLight`).
    pub lights: LightSamples,
}

/// How many lights an `MIS` hit samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSamples {
    /// Every light when the scene has a few, else one chosen by power.
    #[default]
    Auto,
    /// `OneLight`: one light, chosen by power, whatever the count.
    One,
    /// `AllLights`: every light, whatever the count.
    All,
}
