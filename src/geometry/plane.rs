//! An infinite plane. It has no bounding box, so the render scene keeps planes
//! beside the BVH and tests them directly.

use crate::math::{Ray, Vec3};

/// A plane through `point` with unit `normal`, in world space.
#[derive(Clone, Copy, Debug)]
pub struct Plane {
    /// A point on the plane.
    pub point: Vec3,
    /// Unit normal.
    pub normal: Vec3,
}

impl Plane {
    /// The `t` in `(t_min, t_max)` where the ray meets the plane.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let denom = self.normal.dot(ray.d);
        if denom == 0.0 {
            return None;
        }
        let t = self.normal.dot(self.point - ray.o) / denom;
        (t > t_min && t < t_max).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_ray_misses_and_facing_ray_hits() {
        let p = Plane { point: Vec3::new(0.0, -1.0, 0.0), normal: Vec3::Y };
        assert!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::X), 0.0, f32::INFINITY).is_none());
        let t = p.intersect(&Ray::new(Vec3::ZERO, -Vec3::Y), 0.0, f32::INFINITY).unwrap();
        assert_eq!(t, 1.0);
    }
}
