//! The one error type of scene loading: a sentence that says which file and
//! which element (or line) is wrong.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a scene file something is: the line when the format has lines we
/// can recover (XML), and always the element path (`Scene/Objects/Mesh[id=3]/Faces`).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Loc {
    /// 1-based line, if known.
    pub line: Option<u32>,
    /// The element path from the root.
    pub path: String,
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "line {l}, {}", self.path),
            None => write!(f, "{}", self.path),
        }
    }
}

/// A scene could not be loaded. Displayed as `file: location: message`.
#[derive(Debug, thiserror::Error)]
pub struct SceneError {
    /// The file at fault (the scene, or a PLY it references).
    pub file: PathBuf,
    /// The element or line, when known.
    pub loc: Option<Loc>,
    /// What is wrong, as a sentence fragment.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.loc {
            Some(loc) => write!(f, "{}: {}: {}", self.file.display(), loc, self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl SceneError {
    /// An error at a location in a file.
    pub fn at(file: &Path, loc: &Loc, message: impl Into<String>) -> Self {
        SceneError { file: file.to_path_buf(), loc: Some(loc.clone()), message: message.into() }
    }

    /// An error about a whole file.
    pub fn file(file: &Path, message: impl Into<String>) -> Self {
        SceneError { file: file.to_path_buf(), loc: None, message: message.into() }
    }
}

/// Something the loader accepted but a user should know about: an element the
/// renderer does not support yet, a value it corrected, an unknown attribute.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// Where.
    pub loc: Loc,
    /// What.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.loc, self.message)
    }
}

/// A token of a file for an error message: quoted when it looks like a word
/// or a number, otherwise only its length (see [`luster_core::text::shown_token`]).
pub use luster_core::text::shown_token;
