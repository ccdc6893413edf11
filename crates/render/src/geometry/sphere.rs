//! A sphere in object space; its object's transform makes ellipsoids of it.

use luster_core::math::{Aabb, Ray, Vec2, Vec3};
use std::f32::consts::PI;

/// A sphere.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius.
    pub radius: f32,
}

impl Sphere {
    /// The two parameters, in order, where the ray's line meets the sphere,
    /// or `None` when it misses (or the direction is zero). The direction
    /// need not be unit length (rays moved into object space keep their
    /// scale so `t` is the same in both spaces). Volumes use this as the
    /// span of the solid ball.
    #[inline]
    pub fn roots(&self, ray: &Ray) -> Option<(f32, f32)> {
        let oc = ray.o - self.center;
        let a = ray.d.length_squared();
        if a == 0.0 || !a.is_finite() {
            return None;
        }
        let half_b = oc.dot(ray.d);
        // Computing c - b²/a as |oc - (oc·d/a) d|² - r² (Hearn & Baker's form, used by
        // Ray Tracing Gems ch. 7) avoids the cancellation of the textbook
        // discriminant; r² − |f|² is factored so a grazing ray loses no digits either.
        let f = (oc - ray.d * (half_b / a)).length();
        let disc = a * ((self.radius - f) * (self.radius + f));
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let c = oc.length_squared() - self.radius * self.radius;
        let q = -half_b - disc.sqrt().copysign(half_b);
        if q == 0.0 {
            // oc·d = 0 and a tangent line: both roots are where it touches.
            let t = -half_b / a;
            return Some((t, t));
        }
        let (t0, t1) = (c / q, q / a);
        Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
    }

    /// The nearest `t` in `(t_min, t_max)` where the ray meets the sphere.
    /// Always inlined: its callers are the scene's AVX2 traversals, where
    /// an out-of-line call would also spill and reload the traversal's
    /// vector registers.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        if t_min >= 0.0 && self.surely_missed(ray) {
            return None;
        }
        let (t0, t1) = self.roots(ray)?;
        if t0 > t_min && t0 < t_max {
            Some(t0)
        } else if t1 > t_min && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// Whether the ray's line surely meets the sphere at `t ≤ 0` only, or
    /// not at all, by tests far cheaper than the square roots and divisions
    /// of [`Sphere::roots`] and agreeing with them, so that skipping those
    /// changes no result for `t_min ≥ 0`.
    #[inline(always)]
    fn surely_missed(&self, ray: &Ray) -> bool {
        let oc = ray.o - self.center;
        let half_b = oc.dot(ray.d);
        let oc2 = oc.length_squared();
        // The very `c` of `roots`. Outside (`c > 0`) and moving away
        // (`half_b > 0`): there `q = −(half_b + √disc) < 0`, so both `c / q`
        // and `q / a` are negative as computed, not only exactly.
        let c = oc2 - self.radius * self.radius;
        if half_b > 0.0 && c > 0.0 {
            return true;
        }
        // The line's squared distance from the centre, `oc² − half_b²/a`,
        // exceeds r² by 10⁻⁵·oc²: its distance then exceeds r by at least
        // 5·10⁻⁶·|oc|, ten times what rounding can take off the `f` of
        // `roots` (a few ulps of |oc|), so `roots` finds no root either.
        // Rounding here is ~10⁻⁷·oc²; overflow or NaN makes no rejection
        // but one that holds of the exact values.
        half_b * half_b < ray.d.length_squared() * (c - oc2 * 1e-5)
    }

    /// The outward normal at a point on the sphere.
    #[inline]
    pub fn normal(&self, p: Vec3) -> Vec3 {
        (p - self.center) / self.radius
    }

    /// Texture coordinates and their derivatives at a point on the sphere,
    /// with the course's mapping: `θ = acos(y/r)` from the +y pole,
    /// `φ = atan2(z, x)`, `u = (π − φ) / 2π`, `v = θ / π`.
    pub fn uv_frame(&self, p: Vec3) -> (Vec2, Vec3, Vec3) {
        let d = p - self.center;
        let r = self.radius;
        let theta = (d.y / r).clamp(-1.0, 1.0).acos();
        let phi = d.z.atan2(d.x);
        let uv = Vec2::new((PI - phi) / (2.0 * PI), theta / PI);
        // p = c + r (sin θ cos φ, cos θ, sin θ sin φ), φ = π − 2πu, θ = πv.
        let dpdu = Vec3::new(d.z, 0.0, -d.x) * (2.0 * PI);
        let (sin_t, cos_t) = theta.sin_cos();
        let (sin_p, cos_p) = phi.sin_cos();
        let dpdv = Vec3::new(r * cos_t * cos_p, -r * sin_t, r * cos_t * sin_p) * PI;
        (uv, dpdu, dpdv)
    }

    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.center - Vec3::splat(self.radius), self.center + Vec3::splat(self.radius))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_front_and_back() {
        let s = Sphere { center: Vec3::new(0.0, 0.0, -5.0), radius: 1.0 };
        let r = Ray::new(Vec3::ZERO, -Vec3::Z);
        assert!((s.intersect(&r, 0.0, f32::INFINITY).unwrap() - 4.0).abs() < 1e-5);
        // From inside, the far wall.
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), -Vec3::Z);
        assert!((s.intersect(&r, 0.0, f32::INFINITY).unwrap() - 1.0).abs() < 1e-5);
        // A scaled direction scales t.
        let r = Ray::new(Vec3::ZERO, -Vec3::Z * 2.0);
        assert!((s.intersect(&r, 0.0, f32::INFINITY).unwrap() - 2.0).abs() < 1e-5);
        assert!(s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn early_rejection_agrees_with_the_roots() {
        // Rays from a grid of origins, in and around the sphere, in many
        // directions (some grazing): `intersect` must find what the roots
        // alone give.
        let s = Sphere { center: Vec3::new(0.3, -0.2, 0.1), radius: 0.7 };
        let mut n = 0;
        for i in 0..2000 {
            let f = i as f32;
            let o = Vec3::new((f * 0.37).sin(), (f * 0.71).cos(), (f * 1.13).sin()) * 1.5;
            let d = Vec3::new((f * 2.3).cos(), (f * 0.19).sin(), (f * 0.53).cos())
                * (0.5 + (f * 0.07).sin().abs());
            for ray in [Ray::new(o, d), Ray::new(o, s.center - o + d * 1e-4)] {
                let roots = s.roots(&ray);
                let want = roots.and_then(|(t0, t1)| [t0, t1].into_iter().find(|&t| t > 0.0 && t < 100.0));
                assert_eq!(s.intersect(&ray, 0.0, 100.0), want, "ray {i}");
                n += s.surely_missed(&ray) as usize;
            }
        }
        assert!(n > 500, "{n}");
    }

    #[test]
    fn far_small_sphere_is_precise() {
        let s = Sphere { center: Vec3::new(0.0, 0.0, -10000.0), radius: 0.01 };
        let t = s.intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), 0.0, f32::INFINITY).unwrap();
        assert!((t - 9999.99).abs() < 0.01, "{t}");
    }
}
