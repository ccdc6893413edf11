//! The studio a bare model is shown in (`luster render model.obj`, and a
//! glTF file without cameras or lights): a camera that frames the model's
//! bounding sphere, a key and a fill light that follow the camera, and a
//! light ground under the model. [`crate::obj::model`] documents the layout
//! and its defaults; both model formats share this code so they look alike.

use crate::description::{CameraDesc, MaterialDesc, ObjectDesc, PointLightDesc, Projection, Shape};
use crate::error::{Loc, SceneError};
use crate::obj::ModelView;
use luster_core::math::{Transform, Vec3};
use std::path::Path;

/// Key and fill irradiance at the model's centre (255 = white).
pub const KEY: f32 = 190.0;
/// The fill light's irradiance at the model's centre.
pub const FILL: f32 = 60.0;
/// The ambient light: the sky's blue, faint.
pub const AMBIENT: Vec3 = Vec3::new(12.0, 13.0, 15.0);
/// The background: a soft grey-blue.
pub const SKY: Vec3 = Vec3::new(105.0, 130.0, 168.0);

/// The bounding sphere of a set of points: centre (the middle of their
/// bounding box) and radius (the farthest point from it; 1 when all coincide).
pub fn bounding_sphere<I: Iterator<Item = Vec3>>(points: impl Fn() -> I) -> (Vec3, f32) {
    let (lo, hi) = points().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let c = (lo + hi) * 0.5;
    let r = points().map(|p| p.distance(c)).fold(0.0f32, f32::max);
    (c, if r > 0.0 && r.is_finite() { r } else { 1.0 })
}

/// The unit vector from the centre towards a view at `azimuth`, `elevation` degrees.
pub fn direction(azimuth: f32, elevation: f32) -> Vec3 {
    let (a, e) = (azimuth.to_radians(), elevation.to_radians());
    Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
}

/// The image's name for a model file: `<stem>.png`, with what could not
/// name a file safely (a newline, an escape, a backslash) as `_`.
pub fn image_name(path: &Path) -> String {
    let stem = path.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    let stem: String =
        stem.chars().map(|c| if luster_core::text::is_unsafe(c) || c == '\\' { '_' } else { c }).collect();
    format!("{stem}.png")
}

/// The camera that frames a sphere as `view` says.
pub fn framing_camera(
    view: &ModelView,
    center: Vec3,
    radius: f32,
    image_name: String,
    loc: &Loc,
) -> CameraDesc {
    let aspect = view.width as f32 / view.height as f32;
    let half_y = (view.fov_y * 0.5).to_radians();
    let half = half_y.tan().min(half_y.tan() * aspect).atan();
    let distance = view.distance.unwrap_or(1.1 * radius / half.sin());
    let elevation = view.elevation.clamp(-89.0, 89.0);
    CameraDesc {
        id: "model".into(),
        position: center + direction(view.azimuth, elevation) * distance,
        up: Vec3::Y,
        projection: Projection::LookAt { gaze_point: center, fov_y: view.fov_y },
        near_distance: 1.0,
        resolution: (view.width, view.height),
        image_name,
        // The display transform (`view.display`, sRGB by default) makes the
        // PNG: model colours are linear reflectances, as in other renderers.
        tonemaps: Vec::new(),
        num_samples: view.samples,
        noise_threshold: None,
        aperture_size: 0.0,
        focus_distance: 1.0,
        renderer: Default::default(),
        loc: loc.clone(),
    }
}

/// The key and fill lights around a sphere seen as `view` says, giving its
/// centre irradiances of `KEY · scale` and `FILL · scale`.
pub fn lights(view: &ModelView, center: Vec3, radius: f32, scale: f32, loc: &Loc) -> Vec<PointLightDesc> {
    let light = |az: f32, el: f32, irradiance: f32| {
        let d = 4.0 * radius;
        PointLightDesc {
            position: center + direction(view.azimuth + az, el) * d,
            intensity: Vec3::splat(irradiance * scale * d * d),
            loc: loc.clone(),
        }
    };
    vec![light(-45.0, 50.0, KEY), light(60.0, 15.0, FILL)]
}

/// A ground plane under the lowest point `lowest` of a sphere, with the
/// material of index `material`; `None` when the view asks for none or the
/// camera is below it (it would see only the ground).
pub fn ground(
    view: &ModelView,
    camera: &CameraDesc,
    center: Vec3,
    radius: f32,
    lowest: f32,
    material: usize,
    loc: &Loc,
) -> Option<ObjectDesc> {
    (view.ground && camera.position.y > lowest).then(|| ObjectDesc {
        id: "ground".into(),
        shape: Shape::Plane { point: Vec3::new(center.x, lowest - 1e-3 * radius, center.z), normal: Vec3::Y },
        material,
        transform: Transform::IDENTITY,
        motion: Vec3::ZERO,
        textures: Vec::new(),
        loc: loc.clone(),
        attributes: Vec::new(),
        geometry_attributes: Vec::new(),
    })
}

/// The ground's material: mostly ambient, so the floor stays light out to
/// the horizon (point lights fade with distance) and the key light's shadow
/// shows on it.
pub fn ground_material(loc: &Loc) -> MaterialDesc {
    MaterialDesc {
        id: "ground".into(),
        ambient: Vec3::splat(2.6),
        diffuse: Vec3::splat(0.3),
        ..crate::obj::mtl::default_material(loc.clone())
    }
}

/// Refuses views that cannot make an image.
pub fn check(path: &Path, v: &ModelView) -> Result<(), SceneError> {
    let bad = |msg: String| Err(SceneError::file(path, msg));
    if v.width == 0 || v.height == 0 || v.width > 1 << 14 || v.height > 1 << 14 {
        return bad(format!(
            "an image of {}x{} pixels cannot be made (1 to 16384 a side)",
            v.width, v.height
        ));
    }
    if !(v.fov_y > 0.0 && v.fov_y < 180.0) {
        return bad(format!("the field of view must be between 0 and 180 degrees, found {}", v.fov_y));
    }
    if v.distance.is_some_and(|d| !(d > 0.0 && d.is_finite())) {
        return bad("the camera distance must be positive".to_string());
    }
    if !(v.azimuth.is_finite() && v.elevation.is_finite()) || v.samples == 0 {
        return bad("the view's angles must be finite and its samples at least 1".to_string());
    }
    Ok(())
}
