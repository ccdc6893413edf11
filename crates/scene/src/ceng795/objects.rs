//! `VertexData` and `Objects`.
//!
//! | object | reads |
//! |---|---|
//! | `Mesh` | `Material`, `Transformations`, `Faces` (inline 1-based vertex indices, `plyFile="..."`, `objFile="..."` (see [`super::obj_file`]) or `gltfFile="..."` (see [`super::gltf_file`])), `shadingMode="smooth"` |
//! | `Triangle` | `Material`, `Transformations`, `Indices` (three vertex indices) |
//! | `Sphere` | `Material`, `Transformations`, `Center` (a vertex index), `Radius` |
//! | `Ellipsoid` | `Material`, `Transformations`, `Center` (a vertex index), `Radii` (three positive numbers), `Rotation` (optional: angle in degrees, counter-clockwise, and axis x y z) |
//! | `Plane` | `Material`, `Transformations`, `Point` (a vertex index), `Normal` |
//! | `MeshInstance` | `baseMeshId`, `resetTransform`, `Material`, `Transformations` |
//! | `LightMesh` | as `Mesh`, plus `Radiance` (RGB, not negative): an emitter (hw7) |
//! | `LightSphere` | as `Sphere`, plus `Radiance`: an emitter (hw7) |
//!
//! Every object may carry user data for shaders in `Attribute` children
//! (see [`super::attributes`]).
//!
//! Every object may list texture maps in `Textures` (hw4). Texture
//! coordinates come from `TexCoordData`, numbered like `VertexData`: vertex
//! `i` has coordinate `i`. A `Faces` element may shift both numberings
//! (`vertexOffset`, `textureOffset`: the numbers in the list are 0-based and
//! the offset is added to each). An instance without `Textures` uses its
//! base's, as it does its material.
//!
//! Every object but a plane may have a `MotionBlur` translation (x y z): it
//! moves by that much, after its transform, over the shutter interval.
//!
//! `Ellipsoid` is luster's extension of the format (the course makes
//! ellipsoids as scaled spheres): the unit sphere scaled by `Radii` along its
//! own axes, turned by `Rotation` (the convention of the `Rotation`
//! transform), then moved to `Center`, all before its `Transformations`.
//!
//! A `MeshInstance` may instance another instance. Its transform is its own
//! list applied after the base's full transform, or alone when
//! `resetTransform="true"` (hw2 spec, eq. 3). Degenerate inline triangles (two
//! equal indices) are dropped with a warning, as the course's specs advise.

use super::attributes::{self, merged};
use super::gltf_file;
use super::obj_file::{self, Pending};
use super::textures::object_textures;
use super::transforms::compose;
use super::Warnings;
use crate::description::{AttributeList, EmitterDesc, InteriorDesc, MeshSource, ObjectDesc, Shape};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::{Quat, Transform, Vec2, Vec3};
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::Path;

/// What object reading needs from the rest of the file.
pub struct Context<'a> {
    /// Typed reading with errors naming the file.
    pub r: Reader<'a>,
    /// Material id to index.
    pub materials: &'a HashMap<&'a str, usize>,
    /// Texture map id to index.
    pub textures: &'a HashMap<&'a str, usize>,
    /// Named transforms.
    pub transforms: &'a HashMap<String, Transform>,
    /// Shared vertices.
    pub vertices: &'a [Vec3],
    /// Shared texture coordinates.
    pub tex_coords: &'a [Vec2],
    /// Folder of the scene file.
    pub base_dir: &'a Path,
    /// What OBJ meshes add to the scene's lists.
    pub obj: RefCell<Pending>,
    /// Medium id to index (`<Media>`), for `<Interior>`.
    pub media: &'a HashMap<&'a str, usize>,
}

/// Reads `VertexData`: a multiple of three numbers.
pub fn read_vertices(r: &Reader, el: &Element) -> Result<Vec<Vec3>, SceneError> {
    let f = r.floats(el)?;
    if f.len() % 3 != 0 {
        return Err(r.err(el, format!("<VertexData> has {} numbers, which is not a multiple of 3", f.len())));
    }
    Ok(f.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect())
}

/// An instance before its base is resolved.
struct PendingInstance {
    index: usize,
    base_id: String,
    reset: bool,
    material: Option<usize>,
    textures: Option<Vec<usize>>,
    own: Transform,
}

/// Every object, the emitters among them and the interiors they name.
pub type Objects = (Vec<ObjectDesc>, Vec<EmitterDesc>, Vec<InteriorDesc>);

/// Reads every object, resolving instances, the emitters among them and
/// the media that fill them.
pub fn read_all(ctx: &Context, objs: &Element, w: &mut Warnings) -> Result<Objects, SceneError> {
    w.unknown_children(
        objs,
        &["Mesh", "Triangle", "Sphere", "Ellipsoid", "Plane", "MeshInstance", "LightMesh", "LightSphere"],
    );
    let r = &ctx.r;
    let mut out: Vec<ObjectDesc> = Vec::new();
    let mut emitters = Vec::new();
    let mut interiors = Vec::new();
    let mut pending = Vec::new();
    let mut mesh_ids: HashMap<String, usize> = HashMap::new();
    for el in &objs.children {
        let first = out.len();
        // The medium inside, for every object the element makes.
        let interior = |out: &Vec<ObjectDesc>, interiors: &mut Vec<InteriorDesc>| -> Result<(), SceneError> {
            if let Some(i) = el.child("Interior") {
                let id = i.text.trim();
                let medium = *ctx
                    .media
                    .get(id)
                    .ok_or_else(|| r.err(i, format!("medium \"{id}\" is not defined in <Media>")))?;
                interiors.extend((first..out.len()).map(|object| InteriorDesc { object, medium }));
            }
            Ok(())
        };
        if el.name == "Mesh" && (obj_file::is_obj_mesh(el) || gltf_file::is_gltf_mesh(el)) {
            if gltf_file::is_gltf_mesh(el) {
                gltf_file::read(ctx, el, w, &mut out)?;
            } else {
                obj_file::read(ctx, el, w, &mut out)?;
            }
            interior(&out, &mut interiors)?;
            register(&mut mesh_ids, el.attr("id").unwrap_or("").trim(), first, el, w);
            continue;
        }
        let shape = match el.name.as_str() {
            "Mesh" | "LightMesh" => mesh(ctx, el, w)?,
            "Triangle" => {
                w.unknown_children(
                    el,
                    &["Material", "Transformations", "Indices", "MotionBlur", "Textures", attributes::CHILD],
                );
                let ix = r.uints(r.required(el, "Indices")?)?;
                if ix.len() != 3 {
                    return Err(r.err(el, format!("<Indices> needs 3 vertex indices, found {}", ix.len())));
                }
                let idx = r.required(el, "Indices")?;
                let uv = |i: u32| ctx.tex_coords.get((i as usize).wrapping_sub(1)).copied();
                let uvs = match (uv(ix[0]), uv(ix[1]), uv(ix[2])) {
                    (Some(a), Some(b), Some(c)) => Some([a, b, c]),
                    _ => None,
                };
                Shape::Triangle {
                    vertices: [vertex(ctx, idx, ix[0])?, vertex(ctx, idx, ix[1])?, vertex(ctx, idx, ix[2])?],
                    uvs,
                }
            }
            "Sphere" | "LightSphere" => {
                let known = [
                    "Material",
                    "Transformations",
                    "Center",
                    "Radius",
                    "MotionBlur",
                    "Textures",
                    "Interior",
                    attributes::CHILD,
                ];
                w.unknown_children(el, &emitter_children(el, &known));
                let c = r.required(el, "Center")?;
                let center = vertex(ctx, c, r.uint(c)?)?;
                let re = r.required(el, "Radius")?;
                let radius = r.float(re)?;
                if radius <= 0.0 {
                    return Err(r.err(re, format!("<Radius> must be positive, found {radius}")));
                }
                Shape::Sphere { center, radius }
            }
            "Ellipsoid" => ellipsoid(ctx, el, w)?,
            "Plane" => {
                w.unknown_children(
                    el,
                    &["Material", "Transformations", "Point", "Normal", "Textures", attributes::CHILD],
                );
                let p = r.required(el, "Point")?;
                let point = vertex(ctx, p, r.uint(p)?)?;
                let ne = r.required(el, "Normal")?;
                let normal = r.vec3(ne)?;
                if normal.length_squared() == 0.0 {
                    return Err(r.err(ne, "the plane's <Normal> is zero"));
                }
                Shape::Plane { point, normal: normal.normalize() }
            }
            "MeshInstance" => {
                w.unknown_children(
                    el,
                    &["Material", "Transformations", "MotionBlur", "Textures", "Interior", attributes::CHILD],
                );
                let base_id = el
                    .attr("baseMeshId")
                    .map(str::trim)
                    .filter(|s| !s.is_empty())
                    .ok_or_else(|| r.err(el, "<MeshInstance> has no baseMeshId"))?;
                let material = el.child("Material").map(|m| material(ctx, m)).transpose()?;
                pending.push(PendingInstance {
                    index: out.len(),
                    base_id: base_id.to_string(),
                    reset: r.bool_attr(el, "resetTransform", false)?,
                    material,
                    textures: textures(ctx, el)?,
                    own: transform(ctx, el)?,
                });
                let id = el.attr("id").unwrap_or("").trim().to_string();
                register(&mut mesh_ids, &id, out.len(), el, w);
                out.push(ObjectDesc {
                    id,
                    shape: Shape::Instance { mesh: usize::MAX },
                    material: usize::MAX,
                    transform: Transform::IDENTITY,
                    motion: ctx.r.vec3_or(el, "MotionBlur", Vec3::ZERO)?,
                    textures: Vec::new(),
                    loc: el.loc.clone(),
                    attributes: attributes::read(r, el)?,
                    geometry_attributes: Vec::new(),
                });
                interior(&out, &mut interiors)?;
                continue;
            }
            _ => continue,
        };
        let id = el.attr("id").unwrap_or("").trim().to_string();
        if el.name == "Mesh" {
            register(&mut mesh_ids, &id, out.len(), el, w);
        }
        if el.name.starts_with("Light") {
            emitters.push(EmitterDesc { object: out.len(), radiance: radiance(r, el)?, loc: el.loc.clone() });
        }
        out.push(ObjectDesc {
            id,
            shape,
            material: material(ctx, r.required(el, "Material")?)?,
            transform: transform(ctx, el)?,
            motion: if el.name == "Plane" { Vec3::ZERO } else { r.vec3_or(el, "MotionBlur", Vec3::ZERO)? },
            textures: textures(ctx, el)?.unwrap_or_default(),
            loc: el.loc.clone(),
            attributes: Vec::new(),
            geometry_attributes: attributes::read(r, el)?,
        });
        interior(&out, &mut interiors)?;
    }
    resolve_instances(ctx, &mut out, &pending, &mesh_ids, objs)?;
    Ok((out, emitters, interiors))
}

/// The children an object may have: `known`, plus `Radiance` for an emitter.
fn emitter_children<'a>(el: &Element, known: &[&'a str]) -> Vec<&'a str> {
    let mut k = known.to_vec();
    if el.name.starts_with("Light") {
        k.push("Radiance");
    }
    k
}

/// An emitter's `Radiance`: required, three finite numbers, none negative.
fn radiance(r: &Reader, el: &Element) -> Result<Vec3, SceneError> {
    let re = r.required(el, "Radiance")?;
    let v = r.vec3(re)?;
    if v.min_element() < 0.0 || !v.is_finite() {
        return Err(r.err(re, "<Radiance> must be finite and not negative (negative light does not exist)"));
    }
    Ok(v)
}

fn register(ids: &mut HashMap<String, usize>, id: &str, index: usize, el: &Element, w: &mut Warnings) {
    if ids.contains_key(id) {
        w.at(el, format!("mesh id {id} is used twice; instances refer to the first"));
    } else {
        ids.insert(id.to_string(), index);
    }
}

fn mesh(ctx: &Context, el: &Element, w: &mut Warnings) -> Result<Shape, SceneError> {
    let r = &ctx.r;
    let known =
        ["Material", "Transformations", "Faces", "MotionBlur", "Textures", "Interior", attributes::CHILD];
    w.unknown_children(el, &emitter_children(el, &known));
    let smooth = match el.attr("shadingMode").map(str::trim) {
        None | Some("") | Some("flat") => false,
        Some("smooth") => true,
        Some(other) => {
            return Err(r.err(el, format!("shadingMode \"{other}\" is unknown (expected smooth or flat)")))
        }
    };
    let faces = r.required(el, "Faces")?;
    for (k, _) in &faces.attrs {
        if !matches!(k.as_str(), "plyFile" | "type" | "vertexOffset" | "textureOffset") {
            w.at(faces, format!("<Faces> attribute {k} is not supported yet; ignored"));
        }
    }
    if let Some(ply) = faces.attr("plyFile") {
        if ply.trim().is_empty() {
            return Err(r.err(faces, "<Faces> has an empty plyFile attribute"));
        }
        let path = ctx.base_dir.join(ply.trim());
        return Ok(Shape::Mesh { source: MeshSource::Ply(path), smooth });
    }
    let offset =
        |name: &str| -> Result<i64, SceneError> {
            match faces.attr(name).map(str::trim) {
                None => Ok(0),
                Some(v) => v.parse::<i64>().ok().filter(|o| o.abs() <= u32::MAX as i64).ok_or_else(|| {
                    r.err(faces, format!("<Faces> attribute {name}=\"{v}\" is not an integer"))
                }),
            }
        };
    let (vertex_offset, texture_offset) = (offset("vertexOffset")?, offset("textureOffset")?);
    let ix = r.uints(faces)?;
    if ix.len() % 3 != 0 {
        return Err(r.err(faces, format!("<Faces> has {} indices, which is not a multiple of 3", ix.len())));
    }
    let n = ctx.vertices.len();
    let mut tris = Vec::with_capacity(ix.len() / 3);
    let mut degenerate = 0;
    for ix_chunk in ix.chunks_exact(3) {
        let mut c = [0u32; 3];
        for (k, &raw) in ix_chunk.iter().enumerate() {
            let i = raw as i64 + vertex_offset;
            if i <= 0 || i > n as i64 {
                return Err(r.err(
                    faces,
                    format!(
                        "face index {raw}{} is out of range (VertexData has {n} vertices, numbered from 1)",
                        if vertex_offset != 0 {
                            format!(" + vertexOffset {vertex_offset}")
                        } else {
                            String::new()
                        }
                    ),
                ));
            }
            c[k] = i as u32;
        }
        if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
            degenerate += 1;
            continue;
        }
        tris.push([c[0] - 1, c[1] - 1, c[2] - 1]);
    }
    if degenerate > 0 {
        w.at(faces, format!("{degenerate} degenerate triangle(s) skipped"));
    }
    Ok(Shape::Mesh {
        source: MeshSource::Inline { triangles: tris, tex_shift: texture_offset - vertex_offset },
        smooth,
    })
}

/// Reads an `<Ellipsoid>`: its centre (a vertex index), three positive radii
/// and an optional rotation of its axes.
fn ellipsoid(ctx: &Context, el: &Element, w: &mut Warnings) -> Result<Shape, SceneError> {
    let r = &ctx.r;
    w.unknown_children(
        el,
        &[
            "Material",
            "Transformations",
            "Center",
            "Radii",
            "Rotation",
            "MotionBlur",
            "Textures",
            "Interior",
            attributes::CHILD,
        ],
    );
    let c = r.required(el, "Center")?;
    let center = vertex(ctx, c, r.uint(c)?)?;
    let (radii, rotation) = radii_and_rotation(r, el)?;
    Ok(Shape::Ellipsoid { center, radii, rotation })
}

/// An ellipsoid's `Radii` (three positive numbers) and optional `Rotation`
/// (degrees about an axis, as the `Rotation` transform), for objects and
/// for volume bounds alike.
pub fn radii_and_rotation(r: &Reader, el: &Element) -> Result<(Vec3, Quat), SceneError> {
    let re = r.required(el, "Radii")?;
    let radii = r.vec3(re)?;
    // A subnormal radius passes `> 0` but its reciprocal, which intersection
    // divides by, is infinite.
    if radii.min_element() <= 0.0 || !radii.recip().is_finite() {
        return Err(r.err(
            re,
            format!("<Radii> must be three positive numbers, found {} {} {}", radii.x, radii.y, radii.z),
        ));
    }
    let rotation = match el.child("Rotation") {
        None => Quat::IDENTITY,
        Some(ro) => {
            let v = r.floats_n(ro, 4)?;
            let axis = Vec3::new(v[1], v[2], v[3]);
            let largest = axis.abs().max_element();
            if largest == 0.0 {
                return Err(r.err(ro, "<Rotation> has a zero axis"));
            }
            // `Transform::rotation`'s convention: counter-clockwise degrees
            // about the normalized axis, right-handed. Dividing by the largest
            // component first keeps |axis|² from overflowing.
            Quat::from_axis_angle((axis / largest).normalize(), v[0].to_radians())
        }
    };
    Ok((radii, rotation))
}

fn vertex(ctx: &Context, el: &Element, i: u32) -> Result<Vec3, SceneError> {
    let n = ctx.vertices.len();
    if i == 0 || i as usize > n {
        return Err(ctx.r.err(
            el,
            format!("vertex index {i} is out of range (VertexData has {n} vertices, numbered from 1)"),
        ));
    }
    Ok(ctx.vertices[i as usize - 1])
}

pub(super) fn material(ctx: &Context, el: &Element) -> Result<usize, SceneError> {
    let id = el.text.trim();
    ctx.materials
        .get(id)
        .copied()
        .ok_or_else(|| ctx.r.err(el, format!("material \"{id}\" is not defined in <Materials>")))
}

pub(super) fn textures(ctx: &Context, el: &Element) -> Result<Option<Vec<usize>>, SceneError> {
    el.child("Textures").map(|t| object_textures(&ctx.r, t, ctx.textures)).transpose()
}

pub(super) fn transform(ctx: &Context, el: &Element) -> Result<Transform, SceneError> {
    match el.child("Transformations") {
        Some(t) => compose(&ctx.r, t, ctx.transforms),
        None => Ok(Transform::IDENTITY),
    }
}

/// Resolves each instance to the mesh whose triangles it uses and its full
/// transform, following chains of instances and refusing cycles.
fn resolve_instances(
    ctx: &Context,
    out: &mut [ObjectDesc],
    pending: &[PendingInstance],
    mesh_ids: &HashMap<String, usize>,
    objs: &Element,
) -> Result<(), SceneError> {
    let r = &ctx.r;
    let by_index: HashMap<usize, &PendingInstance> = pending.iter().map(|p| (p.index, p)).collect();
    type Resolved = (usize, Transform, usize, Vec<usize>, AttributeList);
    let mut done: HashMap<usize, Resolved> = HashMap::new();
    for p in pending {
        // Walk down the chain, then compose on the way back up.
        let mut chain = vec![p.index];
        let (mesh, mut t, mut mat, mut tex, mut attrs) = loop {
            let cur = *chain.last().unwrap_or(&p.index);
            let inst = by_index[&cur];
            let base = *mesh_ids.get(&inst.base_id).ok_or_else(|| {
                r.err(
                    &loc_el(objs, &out[cur]),
                    format!("baseMeshId \"{}\" names no Mesh or MeshInstance", inst.base_id),
                )
            })?;
            if let Some((m, t, mat, tex, attrs)) = done.get(&base) {
                break (*m, *t, *mat, tex.clone(), attrs.clone());
            }
            if !by_index.contains_key(&base) {
                if ctx.obj.borrow().multi.contains(&base) {
                    return Err(r.err(
                        &loc_el(objs, &out[p.index]),
                        format!(
                            "baseMeshId \"{}\" is an OBJ or glTF mesh with several materials (or glTF \
                             primitives), which makes several objects; an instance needs one (give that \
                             Mesh a <Material>)",
                            inst.base_id
                        ),
                    ));
                }
                // A mesh's attributes are its geometry's, which shaders
                // reach through the instance's object id.
                break (
                    base,
                    out[base].transform,
                    out[base].material,
                    out[base].textures.clone(),
                    Vec::new(),
                );
            }
            if chain.contains(&base) {
                return Err(r.err(
                    &loc_el(objs, &out[p.index]),
                    format!("MeshInstance {} is part of a cycle of instances", out[p.index].id),
                ));
            }
            chain.push(base);
        };
        for &i in chain.iter().rev() {
            let inst = by_index[&i];
            t = if inst.reset { inst.own } else { t.then(&inst.own) };
            mat = inst.material.unwrap_or(mat);
            if let Some(own) = &inst.textures {
                tex = own.clone();
            }
            attrs = merged(&out[i].attributes, &attrs);
            done.insert(i, (mesh, t, mat, tex.clone(), attrs.clone()));
        }
    }
    for (i, (mesh, t, mat, tex, attrs)) in done {
        out[i].shape = Shape::Instance { mesh };
        out[i].transform = t;
        out[i].material = mat;
        out[i].textures = tex;
        out[i].attributes = attrs;
    }
    Ok(())
}

/// An element standing in for an object, so errors carry its location.
fn loc_el(objs: &Element, o: &ObjectDesc) -> Element {
    Element { name: objs.name.clone(), loc: o.loc.clone(), ..Default::default() }
}
