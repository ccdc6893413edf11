//! The local shading frame: `+z` the shading normal, in which every
//! scattering model evaluates and samples directions.

use luster_core::math::{orthonormal_basis, Vec3};

/// An orthonormal frame around a shading normal.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Frame {
    /// The world's axes.
    pub const AXES: Frame = Frame { t: Vec3::X, b: Vec3::Y, n: Vec3::Z };

    /// The frame whose `+z` is the unit normal `n`.
    #[inline]
    pub fn new(n: Vec3) -> Frame {
        let (t, b) = orthonormal_basis(n);
        Frame { t, b, n }
    }

    /// A world direction in local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// A local direction in world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}
