//! luster-core: what every layer of luster may use — geometric maths, safe
//! file access with size limits, image buffers, loaders and writers, and tone
//! mapping.
//!
//! Nothing here knows about scenes, shaders or rendering.
#![warn(missing_docs)]

pub mod file;
pub mod image;
pub mod math;
pub mod memory;
pub mod text;
pub mod tonemap;
pub mod uri;
