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

    /// The frame whose `+z` is the unit normal `n` and whose `+x` lies along
    /// the part of `t` across `n` (any frame where that part vanishes).
    #[inline]
    pub fn with_tangent(n: Vec3, t: Vec3) -> Frame {
        let across = t - n * n.dot(t);
        let l2 = across.length_squared();
        // A tangent (nearly) along the normal says nothing about a direction
        // in the surface.
        if l2.partial_cmp(&(1e-6 * t.length_squared())) != Some(std::cmp::Ordering::Greater)
            || !l2.is_finite()
        {
            return Frame::new(n);
        }
        let t = across / l2.sqrt();
        Frame { t, b: n.cross(t), n }
    }

    /// The tangent, `+x`.
    #[inline]
    pub fn tangent(&self) -> Vec3 {
        self.t
    }

    /// The normal, `+z`.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        self.n
    }

    /// A local direction in world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}
