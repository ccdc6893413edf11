//! `BRDFs`: reflection models that materials name with `BRDF="id"` (hw6).
//!
//! | element | meaning | default |
//! |---|---|---|
//! | `OriginalPhong`, `ModifiedPhong`, `OriginalBlinnPhong`, `ModifiedBlinnPhong`, `TorranceSparrow` | the model; `id` attribute required | |
//! | `normalized` attribute | energy-normalized modified Phong / Blinn-Phong | false |
//! | `kdfresnel` attribute | Torrance-Sparrow diffuse term weighted by `1 - F` | false |
//! | `Exponent` | the lobe's exponent `p` | the material's `PhongExponent` |
//!
//! An unknown model is an error, not a warning: a material that names it would
//! otherwise render with a different reflection model than the scene asks for.

use super::Warnings;
use crate::description::{BrdfDesc, BrdfKind};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use std::collections::HashMap;

const KINDS: [(&str, BrdfKind); 5] = [
    ("OriginalPhong", BrdfKind::OriginalPhong),
    ("ModifiedPhong", BrdfKind::ModifiedPhong),
    ("OriginalBlinnPhong", BrdfKind::OriginalBlinnPhong),
    ("ModifiedBlinnPhong", BrdfKind::ModifiedBlinnPhong),
    ("TorranceSparrow", BrdfKind::TorranceSparrow),
];

/// Reads every BRDF, by id (the first of a repeated id wins).
pub fn read_all(r: &Reader, bs: &Element, w: &mut Warnings) -> Result<HashMap<String, BrdfDesc>, SceneError> {
    let mut out: HashMap<String, BrdfDesc> = HashMap::new();
    for b in &bs.children {
        let desc = read(r, b, w)?;
        if out.contains_key(&desc.id) {
            w.at(b, format!("BRDF id {} is defined twice; the first definition is used", desc.id));
            continue;
        }
        out.insert(desc.id.clone(), desc);
    }
    Ok(out)
}

fn read(r: &Reader, b: &Element, w: &mut Warnings) -> Result<BrdfDesc, SceneError> {
    let Some(&(_, kind)) = KINDS.iter().find(|(name, _)| *name == b.name) else {
        let names: Vec<&str> = KINDS.iter().map(|(n, _)| *n).collect();
        return Err(
            r.err(b, format!("<{}> is not a known BRDF (expected one of {})", b.name, names.join(", ")))
        );
    };
    w.unknown_children(b, &["Exponent"]);
    let Some(id) = b.attr("id").map(str::trim).filter(|s| !s.is_empty()) else {
        return Err(r.err(b, format!("<{}> has no id", b.name)));
    };
    let exponent = match b.child("Exponent") {
        Some(e) => {
            let v = r.float(e)?;
            if v < 0.0 {
                return Err(r.err(e, format!("<Exponent> must not be negative, found {v}")));
            }
            Some(v)
        }
        None => None,
    };
    let normalized = r.bool_attr(b, "normalized", false)?;
    let kd_fresnel = r.bool_attr(b, "kdfresnel", false)?;
    let modified = matches!(kind, BrdfKind::ModifiedPhong | BrdfKind::ModifiedBlinnPhong);
    if normalized && !modified && kind != BrdfKind::TorranceSparrow {
        w.at(b, format!("normalized=\"true\" applies to the modified models only; <{}> ignores it", b.name));
    }
    if kd_fresnel && kind != BrdfKind::TorranceSparrow {
        w.at(b, format!("kdfresnel applies to TorranceSparrow only; <{}> ignores it", b.name));
    }
    Ok(BrdfDesc { id: id.to_string(), kind, exponent, normalized, kd_fresnel, loc: b.loc.clone() })
}
