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
use std::path::{Path, PathBuf};

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

/// Why a PLY file could not be read. Every message names the file.
#[derive(thiserror::Error, Debug)]
pub enum PlyError {
    /// The file could not be opened or read.
    #[error("cannot read PLY file {}: {}", path.display(), crate::scene::io_reason(source))]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: io::Error,
    },
    /// The file does not begin with the `ply` magic line.
    #[error("{} is not a PLY file: it does not begin with the line \"ply\"", path.display())]
    NotPly {
        /// The file.
        path: PathBuf,
    },
    /// The header does not follow the PLY grammar.
    #[error("malformed PLY header in {}{}: {message}", path.display(), at_line(*.line))]
    Header {
        /// The file.
        path: PathBuf,
        /// The header line, counting from 1, when known.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// The header declares more elements than the rest of the file can hold.
    #[error(
        "{} declares {count} '{element}' elements, which need at least {needed} bytes, \
         but only {available} bytes follow the header (truncated file or wrong header)",
        path.display()
    )]
    CountTooLarge {
        /// The file.
        path: PathBuf,
        /// The element whose count does not fit.
        element: String,
        /// Its declared count.
        count: usize,
        /// The fewest bytes the declared elements up to this one can occupy.
        needed: u128,
        /// The bytes after `end_header`.
        available: u64,
    },
    /// A required element (`vertex` or `face`) is absent.
    #[error("{} has no '{element}' element, so it holds no triangle mesh", path.display())]
    MissingElement {
        /// The file.
        path: PathBuf,
        /// The missing element.
        element: &'static str,
    },
    /// A required property is absent.
    #[error("element '{element}' in {} has no property {property}", path.display())]
    MissingProperty {
        /// The file.
        path: PathBuf,
        /// The element.
        element: &'static str,
        /// The property (or the accepted alternatives).
        property: &'static str,
    },
    /// A property the loader uses has a type it cannot use.
    #[error(
        "property '{property}' of element '{element}' in {} has type '{found}', but {expected} is needed",
        path.display()
    )]
    BadPropertyType {
        /// The file.
        path: PathBuf,
        /// The element.
        element: &'static str,
        /// The property.
        property: String,
        /// Its declared type, as written in a header.
        found: String,
        /// What would be accepted.
        expected: &'static str,
    },
    /// The body ends early or an element cannot be decoded.
    #[error("cannot read {element} {index}{} in {}: {message}", at_line(*.line), path.display())]
    Body {
        /// The file.
        path: PathBuf,
        /// The element name.
        element: String,
        /// The element number, counting from 0.
        index: usize,
        /// The line, for ASCII files.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {index}{} in {} has a non-finite coordinate {value}", at_line(*.line), path.display())]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// The vertex number, counting from 0.
        index: usize,
        /// The line, for ASCII files.
        line: Option<usize>,
        /// The offending value.
        value: f32,
    },
    /// A face refers to a vertex that does not exist.
    #[error(
        "face {index}{} in {} refers to vertex {vertex}, but the file has {count} vertices",
        at_line(*.line),
        path.display()
    )]
    IndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// The face number, counting from 0.
        index: usize,
        /// The line, for ASCII files.
        line: Option<usize>,
        /// The bad vertex index.
        vertex: i64,
        /// The number of vertices in the file.
        count: usize,
    },
    /// A face has fewer than three vertex indices.
    #[error(
        "face {index}{} in {} has {len} vertex indices, but a face needs at least 3",
        at_line(*.line),
        path.display()
    )]
    FaceTooSmall {
        /// The file.
        path: PathBuf,
        /// The face number, counting from 0.
        index: usize,
        /// The line, for ASCII files.
        line: Option<usize>,
        /// How many indices it has.
        len: usize,
    },
}

fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(" (line {l})")).unwrap_or_default()
}

/// Reads a PLY triangle mesh; see the [module documentation](self) for what
/// is supported.
pub fn read_ply(path: &Path) -> Result<PlyMesh, PlyError> {
    let io_error = |source| PlyError::Io { path: path.to_owned(), source };
    let file = File::open(path).map_err(io_error)?;
    let file_len = file.metadata().map_err(io_error)?.len();
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
mod tests {
    use super::*;
    use std::time::Instant;

    /// A small mesh written in any encoding: header lines after `format`,
    /// and the body as either text or raw bytes.
    fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).expect("test file is writable");
        path
    }

    fn ok(path: &Path) -> PlyMesh {
        match read_ply(path) {
            Ok(mesh) => mesh,
            Err(e) => panic!("{e}"),
        }
    }

    /// Reads `path`, expects an error, and checks that its message names the
    /// file and contains every one of `parts`.
    fn err(path: &Path, parts: &[&str]) -> PlyError {
        let e = match read_ply(path) {
            Ok(mesh) => panic!("expected an error, got {mesh:?}"),
            Err(e) => e,
        };
        let text = e.to_string();
        println!("{text}");
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("?");
        assert!(text.contains(name), "'{text}' does not name {name}");
        for part in parts {
            assert!(text.contains(part), "'{text}' does not contain '{part}'");
        }
        assert!(!text.contains('\n'), "'{text}' spans several lines");
        e
    }

    const QUAD_ASCII: &str = "ply
format ascii 1.0
comment a unit quad with normals and uvs
element vertex 4
property float x
property float y
property float z
property float nx
property float ny
property float nz
property float u
property float v
element face 1
property list uchar int vertex_indices
end_header
0 0 0 0 0 1 0 0
1 0 0 0 0 1 1 0
1 1 0 0 0 1 1 1
0 1 0 0 0 1 0 1
4 0 1 2 3
";

    /// The quad above in a binary encoding, built by hand.
    fn quad_binary(big_endian: bool) -> Vec<u8> {
        let format = if big_endian { "binary_big_endian" } else { "binary_little_endian" };
        let mut out =
            QUAD_ASCII.split("end_header\n").next().unwrap_or_default().replace("ascii", format).into_bytes();
        out.extend_from_slice(b"end_header\n");
        let f = |out: &mut Vec<u8>, v: f32| {
            out.extend(if big_endian { v.to_be_bytes() } else { v.to_le_bytes() })
        };
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            for v in [x, y, 0.0, 0.0, 0.0, 1.0, x, y] {
                f(&mut out, v);
            }
        }
        out.push(4);
        for i in 0i32..4 {
            out.extend(if big_endian { i.to_be_bytes() } else { i.to_le_bytes() });
        }
        out
    }

    fn header(vertex_props: &str, faces: &str) -> String {
        format!("ply\nformat ascii 1.0\nelement vertex 4\n{vertex_props}element face {faces}end_header\n")
    }

    #[test]
    fn ascii_quad_becomes_two_triangles_with_normals_and_uvs() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mesh = ok(&write(&dir, "quad.ply", QUAD_ASCII.as_bytes()));
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.normals, Some(vec![Vec3::Z; 4]));
        let uvs = mesh.uvs.expect("uvs");
        assert_eq!(uvs[2], Vec2::new(1.0, 1.0));
        assert_eq!(mesh.skipped_degenerate, 0);
    }

    #[test]
    fn binary_encodings_read_the_same_as_ascii() {
        let dir = tempfile::tempdir().expect("tempdir");
        let ascii = ok(&write(&dir, "a.ply", QUAD_ASCII.as_bytes()));
        let le = ok(&write(&dir, "le.ply", &quad_binary(false)));
        let be = ok(&write(&dir, "be.ply", &quad_binary(true)));
        assert_eq!(le, ascii);
        assert_eq!(be, ascii);
        let crlf = ok(&write(&dir, "crlf.ply", QUAD_ASCII.replace('\n', "\r\n").as_bytes()));
        assert_eq!(crlf, ascii);
    }

    #[test]
    fn vertex_index_name_double_coords_and_small_index_types() {
        let dir = tempfile::tempdir().expect("tempdir");
        for list in ["uchar uint", "ushort ushort", "int short", "uint8 char", "uchar uint8"] {
            let text = header(
                "property double x\nproperty double y\nproperty double z\n",
                &format!("2\nproperty list {list} vertex_index\n"),
            ) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
            let mesh = ok(&write(&dir, "vi.ply", text.as_bytes()));
            assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]], "{list}");
            assert!(mesh.normals.is_none() && mesh.uvs.is_none());
        }
    }

    #[test]
    fn uv_names_are_detected() {
        let dir = tempfile::tempdir().expect("tempdir");
        for (u, v) in UV_NAMES {
            let text = header(
                &format!("property float x\nproperty float y\nproperty float z\nproperty float {u}\nproperty float {v}\n"),
                "1\nproperty list uchar int vertex_indices\n",
            ) + "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 0.5\n4 0 1 2 3\n";
            let mesh = ok(&write(&dir, "uv.ply", text.as_bytes()));
            let uvs = mesh.uvs.expect("uvs");
            assert_eq!(uvs[3], Vec2::new(0.0, 0.5), "{u} {v}");
            assert!(mesh.normals.is_none());
        }
    }

    #[test]
    fn other_elements_and_properties_are_ignored() {
        let dir = tempfile::tempdir().expect("tempdir");
        let text = "ply
format ascii 1.0
element material 1
property uchar red
property list uchar float weights
element vertex 3
property float x
property uchar red
property float y
property float z
property float nx
element face 1
property uchar flags
property list uchar int vertex_indices
property list uchar float texcoord
element edge 2
property int vertex1
property int vertex2
end_header
7 2 0.5 0.25
0 255 0 0 9
1 255 0 0 9
0 255 1 0 9
3 3 0 1 2 6 0 0 1 0 0 1
0 1
1 2
";
        let mesh = ok(&write(&dir, "extra.ply", text.as_bytes()));
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(mesh.positions[2], Vec3::Y);
        assert!(mesh.normals.is_none(), "nx alone is not a normal");
    }

    #[test]
    fn degenerate_triangles_are_skipped_and_counted() {
        let dir = tempfile::tempdir().expect("tempdir");
        let text = header(
            "property float x\nproperty float y\nproperty float z\n",
            "4\nproperty list uchar int vertex_indices\n",
        ) + "0 0 0\n1 0 0\n1 1 0\n1 0 0\n3 0 1 2\n3 0 1 1\n3 0 1 3\n4 2 0 0 1\n";
        let mesh = ok(&write(&dir, "degenerate.ply", text.as_bytes()));
        // Kept: (0,1,2) and the quad's second half (2,0,1); dropped: (0,1,1),
        // (0,1,3) whose 1 and 3 coincide, and the quad's (2,0,0).
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [2, 0, 1]]);
        assert_eq!(mesh.skipped_degenerate, 3);
    }

    #[test]
    fn missing_file_and_non_ply_files_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let e = err(&dir.path().join("absent.ply"), &["cannot read"]);
        assert!(matches!(e, PlyError::Io { .. }));
        err(&write(&dir, "mesh.obj", b"v 0 0 0\nf 1 2 3\n"), &["not a PLY file"]);
        err(&write(&dir, "empty.ply", b""), &["not a PLY file"]);
        err(&write(&dir, "plywood.ply", b"plywood\n"), &["not a PLY file"]);
    }

    #[test]
    fn malformed_headers_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let bad_property = "ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n";
        err(&write(&dir, "typo.ply", bad_property.as_bytes()), &["malformed PLY header", "line 4"]);
        let no_end = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n";
        err(&write(&dir, "noend.ply", no_end.as_bytes()), &["malformed PLY header", "end_header"]);
        let no_format = "ply\nelement vertex 0\nend_header\n";
        err(&write(&dir, "noformat.ply", no_format.as_bytes()), &["malformed PLY header", "format"]);
        let mut binary = b"ply\nformat ascii 1.0\ncomment ".to_vec();
        binary.extend([0xff, 0xfe, 0x80, b'\n']);
        err(&write(&dir, "bytes.ply", &binary), &["malformed PLY header", "not text"]);
    }

    #[test]
    fn missing_elements_and_properties_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let no_face = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
        err(&write(&dir, "noface.ply", no_face.as_bytes()), &["no 'face' element"]);
        let no_vertex =
            "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
        err(&write(&dir, "novertex.ply", no_vertex.as_bytes()), &["no 'vertex' element"]);
        let no_z =
            header("property float x\nproperty float y\n", "0\nproperty list uchar int vertex_indices\n");
        err(&write(&dir, "noz.ply", no_z.as_bytes()), &["'vertex'", "no property z"]);
        let no_list = header(
            "property float x\nproperty float y\nproperty float z\n",
            "0\nproperty list uchar int corners\n",
        );
        err(&write(&dir, "nolist.ply", no_list.as_bytes()), &["'face'", "vertex_indices"]);
        let float_list = header(
            "property float x\nproperty float y\nproperty float z\n",
            "0\nproperty list uchar float vertex_indices\n",
        );
        err(
            &write(&dir, "floatlist.ply", float_list.as_bytes()),
            &["'vertex_indices'", "list uchar float", "list of integers"],
        );
        let int_x = header(
            "property int x\nproperty float y\nproperty float z\n",
            "0\nproperty list uchar int vertex_indices\n",
        );
        err(&write(&dir, "intx.ply", int_x.as_bytes()), &["'x'", "'int'", "'float' or 'double'"]);
    }

    #[test]
    fn absurd_counts_fail_before_allocating() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_owned();
        text.push_str(&"\0".repeat(300 - text.len()));
        let start = Instant::now();
        err(
            &write(&dir, "huge.ply", text.as_bytes()),
            &["4000000000 'vertex' elements", "48000000000 bytes", "follow the header"],
        );
        assert!(start.elapsed().as_millis() < 100);
        let ascii = header(
            "property float x\nproperty float y\nproperty float z\n",
            "18446744073709551615\nproperty list uchar int vertex_indices\n",
        ) + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n";
        err(&write(&dir, "hugeascii.ply", ascii.as_bytes()), &["18446744073709551615 'face' elements"]);
        let nothing = "ply\nformat binary_big_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nelement empty 999999999999\nend_header\n";
        // Elements without properties take no bytes in a binary file, so any
        // count is fine, and they are not looped over.
        let start = Instant::now();
        let mesh = ok(&write(&dir, "empty_elements.ply", nothing.as_bytes()));
        assert!(mesh.positions.is_empty() && mesh.triangles.is_empty());
        assert!(start.elapsed().as_millis() < 100);
    }

    #[test]
    fn truncated_bodies_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let full = quad_binary(false);
        err(
            &write(&dir, "cut.ply", &full[..full.len() - 3]),
            &["face 0", "ends before the 1 declared 'face' elements"],
        );
        let vertices_cut = &full[..full.len() - 60];
        err(&write(&dir, "cutvertex.ply", vertices_cut), &["4 'vertex' elements", "at least 128 bytes"]);
        // Long numbers so that the bytes could hold the face: the count check
        // passes and the reader meets the end of the file.
        let ascii =
            QUAD_ASCII.replace("4 0 1 2 3\n", "").replace("0 0 0 0 0 1 0 0", "0.000000000000 0 0 0 0 1 0 0");
        err(&write(&dir, "cut_ascii.ply", ascii.as_bytes()), &["face 0 (line 20)", "ends before"]);
        let short_line = QUAD_ASCII.replace("1 1 0 0 0 1 1 1", "1 1 0 0 0 1 1");
        err(&write(&dir, "shortline.ply", short_line.as_bytes()), &["vertex 2 (line 18)"]);
        let junk = QUAD_ASCII.replace("1 1 0 0 0 1 1 1", "1 1 zero 0 0 1 1 1");
        err(&write(&dir, "junk.ply", junk.as_bytes()), &["vertex 2 (line 18)"]);
    }

    #[test]
    fn bad_faces_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let out_of_range = QUAD_ASCII.replace("4 0 1 2 3", "4 0 1 2 4");
        err(
            &write(&dir, "range.ply", out_of_range.as_bytes()),
            &["face 0 (line 20)", "vertex 4", "has 4 vertices"],
        );
        let negative = QUAD_ASCII.replace("4 0 1 2 3", "3 0 -1 2");
        err(&write(&dir, "negative.ply", negative.as_bytes()), &["face 0", "vertex -1"]);
        let two = QUAD_ASCII.replace("4 0 1 2 3", "2 0 1");
        err(&write(&dir, "two.ply", two.as_bytes()), &["face 0", "2 vertex indices", "at least 3"]);
        let none = QUAD_ASCII.replace("4 0 1 2 3", "0");
        err(&write(&dir, "zero.ply", none.as_bytes()), &["0 vertex indices"]);
        let mut binary = quad_binary(false);
        let n = binary.len();
        binary[n - 4..].copy_from_slice(&100i32.to_le_bytes());
        err(&write(&dir, "range_le.ply", &binary), &["face 0 in", "vertex 100"]);
    }

    #[test]
    fn non_finite_coordinates_are_errors() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mut binary = quad_binary(true);
        let body = binary.len() - 4 * 8 * 4 - 17;
        binary[body + 32 + 4..body + 32 + 8].copy_from_slice(&f32::NAN.to_be_bytes());
        err(&write(&dir, "nan.ply", &binary), &["vertex 1 in", "non-finite", "NaN"]);
        let huge = header(
            "property double x\nproperty double y\nproperty double z\n",
            "1\nproperty list uchar int vertex_indices\n",
        ) + "0 0 0\n1 0 0\n1 1 1e300\n0 1 0\n3 0 1 2\n";
        err(&write(&dir, "inf.ply", huge.as_bytes()), &["vertex 2 (line 12)", "inf"]);
    }

    /// The course scenes, when the shared folder is present.
    fn shared(relative: &str) -> Option<PathBuf> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/ceng795").join(relative);
        if path.exists() {
            Some(path)
        } else {
            println!("skipping: {} is absent", path.display());
            None
        }
    }

    #[test]
    fn course_meshes_load() {
        let cases: &[(&str, usize, usize, bool, bool)] = &[
            ("hw1/json/akif_uslu/ton_Roosendaal_smooth_ply/mesh_1.ply", 8190, 16384, false, false),
            ("hw1/json/akif_uslu/ton_Roosendaal_smooth_ply/mesh_2.ply", 31072, 62160, false, false),
            ("hw1/json/akif_uslu/ton_Roosendaal_smooth_ply/mesh_3.ply", 78, 76, false, false),
            ("hw3/json/ply/cube.ply", 8, 12, false, false),
            ("hw4/xml/veach_ajar/models/Mesh000.ply", 23938, 47872, true, true),
            ("hw4/xml/veach_ajar/models/Mesh008.ply", 4, 2, false, true),
            ("hw4/xml/veach_ajar/models/Mesh009.ply", 39086, 78176, true, true),
            ("hw4/xml/veach_ajar/models/Mesh015_fixed.ply", 8622, 2880, true, false),
        ];
        for &(file, vertices, triangles, normals, uvs) in cases {
            let Some(path) = shared(file) else { return };
            let start = Instant::now();
            let mesh = ok(&path);
            println!(
                "{file}: {} vertices, {} triangles (+{} degenerate) in {:.1} ms",
                mesh.positions.len(),
                mesh.triangles.len(),
                mesh.skipped_degenerate,
                start.elapsed().as_secs_f64() * 1e3
            );
            assert_eq!(mesh.positions.len(), vertices, "{file}");
            assert_eq!(mesh.triangles.len() + mesh.skipped_degenerate, triangles, "{file}");
            assert_eq!(mesh.normals.is_some(), normals, "{file}");
            assert_eq!(mesh.uvs.is_some(), uvs, "{file}");
        }
    }

    #[test]
    fn every_veach_ajar_mesh_loads() {
        let Some(dir) = shared("hw4/xml/veach_ajar/models") else {
            return;
        };
        let Ok(entries) = std::fs::read_dir(&dir) else {
            return;
        };
        let mut count = 0;
        for entry in entries.flatten() {
            let path = entry.path();
            if path.extension().is_some_and(|e| e == "ply") {
                let mesh = ok(&path);
                assert!(!mesh.triangles.is_empty(), "{}", path.display());
                count += 1;
            }
        }
        assert!(count >= 17);
    }

    /// `PLY_BENCH=/tmp/mesh/bumpy_sphere_L8.ply cargo test --release -- --ignored --nocapture load_time`
    #[test]
    #[ignore = "timing; needs PLY_BENCH"]
    fn load_time() {
        let Some(path) = std::env::var_os("PLY_BENCH") else {
            return;
        };
        for _ in 0..5 {
            let start = Instant::now();
            let mesh = ok(Path::new(&path));
            println!(
                "{}: {} vertices, {} triangles in {:.1} ms",
                Path::new(&path).display(),
                mesh.positions.len(),
                mesh.triangles.len(),
                start.elapsed().as_secs_f64() * 1e3
            );
        }
    }
}
