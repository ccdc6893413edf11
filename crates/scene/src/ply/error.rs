//! What can be wrong with a PLY file, as one-sentence errors naming the file.

use std::io;
use std::path::PathBuf;

/// Why a PLY file could not be read. Every message names the file.
#[derive(thiserror::Error, Debug)]
pub enum PlyError {
    /// The file could not be opened or read.
    #[error("cannot read PLY file {}: {}", path.display(), luster_core::file::io_reason(source))]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: io::Error,
    },
    /// The path is not a regular file of acceptable size (a folder, a FIFO, a
    /// device, a file over the cap).
    #[error("cannot read PLY file {}: {why}", path.display())]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// Why, as a sentence fragment.
        why: String,
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
