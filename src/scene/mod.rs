//! Scene loading: formats and the scene description.

pub mod ply;
