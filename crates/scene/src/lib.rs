//! luster-scene: scene loading — the two encodings of the CENG795 format,
//! OBJ models, glTF scenes, PLY meshes, and the plain [`Description`] they produce, every
//! value with the file and line it came from. Nothing here knows the renderer.
#![warn(missing_docs)]

pub mod ceng795;
pub mod description;
pub mod element;
pub mod error;
pub mod gltf;
pub mod hdri;
pub mod json;
pub mod obj;
pub mod ply;
pub mod studio;
pub mod xml;

pub use description::Description;
pub use error::{Loc, SceneError, Warning};

use luster_core::file;
use std::path::Path;

/// Largest scene file accepted; the biggest course scene is a few megabytes.
const MAX_SCENE_BYTES: u64 = 1 << 30;

/// Loads a scene file, choosing the encoding by its extension (`.json` or
/// `.xml`) or, failing that, by its first character. An `.obj` file is a
/// model, rendered in the scene [`obj::model_scene`] makes around it with the
/// default [`obj::ModelView`]; a `.gltf` or `.glb` file is a glTF scene
/// ([`gltf::scene()`]).
pub fn load(path: &Path) -> Result<Description, SceneError> {
    load_viewed(path, &obj::ModelView::default())
}

/// [`load`], with an OBJ model seen through `view`, and `view.display`
/// (`--display`) replacing any scene's display transform.
pub fn load_viewed(path: &Path, view: &obj::ModelView) -> Result<Description, SceneError> {
    if is_obj(path) {
        return obj::model_scene(path, view);
    }
    if gltf::is_gltf(path) {
        return gltf::scene(path, view);
    }
    let mut desc = ceng795::read(path, &element_tree(path)?)?;
    if let Some(d) = view.display {
        desc.display = d;
    }
    Ok(desc)
}

/// A scene file's element tree (XML or JSON, chosen as [`load`] does),
/// before any of it is read as the course's format.
pub fn element_tree(path: &Path) -> Result<element::Element, SceneError> {
    let text = file::read_text(path, MAX_SCENE_BYTES).map_err(|why| {
        if why == "it is a folder" {
            SceneError::file(path, "is a folder, not a scene file")
        } else {
            SceneError::file(path, format!("cannot read the scene: {why}"))
        }
    })?;
    if text.trim().is_empty() {
        return Err(SceneError::file(path, "the scene file is empty"));
    }
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let is_json = match ext.as_deref() {
        Some("json") => true,
        Some("xml") => false,
        _ => text.trim_start().starts_with('{'),
    };
    Ok(if is_json { json::parse(path, &text)? } else { xml::parse(path, &text)? })
}

/// Whether a path names a model rendered in a scene made around it: an
/// OBJ or glTF file, whose `--size` makes its camera.
pub fn is_model(path: &Path) -> bool {
    is_obj(path) || gltf::is_gltf(path)
}

/// Whether a path names an OBJ model (by its extension, in any case).
pub fn is_obj(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}
