//! The scene description: plain data read from a scene file, every item with
//! the location it came from. It knows nothing of rendering and nothing of XML
//! or JSON; `render::Scene::build` turns it into something to trace.

use super::error::{Loc, Warning};
use crate::math::{Quat, Transform, Vec2, Vec3};
use crate::shader::ParamValue;
use std::path::PathBuf;
use std::sync::Arc;

impl Description {
    /// The folders shaders' `require` searches: the scene's folder, its
    /// `<ShaderLibrary>` folders, then `--shader-lib`'s.
    pub fn module_search_path(&self) -> Vec<PathBuf> {
        let mut dirs = vec![self.base_dir.clone()];
        dirs.extend(self.shader_libraries.iter().cloned());
        crate::shader::search_path(&dirs)
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
    /// Offset of secondary ray origins along the normal.
    pub shadow_ray_epsilon: f32,
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
    /// The display transform of the 8-bit images (`Display`, a luster
    /// extension; `course` unless the scene opts in, `srgb` for OBJ models).
    pub display: crate::film::Display,
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
    pub tonemaps: Vec<crate::film::Tonemap>,
    /// Samples per pixel requested by the scene.
    pub num_samples: u32,
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
}

/// An object that emits light: its index in [`Description::objects`] and
/// its radiance (`Radiance` of `LightMesh`/`LightSphere`).
#[derive(Clone, Debug)]
pub struct EmitterDesc {
    /// Index into [`Description::objects`].
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
    /// Index into [`Description::images`].
    pub image: usize,
    /// How the image maps to directions.
    pub mapping: EnvMapping,
    /// How directions are sampled.
    pub sampling: EnvSampling,
    /// Where.
    pub loc: Loc,
}

/// What kind of surface a material is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    /// Blinn-Phong only.
    Plain,
    /// Blinn-Phong plus perfect reflection weighted by `MirrorReflectance`.
    Mirror,
    /// Glass-like: Fresnel reflection and refraction, Beer absorption inside.
    Dielectric,
    /// Metal: reflection weighted by the conductor Fresnel term.
    Conductor,
}

/// A material.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    /// The material's id.
    pub id: String,
    /// Its kind.
    pub kind: MaterialKind,
    /// Ambient reflectance.
    pub ambient: Vec3,
    /// Diffuse reflectance.
    pub diffuse: Vec3,
    /// Specular reflectance.
    pub specular: Vec3,
    /// Mirror reflectance (mirror and conductor).
    pub mirror: Vec3,
    /// Blinn-Phong exponent.
    pub phong_exponent: f32,
    /// Index of refraction (dielectric; real part for conductors).
    pub refraction_index: f32,
    /// Beer's-law absorption coefficient per unit distance (dielectric).
    pub absorption_coefficient: Vec3,
    /// Imaginary part of the index of refraction (conductor).
    pub absorption_index: f32,
    /// Glossiness of mirrors and conductors: how far reflected rays stray (0: perfect).
    pub roughness: f32,
    /// The reflection model named by `BRDF="id"`; the course's Blinn-Phong when absent.
    pub brdf: Option<BrdfDesc>,
    /// Where.
    pub loc: Loc,
}

/// Which reflection model a `<BRDFs>` entry is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrdfKind {
    /// `OriginalPhong`.
    OriginalPhong,
    /// `ModifiedPhong`.
    ModifiedPhong,
    /// `OriginalBlinnPhong`.
    OriginalBlinnPhong,
    /// `ModifiedBlinnPhong`.
    ModifiedBlinnPhong,
    /// `TorranceSparrow`.
    TorranceSparrow,
}

/// A `<BRDFs>` entry.
#[derive(Clone, Debug)]
pub struct BrdfDesc {
    /// Its id.
    pub id: String,
    /// The model.
    pub kind: BrdfKind,
    /// `<Exponent>`; the material's `PhongExponent` when absent.
    pub exponent: Option<f32>,
    /// `normalized="true"` (modified Phong and Blinn-Phong).
    pub normalized: bool,
    /// `kdfresnel="true"` (Torrance-Sparrow): the diffuse term is weighted by `1 - F`.
    pub kd_fresnel: bool,
    /// Where.
    pub loc: Loc,
}

/// Where a mesh's triangles come from.
#[derive(Clone, Debug)]
pub enum MeshSource {
    /// Triangles given inline, as 0-based indices into [`Description::vertices`].
    Inline {
        /// The triangles.
        triangles: Vec<[u32; 3]>,
        /// Added to a vertex index to get the index of its texture coordinate
        /// in [`Description::tex_coords`] (the `Faces` element's
        /// `textureOffset - vertexOffset`; 0 when they are numbered alike).
        tex_shift: i64,
    },
    /// A PLY file with its own vertices.
    Ply(PathBuf),
    /// Vertex arrays read when the scene loaded (an OBJ model's part).
    Arrays(Arc<MeshArrays>),
}

/// A mesh's own vertex arrays, 0-based: what an OBJ file gives.
#[derive(Clone, Debug, Default)]
pub struct MeshArrays {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, when the file has them for every vertex.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, when the file has them for every vertex.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles, as indices into the arrays.
    pub triangles: Vec<[u32; 3]>,
}

/// The shape of an object.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A sphere, before its transform.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
    /// An ellipsoid (luster's `<Ellipsoid>` extension), before its transform:
    /// the unit sphere scaled by `radii`, turned by `rotation`, moved to `center`.
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Radii along the ellipsoid's own axes, all positive.
        radii: Vec3,
        /// Its own axes to object space (the identity when not given).
        rotation: Quat,
    },
    /// A single triangle.
    Triangle {
        /// Its corners.
        vertices: [Vec3; 3],
        /// Texture coordinates of the corners, when `TexCoordData` has them.
        uvs: Option<[Vec2; 3]>,
    },
    /// An infinite plane through `point` with `normal`.
    Plane {
        /// A point on the plane.
        point: Vec3,
        /// Its normal.
        normal: Vec3,
    },
    /// A triangle mesh.
    Mesh {
        /// Its triangles.
        source: MeshSource,
        /// Interpolate vertex normals (`shadingMode="smooth"`): the file's own
        /// normals where [`MeshSource::Arrays`] has them, else area-weighted ones.
        smooth: bool,
    },
    /// A `MeshInstance`: the geometry of another mesh (resolved through any chain
    /// of instances), with this object's own material and full transform.
    Instance {
        /// Index into [`Description::objects`] of the mesh whose triangles are used.
        mesh: usize,
    },
}

/// An object of the scene.
#[derive(Clone, Debug)]
pub struct ObjectDesc {
    /// The object's id (meshes and instances share one namespace).
    pub id: String,
    /// Its shape.
    pub shape: Shape,
    /// Index into [`Description::materials`].
    pub material: usize,
    /// Object to world, composed in the listed order (and, for instances, on
    /// top of the base's transform unless `resetTransform` is true).
    pub transform: Transform,
    /// Translation over the shutter interval (`MotionBlur`): at time `τ` the
    /// object is moved by `τ · motion` after its transform.
    pub motion: Vec3,
    /// Indices into [`Description::texture_maps`], in the order listed.
    pub textures: Vec<usize>,
    /// Where.
    pub loc: Loc,
}

/// An image file that texture maps read.
#[derive(Clone, Debug)]
pub struct ImageDesc {
    /// The image's id.
    pub id: String,
    /// Resolved path.
    pub path: PathBuf,
    /// Whether texels are display-encoded colours to raise to the power 2.2
    /// (`degamma="true"` on the image or on a texture map reading it).
    pub degamma: bool,
    /// Where.
    pub loc: Loc,
}

/// How an image texture is filtered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// The texel the point falls in.
    Nearest,
    /// The four nearest texels, weighted by distance.
    Bilinear,
    /// Bilinear in the two mipmap levels around the pixel's footprint, blended.
    Trilinear,
}

/// What a texture's value does to the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecalMode {
    /// The value is the diffuse reflectance.
    ReplaceKd,
    /// The diffuse reflectance is the mean of the material's and the value.
    BlendKd,
    /// The value is the specular reflectance.
    ReplaceKs,
    /// The value is the colour of camera rays that miss (sampled at the pixel).
    ReplaceBackground,
    /// The value is a tangent-space normal.
    ReplaceNormal,
    /// The value is a height whose gradient perturbs the normal.
    BumpNormal,
    /// The value is the surface's colour, unlit.
    ReplaceAll,
    /// The value is the mirror reflectance (`MirrorReflectance`, the course's
    /// `km`); a luster extension, mainly for shaders' `reflect`. A point of a
    /// material with no mirror part becomes a mirror.
    ReplaceKm,
    /// A shader sets every material output its script defines (base and
    /// specular colour, roughness, metalness, emission, mirror reflectance);
    /// a luster extension for shader maps only (`docs/shaders.md`).
    Material,
}

/// How Perlin noise in [-1, 1] becomes a texture value in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseConversion {
    /// `(n + 1) / 2`: patchy.
    Linear,
    /// `|n|`: veins.
    AbsVal,
}

/// Where a texture map's value comes from.
#[derive(Clone, Debug)]
pub enum TextureSource {
    /// An image, looked up by the surface's texture coordinates.
    Image {
        /// Index into [`Description::images`].
        image: usize,
        /// Filtering.
        interpolation: Interpolation,
        /// Texel values are divided by this (`Normalizer`; 255 by default for
        /// 8-bit images, 1 for floating-point ones when not given).
        normalizer: Option<f32>,
    },
    /// Perlin noise of the object-space position.
    Perlin {
        /// Multiplies the position before the noise (`NoiseScale`).
        scale: f32,
        /// From noise to value.
        conversion: NoiseConversion,
        /// Octaves summed (`NumOctaves`, 1 by default).
        octaves: u32,
    },
    /// A 3D checkerboard of the object-space position.
    Checkerboard {
        /// Squares per unit (`Scale`).
        scale: f32,
        /// Shift of the pattern (`Offset`).
        offset: f32,
        /// Colour of the "black" squares.
        black: Vec3,
        /// Colour of the "white" squares.
        white: Vec3,
    },
    /// A Lua shader script (a luster extension; see `docs/shaders.md`).
    Shader {
        /// The script's path (relative ones resolved against the scene's folder).
        path: PathBuf,
        /// The script's text, read when the scene loads.
        code: String,
        /// `Parameter` elements, in order: what the script reads as `param.NAME`.
        params: Vec<(String, ParamValue)>,
    },
}

/// A texture map.
#[derive(Clone, Debug)]
pub struct TextureMapDesc {
    /// The map's id.
    pub id: String,
    /// Its source.
    pub source: TextureSource,
    /// What it does.
    pub decal: DecalMode,
    /// Height multiplier of bump maps (`BumpFactor`, 1 by default).
    pub bump_factor: f32,
    /// Where.
    pub loc: Loc,
}

/// The region a volume fills, in its own space (before its transform).
#[derive(Clone, Debug, PartialEq)]
pub enum BoundDesc {
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Smallest corner.
        min: Vec3,
        /// Largest corner.
        max: Vec3,
    },
    /// An ellipsoid: the unit ball scaled by `radii`, rotated, then moved to `center`.
    Ellipsoid {
        /// Centre.
        center: Vec3,
        /// Semi-axes along the rotated x, y, z.
        radii: Vec3,
        /// Rotation (identity when none is given).
        rotation: Quat,
    },
}

/// A Lua script with its parameters, as a scene names it.
#[derive(Clone, Debug)]
pub struct ScriptDesc {
    /// The script's path (relative ones resolved against the scene's folder).
    pub path: PathBuf,
    /// The script's text, read when the scene loads.
    pub code: String,
    /// `Parameter` elements, in order: what the script reads as `param.NAME`.
    pub params: Vec<(String, ParamValue)>,
}

/// What a volume does with light.
#[derive(Clone, Debug)]
pub enum VolumeKind {
    /// A participating medium: absorbs, scatters and emits along rays.
    Medium {
        /// Absorption coefficient per unit length at density 1 (σa).
        absorption: Vec3,
        /// Scattering coefficient per unit length at density 1 (σs).
        scattering: Vec3,
        /// Emitted radiance per unit length at density 1 (when the script has no `emission`).
        emission: Vec3,
        /// Henyey–Greenstein asymmetry, −1 (back) to 1 (forward); 0 is isotropic.
        anisotropy: f32,
        /// Orders of the multiple-scattering approximation (1: single scattering only).
        octaves: u32,
    },
    /// A hypertexture: the surface where the density crosses `threshold`,
    /// shaded with a material like any surface.
    Surface {
        /// Index into [`Description::materials`].
        material: usize,
        /// The density of the surface.
        threshold: f32,
        /// Indices into [`Description::texture_maps`].
        textures: Vec<usize>,
    },
}

/// A volume: a bounded region whose density is a constant or a script's.
#[derive(Clone, Debug)]
pub struct VolumeDesc {
    /// The volume's id.
    pub id: String,
    /// The region it fills.
    pub bound: BoundDesc,
    /// Bound to world.
    pub transform: Transform,
    /// Density multiplier (the constant density when there is no script).
    pub density: f32,
    /// The script with `density(s)` (and, for media, optionally `emission(s)`).
    pub script: Option<ScriptDesc>,
    /// Ray-marching step in world units; `None`: chosen from the bound's size.
    pub step: Option<f32>,
    /// Precompute the script's density on a grid of this many cells per edge.
    pub grid: Option<u32>,
    /// Medium or surface.
    pub kind: VolumeKind,
    /// Where.
    pub loc: Loc,
}
