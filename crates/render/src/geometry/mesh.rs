//! A triangle mesh in object space: positions, triangles, optional smooth
//! vertex normals, and the BVH over them.

use crate::accel::{MeshAccel, TriHit};
use luster_core::math::{Aabb, Ray, Vec2, Vec3};

/// A triangle mesh ready to trace.
pub struct Mesh {
    accel: MeshAccel,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per-vertex normals when the mesh is smooth-shaded.
    normals: Option<Vec<Vec3>>,
    /// Each triangle's unit winding normal, when the mesh is flat-shaded
    /// (see [`Mesh::unit_normal`]).
    unit_normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, when the mesh has them.
    uvs: Option<Vec<Vec2>>,
}

/// Texture coordinates and their frame at a point of a triangle.
#[derive(Clone, Copy, Debug)]
pub struct UvFrame {
    /// Interpolated texture coordinates (zero without any).
    pub uv: Vec2,
    /// Object-space ∂p/∂u.
    pub dpdu: Vec3,
    /// Object-space ∂p/∂v.
    pub dpdv: Vec3,
    /// Object-space position.
    pub p: Vec3,
}

impl Mesh {
    /// Builds a mesh; `normals`, when given, are per-vertex shading normals.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, normals: Option<Vec<Vec3>>) -> Mesh {
        let accel = MeshAccel::build(&positions, &triangles);
        let unit_normals = normals.is_none().then(|| {
            let at = |i: u32| positions.get(i as usize).copied().unwrap_or(Vec3::NAN);
            triangles.iter().map(|t| winding_normal(t.map(at)).normalize()).collect()
        });
        Mesh { accel, positions, triangles, normals, unit_normals, uvs: None }
    }

    /// Gives the mesh per-vertex texture coordinates (one per position).
    pub fn with_uvs(mut self, uvs: Option<Vec<Vec2>>) -> Mesh {
        self.uvs = uvs.filter(|u| u.len() == self.positions.len());
        self
    }

    /// Every triangle's corners, object space (an emitting mesh samples them).
    pub fn corners(&self) -> impl Iterator<Item = [Vec3; 3]> + '_ {
        self.triangles.iter().map(|t| t.map(|i| self.positions[i as usize]))
    }

    /// Texture coordinates, ∂p/∂u and ∂p/∂v (constant over a triangle: the
    /// inverse of its uv-to-position map), and the position at a hit. Without
    /// texture coordinates, or where they are degenerate, the derivatives are
    /// any frame around the face.
    pub fn uv_frame(&self, hit: &TriHit) -> UvFrame {
        let t = self.triangles[hit.prim as usize];
        let [a, b, c] = t.map(|i| self.positions[i as usize]);
        let w = 1.0 - hit.u - hit.v;
        let p = a * w + b * hit.u + c * hit.v;
        let (e1, e2) = (b - a, c - a);
        let fallback = || {
            let (s, t) = luster_core::math::orthonormal_basis(e1.cross(e2).normalize_or_zero());
            (s, t)
        };
        let Some(uvs) = &self.uvs else {
            let (dpdu, dpdv) = fallback();
            return UvFrame { uv: Vec2::ZERO, dpdu, dpdv, p };
        };
        let [ta, tb, tc] = t.map(|i| uvs[i as usize]);
        let uv = ta * w + tb * hit.u + tc * hit.v;
        let (d1, d2) = (tb - ta, tc - ta);
        let det = d1.x * d2.y - d1.y * d2.x;
        let (dpdu, dpdv) = if det.abs() > 1e-20 {
            let r = 1.0 / det;
            ((e1 * d2.y - e2 * d1.y) * r, (e2 * d1.x - e1 * d2.x) * r)
        } else {
            fallback()
        };
        UvFrame { uv, dpdu, dpdv, p }
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

    /// The accelerator, for callers that prepare the ray once for many
    /// meshes ([`MeshAccel::intersect_prepared`]).
    #[inline]
    pub fn accel(&self) -> &MeshAccel {
        &self.accel
    }

    /// Whether anything is hit.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.accel.occluded(ray, t_min, t_max)
    }

    /// The unit normal of triangle `prim`'s winding, object space, where the
    /// mesh is flat-shaded: the bits `normals_at(..).0.normalize()` gives
    /// (worked out once at build time, not at every hit: a square root and
    /// a division on the path tracer's every bounce).
    #[inline(always)]
    pub fn unit_normal(&self, prim: u32) -> Option<Vec3> {
        self.unit_normals.as_ref().and_then(|n| n.get(prim as usize)).copied()
    }

    /// Geometric normal (from the winding, unnormalized) and shading normal
    /// (interpolated if smooth, else the geometric one), in object space.
    /// Always inlined: called out of line from the AVX2 intersection, its
    /// two vectors would come back through memory and be read back in wider
    /// loads than they were stored with.
    #[inline(always)]
    pub fn normals_at(&self, hit: &TriHit) -> (Vec3, Vec3) {
        let t = self.triangles[hit.prim as usize];
        let ng = winding_normal(t.map(|i| self.positions[i as usize]));
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

/// The unnormalized normal of a triangle's winding, `(b − a) × (c − a)`.
#[inline(always)]
fn winding_normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a)
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

/// [`vertex_normals`] for a mesh whose vertices may be split at texture seams
/// (an OBJ file's `v/vt` pairs become separate vertices): vertices at exactly
/// the same position share one normal, so a seam does not show as a crease.
pub fn welded_vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut first: std::collections::HashMap<[u32; 3], u32> = std::collections::HashMap::new();
    let canon: Vec<u32> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| *first.entry(p.to_array().map(f32::to_bits)).or_insert(i as u32))
        .collect();
    let welded: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|i| canon[i as usize])).collect();
    let n = vertex_normals(positions, &welded);
    canon.iter().map(|&c| n[c as usize]).collect()
}
