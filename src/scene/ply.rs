//! PLY placeholder (replaced by the real loader).
#![allow(missing_docs)]
use crate::math::Vec3;
use std::path::Path;
pub struct PlyMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub skipped_degenerate: usize,
}
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct PlyError(String);
pub fn read_ply(path: &Path) -> Result<PlyMesh, PlyError> {
    Err(PlyError(format!("{}: PLY not supported yet", path.display())))
}
