//! `Lights`: `AmbientLight` (an RGB radiance every surface receives),
//! `PointLight` (`Position`, RGB `Intensity`; irradiance `I / d²`) and
//! `AreaLight` (a square: `Position` of its centre, `Normal`, edge `Size`, RGB
//! `Radiance`). Other light
//! types get a warning until they are supported.

use super::Warnings;
use crate::math::Vec3;
use crate::scene::description::{AreaLightDesc, PointLightDesc};
use crate::scene::element::{Element, Reader};
use crate::scene::error::SceneError;

/// Reads the ambient light (zero if absent) and the point lights.
pub fn read_all(
    r: &Reader,
    l: &Element,
    w: &mut Warnings,
) -> Result<(Vec3, Vec<PointLightDesc>, Vec<AreaLightDesc>), SceneError> {
    w.unknown_children(l, &["AmbientLight", "PointLight", "AreaLight"]);
    let mut ambient = Vec3::ZERO;
    for (i, a) in l.children_named("AmbientLight").enumerate() {
        if i > 0 {
            w.at(a, "more than one <AmbientLight>; the last one is used");
        }
        ambient = non_negative(r, a)?;
    }
    let mut points = Vec::new();
    for p in l.children_named("PointLight") {
        w.unknown_children(p, &["Position", "Intensity"]);
        points.push(PointLightDesc {
            position: r.vec3(r.required(p, "Position")?)?,
            intensity: non_negative(r, r.required(p, "Intensity")?)?,
            loc: p.loc.clone(),
        });
    }
    let mut areas = Vec::new();
    for a in l.children_named("AreaLight") {
        w.unknown_children(a, &["Position", "Normal", "Size", "Radiance"]);
        let ne = r.required(a, "Normal")?;
        let normal = r.vec3(ne)?;
        if normal.length_squared() == 0.0 {
            return Err(r.err(ne, "the area light's <Normal> is zero"));
        }
        let se = r.required(a, "Size")?;
        let size = r.float(se)?;
        if size <= 0.0 {
            return Err(r.err(se, format!("<Size> must be positive, found {size}")));
        }
        areas.push(AreaLightDesc {
            position: r.vec3(r.required(a, "Position")?)?,
            normal: normal.normalize(),
            size,
            radiance: non_negative(r, r.required(a, "Radiance")?)?,
            loc: a.loc.clone(),
        });
    }
    Ok((ambient, points, areas))
}

fn non_negative(r: &Reader, el: &Element) -> Result<Vec3, SceneError> {
    let v = r.vec3(el)?;
    if v.min_element() < 0.0 {
        return Err(r.err(el, format!("<{}> must not be negative (negative light does not exist)", el.name)));
    }
    Ok(v)
}
