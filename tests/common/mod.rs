//! What the integration tests share.

use std::path::PathBuf;

/// The course folder beside the repository, when it is there.
#[allow(dead_code)] // the golden tests use it, the others do not
pub fn course_root() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/ceng795");
    root.is_dir().then_some(root)
}

/// Writes `files` (name, text) into a fresh temporary folder; returns it.
#[allow(dead_code)] // not every test crate that shares this module writes files
pub fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("a temporary folder");
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).expect("a test file");
    }
    dir
}
