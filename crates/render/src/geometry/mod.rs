//! Render-side shapes: triangle meshes (over a BVH), spheres, ellipsoids and
//! planes, each intersected in its own object space.

pub mod ellipsoid;
pub mod mesh;
pub mod plane;
pub mod sphere;

pub use ellipsoid::Ellipsoid;
pub use mesh::Mesh;
pub use plane::Plane;
pub use sphere::Sphere;
