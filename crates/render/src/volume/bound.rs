//! The region a volume fills: a ball or a box in the volume's own space,
//! placed in the world by an affine transform. An ellipsoid is the unit ball
//! under `translate · rotate · scale`, composed before the volume's own
//! transform, which is exact: rays move into the bound's space without
//! renormalizing, so the ray parameter `t` means the same in both spaces.

use crate::geometry::Sphere;
use crate::texture::TexFrame;
use luster_core::math::{Aabb, Mat4, Ray, Transform, Vec3};
use luster_scene::description::BoundDesc;

#[derive(Clone, Copy, Debug)]
enum Shape {
    Ball { center: Vec3, radius: f32 },
    Box { min: Vec3, max: Vec3 },
}

/// A volume's bound, ready for ray queries.
#[derive(Clone, Debug)]
pub struct Bound {
    shape: Shape,
    /// Bound space to world; `None` for the identity.
    xf: Option<Transform>,
    /// World-space box around it.
    world: Aabb,
}

impl Bound {
    /// The bound `desc` under `transform` (bound space to world).
    pub fn new(desc: &BoundDesc, transform: &Transform) -> Bound {
        let (shape, local) = match *desc {
            BoundDesc::Sphere { center, radius } => (Shape::Ball { center, radius }, None),
            BoundDesc::Box { min, max } => (Shape::Box { min, max }, None),
            BoundDesc::Ellipsoid { center, radii, rotation } => {
                // Radii are checked positive (and not subnormal) when the
                // scene is read, so the scaling is invertible.
                let scale = Transform::scaling(radii).unwrap_or(Transform::IDENTITY);
                let turn = Transform::from_matrix(Mat4::from_quat(rotation)).unwrap_or(Transform::IDENTITY);
                let xf = scale.then(&turn).then(&Transform::translation(center));
                (Shape::Ball { center: Vec3::ZERO, radius: 1.0 }, Some(xf))
            }
        };
        let xf = match local {
            Some(l) => Some(l.then(transform)),
            None => (!transform.is_identity()).then_some(*transform),
        };
        let local_box = match shape {
            Shape::Ball { center, radius } => Aabb::new(center - radius, center + radius),
            Shape::Box { min, max } => Aabb::new(min, max),
        };
        let world = match &xf {
            Some(xf) => xf.aabb(&local_box),
            None => local_box,
        };
        Bound { shape, xf, world }
    }

    /// The box the bound occupies in its own space (where scripts see `s.P`).
    /// For an ellipsoid that is the space before its centre, rotation and
    /// radii, i.e. the unit ball's.
    pub fn local_box(&self) -> Aabb {
        match self.shape {
            Shape::Ball { center, radius } => Aabb::new(center - radius, center + radius),
            Shape::Box { min, max } => Aabb::new(min, max),
        }
    }

    /// The world-space box around the bound.
    pub fn world_box(&self) -> Aabb {
        self.world
    }

    /// A world point in the bound's own space.
    #[inline]
    pub fn to_local(&self, p: Vec3) -> Vec3 {
        match &self.xf {
            Some(xf) => xf.inv_point(p),
            None => p,
        }
    }

    /// A bound-space point in the world.
    #[inline]
    pub fn to_world(&self, p: Vec3) -> Vec3 {
        match &self.xf {
            Some(xf) => xf.point(p),
            None => p,
        }
    }

    /// The ray's origin and direction in the bound's own space (the
    /// direction not renormalized, so `t` means the same in both).
    #[inline]
    pub fn to_local_ray(&self, ray: &Ray) -> (Vec3, Vec3) {
        match &self.xf {
            Some(xf) => (xf.inv_point(ray.o), xf.inv_vector(ray.d)),
            None => (ray.o, ray.d),
        }
    }

    /// Where the ray's line is inside the bound: `(t_in, t_out)` with
    /// `t_in < t_out` (`t_in` is negative when the origin is inside), or `None`.
    pub fn interval(&self, ray: &Ray) -> Option<(f32, f32)> {
        let (o, d) = match &self.xf {
            Some(xf) => (xf.inv_point(ray.o), xf.inv_vector(ray.d)),
            None => (ray.o, ray.d),
        };
        let (t0, t1) = match self.shape {
            Shape::Ball { center, radius } => Sphere { center, radius }.roots(&Ray::new(o, d))?,
            Shape::Box { min, max } => {
                let inv = d.recip();
                let a = (min - o) * inv;
                let b = (max - o) * inv;
                (a.min(b).max_element(), a.max(b).min_element())
            }
        };
        (t0 < t1 && t0.is_finite() && t1.is_finite()).then_some((t0, t1))
    }

    /// The unit outward normal, in the world, of the bound's surface at the
    /// world point `p` (on or near it).
    pub fn normal(&self, p: Vec3) -> Vec3 {
        let q = self.to_local(p);
        let n = match self.shape {
            Shape::Ball { center, .. } => q - center,
            Shape::Box { min, max } => {
                // The face the point is nearest to, relative to the box's size.
                let c = (min + max) * 0.5;
                let h = (max - min) * 0.5;
                let r = (q - c) / h;
                let a = r.abs();
                if a.x >= a.y && a.x >= a.z {
                    Vec3::new(r.x.signum(), 0.0, 0.0)
                } else if a.y >= a.z {
                    Vec3::new(0.0, r.y.signum(), 0.0)
                } else {
                    Vec3::new(0.0, 0.0, r.z.signum())
                }
            }
        };
        let n = match &self.xf {
            Some(xf) => xf.normal_to_world(n),
            None => n,
        };
        n.try_normalize().unwrap_or(Vec3::Z)
    }

    /// The texture frame at world point `p` of a surface inside the bound
    /// whose world normal is `n`: the bound's space is the object space, and
    /// texture coordinates are the course's spherical ones around the centre
    /// of the bound's box, with their derivatives projected onto the surface.
    pub fn tex_frame(&self, p: Vec3, n: Vec3, time: f32, footprint: f32) -> TexFrame {
        let q = self.to_local(p);
        let n_local = match &self.xf {
            // Normals go to the world by the inverse transpose, so back by the transpose.
            Some(xf) => xf.matrix().transpose().transform_vector3(n),
            None => n,
        };
        let n_local = n_local.try_normalize().unwrap_or(Vec3::Z);
        let c = self.local_box().center();
        let sphere = Sphere { center: c, radius: (q - c).length().max(1e-20) };
        let (uv, dpdu, dpdv) = sphere.uv_frame(q);
        let tangent = |v: Vec3| v - n_local * n_local.dot(v);
        TexFrame {
            uv,
            p_object: q,
            p_world: p,
            time,
            p_rest: p,
            rest_in_object: false,
            dpdu: tangent(dpdu),
            dpdv: tangent(dpdv),
            n: n_local,
            to_world: self.xf,
            footprint,
            ctx: Default::default(),
        }
    }

    /// The length of the world box's diagonal (the default step is a fraction of it).
    pub fn diagonal(&self) -> f32 {
        self.world.extent().length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use luster_core::math::Quat;

    #[test]
    fn ball_and_box_intervals() {
        let ball = Bound::new(&BoundDesc::Sphere { center: Vec3::ZERO, radius: 2.0 }, &Transform::IDENTITY);
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert_eq!(ball.interval(&r), Some((3.0, 7.0)));
        let inside = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(ball.interval(&inside), Some((-2.0, 2.0)));
        assert_eq!(ball.interval(&Ray::new(Vec3::new(3.0, 0.0, -5.0), Vec3::Z)), None);
        let b = BoundDesc::Box { min: Vec3::splat(-1.0), max: Vec3::new(1.0, 1.0, 3.0) };
        let bx = Bound::new(&b, &Transform::translation(Vec3::X * 10.0));
        let r = Ray::new(Vec3::new(10.0, 0.0, -5.0), Vec3::Z);
        assert_eq!(bx.interval(&r), Some((4.0, 8.0)));
        assert_eq!(bx.normal(Vec3::new(10.0, 0.2, 3.0)), Vec3::Z);
    }

    #[test]
    fn an_ellipsoid_is_a_scaled_rotated_ball() {
        let rotation = Quat::from_rotation_z(90f32.to_radians());
        let e = BoundDesc::Ellipsoid {
            center: Vec3::new(0.0, 1.0, 0.0),
            radii: Vec3::new(3.0, 1.0, 1.0),
            rotation,
        };
        let b = Bound::new(&e, &Transform::IDENTITY);
        // The long axis now runs along y: from y = -2 to 4.
        let r = Ray::new(Vec3::new(0.0, -10.0, 0.0), Vec3::Y);
        let (t0, t1) = b.interval(&r).unwrap();
        assert!((t0 - 8.0).abs() < 1e-5 && (t1 - 14.0).abs() < 1e-5, "{t0} {t1}");
        let n = b.normal(Vec3::new(0.0, 4.0, 0.0));
        assert!((n - Vec3::Y).length() < 1e-5, "{n}");
        let w = b.world_box();
        assert!((w.min - Vec3::new(-1.0, -2.0, -1.0)).abs().max_element() < 1e-5, "{w:?}");
    }
}
