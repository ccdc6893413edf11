//! What the golden-image tests share.

use std::path::PathBuf;

/// The course folder beside the repository, when it is there.
pub fn course_root() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/ceng795");
    root.is_dir().then_some(root)
}
