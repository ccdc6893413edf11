//! An analytic ellipsoid in object space (luster's `<Ellipsoid>` extension).
//!
//! | parameter | meaning |
//! |---|---|
//! | `center` | centre, object space |
//! | `radii` | semi-axis lengths along the ellipsoid's own x, y, z (all positive) |
//! | `rotation` | turns the ellipsoid's own axes into object space |
//!
//! The ellipsoid is the unit sphere under `p = c + R (r ⊙ q)`: scaled by the
//! radii, rotated, moved to the centre. Every query maps into that local
//! unit-sphere frame, `q = r⁻¹ ⊙ Rᵀ (p − c)`, and answers there: the map is
//! affine, so a ray keeps its parameter `t`, and the quadratic is the unit
//! sphere's, solved in the cancellation-free form [`Sphere`] uses.
//!
//! Texture coordinates are the course's spherical mapping of `q`, so an
//! ellipsoid is textured exactly like a unit sphere under the transform
//! "scale by the radii, rotate, translate to the centre".
//!
//! ```xml
//! <Ellipsoid id="1">
//!     <Material>1</Material>
//!     <Center>3</Center>
//!     <Radii>1 0.5 2</Radii>
//!     <Rotation>30 0 1 0</Rotation>
//! </Ellipsoid>
//! ```

use super::Sphere;
use luster_core::math::{Aabb, Mat3, Quat, Ray, Vec2, Vec3};

/// An ellipsoid: centre, three radii and a rotation of its axes.
#[derive(Clone, Copy, Debug)]
pub struct Ellipsoid {
    center: Vec3,
    radii: Vec3,
    inv_radii: Vec3,
    /// Local axes to object space (orthonormal); its transpose is the inverse.
    rotation: Mat3,
}

impl Ellipsoid {
    /// An ellipsoid with `radii` along its own axes, turned by `rotation`
    /// (normalized here) and centred at `center`. Radii must be positive and
    /// finite: the loader refuses anything else before this is built.
    pub fn new(center: Vec3, radii: Vec3, rotation: Quat) -> Ellipsoid {
        Ellipsoid { center, radii, inv_radii: radii.recip(), rotation: Mat3::from_quat(rotation.normalize()) }
    }

    /// Centre.
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// Radii along the ellipsoid's own axes.
    pub fn radii(&self) -> Vec3 {
        self.radii
    }

    /// The rotation from the ellipsoid's own axes to object space.
    pub fn rotation(&self) -> Mat3 {
        self.rotation
    }

    /// An object-space point in the local unit-sphere frame.
    #[inline]
    fn local_point(&self, p: Vec3) -> Vec3 {
        // Subtract first: for a small ellipsoid far from the origin this keeps
        // the digits that the rotation and scaling would otherwise smear.
        self.rotation.transpose().mul_vec3(p - self.center) * self.inv_radii
    }

    /// The ray in the local unit-sphere frame, with the same `t`.
    #[inline]
    fn local_ray(&self, ray: &Ray) -> Ray {
        let rt = self.rotation.transpose();
        Ray::new(rt.mul_vec3(ray.o - self.center) * self.inv_radii, rt.mul_vec3(ray.d) * self.inv_radii)
    }

    /// The two roots, in order, of `|o + t d|² = 1` in the local frame, or
    /// `None` when the line misses (or the direction is zero).
    #[inline]
    fn roots(&self, ray: &Ray) -> Option<(f32, f32)> {
        Sphere { center: Vec3::ZERO, radius: 1.0 }.roots(&self.local_ray(ray))
    }

    /// The nearest `t` in `(t_min, t_max)` where the ray meets the surface.
    /// The direction need not be unit length.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        // The local ray keeps the world ray's `t`.
        Sphere { center: Vec3::ZERO, radius: 1.0 }.intersect(&self.local_ray(ray), t_min, t_max)
    }

    /// Where the ray's line passes through the solid ellipsoid: the entry and
    /// exit parameters `(t_in, t_out)`, `t_in ≤ t_out`, in units of the
    /// ray's own direction (which need not be unit length). Both may be
    /// negative (the solid is behind the origin); `t_in < 0 ≤ t_out` means
    /// the origin is inside. `None` when the line misses. (Volume bounds
    /// keep the unit ball's space for scripts, so they use `volume::Bound`.)
    pub fn interval(&self, ray: &Ray) -> Option<(f32, f32)> {
        self.roots(ray)
    }

    /// The unit outward normal at an object-space point on the surface: the
    /// gradient of `|q|²`, which is `R (r⁻¹ ⊙ q)` up to a factor.
    #[inline]
    pub fn normal(&self, p: Vec3) -> Vec3 {
        let q = self.local_point(p);
        self.rotation.mul_vec3(q * self.inv_radii).normalize()
    }

    /// Texture coordinates and object-space ∂p/∂u, ∂p/∂v at a point on the
    /// surface: the course's sphere mapping (see [`Sphere::uv_frame`]) of the
    /// local unit-sphere point, with the derivatives carried out of the local
    /// frame (scaled by the radii, rotated).
    pub fn uv_frame(&self, p: Vec3) -> (Vec2, Vec3, Vec3) {
        let q = self.local_point(p);
        let (uv, du, dv) = Sphere { center: Vec3::ZERO, radius: 1.0 }.uv_frame(q);
        (uv, self.rotation.mul_vec3(du * self.radii), self.rotation.mul_vec3(dv * self.radii))
    }

    /// The tight box: along axis `i` the ellipsoid reaches
    /// `sqrt(Σ_j (R_ij r_j)²)` from its centre (the support function of
    /// `R diag(r)` applied to the unit sphere).
    pub fn bounds(&self) -> Aabb {
        let m = self.rotation * Mat3::from_diagonal(self.radii);
        let half = Vec3::new(m.row(0).length(), m.row(1).length(), m.row(2).length());
        Aabb::new(self.center - half, self.center + half)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use luster_core::math::Transform;
    use std::f32::consts::PI;

    /// A small deterministic generator (SplitMix64), so failures reproduce.
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
        }
        fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
        fn unit(&mut self) -> Vec3 {
            loop {
                let v = Vec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
                if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                    return v.normalize();
                }
            }
        }
    }

    /// An ellipsoid and the unit sphere under the equivalent transform
    /// (scale by the radii, rotate, translate to the centre).
    fn pair(center: Vec3, radii: Vec3, degrees: f32, axis: Vec3) -> (Ellipsoid, Transform) {
        let e = Ellipsoid::new(center, radii, Quat::from_axis_angle(axis.normalize(), degrees.to_radians()));
        let xf = Transform::scaling(radii)
            .and_then(|s| Transform::rotation(degrees, axis).map(|r| s.then(&r)))
            .map(|sr| sr.then(&Transform::translation(center)))
            .unwrap_or_default();
        (e, xf)
    }

    /// The entry and exit of the ray's line, in `f64`, with the squared
    /// distance of the line from the local centre (1 on the silhouette).
    fn reference(e: &Ellipsoid, ray: &Ray) -> (Option<(f64, f64)>, f64) {
        let rt = e.rotation.transpose();
        let to64 = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
        let (o, d) = (to64(ray.o - e.center), to64(ray.d));
        let (m, r) = (rt.to_cols_array().map(f64::from), to64(e.radii));
        // Column-major: row i of Rᵀ is (m[i], m[3 + i], m[6 + i]).
        let local = |v: [f64; 3]| -> [f64; 3] {
            std::array::from_fn(|i| (m[i] * v[0] + m[3 + i] * v[1] + m[6 + i] * v[2]) / r[i])
        };
        let (o, d) = (local(o), local(d));
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (a, b, c) = (dot(d, d), dot(o, d), dot(o, o) - 1.0);
        let dist2 = dot(o, o) - b * b / a;
        let disc = b * b - a * c;
        if disc < 0.0 {
            return (None, dist2);
        }
        let s = disc.sqrt();
        (Some(((-b - s) / a, (-b + s) / a)), dist2)
    }

    fn wrapped(a: f32, b: f32) -> f32 {
        let d = (a - b).abs();
        d.min(1.0 - d)
    }

    #[test]
    fn agrees_with_a_transformed_unit_sphere() {
        let unit = Sphere { center: Vec3::ZERO, radius: 1.0 };
        let mut rng = Rng(7);
        let (mut hits, mut grazing_disagreements) = (0, 0);
        for case in 0..40 {
            let center = Vec3::new(rng.range(-5.0, 5.0), rng.range(-5.0, 5.0), rng.range(-5.0, 5.0));
            let radii = Vec3::new(rng.range(0.1, 3.0), rng.range(0.1, 3.0), rng.range(0.1, 3.0));
            let (e, xf) = pair(center, radii, rng.range(-180.0, 180.0), rng.unit());
            for _ in 0..500 {
                // Origins around the ellipsoid, aimed near it so most rays hit.
                let o = center + rng.unit() * rng.range(0.0, 12.0);
                let target = center + rng.unit() * radii.max_element() * rng.range(0.0, 1.3);
                let Some(d) = (target - o).try_normalize() else { continue };
                let ray = Ray::new(o, d * rng.range(0.5, 2.0));
                let local = Ray::new(xf.inv_point(ray.o), xf.inv_vector(ray.d));
                let (te, ts) =
                    (e.intersect(&ray, 1e-4, f32::INFINITY), unit.intersect(&local, 1e-4, f32::INFINITY));
                let (exact, dist2) = reference(&e, &ray);
                let (te, ts) = match (te, ts) {
                    (Some(a), Some(b)) => (a, b),
                    (None, None) => continue,
                    _ => {
                        // Only a ray grazing the silhouette may split them.
                        assert!((dist2 - 1.0).abs() < 1e-4, "case {case}: {te:?} vs {ts:?}, |f|² = {dist2}");
                        grazing_disagreements += 1;
                        continue;
                    }
                };
                hits += 1;
                let scale = 1.0 + ray.o.length() / ray.d.length();
                assert!((te - ts).abs() < 2e-5 * scale, "case {case}: t {te} vs {ts}");
                // Against f64: one of the two roots, to float precision.
                if let Some((t0, t1)) = exact {
                    let err = (te as f64 - t0).abs().min((te as f64 - t1).abs());
                    assert!(err < 1e-5 * scale as f64, "case {case}: t {te} vs exact {t0} {t1}");
                }
                let p = ray.at(te);
                let ns = xf.normal_to_world(unit.normal(local.at(ts))).normalize();
                let ne = e.normal(p);
                assert!((ne.length() - 1.0).abs() < 1e-5);
                assert!(ne.dot(ns) > 1.0 - 1e-5, "case {case}: normal {ne} vs {ns}");
                let (uv_e, du_e, dv_e) = e.uv_frame(p);
                let (uv_s, du_s, dv_s) = unit.uv_frame(local.at(ts));
                // Near the poles u is ill-conditioned; there only v must agree.
                let pole = uv_s.y < 0.01 || uv_s.y > 0.99;
                assert!(pole || wrapped(uv_e.x, uv_s.x) < 1e-4, "case {case}: u {uv_e} vs {uv_s}");
                assert!((uv_e.y - uv_s.y).abs() < 1e-4, "case {case}: v {uv_e} vs {uv_s}");
                if !pole {
                    let (du_s, dv_s) = (xf.vector(du_s), xf.vector(dv_s));
                    let tol = 1e-3 * radii.max_element() * 2.0 * PI;
                    assert!((du_e - du_s).length() < tol, "case {case}: dpdu {du_e} vs {du_s}");
                    assert!((dv_e - dv_s).length() < tol, "case {case}: dpdv {dv_e} vs {dv_s}");
                }
            }
        }
        assert!(hits > 10_000, "only {hits} rays hit");
        assert!(grazing_disagreements < 20, "{grazing_disagreements} grazing rays disagree");
    }

    #[test]
    fn frame_is_the_derivative_of_the_surface() {
        let (e, _) =
            pair(Vec3::new(1.0, -2.0, 0.5), Vec3::new(2.0, 0.5, 1.0), 40.0, Vec3::new(1.0, 1.0, 0.0));
        let at = |u: f32, v: f32| {
            let (phi, theta) = (PI - 2.0 * PI * u, PI * v);
            let q = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            e.center + e.rotation * (q * e.radii)
        };
        for (u, v) in [(0.1, 0.3), (0.45, 0.5), (0.8, 0.7), (0.6, 0.15)] {
            let p = at(u, v);
            let (uv, dpdu, dpdv) = e.uv_frame(p);
            assert!((uv - Vec2::new(u, v)).length() < 1e-4, "{uv} vs {u} {v}");
            let h = 1e-3;
            let fu = (at(u + h, v) - at(u - h, v)) / (2.0 * h);
            let fv = (at(u, v + h) - at(u, v - h)) / (2.0 * h);
            assert!((fu - dpdu).length() < 1e-2 * dpdu.length(), "{fu} vs {dpdu}");
            assert!((fv - dpdv).length() < 1e-2 * dpdv.length(), "{fv} vs {dpdv}");
            // The normal is perpendicular to both, and points outwards.
            let n = e.normal(p);
            assert!(n.dot(dpdu).abs() < 1e-4 * dpdu.length() && n.dot(dpdv).abs() < 1e-4 * dpdv.length());
            assert!(n.dot(p - e.center) > 0.0);
        }
    }

    #[test]
    fn interval_from_inside_outside_and_missing() {
        let (e, _) = pair(Vec3::new(0.0, 0.0, -5.0), Vec3::new(1.0, 2.0, 3.0), 90.0, Vec3::Y);
        // Rotated 90° about y, the 3-long axis lies along x and the 1-long along z.
        let i = e.interval(&Ray::new(Vec3::new(0.0, 0.0, -5.0), -Vec3::Z)).unwrap();
        assert!((i.0 + 1.0).abs() < 1e-5 && (i.1 - 1.0).abs() < 1e-5, "inside: {i:?}");
        let i = e.interval(&Ray::new(Vec3::new(-10.0, 0.0, -5.0), Vec3::X * 2.0)).unwrap();
        assert!((i.0 - 3.5).abs() < 1e-5 && (i.1 - 6.5).abs() < 1e-5, "outside, scaled direction: {i:?}");
        let i = e.interval(&Ray::new(Vec3::new(10.0, 0.0, -5.0), Vec3::X)).unwrap();
        assert!((i.0 + 13.0).abs() < 1e-5 && (i.1 + 7.0).abs() < 1e-5, "behind: {i:?}");
        assert!(e.interval(&Ray::new(Vec3::new(0.0, 2.1, 0.0), -Vec3::Z)).is_none(), "misses above");
        assert!(e.interval(&Ray::new(Vec3::new(0.0, 0.0, -3.9), Vec3::X)).is_none(), "misses in front");
        assert!(e.interval(&Ray::new(Vec3::ZERO, Vec3::ZERO)).is_none(), "no direction");
        // Random origins inside: t_in < 0 < t_out, and both ends lie on the surface.
        let mut rng = Rng(3);
        for _ in 0..1000 {
            let q = rng.unit() * rng.range(0.0, 0.99);
            let o = e.center + e.rotation * (q * e.radii);
            let ray = Ray::new(o, rng.unit());
            let (t0, t1) = e.interval(&ray).unwrap();
            assert!(t0 < 0.0 && t1 > 0.0, "{t0} {t1}");
            for t in [t0, t1] {
                assert!((e.local_point(ray.at(t)).length() - 1.0).abs() < 1e-4);
            }
            // intersect from inside finds the exit.
            assert_eq!(e.intersect(&ray, 0.0, f32::INFINITY), Some(t1));
        }
    }

    #[test]
    fn bounds_contain_the_surface_and_are_tight() {
        let mut rng = Rng(11);
        for _ in 0..20 {
            let center = Vec3::new(rng.range(-3.0, 3.0), rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            let radii = Vec3::new(rng.range(0.05, 4.0), rng.range(0.05, 4.0), rng.range(0.05, 4.0));
            let (e, _) = pair(center, radii, rng.range(-180.0, 180.0), rng.unit());
            let b = e.bounds();
            let slack = 1e-5 * (center.abs().max_element() + radii.max_element());
            for _ in 0..2000 {
                let p = center + e.rotation * (rng.unit() * radii);
                assert!(p.cmpge(b.min - slack).all() && p.cmple(b.max + slack).all(), "{p} outside {b:?}");
            }
            // Tight: the surface point farthest along ±axis i touches face i.
            // For p = c + M q, |q| = 1, with M = R diag(r), that point is
            // q = Mᵀeᵢ / |Mᵀeᵢ|.
            let m = e.rotation * Mat3::from_diagonal(radii);
            for (i, axis) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
                let q = (m.transpose() * axis).normalize();
                let (hi, lo) = (center + m * q, center - m * q);
                assert!((hi[i] - b.max[i]).abs() < slack && (lo[i] - b.min[i]).abs() < slack);
            }
        }
    }

    #[test]
    fn far_small_ellipsoid_is_precise() {
        let (e, _) = pair(Vec3::new(0.0, 0.0, -10000.0), Vec3::new(0.01, 0.02, 0.005), 30.0, Vec3::X);
        let t = e.intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), 0.0, f32::INFINITY).unwrap();
        let (exact, _) = reference(&e, &Ray::new(Vec3::ZERO, -Vec3::Z));
        let t0 = exact.map_or(f64::NAN, |x| x.0);
        assert!((t as f64 - t0).abs() < 2e-3, "{t} vs {t0}");
    }

    #[test]
    fn grazing_rays_keep_their_roots() {
        // A line at distance 1 − 1e-3 from the centre of the unit sphere:
        // the textbook discriminant b² − ac loses about half its digits here.
        let e = Ellipsoid::new(Vec3::new(100.0, 0.0, 0.0), Vec3::ONE, Quat::IDENTITY);
        let h = 1.0 - 1e-3f32;
        let (t0, t1) = e.interval(&Ray::new(Vec3::new(0.0, h, 0.0), Vec3::X)).unwrap();
        let half = (1.0 - h * h).sqrt();
        assert!((t0 - (100.0 - half)).abs() < 1e-4 && (t1 - (100.0 + half)).abs() < 1e-4, "{t0} {t1}");
    }
}
