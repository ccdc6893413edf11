//! glTF materials (metallic-roughness and the KHR material extensions)
//! mapped onto luster's OpenPBR surface.
//!
//! Every glTF material becomes one `DecalMode material` shader map running
//! the built-in script `gltf_pbr.lua` (`material/pbr.lua`), which returns
//! `openpbr{...}` from the material's factors and textures (parameters
//! `material/params.rs` fills), preceded by a `replace_normal` image map when the
//! material has a normal texture. The mapping, its units and what is
//! approximated are in `docs/gltf-materials.md`. A [`MaterialOverride`]
//! replaces a material by a user's Lua material shader instead.
//!
//! The images the shader samples travel in [`GltfMaterial::images`]; the
//! scene they join must hold them ([`GltfMaterial::add_images_to`]), under
//! ids of the form `FILE#images[i]/ENCODING`.

mod images;

mod params;

use crate::ceng795::shader_map::read_script;
use crate::description::{DecalMode, ImageDesc, MaterialDesc, TextureMapDesc, TextureSource};
use crate::error::{Loc, SceneError, Warning};
use crate::obj::PartMap;
use luster_core::math::Vec3;
use luster_core::text::shown;
use luster_shading::shader::ParamValue;
use std::path::{Path, PathBuf};

/// The glTF extensions luster reads (the loader's geometry and lights, and
/// the materials here). Any other in `extensionsUsed` is a warning, in
/// `extensionsRequired` an error.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_unlit",
];

/// The built-in material shader's name, as its errors give it.
pub const PBR_SHADER: &str = "gltf_pbr.lua (built in)";

/// The built-in material shader's text.
pub const PBR_CODE: &str = include_str!("material/pbr.lua");

/// A glTF material as the description takes it: a material and the texture
/// maps (shader and image maps) that make it.
#[derive(Clone, Debug)]
pub struct GltfMaterial {
    /// The material's name in the file (`materials[i]` when it has none).
    pub name: String,
    /// The material (what a renderer without closures shows: the base colour).
    pub material: MaterialDesc,
    /// Its texture maps, in the order they apply.
    pub maps: Vec<PartMap>,
    /// The images its shader map samples by id (`texture()`), which the
    /// description must hold.
    pub images: Vec<ImageDesc>,
}

impl GltfMaterial {
    /// Adds the images the material's shader samples to `images` (a
    /// description's, or [`Additions::images`](crate::obj::Additions)),
    /// each id once.
    pub fn add_images_to(&self, images: &mut Vec<ImageDesc>) {
        for i in &self.images {
            if !images.iter().any(|j| j.id == i.id) {
                images.push(i.clone());
            }
        }
    }
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
/// Checks the file's extensions too: an unsupported one in `extensionsUsed`
/// is a warning, in `extensionsRequired` an error.
pub fn read_materials(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    base_dir: &Path,
    file: &Path,
    overrides: &[MaterialOverride],
    warnings: &mut Vec<Warning>,
) -> Result<Vec<GltfMaterial>, SceneError> {
    check_extensions(doc, file, warnings)?;
    let mut images = images::Images::new(doc, buffers, base_dir, file);
    let mut used = vec![false; overrides.len()];
    let mut out = Vec::with_capacity(doc.materials().len());
    for (i, m) in doc.materials().enumerate() {
        let at = format!("materials[{i}]");
        let name = m.name().map_or_else(|| at.clone(), str::to_string);
        let loc = Loc { line: None, path: at.clone() };
        let [r, g, b, _] = m.pbr_metallic_roughness().base_color_factor();
        let material = fallback(&name, Vec3::new(r, g, b), loc.clone());
        if let Some(k) = overrides.iter().position(|o| o.name == name) {
            used[k] = true;
            let map = override_map(&overrides[k], &name, file, &loc)?;
            out.push(GltfMaterial { name, material, maps: vec![map], images: Vec::new() });
            continue;
        }
        let mapped = params::map(&m, at, doc, &mut images, file, warnings)?;
        let mut maps: Vec<PartMap> = mapped.normal.into_iter().collect();
        maps.push(pbr_map(&name, mapped.params, loc));
        out.push(GltfMaterial { name, material, maps, images: mapped.images });
    }
    for (o, _) in overrides.iter().zip(&used).filter(|(_, u)| !**u) {
        let n = out.len();
        let names: Vec<String> = out.iter().take(8).map(|m| format!("'{}'", shown(&m.name, false))).collect();
        let more = if n > 8 { ", …" } else { "" };
        warnings.push(Warning {
            loc: Loc { line: None, path: "materials".to_string() },
            message: format!(
                "the material override '{}' matches none of the file's {n} material{} ({}{more}); it is not used",
                shown(&o.name, false),
                if n == 1 { "" } else { "s" },
                names.join(", ")
            ),
        });
    }
    Ok(out)
}

/// The material of primitives that name none: Blender's default surface,
/// a grey (0.8) dielectric of roughness 0.5, so that a file renders as
/// Blender imports it.
pub fn default_material(file: &Path) -> GltfMaterial {
    let _ = file;
    let loc = Loc { line: None, path: "(default material)".to_string() };
    let params = vec![
        ("base_color".to_string(), ParamValue::Vec3([0.8; 3])),
        ("metallic".to_string(), ParamValue::Number(0.0)),
        ("roughness".to_string(), ParamValue::Number(0.5)),
    ];
    let name = "(default)".to_string();
    GltfMaterial {
        material: fallback(&name, Vec3::splat(0.8), loc.clone()),
        maps: vec![pbr_map(&name, params, loc)],
        name,
        images: Vec::new(),
    }
}

/// Warns of each unsupported extension the file uses; fails on one it requires.
fn check_extensions(
    doc: &gltf::Document,
    file: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<(), SceneError> {
    let json = doc.as_json();
    if let Some((i, e)) =
        json.extensions_required.iter().enumerate().find(|(_, e)| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
    {
        return Err(SceneError::at(
            file,
            &Loc { line: None, path: format!("extensionsRequired[{i}]") },
            format!("the file requires extension {}, which luster does not support", shown(e, false)),
        ));
    }
    for (i, e) in json.extensions_used.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&e.as_str()) {
            warnings.push(Warning {
                loc: Loc { line: None, path: format!("extensionsUsed[{i}]") },
                message: format!("extension {} is not supported; what it adds is ignored", shown(e, false)),
            });
        }
    }
    Ok(())
}

/// The description's material under a glTF material's shader: its base
/// colour, for what reads the material itself (a renderer that does not
/// run shader maps).
fn fallback(name: &str, base: Vec3, loc: Loc) -> MaterialDesc {
    let base = base.clamp(Vec3::ZERO, Vec3::ONE);
    let mut m = crate::obj::mtl::default_material(loc);
    m.id = name.to_string();
    m.diffuse = base;
    m.ambient = base;
    m
}

/// The built-in shader's map with these parameters.
fn pbr_map(name: &str, params: Vec<(String, ParamValue)>, loc: Loc) -> PartMap {
    let source =
        TextureSource::Shader { path: PathBuf::from(PBR_SHADER), code: PBR_CODE.to_string(), params };
    let map = TextureMapDesc {
        id: format!("{name}/gltf_pbr"),
        source,
        decal: DecalMode::Material,
        bump_factor: 1.0,
        loc,
    };
    PartMap { map, image: None }
}

/// The map of a user's shader replacing material `name`.
fn override_map(o: &MaterialOverride, name: &str, file: &Path, loc: &Loc) -> Result<PartMap, SceneError> {
    let code = read_script(&o.script).map_err(|why| {
        SceneError::at(
            file,
            loc,
            format!(
                "the override of material '{}': cannot read shader script {}: {why}",
                shown(name, false),
                shown(&o.script.display().to_string(), false)
            ),
        )
    })?;
    let source = TextureSource::Shader { path: o.script.clone(), code, params: Vec::new() };
    let map = TextureMapDesc {
        id: format!("{name}/override"),
        source,
        decal: DecalMode::Material,
        bump_factor: 1.0,
        loc: loc.clone(),
    };
    Ok(PartMap { map, image: None })
}

#[cfg(test)]
mod tests;
