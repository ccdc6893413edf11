//! `Textures` (its `Images` and `TextureMap`s) and `TexCoordData` (hw4).
//!
//! | element | reads | default |
//! |---|---|---|
//! | `Images/Image id` | a path relative to the scene file | required |
//! | `degamma` attribute (`_degamma`) on an `Image` or an image `TextureMap` | the image's texels are display-encoded: each is raised to the power 2.2 (on the 0–1 scale for 8- and 16-bit images) | false |
//! | `TextureMap id type` | `type` is `image`, `perlin`, `checkerboard` or `shader` (luster's extension, see [`super::shader_map`]) | required |
//! | `DecalMode` | `replace_kd`, `blend_kd`, `replace_ks`, `replace_background`, `replace_normal`, `bump_normal`, `replace_all`, and luster's `replace_km` (mirror reflectance) | required |
//! | `ImageId` | (image) the `Image` read | required |
//! | `Interpolation` | (image) `nearest`, `bilinear` or `trilinear` | nearest (as the references show) |
//! | `Normalizer` | (image) texel values are divided by it | 255 (1 for EXR/HDR) |
//! | `BumpFactor` | (bump_normal) height multiplier | 1 |
//! | `NoiseScale` | (perlin) position multiplier | 1 |
//! | `NoiseConversion` | (perlin) `linear` or `absval` | linear |
//! | `NumOctaves` | (perlin) octaves summed | 1 |
//! | `Scale`, `Offset` | (checkerboard) squares per unit, pattern shift | 1, 0 |
//! | `BlackColor`, `WhiteColor` | (checkerboard) the two colours | 0 0 0, 1 1 1 |
//!
//! Only one map may replace the background; a second is an error, since
//! which of two backgrounds the author meant cannot be guessed.

use super::Warnings;
use crate::description::{
    DecalMode, ImageDesc, Interpolation, NoiseConversion, TextureMapDesc, TextureSource,
};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Most Perlin octaves accepted: beyond about 24 the octaves are finer than
/// `f32` resolves, and a hostile count must not stall every shading point.
pub const MAX_OCTAVES: u32 = 24;

/// Reads `TexCoordData`: a multiple of two numbers.
pub fn read_tex_coords(r: &Reader, el: &Element) -> Result<Vec<Vec2>, SceneError> {
    let f = r.floats(el)?;
    if f.len() % 2 != 0 {
        return Err(
            r.err(el, format!("<TexCoordData> has {} numbers, which is not a multiple of 2", f.len()))
        );
    }
    Ok(f.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect())
}

/// Reads `Textures`: the images and texture maps.
pub fn read_all(
    r: &Reader,
    el: &Element,
    base_dir: &Path,
    w: &mut Warnings,
) -> Result<(Vec<ImageDesc>, Vec<TextureMapDesc>), SceneError> {
    w.unknown_children(el, &["Images", "TextureMap"]);
    let mut images = Vec::new();
    for imgs in el.children_named("Images") {
        w.unknown_children(imgs, &["Image"]);
        for im in imgs.children_named("Image") {
            let path = im.text.trim();
            if path.is_empty() {
                return Err(r.err(im, "<Image> names no file"));
            }
            let degamma = r.bool_attr(im, "degamma", false)?;
            images.push(ImageDesc::file(id_of(im), base_dir.join(path), degamma, im.loc.clone()));
        }
    }
    let image_ids: HashMap<&str, usize> =
        images.iter().enumerate().rev().map(|(i, im)| (im.id.as_str(), i)).collect();
    let mut maps: Vec<TextureMapDesc> = Vec::new();
    let mut degamma = Vec::new();
    for tm in el.children_named("TextureMap") {
        let m = texture_map(r, tm, &image_ids, base_dir, w)?;
        if m.decal == DecalMode::ReplaceBackground && maps.iter().any(|o| o.decal == m.decal) {
            return Err(r.err(tm, "a second texture map replaces the background; only one may"));
        }
        if let (true, TextureSource::Image { image, .. }) = (r.bool_attr(tm, "degamma", false)?, &m.source) {
            degamma.push(*image);
        }
        maps.push(m);
    }
    for i in degamma {
        images[i].degamma = true;
    }
    Ok((images, maps))
}

fn id_of(el: &Element) -> String {
    el.attr("id").unwrap_or("").trim().to_string()
}

fn texture_map(
    r: &Reader,
    el: &Element,
    image_ids: &HashMap<&str, usize>,
    base_dir: &Path,
    w: &mut Warnings,
) -> Result<TextureMapDesc, SceneError> {
    let decal_el = r.required(el, "DecalMode")?;
    let decal = match decal_el.text.trim() {
        "replace_kd" => DecalMode::ReplaceKd,
        "blend_kd" => DecalMode::BlendKd,
        "replace_ks" => DecalMode::ReplaceKs,
        "replace_background" => DecalMode::ReplaceBackground,
        "replace_normal" => DecalMode::ReplaceNormal,
        "bump_normal" => DecalMode::BumpNormal,
        "replace_all" => DecalMode::ReplaceAll,
        "replace_km" => DecalMode::ReplaceKm,
        "material" => DecalMode::Material,
        other => {
            return Err(r.err(
                decal_el,
                format!(
                    "<DecalMode> \"{other}\" is unknown (expected replace_kd, blend_kd, replace_ks, \
                     replace_km, replace_background, replace_normal, bump_normal, replace_all or material)"
                ),
            ))
        }
    };
    let common = ["DecalMode", "BumpFactor"];
    let kind = el.attr("type").map(str::trim).unwrap_or("");
    let source = match kind {
        "image" => {
            w.unknown_children(el, &[&common[..], &["ImageId", "Interpolation", "Normalizer"]].concat());
            let ie = r.required(el, "ImageId")?;
            let id = ie.text.trim();
            let image = *image_ids
                .get(id)
                .ok_or_else(|| r.err(ie, format!("image \"{id}\" is not defined in <Images>")))?;
            let interpolation = match el.child("Interpolation").map(|e| (e, e.text.trim())) {
                None => Interpolation::Nearest,
                Some((_, "nearest")) => Interpolation::Nearest,
                Some((_, "bilinear")) => Interpolation::Bilinear,
                Some((_, "trilinear")) => Interpolation::Trilinear,
                Some((e, other)) => {
                    return Err(r.err(
                        e,
                        format!(
                        "<Interpolation> \"{other}\" is unknown (expected nearest, bilinear or trilinear)"
                    ),
                    ))
                }
            };
            let normalizer = match el.child("Normalizer") {
                Some(n) => {
                    let v = r.float(n)?;
                    if v <= 0.0 {
                        return Err(r.err(n, format!("<Normalizer> must be positive, found {v}")));
                    }
                    Some(v)
                }
                None => None,
            };
            TextureSource::Image { image, interpolation, normalizer }
        }
        "perlin" => {
            w.unknown_children(el, &[&common[..], &["NoiseScale", "NoiseConversion", "NumOctaves"]].concat());
            let conversion = match el.child("NoiseConversion").map(|e| (e, e.text.trim())) {
                None | Some((_, "linear")) => NoiseConversion::Linear,
                Some((_, "absval")) => NoiseConversion::AbsVal,
                Some((e, other)) => {
                    return Err(r.err(
                        e,
                        format!("<NoiseConversion> \"{other}\" is unknown (expected linear or absval)"),
                    ))
                }
            };
            let octaves = match el.child("NumOctaves") {
                Some(o) => {
                    let n = r.uint(o)?;
                    if n == 0 || n > MAX_OCTAVES {
                        return Err(r.err(o, format!("<NumOctaves> must be 1 to {MAX_OCTAVES}, found {n}")));
                    }
                    n
                }
                None => 1,
            };
            TextureSource::Perlin { scale: r.float_or(el, "NoiseScale", 1.0)?, conversion, octaves }
        }
        "checkerboard" => {
            w.unknown_children(el, &[&common[..], &["Scale", "Offset", "BlackColor", "WhiteColor"]].concat());
            TextureSource::Checkerboard {
                scale: r.float_or(el, "Scale", 1.0)?,
                offset: r.float_or(el, "Offset", 0.0)?,
                black: r.vec3_or(el, "BlackColor", Vec3::ZERO)?,
                white: r.vec3_or(el, "WhiteColor", Vec3::ONE)?,
            }
        }
        "shader" => {
            w.unknown_children(el, &[&common[..], &super::shader_map::CHILDREN[..]].concat());
            super::shader_map::read(r, el, base_dir)?
        }
        "" => {
            return Err(r.err(el, "<TextureMap> has no type (expected image, perlin, checkerboard or shader)"))
        }
        other => {
            return Err(r.err(
                el,
                format!(
                "<TextureMap> type \"{other}\" is unknown (expected image, perlin, checkerboard or shader)"
            ),
            ))
        }
    };
    if decal == DecalMode::Material && !matches!(source, TextureSource::Shader { .. }) {
        return Err(r.err(decal_el, "<DecalMode> material is for shader maps (type=\"shader\") only"));
    }
    Ok(TextureMapDesc {
        id: id_of(el),
        source,
        decal,
        bump_factor: r.float_or(el, "BumpFactor", 1.0)?,
        loc: el.loc.clone(),
    })
}

/// Reads an object's `Textures`: ids of texture maps, resolved to indices.
pub fn object_textures(
    r: &Reader,
    el: &Element,
    ids: &HashMap<&str, usize>,
) -> Result<Vec<usize>, SceneError> {
    el.text
        .split_ascii_whitespace()
        .map(|id| {
            ids.get(id)
                .copied()
                .ok_or_else(|| r.err(el, format!("texture map \"{id}\" is not defined in <Textures>")))
        })
        .collect()
}
