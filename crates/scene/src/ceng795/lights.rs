//! `Lights`: every light type of the course.
//!
//! | element | children | meaning |
//! |---|---|---|
//! | `AmbientLight` | (text) RGB | radiance every surface receives |
//! | `PointLight` | `Position`, `Intensity` | irradiance `I / d²` |
//! | `AreaLight` | `Position`, `Normal`, `Size`, `Radiance` | a square of uniform radiance (hw3) |
//! | `DirectionalLight` | `Direction`, `Radiance` | parallel light travelling along `Direction`, no attenuation (hw5) |
//! | `SpotLight` | `Position`, `Direction`, `Intensity`, `CoverageAngle`, `FalloffAngle` | a point light limited to a cone; angles in degrees, full opening angles (hw5) |
//! | `SphericalDirectionalLight` | `ImageId`; attributes `type` (`latlong`, default, or `probe`) and optional child or attribute `Sampler` (`importance`, default; `uniform`; `cosine`) | an environment map (hw5) |
//!
//! ```xml
//! <SpotLight id="1">
//!     <Position>-0.93 1 0.9</Position> <Direction>1 -1 -1</Direction>
//!     <Intensity>600 600 600</Intensity>
//!     <CoverageAngle>10</CoverageAngle> <FalloffAngle>8</FalloffAngle>
//! </SpotLight>
//! <SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight>
//! ```
//!
//! Intensities and radiances must not be negative; a spot light's
//! `FalloffAngle` must not exceed its `CoverageAngle`; a scene has at most one
//! environment light (a second one is an error: which map is the sky would be
//! a guess).

use super::Warnings;
use crate::description::{
    AreaLightDesc, DirectionalLightDesc, EnvMapping, EnvSampling, EnvironmentLightDesc, ImageDesc,
    PointLightDesc, SpotLightDesc,
};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::Vec3;

/// Everything `Lights` holds.
#[derive(Default)]
pub struct Lights {
    /// Ambient radiance (zero if absent).
    pub ambient: Vec3,
    /// Point lights.
    pub points: Vec<PointLightDesc>,
    /// Square area lights.
    pub areas: Vec<AreaLightDesc>,
    /// Directional lights.
    pub directionals: Vec<DirectionalLightDesc>,
    /// Spot lights.
    pub spots: Vec<SpotLightDesc>,
    /// The environment light.
    pub environment: Option<EnvironmentLightDesc>,
}

/// Reads every light; `images` resolves an environment light's `ImageId`.
pub fn read_all(
    r: &Reader,
    l: &Element,
    images: &[ImageDesc],
    w: &mut Warnings,
) -> Result<Lights, SceneError> {
    w.unknown_children(
        l,
        &[
            "AmbientLight",
            "PointLight",
            "AreaLight",
            "DirectionalLight",
            "SpotLight",
            "SphericalDirectionalLight",
        ],
    );
    let mut out = Lights::default();
    for (i, a) in l.children_named("AmbientLight").enumerate() {
        if i > 0 {
            w.at(a, "more than one <AmbientLight>; the last one is used");
        }
        out.ambient = non_negative(r, a)?;
    }
    for p in l.children_named("PointLight") {
        w.unknown_children(p, &["Position", "Intensity"]);
        out.points.push(PointLightDesc {
            position: r.vec3(r.required(p, "Position")?)?,
            intensity: non_negative(r, r.required(p, "Intensity")?)?,
            loc: p.loc.clone(),
        });
    }
    for a in l.children_named("AreaLight") {
        w.unknown_children(a, &["Position", "Normal", "Size", "Radiance"]);
        let se = r.required(a, "Size")?;
        let size = r.float(se)?;
        if size <= 0.0 {
            return Err(r.err(se, format!("<Size> must be positive, found {size}")));
        }
        out.areas.push(AreaLightDesc {
            position: r.vec3(r.required(a, "Position")?)?,
            normal: unit(r, r.required(a, "Normal")?)?,
            size,
            radiance: non_negative(r, r.required(a, "Radiance")?)?,
            loc: a.loc.clone(),
        });
    }
    for d in l.children_named("DirectionalLight") {
        w.unknown_children(d, &["Direction", "Radiance"]);
        out.directionals.push(DirectionalLightDesc {
            direction: unit(r, r.required(d, "Direction")?)?,
            radiance: non_negative(r, r.required(d, "Radiance")?)?,
            loc: d.loc.clone(),
        });
    }
    for s in l.children_named("SpotLight") {
        out.spots.push(spot(r, s, w)?);
    }
    for (i, e) in l.children_named("SphericalDirectionalLight").enumerate() {
        if i > 0 {
            return Err(
                r.err(e, "only one <SphericalDirectionalLight> (environment light) is supported per scene")
            );
        }
        out.environment = Some(environment(r, e, images, w)?);
    }
    Ok(out)
}

fn spot(r: &Reader, s: &Element, w: &mut Warnings) -> Result<SpotLightDesc, SceneError> {
    w.unknown_children(s, &["Position", "Direction", "Intensity", "CoverageAngle", "FalloffAngle"]);
    let angle = |name: &str| -> Result<f32, SceneError> {
        let el = r.required(s, name)?;
        let a = r.float(el)?;
        if !(0.0..=360.0).contains(&a) {
            return Err(r.err(el, format!("<{name}> must be an angle from 0 to 360 degrees, found {a}")));
        }
        Ok(a)
    };
    let coverage_angle = angle("CoverageAngle")?;
    let falloff_angle = angle("FalloffAngle")?;
    if falloff_angle > coverage_angle {
        let el = s.child("FalloffAngle").unwrap_or(s);
        return Err(r.err(
            el,
            format!(
                "<FalloffAngle> {falloff_angle} is larger than <CoverageAngle> {coverage_angle}; the cone \
                 without fall-off must lie inside the lit cone"
            ),
        ));
    }
    Ok(SpotLightDesc {
        position: r.vec3(r.required(s, "Position")?)?,
        direction: unit(r, r.required(s, "Direction")?)?,
        intensity: non_negative(r, r.required(s, "Intensity")?)?,
        coverage_angle,
        falloff_angle,
        loc: s.loc.clone(),
    })
}

fn environment(
    r: &Reader,
    e: &Element,
    images: &[ImageDesc],
    w: &mut Warnings,
) -> Result<EnvironmentLightDesc, SceneError> {
    w.unknown_children(e, &["ImageId", "Sampler"]);
    let mapping = match e.attr("type").map(|t| t.trim().to_ascii_lowercase()).as_deref() {
        None | Some("") | Some("latlong") => EnvMapping::LatLong,
        Some("probe") => EnvMapping::Probe,
        Some(_) => return Err(r.err(e, "the environment light's type must be latlong or probe")),
    };
    let sampler = e.child("Sampler").map(|c| c.text.as_str()).or_else(|| e.attr("Sampler"));
    let sampling = match sampler.map(|t| t.trim().to_ascii_lowercase()).as_deref() {
        None | Some("") | Some("importance") => EnvSampling::Importance,
        Some("uniform") => EnvSampling::Uniform,
        Some("cosine") => EnvSampling::Cosine,
        Some(_) => {
            return Err(r.err(e, "the environment light's <Sampler> must be importance, uniform or cosine"))
        }
    };
    let id_el = r.required(e, "ImageId")?;
    let id = id_el.text.trim();
    let image = images
        .iter()
        .position(|i| i.id == id)
        .or_else(|| {
            // A number that is no id is read as the course's 1-based index.
            let k: usize = id.parse().ok()?;
            (k >= 1 && k <= images.len()).then(|| k - 1)
        })
        .ok_or_else(|| r.err(id_el, "<ImageId> names no image of <Textures>/<Images>"))?;
    Ok(EnvironmentLightDesc { image, mapping, sampling, rotation: 0.0, strength: 1.0, loc: e.loc.clone() })
}

fn unit(r: &Reader, el: &Element) -> Result<Vec3, SceneError> {
    let v = r.vec3(el)?;
    if v.length_squared() == 0.0 || !v.is_finite() {
        return Err(r.err(el, format!("<{}> must be a non-zero, finite vector", el.name)));
    }
    Ok(v.normalize())
}

fn non_negative(r: &Reader, el: &Element) -> Result<Vec3, SceneError> {
    let v = r.vec3(el)?;
    if v.min_element() < 0.0 || !v.is_finite() {
        return Err(r.err(
            el,
            format!("<{}> must be finite and not negative (negative light does not exist)", el.name),
        ));
    }
    Ok(v)
}
