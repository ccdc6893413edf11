//! `Cameras/Camera`: one image each.
//!
//! | element | meaning |
//! |---|---|
//! | `Position`, `Up` | eye and up vector |
//! | `Gaze` + `NearPlane` (l r b t) | the plain form |
//! | `type="lookAt"`: `GazePoint` (or a `Gaze` direction, as in 2022 files) + `FovY` (degrees) | the look-at form; the horizontal extent follows the aspect ratio |
//! | `handedness` attribute | `right`, the default and the course's only kind; `left` is refused |
//! | `NearDistance` | distance to the image plane |
//! | `ImageResolution` | width height |
//! | `ImageName` | output file name: a relative path without `..`, ending in one of [`OUTPUT_EXTENSIONS`]; `.exr`/`.hdr` also write a tone-mapped `.png` |
//! | `Tonemap` | tone mapping of the image (see [`super::tonemap`]); several allowed |
//! | `NumSamples` | samples per pixel (default 1) |
//! | `NoiseThreshold` | adaptive sampling: a pixel stops once its estimated relative error is below this (luster's extension; 0 or absent: off; `--noise-threshold` replaces it; see docs/passes.md) |
//! | `ApertureSize` | edge of the square lens (default 0: a pinhole) |
//! | `FocusDistance` | distance along the gaze that is in focus (needed with an aperture) |
//! | `Transformations` | named transforms (as for objects) moving the camera: `Position` and `GazePoint` as points, `Gaze` and `Up` as directions (see [`transform_all`]) |
//! | `Renderer`, `RendererParams` | `PathTracing` with any of `NextEventEstimation`, `ImportanceSampling`, `RussianRoulette` (hw7), or luster's `MIS`; see [`renderer`] |
//!
//! No two cameras (nor an `.exr` and its derived `.png`) may write the same
//! file: that is an error before anything is rendered.
//!
//! The course's `hw1/xml/spheres*.xml` give five numbers to `NearPlane`; the
//! first four are used and a warning says so.

use super::Warnings;
use crate::description::{CameraDesc, LightSamples, PathParamsDesc, Projection, RendererDesc};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::image::outputs::{file_key, plan_outputs};
use luster_core::math::{Transform, Vec3};
use std::path::{Component, Path};

/// Largest accepted image side, and pixel count: a scene asking for more is a
/// mistake or an attack, not a render.
pub const MAX_SIDE: u32 = 32768;
/// See [`MAX_SIDE`].
pub const MAX_PIXELS: u64 = 1 << 27;

/// Image formats `image::output` can write, by extension.
pub const OUTPUT_EXTENSIONS: &[&str] = &["png", "jpg", "jpeg", "exr", "hdr"];

/// Reads every camera, refusing two that would write the same file.
pub fn read_all(r: &Reader, cams: &Element, w: &mut Warnings) -> Result<Vec<CameraDesc>, SceneError> {
    w.unknown_children(cams, &["Camera"]);
    let mut out: Vec<CameraDesc> = Vec::new();
    let mut files = std::collections::HashSet::new();
    for c in cams.children_named("Camera") {
        let desc = read(r, c, w)?;
        let plan =
            plan_outputs(&desc.image_name, &desc.tonemaps, Default::default()).map_err(|e| r.err(c, e))?;
        for o in plan {
            if !files.insert(file_key(&o.name)) {
                return Err(r.err(
                    c,
                    format!(
                        "this camera would write {}, which an earlier camera (or this one) already writes",
                        o.name.display()
                    ),
                ));
            }
        }
        out.push(desc);
    }
    Ok(out)
}

fn read(r: &Reader, c: &Element, w: &mut Warnings) -> Result<CameraDesc, SceneError> {
    let kind = c.attr("type").unwrap_or("").trim();
    let look_at = match kind {
        "" | "simple" => false,
        "lookAt" => true,
        other => {
            return Err(r.err(c, format!("camera type \"{other}\" is unknown (expected lookAt or none)")))
        }
    };
    match c.attr("handedness").map(str::trim) {
        None | Some("right") => {}
        Some(other) => {
            return Err(r.err(
                c,
                format!(
                "camera handedness \"{other}\" is not supported (only the course's right-handed cameras are)"
            ),
            ))
        }
    }
    let known: &[&str] = &[
        "Position",
        "Gaze",
        "Up",
        "NearPlane",
        "NearDistance",
        "ImageResolution",
        "ImageName",
        "NumSamples",
        "NoiseThreshold",
        "GazePoint",
        "FovY",
        "ApertureSize",
        "FocusDistance",
        "Tonemap",
        "Transformations",
        "Renderer",
        "RendererParams",
    ];
    w.unknown_children(c, known);

    let position = r.vec3(r.required(c, "Position")?)?;
    let up = r.vec3(r.required(c, "Up")?)?;
    if up.length_squared() == 0.0 {
        return Err(r.err(c, "the camera's <Up> vector is zero"));
    }
    let projection = projection(r, c, position, look_at, w)?;
    let nd = r.required(c, "NearDistance")?;
    let near_distance = r.float(nd)?;
    if near_distance <= 0.0 {
        return Err(r.err(nd, format!("<NearDistance> must be positive, found {near_distance}")));
    }
    let resolution = resolution(r, c)?;
    let name_el = r.required(c, "ImageName")?;
    let image_name = name_el.text.trim().to_string();
    check_image_name(r, name_el, &image_name)?;
    let num_samples = match c.child("NumSamples") {
        Some(ns) => {
            let n = r.uint(ns)?;
            if n == 0 || n > 1 << 20 {
                return Err(r.err(ns, format!("<NumSamples> must be between 1 and {}, found {n}", 1 << 20)));
            }
            n
        }
        None => 1,
    };
    let noise_threshold = match c.child("NoiseThreshold") {
        Some(el) => {
            let t = r.float(el)?;
            if !(0.0..=1.0).contains(&t) {
                return Err(r.err(el, format!("<NoiseThreshold> must be between 0 and 1, found {t}")));
            }
            (t > 0.0).then_some(t)
        }
        None => None,
    };
    let (aperture_size, focus_distance) = lens(r, c, near_distance)?;
    Ok(CameraDesc {
        id: c.attr("id").unwrap_or("").to_string(),
        position,
        up,
        projection,
        near_distance,
        resolution,
        image_name,
        tonemaps: super::tonemap::read_all(r, c, w)?,
        num_samples,
        noise_threshold,
        aperture_size,
        focus_distance,
        renderer: renderer(r, c)?,
        loc: c.loc.clone(),
    })
}

/// The camera's view: a look-at camera's `GazePoint` (or `Gaze`) and `FovY`,
/// or a simple camera's `Gaze` and `NearPlane`.
fn projection(
    r: &Reader,
    c: &Element,
    position: Vec3,
    look_at: bool,
    w: &mut Warnings,
) -> Result<Projection, SceneError> {
    Ok(if look_at {
        // The 2022 course files give look-at cameras a <Gaze> direction
        // instead of a <GazePoint>; both name the same view.
        let gaze_point = match (c.child("GazePoint"), c.child("Gaze")) {
            (Some(gp), _) => r.vec3(gp)?,
            (None, Some(g)) => {
                let gaze = r.vec3(g)?;
                if gaze.length_squared() == 0.0 {
                    return Err(r.err(g, "the camera's <Gaze> vector is zero"));
                }
                position + gaze
            }
            (None, None) => {
                return Err(r.err(c, "a lookAt camera needs a <GazePoint> (or a <Gaze> direction)"))
            }
        };
        let fy = r.required(c, "FovY")?;
        let fov_y = r.float(fy)?;
        if !(fov_y > 0.0 && fov_y < 180.0) {
            return Err(r.err(fy, format!("<FovY> must be between 0 and 180 degrees, found {fov_y}")));
        }
        if (gaze_point - position).length_squared() == 0.0 {
            return Err(r.err(c, "the camera's <GazePoint> is its <Position>, so it looks nowhere"));
        }
        Projection::LookAt { gaze_point, fov_y }
    } else {
        let gaze = r.vec3(r.required(c, "Gaze")?)?;
        if gaze.length_squared() == 0.0 {
            return Err(r.err(c, "the camera's <Gaze> vector is zero"));
        }
        let np = r.required(c, "NearPlane")?;
        let v = r.floats(np)?;
        if v.len() == 5 {
            w.at(np, "<NearPlane> has 5 numbers (a known typo in course files); using the first 4");
        } else if v.len() != 4 {
            return Err(
                r.err(np, format!("<NearPlane> needs 4 numbers (left right bottom top), found {}", v.len()))
            );
        }
        if v[0] == v[1] || v[2] == v[3] {
            return Err(r.err(np, "<NearPlane> has zero width or height"));
        }
        Projection::Plane { gaze, near_plane: [v[0], v[1], v[2], v[3]] }
    })
}

/// `ImageResolution`: two positive integers within the supported size.
fn resolution(r: &Reader, c: &Element) -> Result<(u32, u32), SceneError> {
    let res_el = r.required(c, "ImageResolution")?;
    let res = r.floats_n(res_el, 2)?;
    let (wpx, hpx) = (res[0], res[1]);
    if wpx.fract() != 0.0 || hpx.fract() != 0.0 || wpx < 1.0 || hpx < 1.0 {
        return Err(
            r.err(res_el, format!("<ImageResolution> must be two positive integers, found {wpx} {hpx}"))
        );
    }
    if wpx > MAX_SIDE as f32 || hpx > MAX_SIDE as f32 || (wpx as u64) * (hpx as u64) > MAX_PIXELS {
        return Err(r.err(
            res_el,
            format!("<ImageResolution> {wpx}x{hpx} is beyond the supported {MAX_SIDE} pixels a side and {MAX_PIXELS} pixels in all"),
        ));
    }
    Ok((wpx as u32, hpx as u32))
}

/// `ApertureSize` (0: a pinhole) and `FocusDistance` (needed with an
/// aperture; the near distance otherwise).
fn lens(r: &Reader, c: &Element, near_distance: f32) -> Result<(f32, f32), SceneError> {
    let aperture_size = r.float_or(c, "ApertureSize", 0.0)?;
    if aperture_size < 0.0 {
        return Err(r.err(c, format!("<ApertureSize> must not be negative, found {aperture_size}")));
    }
    let focus_distance = match c.child("FocusDistance") {
        Some(f) => {
            let d = r.float(f)?;
            if d <= 0.0 {
                return Err(r.err(f, format!("<FocusDistance> must be positive, found {d}")));
            }
            d
        }
        None if aperture_size > 0.0 => return Err(r.err(c, "<ApertureSize> needs a <FocusDistance>")),
        None => near_distance,
    };
    Ok((aperture_size, focus_distance))
}

/// Moves every camera of `cams` (read by [`read_all`], in the same order) by
/// its `<Transformations>`, once the scene's named transforms are known. The
/// course's animations orbit the camera this way (a `Rotation` whose angle
/// grows by a degree a frame). The view's sizes (`NearPlane`, `FovY`,
/// `NearDistance`) stay as written; the directions are renormalised where
/// the camera is built, so a scaling only moves the eye.
pub fn transform_all(
    r: &Reader,
    cams: &Element,
    descs: &mut [CameraDesc],
    named: &std::collections::HashMap<String, Transform>,
) -> Result<(), SceneError> {
    for (c, d) in cams.children_named("Camera").zip(descs.iter_mut()) {
        let Some(el) = c.child("Transformations") else { continue };
        let t = super::transforms::compose(r, el, named)?;
        d.position = t.point(d.position);
        d.up = t.vector(d.up);
        d.projection = match d.projection {
            Projection::Plane { gaze, near_plane } => Projection::Plane { gaze: t.vector(gaze), near_plane },
            Projection::LookAt { gaze_point, fov_y } => {
                Projection::LookAt { gaze_point: t.point(gaze_point), fov_y }
            }
        };
        let gaze = match d.projection {
            Projection::Plane { gaze, .. } => gaze,
            Projection::LookAt { gaze_point, .. } => gaze_point - d.position,
        };
        if !(gaze.length_squared() > 0.0 && d.up.length_squared() > 0.0 && d.position.is_finite()) {
            return Err(r.err(el, "the camera's <Transformations> leave it without a direction to look in"));
        }
    }
    Ok(())
}

/// A camera's integrator: `<Renderer>PathTracing</Renderer>` with the words of
/// `<RendererParams>` (none, or an empty element: the course's uniform
/// variant; `MIS`: luster's multiple importance sampling, with `AllLights` or
/// `OneLight` to say how many lights a hit samples), else the course's
/// recursive ray tracer. An unknown renderer or word is an error, and so are
/// `AllLights` and `OneLight` together or without `MIS`.
pub fn renderer(r: &Reader, c: &Element) -> Result<RendererDesc, SceneError> {
    let Some(re) = c.child("Renderer") else {
        if let Some(p) = c.child("RendererParams") {
            return Err(r.err(p, "<RendererParams> needs a <Renderer> (PathTracing) beside it"));
        }
        return Ok(RendererDesc::Whitted);
    };
    match re.text.trim() {
        "PathTracing" => {}
        "RayTracing" | "Whitted" => return Ok(RendererDesc::Whitted),
        _ => return Err(r.err(re, "<Renderer> is unknown (expected PathTracing, RayTracing or Whitted)")),
    }
    let mut p = PathParamsDesc::default();
    let params = c.child("RendererParams");
    let el = params.unwrap_or(c);
    let words = params.map_or("", |e| e.text.as_str());
    let (mut all, mut one) = (false, false);
    for (i, word) in words.split_whitespace().enumerate() {
        let flag = match word {
            "NextEventEstimation" => &mut p.next_event,
            "ImportanceSampling" => &mut p.importance,
            "RussianRoulette" => &mut p.russian_roulette,
            "MIS" => &mut p.mis,
            "AllLights" => &mut all,
            "OneLight" => &mut one,
            _ => {
                return Err(r.err(
                    el,
                    format!(
                        "<RendererParams> word {} is unknown (expected NextEventEstimation, \
                         ImportanceSampling, RussianRoulette, MIS, AllLights or OneLight)",
                        i + 1
                    ),
                ));
            }
        };
        *flag = true;
    }
    if all && one {
        return Err(r.err(el, "<RendererParams> has both AllLights and OneLight; give one of them"));
    }
    if (all || one) && !p.mis {
        let word = if all { "AllLights" } else { "OneLight" };
        return Err(r.err(el, format!("<RendererParams> word {word} needs MIS beside it")));
    }
    p.lights = match (all, one) {
        (true, _) => LightSamples::All,
        (_, true) => LightSamples::One,
        _ => LightSamples::Auto,
    };
    Ok(RendererDesc::PathTracing(p))
}

/// Scene files come from strangers: the image name must stay inside the output
/// folder. Its format is checked here too, before anything is rendered, so a
/// scene whose second camera names a `.bmp` does not fail after the first
/// camera's image is written.
fn check_image_name(r: &Reader, el: &Element, name: &str) -> Result<(), SceneError> {
    if name.is_empty() {
        return Err(r.err(el, "<ImageName> is empty"));
    }
    if let Some(problem) = luster_core::text::file_name_problem(name) {
        return Err(r.err(el, format!("<ImageName> {problem}")));
    }
    let p = Path::new(name);
    if p.is_absolute() || p.has_root() {
        return Err(r.err(
            el,
            format!("<ImageName> \"{name}\" is an absolute path; it must be relative to the output folder"),
        ));
    }
    if p.components().any(|c| !matches!(c, Component::Normal(_))) {
        return Err(r.err(
            el,
            format!(
                "<ImageName> \"{name}\" must stay inside the output folder (a relative path without \"..\")"
            ),
        ));
    }
    let ext = p.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !ext.is_some_and(|e| OUTPUT_EXTENSIONS.contains(&e.as_str())) || name.ends_with('/') {
        return Err(r.err(
            el,
            format!(
                "<ImageName> \"{name}\" must end in .{}, the formats luster writes",
                OUTPUT_EXTENSIONS.join(", .")
            ),
        ));
    }
    Ok(())
}
