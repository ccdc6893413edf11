//! Acceleration structures (placeholder until the BVH lands): same API, brute force.

use crate::math::{Aabb, Ray, Vec3};
use std::ops::Range;

/// Bounding volume hierarchy over primitive boxes.
pub struct Bvh {
    order: Vec<u32>,
    bounds: Aabb,
}

impl Bvh {
    /// Builds over primitive bounds.
    pub fn build(b: &[Aabb]) -> Bvh {
        Bvh { order: (0..b.len() as u32).collect(), bounds: b.iter().fold(Aabb::EMPTY, |a, x| a.union(*x)) }
    }
    /// Leaf ranges index into this permutation.
    pub fn prim_order(&self) -> &[u32] {
        &self.order
    }
    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
    /// Closest-hit traversal.
    pub fn closest<F: FnMut(Range<usize>, &mut f32) -> bool>(
        &self,
        _ray: &Ray,
        mut t_max: f32,
        mut leaf: F,
    ) -> bool {
        leaf(0..self.order.len(), &mut t_max)
    }
    /// Any-hit traversal.
    pub fn any<F: FnMut(Range<usize>, f32) -> bool>(&self, _ray: &Ray, t_max: f32, mut leaf: F) -> bool {
        leaf(0..self.order.len(), t_max)
    }
}

/// A triangle hit.
#[derive(Clone, Copy, Debug)]
pub struct TriHit {
    /// Distance.
    pub t: f32,
    /// Triangle index.
    pub prim: u32,
    /// Barycentric of vertex 1.
    pub u: f32,
    /// Barycentric of vertex 2.
    pub v: f32,
}

/// Triangle mesh accelerator.
pub struct MeshAccel {
    tris: Vec<[Vec3; 3]>,
    bounds: Aabb,
}

impl MeshAccel {
    /// Builds.
    pub fn build(p: &[Vec3], t: &[[u32; 3]]) -> MeshAccel {
        let tris: Vec<[Vec3; 3]> =
            t.iter().map(|i| [p[i[0] as usize], p[i[1] as usize], p[i[2] as usize]]).collect();
        MeshAccel { bounds: Aabb::from_points(tris.iter().flatten().copied()), tris }
    }
    /// Bounds.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
    /// Closest hit.
    pub fn intersect(&self, r: &Ray, t_min: f32, mut t_max: f32) -> Option<TriHit> {
        let mut best = None;
        for (i, tri) in self.tris.iter().enumerate() {
            let e1 = tri[1] - tri[0];
            let e2 = tri[2] - tri[0];
            let p = r.d.cross(e2);
            let det = e1.dot(p);
            if det == 0.0 {
                continue;
            }
            let inv = 1.0 / det;
            let s = r.o - tri[0];
            let u = s.dot(p) * inv;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(e1);
            let v = r.d.dot(q) * inv;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            let t = e2.dot(q) * inv;
            if t > t_min && t < t_max {
                t_max = t;
                best = Some(TriHit { t, prim: i as u32, u, v });
            }
        }
        best
    }
    /// Any hit.
    pub fn occluded(&self, r: &Ray, t_min: f32, t_max: f32) -> bool {
        self.intersect(r, t_min, t_max).is_some()
    }
}
