//! The PLY header: the magic line, the vertex and face layout luster needs,
//! and the declared element counts checked against the file's size before
//! anything is allocated.

use std::fs::File;
use std::io::{BufRead, BufReader, ErrorKind};
use std::path::Path;

use ply_rs_bw::parser::ParseError;
use ply_rs_bw::ply::{ElementDef, Encoding, Header, PropertyType, ScalarType};

use super::PlyError;

/// Refuses files that do not start with `ply` before the header parser sees
/// them, so a JPEG or an OBJ gets a plain "not a PLY file".
pub(super) fn check_magic(reader: &mut BufReader<File>, path: &Path) -> Result<(), PlyError> {
    let start = reader.fill_buf().map_err(|source| PlyError::Io { path: path.to_owned(), source })?;
    match start {
        [b'p', b'l', b'y', b'\n' | b'\r' | b' ' | b'\t', ..] => Ok(()),
        _ => Err(PlyError::NotPly { path: path.to_owned() }),
    }
}

pub(super) fn header_error(path: &Path, e: &ParseError) -> PlyError {
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
pub(super) fn one_sentence(e: &ParseError) -> String {
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
pub(super) struct Layout {
    pub(super) normals: bool,
    pub(super) uvs: bool,
}

/// Largest PLY file accepted: far beyond the course's largest meshes, and a
/// bound on what a wrong path (a device, a disk image) can make us read.
pub const MAX_PLY_BYTES: u64 = 8 << 30;

pub(super) const UV_NAMES: [(&str, &str); 4] =
    [("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t")];

impl Layout {
    pub(super) fn of(header: &Header, path: &Path) -> Result<Self, PlyError> {
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

pub(super) const INDEX_NAMES: [&str; 2] = ["vertex_indices", "vertex_index"];

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
pub(super) fn check_counts(header: &Header, available: u64, path: &Path) -> Result<(), PlyError> {
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
