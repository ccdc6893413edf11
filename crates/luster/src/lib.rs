//! luster: a ray tracer whose heart is a procedural shading language.
//!
//! The flow of data follows the flow of a render, and each stage is a crate:
//!
//! ```text
//! scene file ─parse─▶ scene::Description ─build─▶ render::Scene ─▶ integrator ─▶ film ─▶ image files
//! (XML/JSON/PLY/OBJ)  (plain data + locations)    (BVH, lights, Sync)                (PNG/EXR/HDR)
//! ```
//!
//! `luster-core` (maths, files, images, tone mapping) ← `luster-shading` (the
//! Lua language, noise) ← `luster-scene` (readers and the description) ←
//! `luster-render` (the renderer) ← `luster-qa` (conformance, metrics) ←
//! this crate: the `luster` program's watch server, cluster renders and
//! benchmark, and one place that re-exports every layer's modules for
//! programs that embed luster.
#![warn(missing_docs)]

pub mod bench;
pub mod cluster;
pub mod denoise;
pub mod watch;

pub use luster_core::{file, image, math, memory, text, tonemap};
pub use luster_qa::{conformance, fuzzing, metrics, report};
pub use luster_render::{accel, bsdf, film, geometry, integrator, light, material, render, texture, volume};
pub use luster_scene as scene;
pub use luster_shading::{noise, shader};
