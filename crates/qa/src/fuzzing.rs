//! Entry points shared by the coverage-guided fuzz targets (`fuzz/`) and the
//! fuzz smoke test CI runs (`tests/fuzz_smoke.rs`). Each takes arbitrary
//! bytes, hands them to one loader exactly as a file on disk would reach it,
//! and ignores the outcome: an error is the expected answer to garbage. The
//! only contract is to return; a panic, a hang or runaway memory is a bug.
//!
//! Loaders that read paths get the bytes through a scratch folder (one per
//! thread), so the checks on files (regular file, size caps) run as well.

use luster_render::render::scene::{BuildOptions, Scene};
use luster_scene::{ceng795, json, obj, ply, xml};
use luster_shading::shader::{ShadeInput, ShaderSet, ShaderSource};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// One kind of input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// An XML scene, loaded and built into a render scene (BVH included).
    SceneXml,
    /// A JSON scene, loaded and built.
    SceneJson,
    /// A PLY mesh.
    Ply,
    /// An OBJ model; bytes after a line `#-mtl-` are its MTL file `m.mtl`.
    Obj,
    /// An image file decoded as a texture.
    Image,
    /// A shader script: instrumented, compiled, and its entry points called
    /// once under a short time limit.
    Shader,
}

impl Target {
    /// Every target.
    pub const ALL: [Target; 6] =
        [Target::SceneXml, Target::SceneJson, Target::Ply, Target::Obj, Target::Image, Target::Shader];

    /// The target's name (the fuzz target's and its corpus folder's).
    pub fn name(self) -> &'static str {
        match self {
            Target::SceneXml => "scene_xml",
            Target::SceneJson => "scene_json",
            Target::Ply => "ply",
            Target::Obj => "obj",
            Target::Image => "image",
            Target::Shader => "shader",
        }
    }

    /// Feeds `data` to the target's loader.
    pub fn run(self, data: &[u8]) {
        match self {
            Target::SceneXml => scene(data, "scene.xml", xml::parse),
            Target::SceneJson => scene(data, "scene.json", json::parse),
            Target::Ply => {
                let _ = ply::read_ply(&write("mesh.ply", data));
            }
            Target::Obj => {
                let marker = b"\n#-mtl-\n";
                let split = data.windows(marker.len()).position(|w| w == marker);
                let (model, mtl) = match split {
                    Some(i) => (&data[..i], &data[i + marker.len()..]),
                    None => (data, &[][..]),
                };
                write("m.mtl", mtl);
                let _ = obj::load(&write("model.obj", model));
            }
            Target::Image => {
                let _ = luster_render::texture::image::Image::load(&write("image", data));
            }
            Target::Shader => shader(data),
        }
    }
}

thread_local! {
    static SCRATCH: tempfile::TempDir = tempfile::tempdir().unwrap_or_else(|e| panic!("no scratch folder: {e}"));
}

/// Writes `data` to `name` in this thread's scratch folder.
fn write(name: &str, data: &[u8]) -> PathBuf {
    SCRATCH.with(|d| {
        let p = d.path().join(name);
        std::fs::write(&p, data).unwrap_or_else(|e| panic!("cannot write {}: {e}", p.display()));
        p
    })
}

fn scene(
    data: &[u8],
    name: &str,
    parse: impl Fn(&Path, &str) -> Result<luster_scene::element::Element, luster_scene::SceneError>,
) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = write(name, data);
    let Ok(root) = parse(&path, text) else { return };
    let Ok(desc) = ceng795::read(&path, &root) else { return };
    let _ = Scene::build_with(&desc, &BuildOptions { shader_timeout: Duration::from_millis(20) });
}

fn shader(data: &[u8]) {
    let Ok(code) = std::str::from_utf8(data) else { return };
    let _ = luster_shading::shader::instrument_script(code);
    let src = ShaderSource::new("fuzz", "fuzz.lua", code);
    let Ok(set) = ShaderSet::new(vec![src], Duration::from_millis(20)) else { return };
    let input = ShadeInput {
        p: [0.1, 0.2, 0.3],
        pw: [1.0, 2.0, 3.0],
        n: [0.0, 0.0, 1.0],
        uv: [0.5, 0.5],
        ..ShadeInput::default()
    };
    if set.has_color(0) {
        let _ = set.color(0, &input);
    }
    if set.has_height(0) {
        let _ = set.height(0, &input);
    }
}
