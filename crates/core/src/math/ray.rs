//! A ray: origin and (not necessarily unit) direction.

use glam::Vec3;

/// A ray `o + t d`. Directions of camera and secondary rays are unit length;
/// rays moved into an object's space by a transform keep the scaled length so
/// that `t` stays comparable across spaces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: Vec3,
    /// Direction.
    pub d: Vec3,
}

impl Ray {
    /// A ray from `o` along `d`.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Self {
        Ray { o, d }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}
