//! Watertight ray–triangle intersection (Woop, Benthin and Wald 2013,
//! "Watertight Ray/Triangle Intersection", as in pbrt).
//!
//! The ray is sheared once into a space where it runs along +z from the
//! origin; each triangle is then tested with three 2D edge functions. Two
//! triangles that share an edge compute that edge's function from the same
//! two transformed vertices with the same operations, so the values agree
//! bit for bit (up to sign) and a ray through the edge is inside at least one
//! of them. Möller–Trumbore computes the shared edge differently in each
//! triangle and can leak there. An edge function of exactly zero is redone in
//! `f64`, as the paper prescribes, so the "on the edge" case is decided
//! consistently too.
//!
//! No back-face culling: glass needs the back faces. The direction need not
//! be unit length; `t` is in units of it.

use glam::Vec3;

use luster_core::math::Ray;

/// A triangle as stored for intersection: its three vertices and the index
/// of the input triangle it came from. 40 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Triangle {
    /// The vertices.
    pub v: [[f32; 3]; 3],
    /// Index of the triangle in the caller's input.
    pub prim: u32,
}

/// The per-ray part of the test, computed once per traversal.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    pub(super) o: [f32; 3],
    /// Axis along which the ray's direction is largest, and the other two
    /// in cyclic order (swapped if that component is negative, keeping the
    /// sign of the edge functions consistent with the winding).
    pub(super) kx: usize,
    pub(super) ky: usize,
    pub(super) kz: usize,
    pub(super) sx: f32,
    pub(super) sy: f32,
    pub(super) sz: f32,
}

/// [`WatertightRay::new_lookup`]'s `kx` and `ky` for each `kz` (by pairs: `d[kz]`
/// positive, then negative).
const AXES: [[u8; 2]; 6] = [[1, 2], [2, 1], [2, 0], [0, 2], [0, 1], [1, 0]];

/// A hit: distance and barycentrics (`u` of vertex 1, `v` of vertex 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// Barycentric coordinate of vertex 1.
    pub u: f32,
    /// Barycentric coordinate of vertex 2.
    pub v: f32,
}

impl WatertightRay {
    /// Prepares the shear for `ray`. A zero direction gives a ray that hits
    /// nothing (the shear factors are NaN and every comparison fails).
    #[inline]
    pub fn new(ray: &Ray) -> WatertightRay {
        let d = ray.d;
        let kz = d.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        // The three quotients as one 4-lane division: each lane is the
        // same correctly rounded quotient as a scalar division.
        let s = glam::Vec4::new(-d[kx], -d[ky], 1.0, 1.0) / glam::Vec4::splat(d[kz]);
        WatertightRay { o: ray.o.to_array(), kx, ky, kz, sx: s.x, sy: s.y, sz: s.z }
    }

    /// [`WatertightRay::new`] with `kx` and `ky` looked up rather than
    /// worked out (the same values, so the same bits), for the scene's
    /// queries: there the arithmetic and the indexing of `d` by each
    /// compile to a long run of compares and conditional moves per ray.
    /// Not used by [`super::MeshAccel`]'s own queries, where the table
    /// lookup does not pay.
    #[inline]
    pub(crate) fn new_lookup(ray: &Ray) -> WatertightRay {
        let d = ray.d;
        let kz = d.abs().max_position();
        let c = [d.x, d.y, d.z, 0.0];
        let dz = c[kz & 3];
        let [kx, ky] = AXES[2 * kz + (dz < 0.0) as usize];
        let (kx, ky) = (kx as usize, ky as usize);
        let s = glam::Vec4::new(-c[kx & 3], -c[ky & 3], 1.0, 1.0) / glam::Vec4::splat(dz);
        WatertightRay { o: ray.o.to_array(), kx, ky, kz, sx: s.x, sy: s.y, sz: s.z }
    }

    /// Intersects `tri`, returning a hit with `t_min < t < t_max`.
    #[inline(always)]
    pub fn intersect(&self, tri: &Triangle, t_min: f32, t_max: f32) -> Option<Hit> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let o = &self.o;
        let [p0, p1, p2] = &tri.v;
        // Vertices relative to the origin, permuted so the ray runs along z.
        let a = [p0[kx] - o[kx], p0[ky] - o[ky], p0[kz] - o[kz]];
        let b = [p1[kx] - o[kx], p1[ky] - o[ky], p1[kz] - o[kz]];
        let c = [p2[kx] - o[kx], p2[ky] - o[ky], p2[kz] - o[kz]];
        let (ax, ay) = (a[0] + self.sx * a[2], a[1] + self.sy * a[2]);
        let (bx, by) = (b[0] + self.sx * b[2], b[1] + self.sy * b[2]);
        let (cx, cy) = (c[0] + self.sx * c[2], c[1] + self.sy * c[2]);
        let mut e0 = bx * cy - by * cx;
        let mut e1 = cx * ay - cy * ax;
        let mut e2 = ax * by - ay * bx;
        if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
            // On an edge in f32: decide in f64, where these products are exact.
            let f = |x: f32| x as f64;
            e0 = (f(bx) * f(cy) - f(by) * f(cx)) as f32;
            e1 = (f(cx) * f(ay) - f(cy) * f(ax)) as f32;
            e2 = (f(ax) * f(by) - f(ay) * f(bx)) as f32;
        }
        if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
            return None;
        }
        let det = e0 + e1 + e2;
        // Zero for a triangle seen edge-on, or a degenerate one; NaN fails too.
        if det.is_nan() || det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (self.sz * a[2], self.sz * b[2], self.sz * c[2]);
        let t_scaled = e0 * az + e1 * bz + e2 * cz;
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        // `t > t_min && t < t_max` is false for NaN, so no NaN escapes.
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some(Hit { t, u: e1 * inv, v: e2 * inv })
    }
}

impl Triangle {
    /// The (unnormalized) normal of the winding: `(v1 - v0) × (v2 - v0)`.
    /// Written out: `self.v.map(..)` can be left out of line, a call per
    /// back-face check of a camera ray's hits.
    #[inline(always)]
    pub fn normal(&self) -> luster_core::math::Vec3 {
        use luster_core::math::Vec3;
        let [a, b, c] = self.v;
        let (a, b, c) = (Vec3::from(a), Vec3::from(b), Vec3::from(c));
        (b - a).cross(c - a)
    }

    /// Builds a triangle from three vertices.
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3, prim: u32) -> Triangle {
        Triangle { v: [p0.to_array(), p1.to_array(), p2.to_array()], prim }
    }

    /// True if the triangle has zero area (in `f64`) or a non-finite vertex:
    /// such a triangle can never be hit and is left out of the accelerator.
    pub fn is_degenerate(&self) -> bool {
        let p = self.v.map(|v| [v[0] as f64, v[1] as f64, v[2] as f64]);
        if p.iter().flatten().any(|x| !x.is_finite()) {
            return true;
        }
        let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
        let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
        let n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        n == [0.0; 3]
    }
}
