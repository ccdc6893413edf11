//! Render-side shapes: triangle meshes (over a BVH), spheres and planes, each
//! intersected in its own object space.

pub mod mesh;
pub mod plane;
pub mod sphere;

pub use mesh::Mesh;
pub use plane::Plane;
pub use sphere::Sphere;
