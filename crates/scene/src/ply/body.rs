//! The PLY body: elements read one at a time with ply-rs-bw's typed
//! per-element API into small structs, so a face goes straight into the
//! triangle list without a map or a payload vector in between.

use std::fs::File;
use std::io::{self, BufRead, BufReader, ErrorKind};
use std::path::Path;

use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{BeginList, ElementDef, Encoding, PropertyAccess, PropertyAccessResult};

use super::header::{one_sentence, INDEX_NAMES};
use super::PlyError;

/// The body of the file, read one element at a time.
pub(super) struct Body<'a> {
    pub(super) reader: BufReader<File>,
    pub(super) encoding: Encoding,
    /// The next ASCII line number; `None` for binary files.
    pub(super) line: Option<usize>,
    pub(super) text: String,
    pub(super) path: &'a Path,
}

impl Body<'_> {
    /// Reads every element of `def` as an `E` and hands it to `each` with its
    /// number and (ASCII) line.
    pub(super) fn read<E: PropertyAccess>(
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
pub(super) struct Vertex {
    pub(super) position: [f32; 3],
    pub(super) normal: [f32; 3],
    pub(super) uv: [f32; 2],
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
pub(super) struct Face {
    pub(super) signed: Vec<i32>,
    pub(super) unsigned: Vec<u32>,
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
pub(super) struct Ignored;

impl PropertyAccess for Ignored {
    fn new() -> Self {
        Ignored
    }
}
