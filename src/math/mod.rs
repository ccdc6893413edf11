//! Geometric maths on top of glam: rays, bounding boxes and affine transforms.
//!
//! Points, directions and normals are all `Vec3`; the difference lives in
//! [`Transform`], whose `point`, `vector` and `normal` methods are the only way
//! the renderer moves them between spaces, so a normal can never be moved with
//! the matrix meant for points.

mod aabb;
mod ray;
mod transform;

pub use aabb::Aabb;
pub use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec3A, Vec4};
pub use ray::Ray;
pub use transform::Transform;

/// Builds an orthonormal basis around `n` (Duff et al. 2017, "Building an
/// Orthonormal Basis, Revisited"): no branches on the hot path, no singularity.
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        for n in [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(1.0, 2.0, -3.0).normalize(),
            Vec3::new(0.0, 0.0, -1.0 + 1e-7).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-5);
            assert!((b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5 && t.dot(b).abs() < 1e-5);
        }
    }
}
