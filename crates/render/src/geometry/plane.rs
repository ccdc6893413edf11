//! An infinite plane. It has no bounding box, so the render scene keeps planes
//! beside the BVH and tests them directly.

use luster_core::math::{Ray, Vec3};

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
        let num = self.normal.dot(self.point - ray.o);
        // Signs that differ, or a zero `num`, make `t = num / denom` at most
        // zero, so below any `t_min ≥ 0`: no division (a floor seen from
        // above by most shadow rays).
        if t_min >= 0.0 && ((num.to_bits() ^ denom.to_bits()) >> 31 != 0 || num == 0.0) {
            return None;
        }
        let t = num / denom;
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

    #[test]
    fn plane_behind_or_through_the_origin_is_missed() {
        let p = Plane { point: Vec3::new(0.0, -1.0, 0.0), normal: Vec3::Y };
        assert!(p.intersect(&Ray::new(Vec3::ZERO, Vec3::Y), 0.0, f32::INFINITY).is_none());
        let on = Ray::new(Vec3::new(0.0, -1.0, 0.0), -Vec3::Y);
        assert!(p.intersect(&on, 0.0, f32::INFINITY).is_none());
        // A negative `t_min` still finds `t = 0` and the plane behind.
        assert_eq!(p.intersect(&on, -1.0, f32::INFINITY), Some(0.0));
        let t = p.intersect(&Ray::new(Vec3::ZERO, Vec3::Y), -2.0, f32::INFINITY);
        assert_eq!(t, Some(-1.0));
    }
}
