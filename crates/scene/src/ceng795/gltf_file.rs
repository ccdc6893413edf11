//! `<Mesh><Faces gltfFile="model.glb"/></Mesh>`: a mesh whose geometry is a
//! glTF file's (luster's extension, beside `plyFile` and `objFile`).
//!
//! ```xml
//! <Mesh id="1">
//!     <Transformations>s1 t1</Transformations>
//!     <Faces gltfFile="models/car.glb"/>                          <!-- relative to the scene file -->
//!     <MaterialShader name="Body">shaders/car_paint.lua</MaterialShader>  <!-- optional, repeatable -->
//! </Mesh>
//! ```
//!
//! In JSON: `"Faces": {"_gltfFile": "models/car.glb"}`.
//!
//! The glTF's drawn nodes become objects, one per primitive, each placed by
//! its node's transform and then the Mesh's `Transformations` (a mesh drawn
//! by several nodes is instanced, not copied). With a `<Material>` every
//! object takes it; without one, each keeps its glTF material (mapped as
//! `luster render` maps it, added after the scene's own materials), and a
//! `<MaterialShader name="...">` child replaces the glTF material of that
//! name by a Lua material shader (relative to the scene file).
//! `MotionBlur` and `Textures` apply to every object (the Mesh's `Textures`
//! after the glTF's maps), and so do `Attribute`s (above the file's mesh
//! `extras`, below its node `extras`: see [`super::attributes`]). The glTF's cameras and lights are not used (the
//! scene has its own); a warning says so. A `MeshInstance` may instance a
//! glTF mesh that makes one object; one that makes several is refused.

use super::objects::{material, textures, transform, Context};
use super::Warnings;
use crate::description::{ObjectDesc, Shape};
use crate::element::Element;
use crate::error::{Loc, SceneError};
use crate::gltf::material::{read_materials, MaterialOverride};
use luster_core::math::Vec3;
use std::collections::HashMap;

/// Whether a `Mesh` takes its faces from a glTF file.
pub fn is_gltf_mesh(el: &Element) -> bool {
    el.child("Faces").is_some_and(|f| f.attr("gltfFile").is_some())
}

/// Reads a glTF mesh, pushing its objects onto `out`.
pub fn read(
    ctx: &Context,
    el: &Element,
    w: &mut Warnings,
    out: &mut Vec<ObjectDesc>,
) -> Result<(), SceneError> {
    let r = &ctx.r;
    w.unknown_children(
        el,
        &[
            "Material",
            "Transformations",
            "Faces",
            "MotionBlur",
            "Textures",
            "Interior",
            "MaterialShader",
            super::attributes::CHILD,
        ],
    );
    let attributes = super::attributes::read(r, el)?;
    let (faces, rel) = super::obj_file::file_faces(ctx, el, w, "a gltfFile")?;
    let path = ctx.base_dir.join(rel);
    let model = crate::gltf::read(&path).map_err(|e| r.err(faces, e.to_string()))?;
    for warning in &model.notes.warnings {
        w.at(faces, format!("{rel}: {warning}"));
    }
    let nodes: Vec<gltf::Node> = model.file.doc.nodes().collect();
    if model.placed.iter().any(|p| nodes[p.node].camera().is_some() || nodes[p.node].light().is_some()) {
        w.at(faces, format!("{rel}: the file's cameras and lights are not used in a CENG795 scene"));
    }
    let mut overrides = Vec::new();
    for ms in el.children.iter().filter(|c| c.name == "MaterialShader") {
        let name = ms.attr("name").map(str::trim).filter(|n| !n.is_empty());
        let name =
            name.ok_or_else(|| r.err(ms, "<MaterialShader> needs a name attribute (the glTF material's)"))?;
        let script = ms.text.trim();
        if script.is_empty() {
            return Err(r.err(ms, "<MaterialShader> names no shader script"));
        }
        overrides.push(MaterialOverride { name: name.to_string(), script: ctx.base_dir.join(script) });
    }
    let after = transform(ctx, el)?;
    let motion = r.vec3_or(el, "MotionBlur", Vec3::ZERO)?;
    let own_textures = textures(ctx, el)?.unwrap_or_default();
    let first = out.len();
    let objects = if let Some(m) = el.child("Material") {
        if !overrides.is_empty() {
            w.at(el, "<MaterialShader> is not used: the Mesh's <Material> applies to the whole model");
        }
        let mat = material(ctx, m)?;
        model.objects(first, &after, |_| Ok((mat, own_textures.clone())))?
    } else {
        let mut warnings = Vec::new();
        let doc = &model.file.doc;
        let mats =
            read_materials(doc, &model.file.buffers, &model.file.base_dir, &path, &overrides, &mut warnings)
                .map_err(|e| r.err(faces, e.to_string()))?;
        for warning in &warnings {
            w.at(faces, format!("{rel}: {warning}"));
        }
        let default = crate::gltf::material::default_material(&path);
        let mut pending = ctx.obj.borrow_mut();
        let mut added: HashMap<Option<usize>, (usize, Vec<usize>)> = HashMap::new();
        model.objects(first, &after, |m| {
            let (mat, mut maps) = match added.get(&m) {
                Some(done) => done.clone(),
                None => {
                    let g = m.and_then(|i| mats.get(i)).unwrap_or(&default);
                    let done = pending.add.add_with_maps(&g.material, &g.maps);
                    g.add_images_to(&mut pending.add.images);
                    added.insert(m, done.clone());
                    done
                }
            };
            maps.extend_from_slice(&own_textures);
            Ok((mat, maps))
        })?
    };
    if objects.is_empty() {
        return Err(r.err(faces, format!("{rel}: the file draws no triangles")));
    }
    if objects.len() > 1 {
        ctx.obj.borrow_mut().multi.push(first);
    }
    let id = el.attr("id").unwrap_or("").trim().to_string();
    for mut o in objects {
        o.id = id.clone();
        o.motion = motion;
        o.loc = Loc { line: el.loc.line, path: format!("{} ({rel}: {})", el.loc.path, o.loc.path) };
        if !matches!(o.shape, Shape::Instance { .. }) {
            o.geometry_attributes = super::attributes::merged(&attributes, &o.geometry_attributes);
        }
        out.push(o);
    }
    Ok(())
}
