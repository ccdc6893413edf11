//! Wavefront OBJ models and their MTL materials, read with `tobj`.
//!
//! An OBJ file is read whole when the scene loads: its polygons are
//! triangulated (fans), vertices are unified per `v/vt/vn` triple, and the
//! faces are grouped by material into [`Part`]s: one part, and so one scene
//! object, per material the file uses (`o` and `g` only name faces; faces
//! without a `usemtl` share a light grey default). Each part carries its
//! [`MaterialDesc`] and texture maps (the mapping tables are in [`mtl`] and
//! [`maps`]), ready for a description: [`Additions`] numbers them after what
//! a scene already has.
//!
//! | OBJ | luster |
//! |---|---|
//! | `v`, `vt`, `vn`, `f` (any polygon), negative indices | positions, texture coordinates, normals, triangles |
//! | `vt u v` | `(u, 1 − v)`: OBJ's `v` counts up from the image's bottom, luster's textures count down |
//! | `vn` | smooth shading normals, when every vertex of a part has one |
//! | `mtllib a.mtl [b.mtl ...]`, `usemtl` | the part's material (paths relative to the OBJ) |
//!
//! Errors name the file and the line: a missing OBJ or MTL file, an MTL
//! statement that is not understood, a texture image or shader script that
//! cannot be read, a face index that is 0 or points past the data, a
//! `usemtl` that no library before it defines, a line that is not an OBJ
//! statement. A missing MTL file is an error, not a grey model: the model
//! would render, but not as its author made it. Statements luster does not
//! use (lines, curves, `Ke`, `map_Ka`, ...) get warnings.
//!
//! Two ways in: `luster render model.obj` ([`model_scene`]), and a CENG795
//! scene's `<Mesh><Faces objFile="model.obj"/></Mesh>`
//! (`scene::ceng795::obj_file`).

mod additions;
pub mod maps;
pub mod model;
pub mod mtl;
mod scan;

pub use additions::Additions;
pub use model::{model_scene, ModelView};

use crate::description::{ImageDesc, MaterialDesc, MeshArrays, TextureMapDesc};
use crate::error::{Loc, SceneError, Warning};
use luster_core::math::{Vec2, Vec3};
use mtl::MtlFile;
use std::cell::Cell;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest OBJ file accepted.
const MAX_OBJ_BYTES: u64 = 1 << 30;

/// A texture map of a part, with the image it reads (numbered when the part
/// is added to a description).
#[derive(Clone, Debug)]
pub struct PartMap {
    /// The map; an image map's image index is set by [`Additions::add_part`].
    pub map: TextureMapDesc,
    /// The image, for image maps.
    pub image: Option<ImageDesc>,
}

/// The faces of an OBJ model that share one material.
#[derive(Clone, Debug)]
pub struct Part {
    /// The material's name (`(none)` for faces without one).
    pub name: String,
    /// The geometry.
    pub arrays: Arc<MeshArrays>,
    /// The material.
    pub material: MaterialDesc,
    /// Its texture maps, in the order they apply.
    pub maps: Vec<PartMap>,
}

/// An OBJ file read.
#[derive(Clone, Debug)]
pub struct ObjModel {
    /// The file.
    pub file: PathBuf,
    /// One part per material, in order of first use.
    pub parts: Vec<Part>,
    /// What was accepted but ignored.
    pub warnings: Vec<Warning>,
}

impl ObjModel {
    /// Whether every part has normals from the file.
    pub fn has_normals(&self) -> bool {
        self.parts.iter().all(|p| p.arrays.normals.is_some())
    }

    /// All parts as one mesh (for a scene that gives the model one material).
    pub fn merged(&self) -> MeshArrays {
        let mut out = MeshArrays::default();
        let all_normals = self.has_normals();
        let all_uvs = self.parts.iter().all(|p| p.arrays.uvs.is_some());
        let (mut normals, mut uvs) = (Vec::new(), Vec::new());
        for p in &self.parts {
            let a = &p.arrays;
            let base = out.positions.len() as u32;
            out.positions.extend_from_slice(&a.positions);
            out.triangles.extend(a.triangles.iter().map(|t| t.map(|i| i + base)));
            normals.extend_from_slice(a.normals.as_deref().unwrap_or(&[]));
            uvs.extend_from_slice(a.uvs.as_deref().unwrap_or(&[]));
        }
        out.normals = all_normals.then_some(normals);
        out.uvs = all_uvs.then_some(uvs);
        out
    }
}

/// Where line `line` of `file` is, for messages (`file, line N`; the file
/// alone for line 0).
pub fn at(file: &Path, line: u32) -> Loc {
    let path = match line {
        0 => file.display().to_string(),
        l => format!("{}, line {l}", file.display()),
    };
    Loc { line: None, path }
}

/// Where line `line` of the OBJ file itself is: its warnings are shown
/// after the file's name (`model.obj: line 12: ...`; `geometry` for the
/// whole file).
fn own(line: u32) -> Loc {
    let path = if line == 0 { "geometry".to_string() } else { format!("line {line}") };
    Loc { line: None, path }
}

/// An error on line `line` of `file` (the whole file for line 0).
fn line_err(file: &Path, line: u32, msg: impl std::fmt::Display) -> SceneError {
    match line {
        0 => SceneError::file(file, msg.to_string()),
        l => SceneError::file(file, format!("line {l}: {msg}")),
    }
}

/// Reads an OBJ file, its material libraries, and their images' and
/// scripts' presence (images are decoded when the scene is built).
pub fn load(path: &Path) -> Result<ObjModel, SceneError> {
    let text = mtl::read_text(path, MAX_OBJ_BYTES)
        .map_err(|why| SceneError::file(path, format!("cannot read the OBJ file: {why}")))?;
    let sc = scan::scan(&text).map_err(|(line, msg)| line_err(path, line, msg))?;
    let mut warnings: Vec<Warning> =
        sc.warnings.iter().map(|(l, m)| Warning { loc: own(*l), message: m.clone() }).collect();
    let dir = path.parent().unwrap_or(Path::new(""));

    // Material libraries, each `mtllib` statement's files in order: tobj asks
    // for them in the same order, and numbers their materials one after another.
    let mut files: Vec<MtlFile> = Vec::new();
    let mut per_statement: Vec<Vec<usize>> = Vec::new();
    for lib in &sc.mtllibs {
        let whole = dir.join(&lib.name);
        let names: Vec<&str> =
            if whole.is_file() { vec![lib.name.as_str()] } else { lib.name.split_whitespace().collect() };
        let mut ids = Vec::new();
        for n in names {
            let f = mtl::read(&dir.join(n)).map_err(|e| line_err(path, lib.line, e))?;
            warnings.extend(f.warnings.iter().cloned());
            ids.push(files.len());
            files.push(f);
        }
        per_statement.push(ids);
    }
    for u in &sc.usemtls {
        let defined = sc
            .mtllibs
            .iter()
            .zip(&per_statement)
            .filter(|(l, _)| l.line < u.line)
            .any(|(_, ids)| ids.iter().any(|&f| files[f].materials.iter().any(|m| m.name == u.name)));
        if !defined {
            let libs: Vec<String> = files.iter().map(|f| f.path.display().to_string()).collect();
            let why = if libs.is_empty() {
                "no material library (mtllib) is given".to_string()
            } else {
                format!("no material library before this line defines it ({})", libs.join(", "))
            };
            return Err(line_err(
                path,
                u.line,
                format!("usemtl {}: {why}", crate::error::shown_token(&u.name)),
            ));
        }
    }
    // tobj's material numbering: (file, material in file) for each global index.
    let origin: Vec<(usize, usize)> = per_statement
        .iter()
        .flatten()
        .flat_map(|&f| (0..files[f].materials.len()).map(move |m| (f, m)))
        .collect();

    let opts =
        tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let next = Cell::new(0usize);
    let mut reader = CountingReader::new(text.as_bytes());
    let (models, _) = tobj::load_obj_buf(&mut reader, &opts, |_| {
        let i = next.get();
        next.set(i + 1);
        let mats: Vec<tobj::Material> = per_statement
            .get(i)
            .map(|ids| ids.iter().flat_map(|&f| files[f].materials.iter().cloned()).collect())
            .unwrap_or_default();
        let map = mats.iter().enumerate().map(|(k, m)| (m.name.clone(), k)).collect();
        Ok((mats, map))
    })
    .map_err(|e| line_err(path, reader.line(), e))?;

    // Group the models' meshes by material, in order of first use.
    let mut keys: Vec<Option<usize>> = Vec::new();
    for m in &models {
        if !keys.contains(&m.mesh.material_id) {
            keys.push(m.mesh.material_id);
        }
    }
    let mut parts = Vec::new();
    let mut skipped = 0;
    for key in keys {
        let meshes: Vec<&tobj::Mesh> =
            models.iter().map(|m| &m.mesh).filter(|m| m.material_id == key).collect();
        let (arrays, dropped) = arrays(&meshes, &mut warnings);
        skipped += dropped;
        if arrays.triangles.is_empty() {
            continue;
        }
        let (name, material, maps) = match key.and_then(|g| origin.get(g)) {
            Some(&(f, m)) => {
                let (mat, maps) = mtl::material(&files[f], m, &mut warnings)
                    .map_err(|e| SceneError::file(path, e.to_string()))?;
                (mat.id.clone(), mat, maps)
            }
            None => ("(none)".to_string(), mtl::default_material(at(path, 0)), Vec::new()),
        };
        parts.push(Part { name, arrays: Arc::new(arrays), material, maps });
    }
    if skipped > 0 {
        warnings.push(Warning { loc: own(0), message: format!("{skipped} degenerate triangle(s) skipped") });
    }
    if parts.is_empty() {
        return Err(SceneError::file(path, "the file has no faces with area"));
    }
    Ok(ObjModel { file: path.to_path_buf(), parts, warnings })
}

/// One part's arrays from tobj's meshes; also the number of degenerate
/// triangles dropped. Normals and texture coordinates are kept only when
/// every vertex has them.
fn arrays(meshes: &[&tobj::Mesh], warnings: &mut Vec<Warning>) -> (MeshArrays, usize) {
    let mut out = MeshArrays::default();
    let (mut normals, mut uvs) = (Some(Vec::new()), Some(Vec::new()));
    let mut skipped = 0;
    for m in meshes {
        let base = out.positions.len() as u32;
        let n = m.positions.len() / 3;
        out.positions.extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        for t in m.indices.chunks_exact(3) {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                skipped += 1;
            } else {
                out.triangles.push([t[0] + base, t[1] + base, t[2] + base]);
            }
        }
        if m.normals.len() == 3 * n {
            if let Some(v) = normals.as_mut() {
                v.extend(m.normals.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
            }
        } else {
            normals = None;
        }
        if m.texcoords.len() == 2 * n {
            if let Some(v) = uvs.as_mut() {
                v.extend(m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])));
            }
        } else {
            uvs = None;
        }
    }
    let any = |f: fn(&tobj::Mesh) -> bool| meshes.iter().any(|m| f(m));
    if normals.is_none() && any(|m| !m.normals.is_empty()) {
        warnings.push(Warning {
            loc: own(0),
            message: "some faces have normals and some not; normals are computed instead".into(),
        });
    }
    if uvs.is_none() && any(|m| !m.texcoords.is_empty()) {
        warnings.push(Warning {
            loc: own(0),
            message: "some faces have texture coordinates and some not; none are used".into(),
        });
    }
    out.normals = normals;
    out.uvs = uvs;
    (out, skipped)
}

/// A byte reader that counts the lines handed out, so an error from tobj,
/// which names no line, can be placed: tobj reads line by line and stops at
/// the first error, so the last line read is the one at fault.
pub(crate) struct CountingReader<'a> {
    bytes: &'a [u8],
    pos: usize,
    newlines: usize,
}

impl<'a> CountingReader<'a> {
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        CountingReader { bytes, pos: 0, newlines: 0 }
    }

    /// The 1-based line of the last byte read.
    pub(crate) fn line(&self) -> u32 {
        let open = self.pos > 0 && self.bytes[self.pos - 1] != b'\n';
        (self.newlines + usize::from(open)) as u32
    }
}

impl Read for CountingReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.bytes.len() - self.pos);
        buf[..n].copy_from_slice(&self.bytes[self.pos..self.pos + n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for CountingReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.bytes[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        let end = (self.pos + amt).min(self.bytes.len());
        self.newlines += self.bytes[self.pos..end].iter().filter(|&&b| b == b'\n').count();
        self.pos = end;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load_text(obj: &str) -> Result<ObjModel, SceneError> {
        let dir = tempfile::tempdir().expect("a temporary folder");
        let p = dir.path().join("m.obj");
        std::fs::write(&p, obj).expect("write");
        load(&p)
    }

    #[test]
    fn tobj_errors_get_their_line() {
        let e = load_text("v 0 0 0\nv 1 0 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err().to_string();
        assert!(e.contains("line 2: scaling (w) by zero"), "{e}");
    }

    #[test]
    fn counting_reader_counts_lines_read() {
        let mut r = CountingReader::new(b"a\nbb\nc");
        let mut s = String::new();
        r.read_line(&mut s).unwrap();
        assert_eq!(r.line(), 1);
        r.read_line(&mut s).unwrap();
        r.read_line(&mut s).unwrap();
        assert_eq!((r.line(), s.as_str()), (3, "a\nbb\nc"));
    }

    #[test]
    fn faces_without_material_get_the_default_and_parts_merge() {
        let m = load_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n").expect("loads");
        assert_eq!((m.parts.len(), m.parts[0].name.as_str()), (1, "(none)"));
        assert!(!m.has_normals() && m.parts[0].arrays.uvs.is_none());
        assert_eq!(m.merged().triangles, [[0, 1, 2], [1, 3, 2]]);
    }
}
