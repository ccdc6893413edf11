//! Acceleration structures: a binned-SAH BVH and the triangle-mesh accelerator built on it.
//!
//! - [`Bvh`] knows only primitive boxes. It is generic over what a leaf holds:
//!   traversal hands the caller leaf ranges in a closure, so the same tree type
//!   serves triangles inside a mesh and instances or spheres at the top level,
//!   with the leaf test inlined either way. It is built as a binary binned-SAH
//!   tree (`bvh_build`, private) and collapsed into 4-wide nodes for
//!   traversal.
//! - [`MeshAccel`] is a `Bvh` over a triangle mesh plus the triangles copied in
//!   leaf order, intersected with the watertight test of [`triangle`].
//!
//! ```
//! use luster_render::accel::MeshAccel;
//! use luster_render::math::{Ray, Vec3};
//!
//! let positions = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
//! let mesh = MeshAccel::build(&positions, &[[0, 1, 2]]);
//! let hit = mesh.intersect(&Ray::new(Vec3::new(0.0, 0.0, 2.0), -Vec3::Z), 0.0, f32::INFINITY);
//! assert_eq!(hit.map(|h| (h.t, h.prim)), Some((2.0, 0)));
//! ```

pub mod bvh;
mod bvh_build;
pub mod mesh_accel;
pub mod tri_block;
pub mod triangle;

pub use bvh::Bvh;
pub use mesh_accel::{MeshAccel, TriHit};
