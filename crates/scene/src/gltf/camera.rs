//! glTF cameras: a perspective camera placed by its node, looking down its
//! node's −Z with +Y up (the node's scale is ignored, as the specification
//! says).
//!
//! | glTF | luster |
//! |---|---|
//! | `perspective.yfov` (radians) | the vertical field of view |
//! | `perspective.aspectRatio` | the horizontal extent, and the image's width (600 pixels high) unless `--size` gives the size; without it, the image's aspect (800×600 by default) |
//! | `perspective.znear`, `zfar` | not used: rays start at the eye and are not clipped |
//! | `orthographic` | not used (a warning): luster's cameras are perspective |
//!
//! Cameras are numbered in the order their nodes are drawn (depth first
//! through the scene): `--camera N` picks one, the first by default.

use super::nodes::Placed;
use super::Notes;
use crate::description::{CameraDesc, Projection};
use crate::error::Loc;
use crate::obj::ModelView;
use luster_core::math::Vec3;

/// Height of a glTF camera's image when `aspectRatio` sets its width.
const HEIGHT: u32 = 600;

/// A perspective camera of the scene: its node's world transform and
/// the camera's index in the document.
#[derive(Clone, Debug)]
pub struct SceneCamera {
    /// The node carrying it.
    pub placed: Placed,
    /// Index into the document's cameras.
    pub camera: usize,
}

/// The perspective cameras of the drawn nodes, in their order; an
/// orthographic one is left out with a warning.
pub fn cameras(doc: &gltf::Document, placed: &[Placed], notes: &mut Notes) -> Vec<SceneCamera> {
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut out = Vec::new();
    for p in placed {
        let Some(cam) = nodes[p.node].camera() else { continue };
        match cam.projection() {
            gltf::camera::Projection::Perspective(_) => {
                out.push(SceneCamera { placed: p.clone(), camera: cam.index() })
            }
            gltf::camera::Projection::Orthographic(_) => notes.warn(
                &format!("cameras[{}]", cam.index()),
                "orthographic cameras are not supported (luster's cameras are perspective); not used",
            ),
        }
    }
    out
}

/// The description's camera for `cam`, its image named `image_name`.
pub fn camera_desc(
    doc: &gltf::Document,
    cam: &SceneCamera,
    view: &ModelView,
    image_name: String,
) -> CameraDesc {
    let (yfov, aspect) = match doc.cameras().nth(cam.camera).as_ref().map(|c| c.projection()) {
        Some(gltf::camera::Projection::Perspective(p)) => (p.yfov(), p.aspect_ratio()),
        _ => (0.8, None),
    };
    // A file's aspect ratio sets the image's shape unless the size was asked for.
    let resolution = match aspect {
        Some(a) if !view.sized && a.is_finite() && a > 0.0 => {
            (((HEIGHT as f32 * a).round() as u32).clamp(1, 16384), HEIGHT)
        }
        _ => (view.width, view.height),
    };
    let image_aspect = resolution.0 as f32 / resolution.1 as f32;
    let half_h = (yfov.clamp(1e-4, 3.1) * 0.5).tan();
    let half_w = half_h * image_aspect;
    let w = &cam.placed.world;
    CameraDesc {
        id: format!("cameras[{}]", cam.camera),
        position: w.point(Vec3::ZERO),
        up: w.vector(Vec3::Y),
        projection: Projection::Plane {
            gaze: w.vector(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z),
            near_plane: [-half_w, half_w, -half_h, half_h],
        },
        near_distance: 1.0,
        resolution,
        image_name,
        tonemaps: Vec::new(),
        num_samples: view.samples,
        noise_threshold: None,
        aperture_size: 0.0,
        focus_distance: 1.0,
        renderer: Default::default(),
        loc: Loc { line: None, path: format!("nodes[{}]", cam.placed.node) },
    }
}
