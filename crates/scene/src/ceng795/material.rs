//! `Materials/Material`.
//!
//! | element | meaning | default |
//! |---|---|---|
//! | `type` attribute | `mirror`, `dielectric`, `conductor`, or none | none |
//! | `AmbientReflectance`, `DiffuseReflectance`, `SpecularReflectance` | Blinn-Phong RGB | 0 |
//! | `PhongExponent` | specular exponent | 1 |
//! | `MirrorReflectance` | RGB weight of the reflected ray | 0 |
//! | `RefractionIndex` | dielectric index, or a conductor's real part | 1 |
//! | `AbsorptionCoefficient` | dielectric Beer's-law RGB coefficient | 0 |
//! | `AbsorptionIndex` | a conductor's imaginary part | 0 |
//! | `Roughness` | glossy spread of mirror, conductor and dielectric rays | 0 |
//! | `Transparency` | the older course files' mark of a transparent material: without a `type`, a non-zero value makes it a dielectric (its `RefractionIndex`, Fresnel weights) | none |
//! | `degamma` attribute (`_degamma`) | the four reflectance colours are raised to the power 2.2 | false |
//! | `BRDF` attribute | id of a [`brdf`](super::brdf) entry replacing Blinn-Phong | none |
//!
//! `degamma="true"` (hw5 `cube_point_hdr`: "read these values by applying
//! degamma transform") says the colours were picked on a display and turns
//! them linear: `c^2.2` per channel. The course's `.exr` shows it: that
//! cube's red-to-green ratio is 3.105 = (0.651/0.389)^2.2, not 1.674.
//!
//! Only `type="mirror"` (or conductor) makes `MirrorReflectance` reflect: the
//! course's scenes give plain materials a mirror reflectance that their
//! reference images ignore (hw1 `car_smooth_fixed`, `rt_raven`).

use super::Warnings;
use crate::description::{BrdfDesc, MaterialDesc, MaterialKind};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::Vec3;
use std::collections::HashMap;

/// The exponent of `degamma="true"`.
pub const DEGAMMA: f32 = 2.2;

/// Reads every material.
pub fn read_all(
    r: &Reader,
    ms: &Element,
    brdfs: &HashMap<String, BrdfDesc>,
    w: &mut Warnings,
) -> Result<Vec<MaterialDesc>, SceneError> {
    w.unknown_children(ms, &["Material"]);
    let mut out: Vec<MaterialDesc> = Vec::new();
    for m in ms.children_named("Material") {
        let desc = read(r, m, brdfs, w)?;
        if out.iter().any(|o| o.id == desc.id) {
            w.at(m, format!("material id {} is defined twice; the first definition is used", desc.id));
        }
        out.push(desc);
    }
    Ok(out)
}

fn read(
    r: &Reader,
    m: &Element,
    brdfs: &HashMap<String, BrdfDesc>,
    w: &mut Warnings,
) -> Result<MaterialDesc, SceneError> {
    w.unknown_children(
        m,
        &[
            "AmbientReflectance",
            "DiffuseReflectance",
            "SpecularReflectance",
            "MirrorReflectance",
            "PhongExponent",
            "RefractionIndex",
            "AbsorptionCoefficient",
            "AbsorptionIndex",
            "Roughness",
            "Transparency",
        ],
    );
    let id = m.attr("id").map(str::trim).filter(|s| !s.is_empty());
    let Some(id) = id else {
        return Err(r.err(m, "<Material> has no id"));
    };
    let mirror = r.vec3_or(m, "MirrorReflectance", Vec3::ZERO)?;
    let kind = match m.attr("type").map(str::trim).unwrap_or("") {
        "" if m
            .child("Transparency")
            .map(|t| r.vec3(t))
            .transpose()?
            .is_some_and(|t| t.max_element() > 0.0) =>
        {
            MaterialKind::Dielectric
        }
        "" => MaterialKind::Plain,
        "mirror" => MaterialKind::Mirror,
        "dielectric" => MaterialKind::Dielectric,
        "conductor" => MaterialKind::Conductor,
        other => {
            w.at(m, format!("material type \"{other}\" is not supported yet; treated as plain Blinn-Phong"));
            MaterialKind::Plain
        }
    };
    let refraction_index = r.float_or(m, "RefractionIndex", 1.0)?;
    if refraction_index <= 0.0 {
        return Err(r.err(m, format!("<RefractionIndex> must be positive, found {refraction_index}")));
    }
    let absorption_coefficient = r.vec3_or(m, "AbsorptionCoefficient", Vec3::ZERO)?;
    let brdf = match m.attr("BRDF").map(str::trim) {
        None => None,
        Some(b) => match brdfs.get(b) {
            Some(desc) => Some(desc.clone()),
            None => {
                return Err(
                    r.err(m, format!("material {id} names BRDF \"{b}\", which <BRDFs> does not define"))
                )
            }
        },
    };
    if absorption_coefficient.min_element() < 0.0 {
        return Err(r.err(m, "<AbsorptionCoefficient> must not be negative"));
    }
    let degamma = r.bool_attr(m, "degamma", false)?;
    let colour = |name: &str| -> Result<Vec3, SceneError> {
        let c = r.vec3_or(m, name, Vec3::ZERO)?;
        Ok(if degamma { c.max(Vec3::ZERO).powf(DEGAMMA) } else { c })
    };
    Ok(MaterialDesc {
        id: id.to_string(),
        kind,
        ambient: colour("AmbientReflectance")?,
        diffuse: colour("DiffuseReflectance")?,
        specular: colour("SpecularReflectance")?,
        mirror: if degamma { mirror.max(Vec3::ZERO).powf(DEGAMMA) } else { mirror },
        phong_exponent: r.float_or(m, "PhongExponent", 1.0)?,
        refraction_index,
        absorption_coefficient,
        absorption_index: r.float_or(m, "AbsorptionIndex", 0.0)?,
        roughness: non_negative_roughness(r, m)?,
        brdf,
        loc: m.loc.clone(),
    })
}

fn non_negative_roughness(r: &Reader, m: &Element) -> Result<f32, SceneError> {
    let v = r.float_or(m, "Roughness", 0.0)?;
    if v < 0.0 {
        return Err(r.err(m, format!("<Roughness> must not be negative, found {v}")));
    }
    Ok(v)
}
