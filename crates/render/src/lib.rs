//! luster-render: builds an immutable, `Sync` render scene from a scene
//! description and renders it.
//!
//! ```text
//! luster_scene::Description ─build─▶ render::Scene ─▶ integrator ─▶ film ─▶ image files
//!                                    (BVH, lights, Sync)
//! ```
//!
//! - [`accel`], [`geometry`]: the two-level BVH and the shapes in it.
//! - [`bsdf`], [`material`]: how surfaces scatter light.
//! - [`light`], [`texture`], [`volume`]: lights, textures, volumes.
//! - [`integrator`]: the recursive (Whitted) ray tracer and the path tracer.
//! - [`film`]: linear radiance per pixel and the files written from it.
//! - [`render`]: the render scene, camera, sampler and the tile loop.
#![warn(missing_docs)]

pub mod accel;
pub mod bsdf;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod render;
pub mod texture;
pub mod volume;

/// Geometric maths, from `luster-core`.
pub use luster_core::math;
