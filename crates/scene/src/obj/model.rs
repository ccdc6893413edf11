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
//! grey-blue ([`crate::studio`] holds this layout; glTF files without
//! cameras or lights use it too). An HDRI (`--env`, [`crate::hdri`])
//! replaces the key, fill and ambient lights (the [`Studio`] of the
//! description). The output image is `<stem>.png`, through the display transform
//! `srgb` unless `--display` names another (docs/hdr.md): MTL colours are
//! linear reflectances and 8-bit `map_Kd` images are sRGB-decoded, as other
//! renderers read them, and the values above are tuned for that.

use super::{load, Additions, ObjModel};
use crate::description::{Description, MeshSource, ObjectDesc, Shape, Studio};
use crate::error::{Loc, SceneError, Warning};
use crate::studio;
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
    /// Whether `width` and `height` were asked for (`--size`); when not, a
    /// glTF camera's `aspectRatio` sets the width.
    pub sized: bool,
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
            sized: false,
            camera: None,
            material_shaders: Vec::new(),
        }
    }
}

/// The bounding sphere of a model: centre and radius (at least a tiny bit).
pub fn bounding_sphere(model: &ObjModel) -> (Vec3, f32) {
    studio::bounding_sphere(|| model.parts.iter().flat_map(|p| p.arrays.positions.iter().copied()))
}

/// The scene of `luster render model.obj`.
pub fn model_scene(path: &Path, view: &ModelView) -> Result<Description, SceneError> {
    studio::check(path, view)?;
    let model = load(path)?;
    let (center, radius) = bounding_sphere(&model);
    let file_name = path.file_name().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    let loc = super::at(path, 0);
    let camera = studio::framing_camera(view, center, radius, studio::image_name(path), &loc);
    let point_lights = studio::lights(view, center, radius, 1.0, &loc);

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
            attributes: Vec::new(),
            geometry_attributes: Vec::new(),
        });
    }
    let lowest =
        model.parts.iter().flat_map(|p| p.arrays.positions.iter().map(|p| p.y)).fold(f32::INFINITY, f32::min);
    if view.ground && camera.position.y > lowest {
        let material = add.add_material(studio::ground_material(&loc));
        objects.extend(studio::ground(view, &camera, center, radius, lowest, material, &loc));
    }
    let warnings: Vec<Warning> = model.warnings;
    // All of it is the studio's: an HDRI replaces the lights and reads the
    // materials (the ground's too) as albedos.
    let studio = Studio {
        point_lights: (0..point_lights.len()).collect(),
        ambient: true,
        materials: (0..add.materials.len()).collect(),
        ground: None,
    };
    Ok(Description {
        file: path.to_path_buf(),
        base_dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        shader_libraries: Vec::new(),
        max_recursion_depth: 6,
        background: studio::SKY,
        shadow_ray_epsilon: None,
        intersection_test_epsilon: 1e-6,
        cameras: vec![camera],
        ambient_light: studio::AMBIENT,
        point_lights,
        area_lights: Vec::new(),
        directional_lights: Vec::new(),
        spot_lights: Vec::new(),
        environment_light: None,
        studio: Some(studio),
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
