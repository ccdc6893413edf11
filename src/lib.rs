//! luster: a ray tracer whose heart is a procedural shading language.
//!
//! The flow of data follows the flow of a render:
//!
//! ```text
//! scene file ─parse─▶ scene::Description ─build─▶ render::Scene ─▶ integrator ─▶ film ─▶ image files
//! (XML/JSON/PLY)      (plain data + locations)    (BVH, lights, Sync)                (PNG/EXR/HDR)
//! ```
//!
//! The renderer never sees XML or JSON: [`scene`] turns either encoding of the
//! CENG795 format into one typed description that remembers where each value
//! came from, and [`render`] builds an immutable scene from it.
#![warn(missing_docs)]

pub mod accel;
pub mod bench;
pub mod bsdf;
pub mod cluster;
pub mod conformance;
pub mod film;
pub mod fuzzing;
pub mod geometry;
pub mod image;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod noise;
pub mod render;
pub mod report;
pub mod scene;
pub mod shader;
pub mod texture;
pub mod volume;
pub mod watch;
