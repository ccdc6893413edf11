//! Affine transforms that carry their inverse.
//!
//! The course composes transformations in the order they are listed: for
//! `r1 t1 s2 r2` the matrix is `R2 S2 T1 R1` (hw2 spec, eq. 1). [`Transform::then`]
//! expresses exactly that: `a.then(b)` applies `a` first.

use glam::{Mat3, Mat4, Vec3};

/// An affine transform with its inverse, so normals (inverse transpose) and
/// rays into object space never need a run-time inversion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    m: Mat4,
    inv: Mat4,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform { m: Mat4::IDENTITY, inv: Mat4::IDENTITY };

    /// A translation by `t`.
    pub fn translation(t: Vec3) -> Self {
        Transform { m: Mat4::from_translation(t), inv: Mat4::from_translation(-t) }
    }

    /// A scaling by `s`. Returns `None` if a factor is zero (not invertible).
    pub fn scaling(s: Vec3) -> Option<Self> {
        (s.x != 0.0 && s.y != 0.0 && s.z != 0.0)
            .then(|| Transform { m: Mat4::from_scale(s), inv: Mat4::from_scale(s.recip()) })
    }

    /// A counter-clockwise rotation of `degrees` about `axis` (right-handed).
    /// Returns `None` for a zero axis.
    pub fn rotation(degrees: f32, axis: Vec3) -> Option<Self> {
        let len = axis.length();
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let m = Mat4::from_axis_angle(axis / len, degrees.to_radians());
        Some(Transform { m, inv: m.transpose() })
    }

    /// A general affine matrix, given row by row as the course writes it.
    /// Returns `None` if it is singular or projective.
    pub fn from_rows(rows: [f32; 16]) -> Option<Self> {
        let m = Mat4::from_cols_array(&rows).transpose();
        let last = m.row(3);
        if (last - glam::Vec4::new(0.0, 0.0, 0.0, 1.0)).abs().max_element() > 1e-6 {
            return None;
        }
        Self::from_matrix(m)
    }

    /// Wraps a matrix, inverting it. `None` if singular.
    pub fn from_matrix(m: Mat4) -> Option<Self> {
        let det = m.determinant();
        (det != 0.0 && det.is_finite()).then(|| Transform { m, inv: m.inverse() })
    }

    /// `self` followed by `next`: the matrix `next * self`.
    pub fn then(&self, next: &Transform) -> Transform {
        Transform { m: next.m * self.m, inv: self.inv * next.inv }
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Transform {
        Transform { m: self.inv, inv: self.m }
    }

    /// The forward matrix.
    pub fn matrix(&self) -> Mat4 {
        self.m
    }

    /// True if this is (numerically) the identity.
    pub fn is_identity(&self) -> bool {
        self.m.abs_diff_eq(Mat4::IDENTITY, 1e-7)
    }

    /// True if the transform flips handedness (negative determinant).
    pub fn swaps_handedness(&self) -> bool {
        Mat3::from_mat4(self.m).determinant() < 0.0
    }

    /// Transforms a point.
    #[inline]
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.m.transform_point3(p)
    }

    /// Transforms a direction (no translation).
    #[inline]
    pub fn vector(&self, v: Vec3) -> Vec3 {
        self.m.transform_vector3(v)
    }

    /// Transforms a surface normal by the inverse transpose, so it stays
    /// perpendicular to transformed tangents. The result is not normalized.
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        self.inv.transpose().transform_vector3(n)
    }

    /// Moves a point by the inverse (world to object space).
    #[inline]
    pub fn inv_point(&self, p: Vec3) -> Vec3 {
        self.inv.transform_point3(p)
    }

    /// Moves a direction by the inverse (world to object space).
    #[inline]
    pub fn inv_vector(&self, v: Vec3) -> Vec3 {
        self.inv.transform_vector3(v)
    }

    /// Moves an object-space normal to world space given that the transform's
    /// inverse is at hand: `n_world = M^-T n_obj`.
    #[inline]
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        let i = &self.inv;
        // (M^-1)^T n: dot n with the columns of M^-1 (its rows of the transpose).
        Vec3::new(i.x_axis.truncate().dot(n), i.y_axis.truncate().dot(n), i.z_axis.truncate().dot(n))
    }

    /// The box around this transform of `b`'s eight corners.
    pub fn aabb(&self, b: &crate::math::Aabb) -> crate::math::Aabb {
        if b.is_empty() {
            return *b;
        }
        crate::math::Aabb::from_points((0..8).map(|i| {
            self.point(Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            ))
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).abs().max_element() < 1e-5
    }

    #[test]
    fn listed_order_is_application_order() {
        // "r1 t1": rotate first, then translate. Rotating (1,0,0) by 90° about z
        // gives (0,1,0); translating by (5,0,0) gives (5,1,0).
        let r = Transform::rotation(90.0, Vec3::Z).unwrap();
        let t = Transform::translation(Vec3::new(5.0, 0.0, 0.0));
        let m = r.then(&t);
        assert!(close(m.point(Vec3::X), Vec3::new(5.0, 1.0, 0.0)));
        // The other order gives a different point: (6,0,0) rotated is (0,6,0).
        let m2 = t.then(&r);
        assert!(close(m2.point(Vec3::X), Vec3::new(0.0, 6.0, 0.0)));
    }

    #[test]
    fn rotation_is_counter_clockwise() {
        let r = Transform::rotation(90.0, Vec3::Z).unwrap();
        assert!(close(r.point(Vec3::X), Vec3::Y));
        let r = Transform::rotation(90.0, Vec3::X).unwrap();
        assert!(close(r.point(Vec3::Y), Vec3::Z));
    }

    #[test]
    fn normals_stay_perpendicular_under_nonuniform_scale() {
        let s = Transform::scaling(Vec3::new(4.0, 1.0, 1.0))
            .unwrap()
            .then(&Transform::rotation(30.0, Vec3::new(1.0, 1.0, 0.0)).unwrap());
        let n = Vec3::new(1.0, 1.0, 0.0).normalize();
        let tangent = Vec3::new(1.0, -1.0, 0.0);
        let nt = s.normal(n);
        let tt = s.vector(tangent);
        assert!(nt.dot(tt).abs() < 1e-5);
        assert!(close(s.normal_to_world(n), nt));
        // Using the point matrix on the normal would be wrong here.
        assert!(s.vector(n).dot(tt).abs() > 0.1);
    }

    #[test]
    fn inverse_round_trips() {
        let t = Transform::translation(Vec3::new(1.0, 2.0, 3.0))
            .then(&Transform::scaling(Vec3::new(2.0, -1.0, 0.5)).unwrap())
            .then(&Transform::rotation(37.0, Vec3::new(0.2, 1.0, 0.3)).unwrap());
        let p = Vec3::new(-0.3, 7.0, 2.5);
        assert!(close(t.inv_point(t.point(p)), p));
        assert!(close(t.inverse().point(t.point(p)), p));
        assert!(t.swaps_handedness());
    }

    #[test]
    fn composite_rows_are_row_major() {
        let m = Transform::from_rows([
            1.0, 0.0, 0.0, 3.0, //
            0.0, 1.0, 0.0, 4.0, //
            0.0, 0.0, 1.0, 5.0, //
            0.0, 0.0, 0.0, 1.0,
        ])
        .unwrap();
        assert!(close(m.point(Vec3::ZERO), Vec3::new(3.0, 4.0, 5.0)));
        assert!(Transform::scaling(Vec3::new(0.0, 1.0, 1.0)).is_none());
    }
}
