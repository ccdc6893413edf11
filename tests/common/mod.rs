//! What the integration tests share.

use std::path::PathBuf;

/// The course folder beside the repository, when it is there.
///
/// Without it a golden test cannot run. On a developer's machine it says so
/// and skips; on CI (`CI=true`, as every CI service sets it) a missing folder
/// is a broken checkout, and the test fails rather than pass unseen.
#[allow(dead_code)] // the golden tests use it, the others do not
pub fn course_root(what: &str) -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/ceng795");
    if root.is_dir() {
        return Some(root);
    }
    let on_ci = std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1");
    assert!(
        !on_ci,
        "CI=true but {} is missing, so the {what} golden images cannot be checked",
        root.display()
    );
    eprintln!("skipped: {} is absent, so the {what} golden images were not checked", root.display());
    None
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
