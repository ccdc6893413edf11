//! A triangle mesh in object space: positions, triangles, optional smooth
//! vertex normals, and the BVH over them.

use crate::accel::{MeshAccel, TriHit};
use crate::math::{Aabb, Ray, Vec3};

/// A triangle mesh ready to trace.
pub struct Mesh {
    accel: MeshAccel,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per-vertex normals when the mesh is smooth-shaded.
    normals: Option<Vec<Vec3>>,
}

impl Mesh {
    /// Builds a mesh; `normals`, when given, are per-vertex shading normals.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, normals: Option<Vec<Vec3>>) -> Mesh {
        let accel = MeshAccel::build(&positions, &triangles);
        Mesh { accel, positions, triangles, normals }
    }

    /// Object-space bounds.
    pub fn bounds(&self) -> Aabb {
        self.accel.bounds()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The closest hit; `cull` as in [`MeshAccel::intersect_culled`].
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32, cull: f32) -> Option<TriHit> {
        self.accel.intersect_culled(ray, t_min, t_max, cull)
    }

    /// Whether anything is hit.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.accel.occluded(ray, t_min, t_max)
    }

    /// Geometric normal (from the winding, unnormalized) and shading normal
    /// (interpolated if smooth, else the geometric one), in object space.
    #[inline]
    pub fn normals_at(&self, hit: &TriHit) -> (Vec3, Vec3) {
        let t = self.triangles[hit.prim as usize];
        let [a, b, c] = t.map(|i| self.positions[i as usize]);
        let ng = (b - a).cross(c - a);
        let ns = match &self.normals {
            Some(n) => {
                let w = 1.0 - hit.u - hit.v;
                let s = n[t[0] as usize] * w + n[t[1] as usize] * hit.u + n[t[2] as usize] * hit.v;
                if s.length_squared() > 0.0 {
                    s
                } else {
                    ng
                }
            }
            None => ng,
        };
        (ng, ns)
    }
}

/// Smooth vertex normals: at each vertex, the area-weighted sum of the normals
/// of the faces around it (the unnormalized cross products), so slivers do not
/// tilt the shading.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let fnorm = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += fnorm;
        }
    }
    for v in &mut n {
        *v = v.normalize_or_zero();
    }
    n
}
