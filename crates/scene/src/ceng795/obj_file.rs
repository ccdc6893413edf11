//! `<Mesh><Faces objFile="model.obj"/></Mesh>`: a mesh whose geometry is an
//! OBJ model (luster's extension, beside the course's `plyFile`).
//!
//! ```xml
//! <Mesh id="1">
//!     <Transformations>s1 t1</Transformations>
//!     <Faces objFile="models/cube.obj"/>          <!-- relative to the scene file -->
//! </Mesh>
//! ```
//!
//! In JSON: `"Faces": {"_objFile": "models/cube.obj"}`.
//!
//! | the Mesh has | objects made |
//! |---|---|
//! | a `<Material>` | one: the whole model with that material (its MTL files are still read and checked) |
//! | no `<Material>` | one per material the OBJ uses, each with its MTL material and maps, in the scene's lists after the scene's own |
//!
//! `Transformations`, `MotionBlur` and `Textures` apply to every object the
//! mesh makes (its `Textures` after the MTL's maps). `shadingMode` chooses
//! the normals: `smooth` the file's `vn` (or, without them, area-weighted
//! vertex normals), `flat` the faces' own; without the attribute, the file's
//! normals when it has them, else flat. A `MeshInstance` may instance an OBJ
//! mesh with one material; one with several makes several objects, which an
//! instance cannot name, so it is refused with a message saying so.

use super::objects::{material, textures, transform, Context};
use super::Warnings;
use crate::description::{MeshSource, ObjectDesc, Shape};
use crate::element::Element;
use crate::error::{Loc, SceneError};
use crate::obj::{self, Additions};
use luster_core::math::Vec3;
use std::sync::Arc;

/// What OBJ meshes add while the objects are read.
#[derive(Debug, Default)]
pub struct Pending {
    /// Their materials, images and maps.
    pub add: Additions,
    /// Object index of the first object of each mesh that made several.
    pub multi: Vec<usize>,
}

impl Pending {
    /// Nothing yet, for a scene with this many materials, images and maps.
    pub fn new(materials: usize, images: usize, texture_maps: usize) -> Pending {
        Pending { add: Additions::new(materials, images, texture_maps), multi: Vec::new() }
    }
}

/// Whether a `Mesh` takes its faces from an OBJ file.
pub fn is_obj_mesh(el: &Element) -> bool {
    el.child("Faces").is_some_and(|f| f.attr("objFile").is_some())
}

/// Reads an OBJ mesh, pushing its object or objects onto `out`.
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
            super::attributes::CHILD,
        ],
    );
    let attributes = super::attributes::read(r, el)?;
    let (faces, rel) = file_faces(ctx, el, w, "an objFile")?;
    let model = obj::load(&ctx.base_dir.join(rel)).map_err(|e| r.err(faces, e.to_string()))?;
    for warning in &model.warnings {
        w.at(faces, format!("{rel}: {warning}"));
    }
    let smooth = match el.attr("shadingMode").map(str::trim) {
        None | Some("") => model.has_normals(),
        Some("flat") => false,
        Some("smooth") => true,
        Some(other) => {
            return Err(r.err(el, format!("shadingMode \"{other}\" is unknown (expected smooth or flat)")))
        }
    };
    let id = el.attr("id").unwrap_or("").trim().to_string();
    let own_textures = textures(ctx, el)?.unwrap_or_default();
    let object = |shape, material, textures, loc| -> Result<ObjectDesc, SceneError> {
        Ok(ObjectDesc {
            id: id.clone(),
            shape,
            material,
            transform: transform(ctx, el)?,
            motion: r.vec3_or(el, "MotionBlur", Vec3::ZERO)?,
            textures,
            loc,
            attributes: Vec::new(),
            geometry_attributes: attributes.clone(),
        })
    };
    if let Some(m) = el.child("Material") {
        let shape = Shape::Mesh { source: MeshSource::Arrays(Arc::new(model.merged())), smooth };
        out.push(object(shape, material(ctx, m)?, own_textures, el.loc.clone())?);
        return Ok(());
    }
    let mut pending = ctx.obj.borrow_mut();
    if model.parts.len() > 1 {
        pending.multi.push(out.len());
    }
    for part in &model.parts {
        let (mat, mut maps) = pending.add.add_part(part);
        maps.extend_from_slice(&own_textures);
        let loc = match model.parts.len() {
            1 => el.loc.clone(),
            _ => Loc { line: el.loc.line, path: format!("{} (material {})", el.loc.path, part.name) },
        };
        let shape = Shape::Mesh { source: MeshSource::Arrays(part.arrays.clone()), smooth };
        out.push(object(shape, mat, maps, loc)?);
    }
    Ok(())
}

/// The `<Faces>` of a mesh whose faces come from a file, and the file's
/// path as written: `attr` names the attribute with its article (`an
/// objFile`, `a gltfFile`). Other attributes and inline indices are warned
/// about; an empty path is an error.
pub fn file_faces<'e>(
    ctx: &Context,
    el: &'e Element,
    w: &mut Warnings,
    attr: &str,
) -> Result<(&'e Element, &'e str), SceneError> {
    let r = &ctx.r;
    let name = attr.rsplit(' ').next().unwrap_or(attr);
    let faces = r.required(el, "Faces")?;
    for (k, _) in &faces.attrs {
        if k != name {
            w.at(faces, format!("<Faces> attribute {k} does not apply to {attr}; ignored"));
        }
    }
    if !faces.text.trim().is_empty() {
        w.at(
            faces,
            format!("<Faces> with {attr} takes its faces from the file; the indices given are ignored"),
        );
    }
    let rel = faces.attr(name).unwrap_or("").trim();
    if rel.is_empty() {
        return Err(r.err(faces, format!("<Faces> has an empty {name} attribute")));
    }
    Ok((faces, rel))
}
