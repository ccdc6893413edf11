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
//! into small structs implementing [`PropertyAccess`], so a face goes straight
//! into the triangle list without a map or a payload vector in between.

use std::fs::File;
use std::io::{self, BufRead, BufReader, ErrorKind, Seek};
use std::path::Path;

mod error;

pub use error::PlyError;
use ply_rs_bw::parser::{ParseError, Parser, Reader};
use ply_rs_bw::ply::{
    BeginList, ElementDef, Encoding, Header, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};

use crate::math::{Vec2, Vec3};

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
    let (file, file_len) = crate::scene::file::open_regular(path, MAX_PLY_BYTES)
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

/// Refuses files that do not start with `ply` before the header parser sees
/// them, so a JPEG or an OBJ gets a plain "not a PLY file".
fn check_magic(reader: &mut BufReader<File>, path: &Path) -> Result<(), PlyError> {
    let start = reader.fill_buf().map_err(|source| PlyError::Io { path: path.to_owned(), source })?;
    match start {
        [b'p', b'l', b'y', b'\n' | b'\r' | b' ' | b'\t', ..] => Ok(()),
        _ => Err(PlyError::NotPly { path: path.to_owned() }),
    }
}

fn header_error(path: &Path, e: &ParseError) -> PlyError {
    if e.kind() == ErrorKind::InvalidData && e.line().is_none() {
        // Non-UTF-8 bytes inside the header come through as an I/O error.
        return PlyError::Header {
            path: path.to_owned(),
            line: None,
            message: "it contains bytes that are not text before 'end_header'".into(),
        };
    }
    PlyError::Header { path: path.to_owned(), line: e.line(), message: one_sentence(e) }
}

/// ply-rs-bw's messages span several lines and start with "Line N: "; the
/// line goes into our own field, and the rest is folded onto one line.
fn one_sentence(e: &ParseError) -> String {
    let text = e.to_string();
    let text = match e.line() {
        Some(line) => text.strip_prefix(&format!("Line {line}: ")).unwrap_or(&text).to_owned(),
        None => text,
    };
    let folded = text.split_whitespace().collect::<Vec<_>>().join(" ");
    folded.trim_end_matches(['.', ',']).to_owned()
}

/// What the vertex element carries besides positions (checked in the header,
/// so the body readers need no further type checks).
struct Layout {
    normals: bool,
    uvs: bool,
}

/// Largest PLY file accepted: far beyond the course's largest meshes, and a
/// bound on what a wrong path (a device, a disk image) can make us read.
pub const MAX_PLY_BYTES: u64 = 8 << 30;

const UV_NAMES: [(&str, &str); 4] =
    [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

impl Layout {
    fn of(header: &Header, path: &Path) -> Result<Self, PlyError> {
        let missing_element = |element| PlyError::MissingElement { path: path.to_owned(), element };
        let vertex = header.elements.get("vertex").ok_or_else(|| missing_element("vertex"))?;
        let face = header.elements.get("face").ok_or_else(|| missing_element("face"))?;

        // A float property: Ok(true) if present with a usable type.
        let float = |name: &str| -> Result<bool, PlyError> {
            match vertex.properties.get(name).map(|p| &p.data_type) {
                None => Ok(false),
                Some(PropertyType::Scalar(ScalarType::Float | ScalarType::Double)) => Ok(true),
                Some(other) => Err(PlyError::BadPropertyType {
                    path: path.to_owned(),
                    element: "vertex",
                    property: name.to_owned(),
                    found: type_name(other),
                    expected: "'float' or 'double'",
                }),
            }
        };
        for axis in ["x", "y", "z"] {
            if !float(axis)? {
                return Err(PlyError::MissingProperty {
                    path: path.to_owned(),
                    element: "vertex",
                    property: axis,
                });
            }
        }
        let normals = float("nx")? & float("ny")? & float("nz")?;
        let mut uvs = false;
        for (u, v) in UV_NAMES {
            uvs |= float(u)? & float(v)?;
        }

        let (name, list) = INDEX_NAMES
            .iter()
            .find_map(|&n| face.properties.get(n).map(|p| (n, &p.data_type)))
            .ok_or(PlyError::MissingProperty {
                path: path.to_owned(),
                element: "face",
                property: "vertex_indices (or vertex_index)",
            })?;
        match list {
            PropertyType::List(count, index) if is_integer(count) && is_integer(index) => {}
            other => {
                return Err(PlyError::BadPropertyType {
                    path: path.to_owned(),
                    element: "face",
                    property: name.to_owned(),
                    found: type_name(other),
                    expected: "a list of integers",
                })
            }
        }
        Ok(Layout { normals, uvs })
    }
}

const INDEX_NAMES: [&str; 2] = ["vertex_indices", "vertex_index"];

fn is_integer(t: &ScalarType) -> bool {
    !matches!(t, ScalarType::Float | ScalarType::Double)
}

fn scalar_name(t: &ScalarType) -> &'static str {
    match t {
        ScalarType::Char => "char",
        ScalarType::UChar => "uchar",
        ScalarType::Short => "short",
        ScalarType::UShort => "ushort",
        ScalarType::Int => "int",
        ScalarType::UInt => "uint",
        ScalarType::Float => "float",
        ScalarType::Double => "double",
    }
}

fn type_name(t: &PropertyType) -> String {
    match t {
        PropertyType::Scalar(s) => scalar_name(s).to_owned(),
        PropertyType::List(count, item) => {
            format!("list {} {}", scalar_name(count), scalar_name(item))
        }
    }
}

fn scalar_size(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes one element can occupy: binary scalars have fixed sizes
/// and a list at least its count; in ASCII every value is at least one digit
/// and one separator, and every element at least a line break.
fn min_element_bytes(def: &ElementDef, encoding: Encoding) -> u64 {
    let props = def.properties.values();
    match encoding {
        Encoding::Ascii => (2 * def.properties.len() as u64).max(1),
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => props
            .map(|p| match &p.data_type {
                PropertyType::Scalar(s) | PropertyType::List(s, _) => scalar_size(s),
            })
            .sum(),
    }
}

/// Checks the declared counts against the bytes after the header, so a
/// corrupt or hostile header cannot make us allocate or loop for billions of
/// elements that are not there.
fn check_counts(header: &Header, available: u64, path: &Path) -> Result<(), PlyError> {
    // An ASCII file may omit the final line break.
    let slack = u128::from(header.encoding == Encoding::Ascii);
    let mut needed = 0u128;
    for def in header.elements.values() {
        // No overflow: a product is below 2^128 - 2^65 and `needed` stays
        // below 2^64 until it fails the test.
        needed =
            needed.saturating_add(def.count as u128 * u128::from(min_element_bytes(def, header.encoding)));
        if needed > u128::from(available) + slack {
            return Err(PlyError::CountTooLarge {
                path: path.to_owned(),
                element: def.name.clone(),
                count: def.count,
                needed,
                available,
            });
        }
    }
    Ok(())
}

/// The body of the file, read one element at a time.
struct Body<'a> {
    reader: BufReader<File>,
    encoding: Encoding,
    /// The next ASCII line number; `None` for binary files.
    line: Option<usize>,
    text: String,
    path: &'a Path,
}

impl Body<'_> {
    /// Reads every element of `def` as an `E` and hands it to `each` with its
    /// number and (ASCII) line.
    fn read<E: PropertyAccess>(
        &mut self,
        def: &ElementDef,
        mut each: impl FnMut(usize, Option<usize>, E) -> Result<(), PlyError>,
    ) -> Result<(), PlyError> {
        let parser = Parser::<E>::new();
        let binary = self.encoding != Encoding::Ascii;
        if binary && def.properties.is_empty() {
            return Ok(()); // zero bytes each; nothing to read
        }
        for index in 0..def.count {
            let line = self.line;
            let element = match self.encoding {
                Encoding::Ascii => {
                    self.text.clear();
                    match self.reader.read_line(&mut self.text) {
                        Ok(0) => Err(io::Error::from(ErrorKind::UnexpectedEof).into()),
                        Ok(_) => parser.read_ascii_element(&self.text, def),
                        Err(e) => Err(e.into()),
                    }
                }
                Encoding::BinaryLittleEndian => parser.read_little_endian_element(&mut self.reader, def),
                Encoding::BinaryBigEndian => parser.read_big_endian_element(&mut self.reader, def),
            };
            let element = element.map_err(|e| PlyError::Body {
                path: self.path.to_owned(),
                element: def.name.clone(),
                index,
                line,
                message: if e.kind() == ErrorKind::UnexpectedEof {
                    format!(
                        "the file ends before the {} declared '{}' elements (truncated?)",
                        def.count, def.name
                    )
                } else if e.kind() == ErrorKind::InvalidData && binary {
                    one_sentence(&e)
                } else if e.kind() == ErrorKind::InvalidData {
                    "the line is not valid UTF-8 text".to_owned()
                } else {
                    one_sentence(&e)
                },
            })?;
            each(index, line, element)?;
            self.line = line.map(|l| l + 1);
        }
        Ok(())
    }
}

/// One vertex, filled by ply-rs-bw's typed setters.
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
}

impl Vertex {
    fn set(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.position[0],
            "y" => &mut self.position[1],
            "z" => &mut self.position[2],
            "nx" => &mut self.normal[0],
            "ny" => &mut self.normal[1],
            "nz" => &mut self.normal[2],
            "u" | "s" | "texture_u" | "texture_s" => &mut self.uv[0],
            "v" | "t" | "texture_v" | "texture_t" => &mut self.uv[1],
            _ => return PropertyAccessResult::Ignored,
        };
        *slot = value;
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex { position: [0.0; 3], normal: [0.0; 3], uv: [0.0; 2] }
    }
    fn set_float(&mut self, name: &str, value: f32) -> PropertyAccessResult {
        self.set(name, value)
    }
    fn set_double(&mut self, name: &str, value: f64) -> PropertyAccessResult {
        // Out-of-range doubles become infinite here and are refused later.
        self.set(name, value as f32)
    }
}

/// One face's index list. Signed lists land in `signed`, unsigned ones in
/// `unsigned`; 32-bit lists are filled in place by the parser.
#[derive(Default)]
struct Face {
    signed: Vec<i32>,
    unsigned: Vec<u32>,
}

fn is_index_list(name: &str) -> bool {
    INDEX_NAMES.contains(&name)
}

impl Face {
    fn take_signed(&mut self, name: &str, values: impl Iterator<Item = i32>) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        self.signed.clear();
        self.signed.extend(values);
        PropertyAccessResult::Set
    }
    fn take_unsigned(&mut self, name: &str, values: impl Iterator<Item = u32>) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        self.unsigned.clear();
        self.unsigned.extend(values);
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Face::default()
    }
    fn begin_list_int(&mut self, name: &str, _len: usize) -> BeginList<'_, i32> {
        if is_index_list(name) {
            BeginList::Fill(&mut self.signed)
        } else {
            BeginList::UseSetter
        }
    }
    fn begin_list_uint(&mut self, name: &str, _len: usize) -> BeginList<'_, u32> {
        if is_index_list(name) {
            BeginList::Fill(&mut self.unsigned)
        } else {
            BeginList::UseSetter
        }
    }
    fn set_list_char(&mut self, name: &str, value: Vec<i8>) -> PropertyAccessResult {
        self.take_signed(name, value.into_iter().map(i32::from))
    }
    fn set_list_short(&mut self, name: &str, value: Vec<i16>) -> PropertyAccessResult {
        self.take_signed(name, value.into_iter().map(i32::from))
    }
    fn set_list_uchar(&mut self, name: &str, value: Vec<u8>) -> PropertyAccessResult {
        self.take_unsigned(name, value.into_iter().map(u32::from))
    }
    fn set_list_ushort(&mut self, name: &str, value: Vec<u16>) -> PropertyAccessResult {
        self.take_unsigned(name, value.into_iter().map(u32::from))
    }
}

/// An element (or a property) nobody asked for: read past and dropped.
struct Ignored;

impl PropertyAccess for Ignored {
    fn new() -> Self {
        Ignored
    }
}

#[cfg(test)]
mod tests;
