//! A scene made around one OBJ model, for `luster render model.obj`: a camera
//! that frames the model, a key light, a fill light and sky-coloured ambient
//! light, and a grey ground under it.
//!
//! The model's bounding sphere (centre: the middle of its bounding box;
//! radius: the farthest vertex from it) sets the scale of everything, so a
//! model in millimetres and one in kilometres render alike:
//!
//! | setting | default | [`ModelView`] field (`luster render` flag) |
//! |---|---|---|
//! | image | 800×600, 4 samples per pixel | `width`, `height` (`--size WxH`), `samples` (`--spp`) |
//! | camera direction | 35° to the right of the front (+z), 25° above | `azimuth` (`--azimuth`), `elevation` (`--elevation`), degrees |
//! | vertical field of view | 40° | `fov_y` (`--fov`) |
//! | camera distance | the bounding sphere just fits the narrower field of view, with a 10% margin | `distance` (`--distance`), in model units from the sphere's centre |
//! | ground | a light grey plane under the lowest vertex (y up, as OBJ files are), left out when the camera is below it | `ground` (`--no-ground`) |
//!
//! The lights follow the camera, so every view is lit like a studio shot: the
//! key light 45° to the camera's left and 50° up, the fill 60° to its right
//! and 15° up, both four radii from the centre, with intensities that give
//! the centre an irradiance of 190 and 60 (in the course's units, where 255
//! is white), and an ambient light of about 13 with the blue tint of the sky.
//! The ground is lit mostly by the ambient light (its ambient reflectance is
//! 2.6), so it stays light out to the horizon, where point lights would fade,
//! and the key light's shadow still shows on it. The background is a soft
//! grey-blue. The output image is `<stem>.png`, through the display transform
//! `srgb` unless `--display` names another (docs/hdr.md): MTL colours are
//! linear reflectances and 8-bit `map_Kd` images are sRGB-decoded, as other
//! renderers read them, and the values above are tuned for that.

use super::{load, Additions, ObjModel};
use crate::description::{
    CameraDesc, Description, MaterialDesc, MeshSource, ObjectDesc, PointLightDesc, Projection, Shape,
};
use crate::error::{Loc, SceneError, Warning};
use luster_core::math::{Transform, Vec3};
use std::path::Path;

/// How to look at a model: see the module table.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelView {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub samples: u32,
    /// Degrees around the vertical axis from the front (+z), positive to the right (+x).
    pub azimuth: f32,
    /// Degrees above the horizon, −89 to 89.
    pub elevation: f32,
    /// Vertical field of view, degrees.
    pub fov_y: f32,
    /// Camera distance from the bounding sphere's centre; `None` frames the sphere.
    pub distance: Option<f32>,
    /// Put a ground plane under the model.
    pub ground: bool,
    /// The display transform (`--display`), overriding the scene's or, for a
    /// model, `srgb`. Applies to scene files too (see [`crate::load_viewed`]).
    pub display: Option<luster_core::tonemap::Display>,
    /// Which of a glTF file's cameras to use (`--camera N`, 0-based); `None`:
    /// the first, or a framing camera when the file has none.
    pub camera: Option<usize>,
    /// Lua material shaders replacing glTF materials by name (`--material NAME=FILE.lua`).
    pub material_shaders: Vec<crate::gltf::material::MaterialOverride>,
}

impl Default for ModelView {
    fn default() -> ModelView {
        ModelView {
            width: 800,
            height: 600,
            samples: 4,
            azimuth: 35.0,
            elevation: 25.0,
            fov_y: 40.0,
            distance: None,
            ground: true,
            display: None,
            camera: None,
            material_shaders: Vec::new(),
        }
    }
}

/// Key and fill irradiance at the model's centre, and the ambient light.
const KEY: f32 = 190.0;
const FILL: f32 = 60.0;
const AMBIENT: Vec3 = Vec3::new(12.0, 13.0, 15.0);
const SKY: Vec3 = Vec3::new(105.0, 130.0, 168.0);

/// The bounding sphere of a model: centre and radius (at least a tiny bit).
pub fn bounding_sphere(model: &ObjModel) -> (Vec3, f32) {
    let points = || model.parts.iter().flat_map(|p| p.arrays.positions.iter().copied());
    let (lo, hi) = points().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let c = (lo + hi) * 0.5;
    let r = points().map(|p| p.distance(c)).fold(0.0f32, f32::max);
    (c, if r > 0.0 { r } else { 1.0 })
}

/// The unit vector from the centre towards a view at `azimuth`, `elevation` degrees.
fn direction(azimuth: f32, elevation: f32) -> Vec3 {
    let (a, e) = (azimuth.to_radians(), elevation.to_radians());
    Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
}

/// The scene of `luster render model.obj`.
pub fn model_scene(path: &Path, view: &ModelView) -> Result<Description, SceneError> {
    check(path, view)?;
    let model = load(path)?;
    let (center, radius) = bounding_sphere(&model);
    let aspect = view.width as f32 / view.height as f32;
    let half_y = (view.fov_y * 0.5).to_radians();
    let half = half_y.tan().min(half_y.tan() * aspect).atan();
    let distance = view.distance.unwrap_or(1.1 * radius / half.sin());
    let elevation = view.elevation.clamp(-89.0, 89.0);
    let eye = center + direction(view.azimuth, elevation) * distance;
    let stem = path.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    // The image is named after the model; what could not name a file safely
    // (a newline, an escape) becomes `_`.
    let stem: String =
        stem.chars().map(|c| if luster_core::text::is_unsafe(c) || c == '\\' { '_' } else { c }).collect();
    let file_name = path.file_name().map_or_else(|| stem.clone(), |s| s.to_string_lossy().into_owned());
    let loc = super::at(path, 0);
    let camera = CameraDesc {
        id: "model".into(),
        position: eye,
        up: Vec3::Y,
        projection: Projection::LookAt { gaze_point: center, fov_y: view.fov_y },
        near_distance: 1.0,
        resolution: (view.width, view.height),
        image_name: format!("{stem}.png"),
        // The display transform (`view.display`, sRGB by default) makes the
        // PNG: MTL colours are linear reflectances, as in other renderers.
        tonemaps: Vec::new(),
        num_samples: view.samples,
        noise_threshold: None,
        aperture_size: 0.0,
        focus_distance: 1.0,
        renderer: Default::default(),
        loc: loc.clone(),
    };
    let light = |az: f32, el: f32, irradiance: f32| {
        let d = 4.0 * radius;
        PointLightDesc {
            position: center + direction(view.azimuth + az, el) * d,
            intensity: Vec3::splat(irradiance * d * d),
            loc: loc.clone(),
        }
    };
    let point_lights = vec![light(-45.0, 50.0, KEY), light(60.0, 15.0, FILL)];

    let mut add = Additions::new(0, 0, 0);
    let mut objects = Vec::new();
    let smooth = model.has_normals();
    for part in &model.parts {
        let (material, textures) = add.add_part(part);
        objects.push(ObjectDesc {
            id: part.name.clone(),
            shape: Shape::Mesh { source: MeshSource::Arrays(part.arrays.clone()), smooth },
            material,
            transform: Transform::IDENTITY,
            motion: Vec3::ZERO,
            textures,
            loc: Loc { line: None, path: format!("{file_name} (material {})", part.name) },
        });
    }
    let lowest =
        model.parts.iter().flat_map(|p| p.arrays.positions.iter().map(|p| p.y)).fold(f32::INFINITY, f32::min);
    // A camera below the ground would see only the ground.
    if view.ground && eye.y > lowest {
        let material = add.add_material(MaterialDesc {
            id: "ground".into(),
            // Mostly ambient: a light floor all the way to the horizon (point
            // lights fade with distance), where the key light's shadow shows.
            ambient: Vec3::splat(2.6),
            diffuse: Vec3::splat(0.3),
            ..super::mtl::default_material(loc.clone())
        });
        objects.push(ObjectDesc {
            id: "ground".into(),
            shape: Shape::Plane {
                point: Vec3::new(center.x, lowest - 1e-3 * radius, center.z),
                normal: Vec3::Y,
            },
            material,
            transform: Transform::IDENTITY,
            motion: Vec3::ZERO,
            textures: Vec::new(),
            loc: loc.clone(),
        });
    }
    let warnings: Vec<Warning> = model.warnings;
    Ok(Description {
        file: path.to_path_buf(),
        base_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        shader_libraries: Vec::new(),
        max_recursion_depth: 6,
        background: SKY,
        shadow_ray_epsilon: None,
        intersection_test_epsilon: 1e-6,
        cameras: vec![camera],
        ambient_light: AMBIENT,
        point_lights,
        area_lights: Vec::new(),
        directional_lights: Vec::new(),
        spot_lights: Vec::new(),
        environment_light: None,
        emitters: Vec::new(),
        materials: add.materials,
        vertices: Vec::new(),
        tex_coords: Vec::new(),
        images: add.images,
        texture_maps: add.texture_maps,
        background_texture: None,
        objects,
        volumes: Vec::new(),
        media: Vec::new(),
        interiors: Vec::new(),
        display: view.display.unwrap_or(luster_core::tonemap::Display::Srgb),
        warnings,
    })
}

/// Refuses views that cannot make an image.
fn check(path: &Path, v: &ModelView) -> Result<(), SceneError> {
    let bad = |msg: String| Err(SceneError::file(path, msg));
    if v.width == 0 || v.height == 0 || v.width > 1 << 14 || v.height > 1 << 14 {
        return bad(format!(
            "an image of {}x{} pixels cannot be made (1 to 16384 a side)",
            v.width, v.height
        ));
    }
    if !(v.fov_y > 0.0 && v.fov_y < 180.0) {
        return bad(format!("the field of view must be between 0 and 180 degrees, found {}", v.fov_y));
    }
    if v.distance.is_some_and(|d| !(d > 0.0 && d.is_finite())) {
        return bad("the camera distance must be positive".to_string());
    }
    if !(v.azimuth.is_finite() && v.elevation.is_finite()) || v.samples == 0 {
        return bad("the view's angles must be finite and its samples at least 1".to_string());
    }
    Ok(())
}
