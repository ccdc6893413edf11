//! The scene of `luster render scene.gltf`: the file's objects, its first
//! perspective camera (or `--camera N`) and its `KHR_lights_punctual`
//! lights, path-traced (luster's MIS path tracer) through the `srgb`
//! display transform.
//!
//! What the file lacks comes from the studio of `luster render model.obj`
//! ([`crate::studio`]): without a camera, one that frames the drawn
//! objects' bounding sphere (`--azimuth`, `--elevation`, `--fov`,
//! `--distance`, `--size` apply); without lights, the key and fill lights
//! (scaled by π, as the path tracer's diffuse surfaces divide by it), a
//! soft sky-blue background that lights the scene faintly, and a ground
//! under it (`--no-ground`). A file with lights is lit by them alone, on a
//! black background. The image is `<stem>.png`, 64 samples per pixel
//! unless `--spp` says otherwise.

use super::{camera, lights, material};
use crate::description::{
    Description, MeshArrays, MeshSource, ObjectDesc, PathParamsDesc, RendererDesc, Shape, Studio,
};
use crate::error::{Loc, SceneError};
use crate::obj::{Additions, ModelView};
use crate::studio;
use luster_core::math::{Aabb, Transform, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Samples per pixel of a glTF scene's camera.
const SAMPLES: u32 = 64;

/// Bounces after the camera ray.
const DEPTH: u32 = 8;

/// Most vertices (counting each instance's) whose world positions frame
/// the studio camera exactly; beyond, the corners of each object's box do.
const EXACT_FRAMING: usize = 1 << 24;

/// The scene of a glTF file seen through `view`.
pub fn scene(path: &Path, view: &ModelView) -> Result<Description, SceneError> {
    studio::check(path, view)?;
    let mut model = super::read(path)?;
    let doc = &model.file.doc;
    let mut warnings = Vec::new();
    let mats = material::read_materials(
        doc,
        &model.file.buffers,
        &model.file.base_dir,
        path,
        &view.material_shaders,
        &mut warnings,
    )?;
    let default = material::default_material(path);
    let mut add = Additions::new(0, 0, 0);
    let mut added: HashMap<Option<usize>, (usize, Vec<usize>)> = HashMap::new();
    let mut objects = model.objects(0, &Transform::IDENTITY, |m| {
        if let Some(done) = added.get(&m) {
            return Ok(done.clone());
        }
        let g = m.and_then(|i| mats.get(i)).unwrap_or(&default);
        let done = add.add_with_maps(&g.material, &g.maps);
        g.add_images_to(&mut add.images);
        added.insert(m, done.clone());
        Ok(done)
    })?;
    if objects.is_empty() {
        return Err(SceneError::file(
            path,
            "the scene draws no triangles (no node of it has a mesh of triangles)",
        ));
    }
    let cameras = camera::cameras(doc, &model.placed, &mut model.notes);
    let lights = lights::lights(doc, &model.placed, &mut model.notes);
    let loc = Loc { line: None, path: path.display().to_string() };
    let (center, radius, lowest) = bounds(&objects);
    let image_name = studio::image_name(path);
    let mut camera = match view.camera {
        Some(n) if n >= cameras.len() => {
            return Err(SceneError::file(
                path,
                format!(
                    "--camera {n}: the file has {} perspective camera{} (numbered from 0)",
                    cameras.len(),
                    if cameras.len() == 1 { "" } else { "s" }
                ),
            ))
        }
        Some(n) => camera::camera_desc(doc, &cameras[n], view, image_name),
        None => match cameras.first() {
            Some(c) => camera::camera_desc(doc, c, view, image_name),
            None => studio::framing_camera(view, center, radius, image_name, &loc),
        },
    };
    camera.num_samples = SAMPLES;
    camera.renderer = RendererDesc::PathTracing(PathParamsDesc { mis: true, ..Default::default() });
    let mut desc_lights = lights;
    let mut background = Vec3::ZERO;
    let mut studio_parts = None;
    if desc_lights.is_empty() {
        desc_lights.point = studio::lights(view, center, radius, std::f32::consts::PI, &loc);
        // The sky dome lights the model about as the OBJ studio's ambient light does.
        background = studio::SKY * 0.3;
        let ground_material = add.add_material(studio::ground_material(&loc));
        let before = objects.len();
        objects.extend(studio::ground(view, &camera, center, radius, lowest, ground_material, &loc));
        // An HDRI (`--env`) replaces the studio's lights and its ground:
        // the file is then lit and seen as Blender imports it.
        studio_parts = Some(Studio {
            point_lights: (0..desc_lights.point.len()).collect(),
            ambient: false,
            materials: vec![ground_material],
            ground: (objects.len() == before + 1).then_some(before),
        });
    }
    let mut all_warnings = model.notes.warnings;
    all_warnings.extend(warnings);
    Ok(Description {
        file: path.to_path_buf(),
        base_dir: model.file.base_dir.clone(),
        shader_libraries: Vec::new(),
        max_recursion_depth: DEPTH,
        background,
        shadow_ray_epsilon: None,
        intersection_test_epsilon: 1e-6,
        cameras: vec![camera],
        ambient_light: Vec3::ZERO,
        point_lights: desc_lights.point,
        area_lights: Vec::new(),
        directional_lights: desc_lights.directional,
        spot_lights: desc_lights.spot,
        environment_light: None,
        studio: studio_parts,
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
        warnings: all_warnings,
    })
}

/// The bounding sphere of the objects in world space (centre, radius) and
/// their lowest height.
fn bounds(objects: &[ObjectDesc]) -> (Vec3, f32, f32) {
    fn arrays<'a>(objects: &'a [ObjectDesc], o: &'a ObjectDesc) -> Option<&'a MeshArrays> {
        let mesh = match o.shape {
            Shape::Instance { mesh } => &objects[mesh],
            _ => o,
        };
        match &mesh.shape {
            Shape::Mesh { source: MeshSource::Arrays(a), .. } => Some(a),
            _ => None,
        }
    }
    let vertices: usize = objects.iter().filter_map(|o| arrays(objects, o)).map(|a| a.positions.len()).sum();
    let exact = vertices <= EXACT_FRAMING;
    let points = || {
        objects.iter().filter_map(move |o| arrays(objects, o).map(|a| (o, a))).flat_map(move |(o, a)| {
            let corners: Vec<Vec3> = if exact {
                Vec::new()
            } else {
                let b = o.transform.aabb(&Aabb::from_points(a.positions.iter().copied()));
                (0..8)
                    .map(|i| {
                        Vec3::new(
                            if i & 1 == 0 { b.min.x } else { b.max.x },
                            if i & 2 == 0 { b.min.y } else { b.max.y },
                            if i & 4 == 0 { b.min.z } else { b.max.z },
                        )
                    })
                    .collect()
            };
            let all = exact.then_some(a.positions.iter().map(move |p| o.transform.point(*p)));
            all.into_iter().flatten().chain(corners)
        })
    };
    let (center, radius) = studio::bounding_sphere(points);
    let lowest = points().map(|p| p.y).fold(f32::INFINITY, f32::min);
    (center, radius, if lowest.is_finite() { lowest } else { center.y - radius })
}
