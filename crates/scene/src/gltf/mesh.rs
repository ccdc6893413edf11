//! glTF meshes: each primitive's attributes and indices read into a
//! [`MeshArrays`], with strips and fans triangulated.
//!
//! | glTF | luster |
//! |---|---|
//! | `POSITION` | positions (finite values only) |
//! | `NORMAL` | smooth shading normals; without them the faces are flat, as the specification asks |
//! | `TEXCOORD_0` (floats, or normalized unsigned bytes and shorts) | texture coordinates as they are: glTF's (0, 0) is the image's top-left corner, as in luster's textures |
//! | `indices` | triangles; each index checked against the vertex count |
//! | mode `TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN` | triangles (strips alternate their winding as the specification says) |
//! | mode `POINTS`, `LINES`, `LINE_LOOP`, `LINE_STRIP` | skipped, with a warning |
//! | `TANGENT`, `TEXCOORD_1`+, `COLOR_n`, `JOINTS_n`/`WEIGHTS_n`, morph targets | not used; one warning each |
//!
//! Degenerate triangles (an index twice) are dropped with one warning.

use super::accessor::Accessors;
use super::document::at;
use super::Notes;
use crate::description::MeshArrays;
use crate::error::SceneError;
use gltf::mesh::Mode;
use gltf::Semantic;
use luster_core::math::{Vec2, Vec3};
use std::sync::Arc;

/// A primitive read: its arrays and the index of its material in the
/// document (`None`: the default material).
#[derive(Clone, Debug)]
pub struct Primitive {
    /// `meshes[m].primitives[p]`.
    pub path: String,
    /// The geometry.
    pub arrays: Arc<MeshArrays>,
    /// Index into the document's materials.
    pub material: Option<usize>,
}

/// Reads every triangle primitive of `mesh`; points and lines are skipped
/// with a warning.
pub fn read(acc: &Accessors, mesh: &gltf::Mesh, notes: &mut Notes) -> Result<Vec<Primitive>, SceneError> {
    let mut out = Vec::new();
    for prim in mesh.primitives() {
        let path = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        let mode = prim.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            notes.warn(
                &path,
                format!("{mode:?} primitives are not rendered (luster draws surfaces); skipped"),
            );
            continue;
        }
        for (semantic, _) in prim.attributes() {
            let unused = match semantic {
                Semantic::Tangents => {
                    "TANGENT attributes are not used (tangents come from the texture coordinates)"
                }
                Semantic::TexCoords(n) if n > 0 => "texture coordinate sets after TEXCOORD_0 are not used",
                Semantic::Colors(_) => "vertex colours (COLOR_n) are not used",
                Semantic::Joints(_) | Semantic::Weights(_) => {
                    "skinning (JOINTS_n, WEIGHTS_n) is not applied; meshes are drawn in their bind pose"
                }
                Semantic::Extras(_) => "application-specific attributes (_NAME) are not used",
                _ => continue,
            };
            notes.once(&path, unused);
        }
        if prim.morph_targets().len() > 0 {
            notes.once(&path, "morph targets are not applied; meshes are drawn in their base shape");
        }
        let pos_acc = prim
            .get(&Semantic::Positions)
            .ok_or_else(|| at(acc.file, format!("{path}.attributes"), "the primitive has no POSITION"))?;
        let positions: Vec<Vec3> =
            acc.floats::<3>(&pos_acc, "POSITION")?.into_iter().map(Vec3::from).collect();
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(at(
                acc.file,
                format!("accessors[{}]", pos_acc.index()),
                format!("vertex {i} is not a finite position"),
            ));
        }
        let n = positions.len();
        let same_count = |a: &gltf::Accessor, what: &str| -> Result<(), SceneError> {
            if a.count() == n {
                Ok(())
            } else {
                Err(at(
                    acc.file,
                    format!("accessors[{}]", a.index()),
                    format!("{what} has {} elements but POSITION has {n}", a.count()),
                ))
            }
        };
        let normals = match prim.get(&Semantic::Normals) {
            Some(a) => {
                same_count(&a, "NORMAL")?;
                let v: Vec<Vec3> = acc.floats::<3>(&a, "NORMAL")?.into_iter().map(Vec3::from).collect();
                if let Some(i) = v.iter().position(|n| !n.is_finite()) {
                    return Err(at(
                        acc.file,
                        format!("accessors[{}]", a.index()),
                        format!("normal {i} is not finite"),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        let uvs = match prim.get(&Semantic::TexCoords(0)) {
            Some(a) => {
                same_count(&a, "TEXCOORD_0")?;
                let v: Vec<Vec2> = acc.floats::<2>(&a, "TEXCOORD_0")?.into_iter().map(Vec2::from).collect();
                if let Some(i) = v.iter().position(|t| !t.is_finite()) {
                    return Err(at(
                        acc.file,
                        format!("accessors[{}]", a.index()),
                        format!("texture coordinate {i} is not finite"),
                    ));
                }
                Some(v)
            }
            None => None,
        };
        let (indices, index_path) = match prim.indices() {
            Some(a) => {
                let ix = acc.indices(&a)?;
                if let Some(bad) = ix.iter().find(|&&i| i as usize >= n) {
                    return Err(at(
                        acc.file,
                        format!("accessors[{}]", a.index()),
                        format!("index {bad} is out of range of the {n} vertices of {path}"),
                    ));
                }
                (Some(ix), format!("accessors[{}]", a.index()))
            }
            None => (None, path.clone()),
        };
        let count = indices.as_ref().map_or(n, Vec::len);
        let vertex = |k: usize| indices.as_ref().map_or(k as u32, |ix| ix[k]);
        let (triangles, degenerate) = triangulate(mode, count, vertex);
        if degenerate > 0 {
            notes.warn(&index_path, format!("{degenerate} degenerate triangle(s) skipped"));
        }
        if triangles.is_empty() {
            notes.warn(&path, "the primitive has no triangles; skipped");
            continue;
        }
        out.push(Primitive {
            path,
            arrays: Arc::new(MeshArrays { positions, normals, uvs, triangles }),
            material: prim.material().index(),
        });
    }
    Ok(out)
}

/// The triangles of `count` vertices (`vertex(k)` is the k-th) in `mode`,
/// and the number of degenerate ones left out.
fn triangulate(mode: Mode, count: usize, vertex: impl Fn(usize) -> u32) -> (Vec<[u32; 3]>, usize) {
    let corners: Box<dyn Iterator<Item = [usize; 3]>> = match mode {
        Mode::TriangleStrip => Box::new((0..count.saturating_sub(2)).map(|i| {
            // Every other triangle turns the other way, so all face alike.
            if i % 2 == 0 {
                [i, i + 1, i + 2]
            } else {
                [i + 1, i, i + 2]
            }
        })),
        Mode::TriangleFan => Box::new((1..count.saturating_sub(1)).map(|i| [i, i + 1, 0])),
        _ => Box::new((0..count / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2])),
    };
    let mut tris = Vec::with_capacity(match mode {
        Mode::Triangles => count / 3,
        _ => count.saturating_sub(2),
    });
    let mut degenerate = 0;
    for c in corners {
        let t = c.map(&vertex);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            degenerate += 1;
        } else {
            tris.push(t);
        }
    }
    (tris, degenerate)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_alternate_and_fans_turn_about_the_first_vertex() {
        let id = |k: usize| k as u32;
        assert_eq!(triangulate(Mode::TriangleStrip, 5, id).0, [[0, 1, 2], [2, 1, 3], [2, 3, 4]]);
        assert_eq!(triangulate(Mode::TriangleFan, 5, id).0, [[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
        assert_eq!(triangulate(Mode::Triangles, 7, id).0, [[0, 1, 2], [3, 4, 5]]);
        let ix = [0u32, 1, 1, 2, 3, 4];
        assert_eq!(triangulate(Mode::Triangles, 6, |k| ix[k]), (vec![[2, 3, 4]], 1));
    }
}
