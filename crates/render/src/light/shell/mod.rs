//! Which faces of a light mesh a point can see: the near side of a convex
//! emitter.
//!
//! The course's mesh lights are small boxes (`LightMesh`, hw7) that emit from
//! both faces of every triangle, since their winding is not consistent. Seen
//! from outside, a point on the box's far side is always behind its near
//! side, so a light sample drawn there by area would be wasted: half the
//! samples of a box seen from below, nearly all of them from a ceiling beside
//! it. A light mesh that is a [`Shell`] draws its points only on the faces
//! the shading point sees ([`Shell::facing`]), with the density over their
//! area alone.
//!
//! A [`Shell`] is what the mesh must be for that to be exact: every
//! triangle lies on one of a few planes with every vertex of the mesh on one
//! side (a convex polyhedron's surface, each plane's outer side known), its
//! edges are each shared by two triangles except those around holes, and the
//! holes' edges all lie on one plane that is also a face of the hull (the
//! course's boxes are open at the top, flush with the ceiling). Then from a
//! point `o` outside the hull and not beyond the hole's plane, the segment to
//! a point `q` on a face whose outer side looks away from `o` arrives at `q`
//! from inside the hull: it entered the hull first, through a triangle and
//! not the hole, and so is blocked. A mesh that is no such shell draws
//! from all of its area.

use luster_core::math::Vec3;
use std::collections::HashMap;

/// Meshes with more distinct face planes draw from all of their area
/// (a point is tested against every plane, per sample).
pub const MAX_PLANES: usize = 8;

/// A plane `n · x = d` with unit `n` pointing out of the hull.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plane {
    n: Vec3,
    d: f32,
}

impl Plane {
    /// Signed distance of `x`, positive outside.
    #[inline]
    fn dist(&self, x: Vec3) -> f32 {
        self.n.dot(x) - self.d
    }
}

/// The convex shell a light mesh forms (see the module's doc).
#[derive(Clone, Debug)]
pub struct Shell {
    /// The hull's planes that carry triangles, outward.
    faces: Vec<Plane>,
    /// The plane of the holes, outward, if the mesh is open.
    hole: Option<Plane>,
    /// `faces` lane by lane (normals' x, y, z and the offsets), padded to
    /// [`MAX_PLANES`] with planes no point is outside of: [`Shell::facing`]
    /// tests them all at once.
    lanes: [[f32; MAX_PLANES]; 4],
    /// Distances below this are treated as on the plane: a point must be
    /// farther than this on the side a test needs.
    tol: f32,
}

impl Shell {
    /// The shell of the world-space triangles `tris` (corners), or `None`
    /// where the mesh is no convex shell of at most [`MAX_PLANES`] planes:
    /// flat, concave, in pieces, with a non-manifold edge, or with holes
    /// that are not on one plane of the hull.
    pub fn new(tris: &[[Vec3; 3]]) -> Option<Shell> {
        let verts: Vec<Vec3> = tris.iter().flatten().copied().collect();
        let (lo, hi) =
            verts.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let extent = (hi - lo).length();
        if !(extent > 0.0 && extent.is_finite()) {
            return None;
        }
        let tol = extent * 1e-5;
        let mut faces: Vec<Plane> = Vec::new();
        for [a, b, c] in tris {
            let n = (*b - *a).cross(*c - *a).normalize_or_zero();
            if n == Vec3::ZERO {
                return None;
            }
            let on =
                |p: &Plane| [a, b, c].iter().all(|v| p.dist(**v).abs() <= tol) && p.n.dot(n).abs() > 0.999;
            if !faces.iter().any(on) {
                if faces.len() == MAX_PLANES {
                    return None;
                }
                faces.push(Plane { n, d: n.dot(*a) });
            }
        }
        for f in &mut faces {
            *f = turned_out(*f, &verts, tol)?;
        }
        let hole = match hole_vertices(tris)? {
            rim if rim.is_empty() => None,
            rim => Some(turned_out(plane_through(&rim, tol)?, &verts, tol)?),
        };
        let mut lanes =
            [[0.0; MAX_PLANES], [0.0; MAX_PLANES], [0.0; MAX_PLANES], [f32::INFINITY; MAX_PLANES]];
        for (k, f) in faces.iter().enumerate() {
            (lanes[0][k], lanes[1][k], lanes[2][k], lanes[3][k]) = (f.n.x, f.n.y, f.n.z, f.d);
        }
        Some(Shell { faces, hole, tol, lanes })
    }

    /// The face (an index below [`faces`](Self::faces)) that the triangle
    /// with corner `a` and unit normal `n` lies on.
    pub fn face_of(&self, a: Vec3, n: Vec3) -> Option<usize> {
        self.faces.iter().position(|f| f.dist(a).abs() <= self.tol && f.n.dot(n).abs() > 0.999)
    }

    /// How many faces the shell has (at most [`MAX_PLANES`]).
    pub fn faces(&self) -> usize {
        self.faces.len()
    }

    /// `n`, the unit normal of a triangle of the shell with corner `a`,
    /// turned to point out of the hull.
    pub fn outward(&self, a: Vec3, n: Vec3) -> Vec3 {
        match self.face_of(a, n).map(|k| self.faces[k]) {
            Some(f) if f.n.dot(n) < 0.0 => -n,
            _ => n,
        }
    }

    /// The faces whose points `o` may see, as a mask (bit `k` for face
    /// `k`): those whose outer side `o` is on. Every point of another face
    /// is behind it, so a segment from `o` arrives there from inside the
    /// hull, having entered it through a face (not the hole: `o` is not
    /// beyond the hole's plane, so neither is any point of the segment).
    /// 0 where `o` may see every face: inside the hull, or beyond the
    /// hole's plane, where the open side shows the inside. Exact tests,
    /// with no tolerance: a face that `o` is within rounding of is seen
    /// edge-on, and counts nothing either way.
    #[inline]
    pub fn facing(&self, o: Vec3) -> u32 {
        if self.hole.is_some_and(|h| h.dist(o) > 0.0) {
            return 0;
        }
        let [nx, ny, nz, d] = &self.lanes;
        (0..MAX_PLANES)
            .fold(0, |m, k| m | (u32::from(nx[k] * o.x + ny[k] * o.y + nz[k] * o.z - d[k] > 0.0) << k))
    }
}

/// `p` turned so that every vertex lies on its inner side; `None` where
/// vertices lie on both sides (concave, or several pieces) or all on it (a
/// flat mesh, which has no inside).
fn turned_out(p: Plane, verts: &[Vec3], tol: f32) -> Option<Plane> {
    let (lo, hi) = verts.iter().fold((0.0f32, 0.0f32), |(lo, hi), &v| {
        let s = p.dist(v);
        (lo.min(s), hi.max(s))
    });
    match (lo < -tol, hi > tol) {
        (true, false) => Some(p),
        (false, true) => Some(Plane { n: -p.n, d: -p.d }),
        _ => None,
    }
}

/// The corners on the mesh's boundary (edges of one triangle), with
/// corners matched by their exact position; `None` where an edge has more
/// than two triangles.
fn hole_vertices(tris: &[[Vec3; 3]]) -> Option<Vec<Vec3>> {
    type Corner = [u32; 3];
    let key = |v: Vec3| -> Corner { v.to_array().map(f32::to_bits) };
    // Each edge's count of triangles and its two corners.
    let mut edges: HashMap<(Corner, Corner), (u32, Vec3, Vec3)> = HashMap::new();
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (ka, kb) = (key(a), key(b));
            let e = edges.entry(if ka < kb { (ka, kb) } else { (kb, ka) }).or_insert((0, a, b));
            e.0 += 1;
        }
    }
    if edges.values().any(|e| e.0 > 2) {
        return None;
    }
    Some(edges.values().filter(|e| e.0 == 1).flat_map(|e| [e.1, e.2]).collect())
}

/// The plane through all of `pts`, or `None` where they do not span one
/// (collinear) or do not lie on one.
fn plane_through(pts: &[Vec3], tol: f32) -> Option<Plane> {
    let a = pts[0];
    let b = *pts.iter().max_by(|p, q| (**p - a).length_squared().total_cmp(&(**q - a).length_squared()))?;
    let c = *pts.iter().max_by(|p, q| {
        let area = |x: &Vec3| (b - a).cross(*x - a).length_squared();
        area(p).total_cmp(&area(q))
    })?;
    let n = (b - a).cross(c - a).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    let p = Plane { n, d: n.dot(a) };
    pts.iter().all(|v| p.dist(*v).abs() <= tol).then_some(p)
}

#[cfg(test)]
mod tests;
