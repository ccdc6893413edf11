//! Reads the CENG795 course scene format (either encoding, already turned into
//! an [`Element`] tree) into a [`Description`].
//!
//! Top-level elements read here:
//!
//! | element | meaning | default |
//! |---|---|---|
//! | `MaxRecursionDepth` | reflection/refraction bounces, at most [`MAX_RECURSION_DEPTH`] | 6 |
//! | `BackgroundColor` | RGB of rays that miss | 0 0 0 |
//! | `ShadowRayEpsilon` | offset of secondary ray origins; `auto`: 32 units in the last place of the hit's coordinates (`Scene::offset`) | 1e-3 (the course's images depend on it) |
//! | `IntersectionTestEpsilon` | intersection tolerance | 1e-6 |
//! | `Cameras/Camera` | see [`camera`] | required |
//! | `Lights` (ambient, point, area, directional, spot, environment) | see [`lights`] | none |
//! | `BRDFs` | reflection models materials name, see [`brdf`] | none |
//! | `Materials/Material` | see [`material`] | |
//! | `Transformations`, `VertexData`, `Objects` | see [`objects`] (and [`obj_file`] for OBJ meshes) | |
//! | `Textures`, `TexCoordData` | see [`textures`] | none |
//! | `Volumes` | media and hypertextures (a luster extension), see [`volumes`] | none |
//! | `Media` | homogeneous media filling objects named by their `Interior` (a luster extension), see [`media`] | none |
//! | `Display` | the display transform of the 8-bit images: `course`, `srgb`, `aces` or `filmic` (a luster extension, see `luster_core::tonemap::display` and docs/hdr.md) | course |
//!
//! Anything else gets a warning naming it, so a scene that relies on a feature
//! luster lacks says so instead of rendering silently wrong.

pub mod attributes;
pub mod brdf;
pub mod camera;
pub mod gltf_file;
pub mod lights;
pub mod material;
pub mod media;
pub mod obj_file;
pub mod objects;
pub mod shader_map;
pub mod textures;
pub mod tonemap;
pub mod transforms;
pub mod volumes;

use super::description::Description;
use super::element::{Element, Reader};
use super::error::{SceneError, Warning};
use luster_core::math::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Deepest recursion accepted. The integrator recurses once per bounce, so a
/// depth in the thousands overflows a worker's stack between two mirrors; the
/// course's scenes use at most 6.
pub const MAX_RECURSION_DEPTH: u32 = 100;

/// Collects warnings while reading.
#[derive(Default)]
pub struct Warnings(pub Vec<Warning>);

impl Warnings {
    /// Records a warning at `el`.
    pub fn at(&mut self, el: &Element, msg: impl Into<String>) {
        self.0.push(Warning { loc: el.loc.clone(), message: msg.into() });
    }

    /// Warns about every child of `el` whose name is not in `known`.
    pub fn unknown_children(&mut self, el: &Element, known: &[&str]) {
        for c in &el.children {
            if !known.contains(&c.name.as_str()) {
                self.at(c, format!("<{}> inside <{}> is not supported yet; ignored", c.name, el.name));
            }
        }
    }
}

/// Builds a description from the root element of a scene file.
pub fn read(file: &Path, root: &Element) -> Result<Description, SceneError> {
    let r = Reader { file };
    if root.name != "Scene" {
        return Err(r.err(root, format!("the root element must be <Scene>, found <{}>", root.name)));
    }
    let mut w = Warnings::default();
    w.unknown_children(
        root,
        &[
            "MaxRecursionDepth",
            "BackgroundColor",
            "ShadowRayEpsilon",
            "IntersectionTestEpsilon",
            "Cameras",
            "Lights",
            "BRDFs",
            "Materials",
            "Transformations",
            "VertexData",
            "TexCoordData",
            "Textures",
            "Objects",
            "Volumes",
            "Media",
            "ShaderLibrary",
            "Display",
        ],
    );
    let display = display(&r, root)?;
    let max_recursion_depth = max_recursion_depth(&r, root)?;
    let (shadow_ray_epsilon, intersection_test_epsilon) = epsilons(&r, root)?;

    let mut cameras = match root.child("Cameras") {
        Some(c) => camera::read_all(&r, c, &mut w)?,
        None => Vec::new(),
    };
    if cameras.is_empty() {
        return Err(r.err(root, "the scene has no <Camera>, so there is no image to render"));
    }
    let brdfs = match root.child("BRDFs") {
        Some(b) => brdf::read_all(&r, b, &mut w)?,
        None => HashMap::new(),
    };
    let mut materials = match root.child("Materials") {
        Some(m) => material::read_all(&r, m, &brdfs, &mut w)?,
        None => Vec::new(),
    };
    let material_ids: HashMap<&str, usize> =
        materials.iter().enumerate().rev().map(|(i, m)| (m.id.as_str(), i)).collect();
    let transforms = match root.child("Transformations") {
        Some(t) => transforms::read_all(&r, t, &mut w)?,
        None => HashMap::new(),
    };
    if let Some(c) = root.child("Cameras") {
        camera::transform_all(&r, c, &mut cameras, &transforms)?;
    }
    let vertices = match root.child("VertexData") {
        Some(v) => objects::read_vertices(&r, v)?,
        None => Vec::new(),
    };
    let tex_coords = match root.child("TexCoordData") {
        Some(t) => textures::read_tex_coords(&r, t)?,
        None => Vec::new(),
    };
    let base_dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    let shader_libraries = shader_libraries(&r, root, &base_dir)?;
    let (mut images, mut texture_maps) = match root.child("Textures") {
        Some(t) => textures::read_all(&r, t, &base_dir, &mut w)?,
        None => (Vec::new(), Vec::new()),
    };
    // After the images: an environment light names one.
    let lights = match root.child("Lights") {
        Some(l) => lights::read_all(&r, l, &images, &mut w)?,
        None => lights::Lights::default(),
    };
    let texture_ids: HashMap<&str, usize> =
        texture_maps.iter().enumerate().rev().map(|(i, m)| (m.id.as_str(), i)).collect();
    let media = match root.child("Media") {
        Some(m) => media::read_all(&r, m, &mut w)?,
        None => Vec::new(),
    };
    let media_ids: HashMap<&str, usize> = media.iter().enumerate().map(|(i, m)| (m.id.as_str(), i)).collect();
    let ((objects, emitters, interiors), obj_additions) = match root.child("Objects") {
        Some(o) => {
            let ctx = objects::Context {
                r,
                materials: &material_ids,
                textures: &texture_ids,
                transforms: &transforms,
                vertices: &vertices,
                tex_coords: &tex_coords,
                base_dir: &base_dir,
                obj: std::cell::RefCell::new(obj_file::Pending::new(
                    materials.len(),
                    images.len(),
                    texture_maps.len(),
                )),
                media: &media_ids,
            };
            let objects = objects::read_all(&ctx, o, &mut w)?;
            (objects, ctx.obj.into_inner().add)
        }
        None => ((Vec::new(), Vec::new(), Vec::new()), Default::default()),
    };
    let volumes = match root.child("Volumes") {
        Some(v) => {
            let ctx = volumes::Context {
                r,
                materials: &material_ids,
                textures: &texture_ids,
                transforms: &transforms,
                base_dir: &base_dir,
            };
            volumes::read_all(&ctx, v, &mut w)?
        }
        None => Vec::new(),
    };
    // OBJ meshes' materials and maps, numbered after the scene's own.
    materials.extend(obj_additions.materials);
    images.extend(obj_additions.images);
    texture_maps.extend(obj_additions.texture_maps);
    Ok(Description {
        file: file.to_path_buf(),
        base_dir,
        shader_libraries,
        max_recursion_depth,
        background: r.vec3_or(root, "BackgroundColor", Vec3::ZERO)?,
        shadow_ray_epsilon,
        intersection_test_epsilon,
        cameras,
        ambient_light: lights.ambient,
        point_lights: lights.points,
        area_lights: lights.areas,
        directional_lights: lights.directionals,
        spot_lights: lights.spots,
        environment_light: lights.environment,
        studio: None,
        emitters,
        materials,
        vertices,
        tex_coords,
        background_texture: texture_maps
            .iter()
            .position(|m| m.decal == super::description::DecalMode::ReplaceBackground),
        images,
        texture_maps,
        objects,
        volumes,
        media,
        interiors,
        display,
        warnings: w.0,
    })
}

/// `<Display>`: the display transform of the 8-bit images (`course` when absent).
fn display(r: &Reader, root: &Element) -> Result<luster_core::tonemap::Display, SceneError> {
    Ok(match root.child("Display") {
        Some(el) => luster_core::tonemap::Display::parse(&el.text).ok_or_else(|| {
            r.err(
                el,
                format!(
                    "<Display> names a display transform luster does not know (expected {})",
                    luster_core::tonemap::Display::NAMES
                ),
            )
        })?,
        None => luster_core::tonemap::Display::Course,
    })
}

/// `<MaxRecursionDepth>` (6 when absent), within [`MAX_RECURSION_DEPTH`].
fn max_recursion_depth(r: &Reader, root: &Element) -> Result<u32, SceneError> {
    Ok(match root.child("MaxRecursionDepth") {
        Some(el) => {
            let d = r.uint(el)?;
            if d > MAX_RECURSION_DEPTH {
                return Err(r.err(
                    el,
                    format!("<MaxRecursionDepth> {d} is more than the {MAX_RECURSION_DEPTH} supported"),
                ));
            }
            d
        }
        None => 6,
    })
}

/// `<ShadowRayEpsilon>` (the course's 1e-3 when absent, `None` for `auto`)
/// and `<IntersectionTestEpsilon>`, neither negative.
fn epsilons(r: &Reader, root: &Element) -> Result<(Option<f32>, f32), SceneError> {
    let auto = root.child("ShadowRayEpsilon").is_some_and(|e| e.text.trim().eq_ignore_ascii_case("auto"));
    let shadow_ray_epsilon = if auto { 0.0 } else { r.float_or(root, "ShadowRayEpsilon", 1e-3)? };
    let intersection_test_epsilon = r.float_or(root, "IntersectionTestEpsilon", 1e-6)?;
    for (name, v) in
        [("ShadowRayEpsilon", shadow_ray_epsilon), ("IntersectionTestEpsilon", intersection_test_epsilon)]
    {
        if v < 0.0 {
            return Err(r.err(root.child(name).unwrap_or(root), format!("<{name}> must not be negative")));
        }
    }
    Ok(((!auto).then_some(shadow_ray_epsilon), intersection_test_epsilon))
}

/// `<ShaderLibrary>` folders, relative to the scene file's folder.
fn shader_libraries(r: &Reader, root: &Element, base_dir: &Path) -> Result<Vec<PathBuf>, SceneError> {
    let mut shader_libraries = Vec::new();
    for lib in root.children_named("ShaderLibrary") {
        let rel = lib.text.trim();
        if rel.is_empty() {
            return Err(r.err(lib, "<ShaderLibrary> names no folder"));
        }
        shader_libraries.push(base_dir.join(rel));
    }
    Ok(shader_libraries)
}
