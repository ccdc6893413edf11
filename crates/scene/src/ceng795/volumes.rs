//! `<Volumes>`: luster's extension of the CENG795 format for participating
//! media and hypertextures (see the README's "Volumes" section).
//!
//! ```xml
//! <Volumes>
//!     <Volume id="cloud">
//!         <Sphere><Center>0 1 0</Center><Radius>1</Radius></Sphere>
//!         <Transformations>s1</Transformations>
//!         <Shader>shaders/cloud.lua</Shader>
//!         <Parameter name="scale">2</Parameter>
//!         <Density>4</Density>
//!         <Absorption>0.2 0.2 0.2</Absorption>
//!         <Scattering>1 1 1</Scattering>
//!     </Volume>
//!     <Hypertexture id="fuzz">
//!         <Box><Min>-1 -1 -1</Min><Max>1 1 1</Max></Box>
//!         <Material>1</Material>
//!         <Shader>shaders/fuzzy.lua</Shader>
//!         <Threshold>0.5</Threshold>
//!     </Hypertexture>
//! </Volumes>
//! ```
//!
//! | element | reads | default |
//! |---|---|---|
//! | bound (one of) | `Sphere` (`Center` x y z, `Radius`), `Box` (`Min`, `Max`), `Ellipsoid` (`Center`, `Radii`, optional `Rotation` = angle ax ay az) — coordinates inline, in the volume's space | required |
//! | `Transformations` | named transforms, as for objects | none |
//! | `Shader`, `Parameter` | a script defining `density(s)` (media may add `emission(s)`), read as for shader maps | none: constant density |
//! | `Density` | the constant density, or a factor on the script's | 1 |
//! | `StepSize` | ray-marching step, world units | 1/64 of the bound's world diagonal |
//! | `GridResolution` | bake the script's density (and emission) on N³ points (2 to 512, at most 1 GiB of samples) | none: exact |
//! | `Absorption`, `Scattering` (media) | σa, σs per unit length at density 1 | 1 1 1, 0 0 0 |
//! | `Emission` (media) | emitted radiance per unit length at density 1 | 0 0 0 |
//! | `Anisotropy` (media) | Henyey–Greenstein g, −0.99 to 0.99 | 0 |
//! | `ScatteringOctaves` (media) | terms of the multiple-scattering approximation, 1 to 8 (1: single scattering) | 1 |
//! | `Material`, `Threshold`, `Textures` (hypertextures) | the surface's material, the density of the surface, its texture maps | required, 0.5, none |

use super::objects::radii_and_rotation;
use super::shader_map;
use super::textures::object_textures;
use super::transforms::compose;
use super::Warnings;
use crate::description::{BoundDesc, VolumeDesc, VolumeKind};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::{Transform, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Largest `GridResolution`: 512³ floats are half a gigabyte.
pub const MAX_GRID: u32 = 512;

/// Most `ScatteringOctaves`: each halves the last one's contribution.
pub const MAX_OCTAVES: u32 = 8;

/// What volume reading needs from the rest of the file.
pub struct Context<'a> {
    /// Typed reading with errors naming the file.
    pub r: Reader<'a>,
    /// Material id to index.
    pub materials: &'a HashMap<&'a str, usize>,
    /// Texture map id to index.
    pub textures: &'a HashMap<&'a str, usize>,
    /// Named transforms.
    pub transforms: &'a HashMap<String, Transform>,
    /// Folder of the scene file.
    pub base_dir: &'a Path,
}

const COMMON: [&str; 9] = [
    "Sphere",
    "Box",
    "Ellipsoid",
    "Transformations",
    "Shader",
    "Parameter",
    "Density",
    "StepSize",
    "GridResolution",
];

/// Reads every `Volume` and `Hypertexture` of a `Volumes` element.
pub fn read_all(ctx: &Context, el: &Element, w: &mut Warnings) -> Result<Vec<VolumeDesc>, SceneError> {
    w.unknown_children(el, &["Volume", "Hypertexture"]);
    let r = &ctx.r;
    let mut out = Vec::new();
    for v in &el.children {
        let kind = match v.name.as_str() {
            "Volume" => {
                let extra = ["Absorption", "Scattering", "Emission", "Anisotropy", "ScatteringOctaves"];
                w.unknown_children(v, &[&COMMON[..], &extra[..]].concat());
                let non_negative = |name: &str, default: Vec3| -> Result<Vec3, SceneError> {
                    let c = r.vec3_or(v, name, default)?;
                    if c.min_element() < 0.0 || !c.is_finite() {
                        return Err(
                            r.err(v.child(name).unwrap_or(v), format!("<{name}> must be finite and ≥ 0"))
                        );
                    }
                    Ok(c)
                };
                let anisotropy = r.float_or(v, "Anisotropy", 0.0)?;
                if !(-0.99..=0.99).contains(&anisotropy) {
                    return Err(r.err(
                        v.child("Anisotropy").unwrap_or(v),
                        format!("<Anisotropy> must lie between -0.99 and 0.99, found {anisotropy}"),
                    ));
                }
                let octaves = match v.child("ScatteringOctaves") {
                    Some(o) => {
                        let n = r.uint(o)?;
                        if !(1..=MAX_OCTAVES).contains(&n) {
                            return Err(r.err(
                                o,
                                format!("<ScatteringOctaves> must be 1 to {MAX_OCTAVES}, found {n}"),
                            ));
                        }
                        n
                    }
                    None => 1,
                };
                VolumeKind::Medium {
                    octaves,
                    absorption: non_negative("Absorption", Vec3::ONE)?,
                    scattering: non_negative("Scattering", Vec3::ZERO)?,
                    emission: non_negative("Emission", Vec3::ZERO)?,
                    anisotropy,
                }
            }
            "Hypertexture" => {
                let extra = ["Material", "Threshold", "Textures"];
                w.unknown_children(v, &[&COMMON[..], &extra[..]].concat());
                let m = r.required(v, "Material")?;
                let id = m.text.trim();
                let material = *ctx
                    .materials
                    .get(id)
                    .ok_or_else(|| r.err(m, format!("material \"{id}\" is not defined in <Materials>")))?;
                let threshold = r.float_or(v, "Threshold", 0.5)?;
                if !threshold.is_finite() {
                    return Err(r.err(v, "<Threshold> must be finite"));
                }
                let textures = match v.child("Textures") {
                    Some(t) => object_textures(r, t, ctx.textures)?,
                    None => Vec::new(),
                };
                VolumeKind::Surface { material, threshold, textures }
            }
            _ => continue,
        };
        out.push(volume(ctx, v, kind)?);
    }
    Ok(out)
}

/// The parts every volume has.
fn volume(ctx: &Context, v: &Element, kind: VolumeKind) -> Result<VolumeDesc, SceneError> {
    let r = &ctx.r;
    let density = r.float_or(v, "Density", 1.0)?;
    if density < 0.0 || !density.is_finite() {
        return Err(r.err(
            v.child("Density").unwrap_or(v),
            format!("<Density> must be finite and ≥ 0, found {density}"),
        ));
    }
    let step = match v.child("StepSize") {
        Some(s) => {
            let x = r.float(s)?;
            if !(x > 0.0 && x.is_finite()) {
                return Err(r.err(s, format!("<StepSize> must be positive, found {x}")));
            }
            Some(x)
        }
        None => None,
    };
    let script = match v.child("Shader") {
        Some(_) => Some(shader_map::script(r, v, ctx.base_dir)?),
        None => None,
    };
    let grid = match v.child("GridResolution") {
        Some(g) => {
            let n = r.uint(g)?;
            if !(2..=MAX_GRID).contains(&n) {
                return Err(r.err(g, format!("<GridResolution> must be 2 to {MAX_GRID}, found {n}")));
            }
            if script.is_none() {
                return Err(r.err(g, "<GridResolution> needs a <Shader>: a constant density needs no grid"));
            }
            Some(n)
        }
        None => None,
    };
    if script.is_none() && matches!(kind, VolumeKind::Surface { .. }) {
        return Err(r.err(v, "a <Hypertexture> needs a <Shader> whose density(s) gives its shape"));
    }
    let transform = match v.child("Transformations") {
        Some(t) => compose(r, t, ctx.transforms)?,
        None => Transform::IDENTITY,
    };
    Ok(VolumeDesc {
        id: v.attr("id").unwrap_or("").trim().to_string(),
        bound: bound(r, v)?,
        transform,
        density,
        script,
        step,
        grid,
        kind,
        loc: v.loc.clone(),
    })
}

/// The one bound child of a volume.
fn bound(r: &Reader, v: &Element) -> Result<BoundDesc, SceneError> {
    let found: Vec<&Element> =
        v.children.iter().filter(|c| matches!(c.name.as_str(), "Sphere" | "Box" | "Ellipsoid")).collect();
    let b = match found[..] {
        [b] => b,
        [] => return Err(r.err(v, format!("<{}> needs a bound: <Sphere>, <Box> or <Ellipsoid>", v.name))),
        _ => return Err(r.err(found[1], format!("<{}> has more than one bound", v.name))),
    };
    Ok(match b.name.as_str() {
        "Sphere" => {
            let re = r.required(b, "Radius")?;
            let radius = r.float(re)?;
            if !(radius > 0.0 && radius.is_finite()) {
                return Err(r.err(re, format!("<Radius> must be positive, found {radius}")));
            }
            BoundDesc::Sphere { center: r.vec3(r.required(b, "Center")?)?, radius }
        }
        "Box" => {
            let (lo, hi) = (r.required(b, "Min")?, r.required(b, "Max")?);
            let (min, max) = (r.vec3(lo)?, r.vec3(hi)?);
            if !(min.cmplt(max).all() && min.is_finite() && max.is_finite()) {
                return Err(r.err(b, "<Min> must be below <Max> on every axis"));
            }
            BoundDesc::Box { min, max }
        }
        _ => {
            let (radii, rotation) = radii_and_rotation(r, b)?;
            BoundDesc::Ellipsoid { center: r.vec3(r.required(b, "Center")?)?, radii, rotation }
        }
    })
}
