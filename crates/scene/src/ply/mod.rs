//! PLY (Stanford polygon) triangle meshes, read with `ply-rs-bw`.
//!
//! [`read_ply`] turns a `.ply` file into a [`PlyMesh`]: positions, optional
//! per-vertex normals and texture coordinates, and triangles.
//!
//! | What                   | Supported                                                       |
//! |------------------------|-----------------------------------------------------------------|
//! | encodings              | `ascii`, `binary_little_endian`, `binary_big_endian`            |
//! | `vertex` x y z         | required; `float` or `double`                                   |
//! | `vertex` nx ny nz      | optional normals, used when all three are present               |
//! | `vertex` uv            | optional; `u v`, `s t`, `texture_u texture_v` or `texture_s texture_t` |
//! | `face` index list      | `vertex_indices` or `vertex_index`; any integer count and index types |
//! | polygons               | quads and n-gons are fan-triangulated (0,1,2), (0,2,3), ...     |
//! | anything else          | other elements and properties are read past and ignored          |
//!
//! ```text
//! ply
//! format ascii 1.0
//! element vertex 4
//! property float x
//! property float y
//! property float z
//! element face 1
//! property list uchar int vertex_indices
//! end_header
//! 0 0 0
//! 1 0 0
//! 1 1 0
//! 0 1 0
//! 4 0 1 2 3
//! ```
//!
//! Triangles with two equal indices or two vertices at the same position have
//! no area and no well-defined normal; they are dropped and counted in
//! [`PlyMesh::skipped_degenerate`].
//!
//! Every problem with the file is a [`PlyError`], never a panic: a header whose
//! element counts cannot fit in the bytes that follow it is refused before
//! anything is allocated, and out-of-range indices, short faces and non-finite
//! coordinates are reported with the element number (and line, for ASCII).
//! Element numbers in messages count from 0, like the indices in the file.
//!
//! Elements are read one at a time with ply-rs-bw's typed per-element API
//! ([`Parser::read_ascii_element`], [`Parser::read_little_endian_element`], ...)
//! into small structs implementing `PropertyAccess`, so a face goes straight
//! into the triangle list without a map or a payload vector in between.

use std::io::{BufReader, Seek};
use std::path::Path;

mod body;
mod error;
mod header;

use body::{Body, Face, Ignored, Vertex};
pub use error::PlyError;
pub use header::MAX_PLY_BYTES;
use header::{check_counts, check_magic, header_error, Layout};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::Encoding;

use luster_core::math::{Vec2, Vec3};

/// A triangle mesh read from a PLY file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlyMesh {
    /// Vertex positions, in file order.
    pub positions: Vec<Vec3>,
    /// Per-vertex normals, present when the vertex element has `nx ny nz`.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, present when the vertex element has
    /// `u v`, `s t`, `texture_u texture_v` or `texture_s texture_t`.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as indices into `positions`; polygons are fan-triangulated.
    pub triangles: Vec<[u32; 3]>,
    /// Triangles dropped because two of their vertices coincide (same index or
    /// same position).
    pub skipped_degenerate: usize,
}

/// Reads a PLY triangle mesh; see the [module documentation](self) for what
/// is supported.
pub fn read_ply(path: &Path) -> Result<PlyMesh, PlyError> {
    let io_error = |source| PlyError::Io { path: path.to_owned(), source };
    let (file, file_len) = luster_core::file::open_regular(path, MAX_PLY_BYTES)
        .map_err(|why| PlyError::Unreadable { path: path.to_owned(), why })?;
    let mut reader = Reader::new(BufReader::with_capacity(1 << 16, file));

    check_magic(reader.get_mut(), path)?;
    let header = Parser::<Ignored>::new().read_header(&mut reader).map_err(|e| header_error(path, &e))?;
    let layout = Layout::of(&header, path)?;
    let header_end = reader.get_mut().stream_position().map_err(io_error)?;
    check_counts(&header, file_len.saturating_sub(header_end), path)?;

    let vertex_count = header.elements.get("vertex").map_or(0, |e| e.count);
    let face_count = header.elements.get("face").map_or(0, |e| e.count);
    let mut body = Body {
        line: (header.encoding == Encoding::Ascii).then(|| reader.line()),
        encoding: header.encoding,
        reader: reader.into_inner(),
        text: String::new(),
        path,
    };

    // The counts were checked against the file size, so these are bounded.
    let mut mesh = PlyMesh {
        positions: Vec::with_capacity(vertex_count),
        normals: layout.normals.then(|| Vec::with_capacity(vertex_count)),
        uvs: layout.uvs.then(|| Vec::with_capacity(vertex_count)),
        triangles: Vec::with_capacity(face_count),
        skipped_degenerate: 0,
    };
    let mut polygon = Vec::<u32>::new();
    for def in header.elements.values() {
        match def.name.as_str() {
            "vertex" => body.read::<Vertex>(def, |index, line, v: Vertex| {
                if let Some(&value) = v.position.iter().find(|c| !c.is_finite()) {
                    return Err(PlyError::NonFinite { path: path.to_owned(), index, line, value });
                }
                mesh.positions.push(Vec3::from(v.position));
                if let Some(normals) = &mut mesh.normals {
                    normals.push(Vec3::from(v.normal));
                }
                if let Some(uvs) = &mut mesh.uvs {
                    uvs.push(Vec2::from(v.uv));
                }
                Ok(())
            })?,
            "face" => body.read::<Face>(def, |index, line, f: Face| {
                polygon.clear();
                let out_of_range = |vertex: i64| PlyError::IndexOutOfRange {
                    path: path.to_owned(),
                    index,
                    line,
                    vertex,
                    count: vertex_count,
                };
                for &i in &f.signed {
                    let i = u32::try_from(i).map_err(|_| out_of_range(i64::from(i)))?;
                    polygon.push(i);
                }
                polygon.extend_from_slice(&f.unsigned);
                if let Some(&bad) = polygon.iter().find(|&&i| i as usize >= vertex_count) {
                    return Err(out_of_range(i64::from(bad)));
                }
                if polygon.len() < 3 {
                    return Err(PlyError::FaceTooSmall {
                        path: path.to_owned(),
                        index,
                        line,
                        len: polygon.len(),
                    });
                }
                let first = polygon[0];
                mesh.triangles.extend(polygon[1..].windows(2).map(|w| [first, w[0], w[1]]));
                Ok(())
            })?,
            _ => body.read::<Ignored>(def, |_, _, _| Ok(()))?,
        }
    }

    // Positions are complete only now (the vertex element may follow the
    // faces), so degenerate triangles are removed in a final pass.
    let positions = &mesh.positions;
    let before = mesh.triangles.len();
    mesh.triangles.retain(|&[a, b, c]| {
        let (pa, pb, pc) = (positions[a as usize], positions[b as usize], positions[c as usize]);
        a != b && b != c && a != c && pa != pb && pb != pc && pa != pc
    });
    mesh.skipped_degenerate = before - mesh.triangles.len();
    Ok(mesh)
}

#[cfg(test)]
mod tests;
