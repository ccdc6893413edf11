//! Object lights (hw7): `LightMesh` and `LightSphere`, geometry that is also a
//! light. The object itself is traced like any mesh or sphere (a camera or a
//! bounce that hits it sees its `Radiance`); this module is the light side,
//! drawing points on it for next-event estimation and giving the density of
//! a direction that reaches it, which multiple importance sampling needs.
//!
//! | emitter | sampled | density of `ω` (solid angle) |
//! |---|---|---|
//! | `LightMesh` | a triangle by area, then a uniform point on it | `d² / (A |n · ω|)`, `A` the area the point may see |
//! | `LightSphere` | a uniform direction in the cone the sphere subtends | `1 / (2π (1 − cos θmax))`, `sin θmax = R / d_c` |
//!
//! Sampling the cone instead of the surface never wastes a sample on the far
//! side of the sphere, and its density does not blow up at grazing angles.
//! A mesh emits from both faces (like the course's square area lights; the
//! course's mesh lights are closed boxes whose winding is not consistent),
//! a sphere from its outside. Where the mesh is a convex shell (the course's
//! boxes), its far side is blocked by its near side: points are drawn only
//! on the faces the shading point sees, and `A` is their area
//! ([`LightMesh::point_seen`], `shell/`).
//!
//! A `MotionBlur` translation moves the light with its object: a sample for
//! a ray at shutter time `t` is drawn on the light moved by `t · motion`,
//! where the ray itself would find it (the density does not change, since a
//! translation keeps areas, normals and the subtended cone).
//!
//! ```xml
//! <LightSphere id="1">
//!     <Material>1</Material> <Center>11</Center> <Radius>0.2</Radius>
//!     <Radiance>31.831 31.831 31.831</Radiance>
//! </LightSphere>
//! ```

use super::shell::{Shell, MAX_PLANES};
use luster_core::math::{orthonormal_basis, sin_cos_turns, Mat3, Transform, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// Lights with at most this many triangles pick one by a linear count.
const SCAN_TRIANGLES: usize = 32;

/// A mesh that emits `radiance` from every point of both faces, in world space.
#[derive(Clone, Debug)]
pub struct LightMesh {
    /// Each triangle as a corner, two edges and its unit normal; on a
    /// shell, sorted by face.
    tris: Vec<[Vec3; 4]>,
    /// Each triangle's span of the running sums of the areas: the sum
    /// before it (0 for the first) and the sum up to it, read as a pair
    /// without bounds tests or a branch for the first triangle.
    spans: Vec<(f32, f32)>,
    /// The total area, the last span's end (never empty).
    total: f32,
    /// For a light of at most [`SCAN_TRIANGLES`], the spans' ends in blocks of four,
    /// the last padded with `+∞`: counted a block at a time in vector lanes
    /// rather than one element at a time. A pad counts only for an infinite
    /// `target`, where the count
    /// is clamped to the last triangle anyway.
    scan: Vec<[f32; 4]>,
    /// RGB radiance.
    pub radiance: Vec3,
    /// World-space translation over the shutter interval (`MotionBlur`).
    pub motion: Vec3,
    /// Where the mesh is a convex shell, which hides its far side: its
    /// faces, each a run of `tris`, whose normals there point out (boxed:
    /// most meshes have none).
    faces: Option<Box<Faces>>,
}

/// A convex light mesh's faces, for drawing points only on those a point
/// sees.
#[derive(Clone, Debug)]
struct Faces {
    shell: Shell,
    /// Per face of `shell`: its triangles' range in `tris`, the area sum
    /// before its first triangle and its area; padded with empty runs to
    /// [`MAX_PLANES`], so that a mask's areas are summed at once.
    runs: [Run; MAX_PLANES],
}

#[derive(Clone, Copy, Debug, Default)]
struct Run {
    first: u32,
    end: u32,
    before: f32,
    area: f32,
}

impl LightMesh {
    /// From object-space corners and the object's transform; `None` when the
    /// mesh has no area.
    pub fn new(
        corners: impl Iterator<Item = [Vec3; 3]>,
        xf: &Transform,
        radiance: Vec3,
    ) -> Option<LightMesh> {
        let mut world: Vec<[Vec3; 3]> = corners
            .map(|c| c.map(|p| xf.point(p)))
            .filter(|[a, b, c]| {
                let area = 0.5 * (*b - *a).cross(*c - *a).length();
                area > 0.0 && area.is_finite()
            })
            .collect();
        let normal = |[a, b, c]: &[Vec3; 3]| (*b - *a).cross(*c - *a).normalize();
        // A shell's triangles in runs, one run per face.
        let shell = Shell::new(&world).and_then(|s| {
            let face: Vec<usize> = world.iter().map(|t| s.face_of(t[0], normal(t))).collect::<Option<_>>()?;
            let mut order: Vec<usize> = (0..world.len()).collect();
            order.sort_by_key(|&i| face[i]);
            world = order.iter().map(|&i| world[i]).collect();
            Some((s, order.iter().map(|&i| face[i]).collect::<Vec<_>>()))
        });
        let mut tris = Vec::with_capacity(world.len());
        let mut cdf = Vec::with_capacity(world.len());
        let mut total = 0.0f32;
        for t @ [a, b, c] in &world {
            total += 0.5 * (*b - *a).cross(*c - *a).length();
            let n = normal(t);
            tris.push([*a, *b - *a, *c - *a, shell.as_ref().map_or(n, |(s, _)| s.outward(*a, n))]);
            cdf.push(total);
        }
        let scan = if cdf.len() <= SCAN_TRIANGLES {
            cdf.chunks(4)
                .map(|c| std::array::from_fn(|k| c.get(k).copied().unwrap_or(f32::INFINITY)))
                .collect()
        } else {
            Vec::new()
        };
        let spans: Vec<(f32, f32)> =
            cdf.iter().scan(0.0, |lo, &hi| Some((std::mem::replace(lo, hi), hi))).collect();
        let faces = shell.map(|(shell, face)| {
            let mut runs = [Run::default(); MAX_PLANES];
            for (k, run) in runs.iter_mut().enumerate().take(shell.faces()) {
                let first = face.partition_point(|&f| f < k);
                let end = face.partition_point(|&f| f <= k);
                let before = spans.get(first).map_or(total, |s| s.0);
                let after = if end > 0 { spans[end - 1].1 } else { 0.0 };
                *run = Run { first: first as u32, end: end as u32, before, area: (after - before).max(0.0) };
            }
            Box::new(Faces { shell, runs })
        });
        (total > 0.0).then_some(LightMesh { tris, spans, scan, total, radiance, motion: Vec3::ZERO, faces })
    }

    /// Total area.
    #[inline]
    pub fn area(&self) -> f32 {
        self.total
    }

    /// The faces the point `p` (the light at rest) sees, as
    /// `Shell::facing`'s mask, and their area; `None` where `p` may see
    /// every point (a mesh that is no shell, or `p` inside it).
    #[inline(always)]
    fn seen(&self, p: Vec3) -> Option<(u32, f32)> {
        let f = self.faces.as_ref()?;
        let mask = f.shell.facing(p);
        if mask == 0 {
            return None;
        }
        let area = (0..MAX_PLANES).map(|k| if mask >> k & 1 != 0 { f.runs[k].area } else { 0.0 }).sum();
        Some((mask, area))
    }

    /// A point drawn uniformly by area from `(u1, u2)` over every triangle, and its unit normal.
    #[inline(always)]
    pub fn point(&self, (u1, u2): (f32, f32)) -> (Vec3, Vec3) {
        self.point_in(u1 * self.total, u2, 0, self.tris.len())
    }

    /// A point of the light at rest drawn uniformly by area from `(u1, u2)`
    /// over the part of the mesh that the point `p` may see at shutter
    /// `time`, its unit normal, and the area it was drawn from (for
    /// [`sample_from`](Self::sample_from)'s density): on a convex shell, the
    /// faces `p` is outside of (`Shell::facing`); on any other mesh, all of it.
    #[inline(always)]
    pub fn point_seen(&self, (u1, u2): (f32, f32), p: Vec3, time: f32) -> (Vec3, Vec3, f32) {
        let (Some((mask, area)), Some(f)) = (self.seen(p - self.motion * time), self.faces.as_ref()) else {
            let (q, n) = self.point((u1, u2));
            return (q, n, self.total);
        };
        // Walk the seen faces' areas; the part of `u1` left in a face picks
        // a point of its run of the sums.
        let mut left = u1 * area;
        let mut last = f.runs[0];
        for (k, r) in f.runs.iter().enumerate() {
            if mask >> k & 1 == 0 {
                continue;
            }
            last = *r;
            if left < r.area {
                break;
            }
            left -= r.area;
        }
        let (q, n) =
            self.point_in(last.before + left.min(last.area), u2, last.first as usize, last.end as usize);
        (q, n, area)
    }

    /// The point of the sums at `target`, in the triangles `first..end`.
    #[inline(always)]
    fn point_in(&self, target: f32, u2: f32, first: usize, end: usize) -> (Vec3, Vec3) {
        // A light of a few triangles (the course's boxes have ten) is
        // searched by counting, without the binary search's unpredictable
        // branches; both find the first sum above `target`.
        let i = if self.spans.len() <= SCAN_TRIANGLES {
            count_at_most(&self.scan, target)
        } else {
            self.spans.partition_point(|&(_, hi)| hi <= target)
        };
        let i = i.clamp(first, end - 1);
        let (lo, hi) = self.spans[i];
        // The part of the sums left over inside the chosen triangle is uniform again.
        let u1 = ((target - lo) / (hi - lo)).clamp(0.0, 1.0);
        let [a, e1, e2, n] = self.tris[i];
        let s = u1.sqrt();
        let (b1, b2) = (1.0 - s, u2 * s);
        (a + e1 * b1 + e2 * b2, n)
    }

    /// Solid-angle density of reaching the point `q` (normal `n`) from `p`
    /// through [`point_seen`](Self::point_seen), both where they are at
    /// shutter `time`.
    #[inline]
    pub fn pdf(&self, p: Vec3, q: Vec3, n: Vec3, time: f32) -> f32 {
        let area = self.seen(p - self.motion * time).map_or(self.total, |s| s.1);
        LightMesh::pdf_drawn(p, q, n, area)
    }

    /// [`pdf`](Self::pdf) of the point `q` (normal `n`) from `p` where
    /// `area` is the area it was drawn from ([`point_seen`](Self::point_seen)).
    #[inline(always)]
    pub fn pdf_drawn(p: Vec3, q: Vec3, n: Vec3, area: f32) -> f32 {
        let to = q - p;
        let d2 = to.length_squared();
        let cos = n.dot(to).abs() / d2.sqrt();
        if cos <= 0.0 {
            return 0.0;
        }
        d2 / (area * cos)
    }

    /// The world-space box of the mesh at rest, as its lower and upper
    /// corners (a light tree's bounds; `motion` not included).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.tris.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &[a, e1, e2, _]| {
            let (b, c) = (a + e1, a + e2);
            (lo.min(a).min(b).min(c), hi.max(a).max(b).max(c))
        })
    }

    /// Each triangle's unit normal (outward where the mesh is a convex
    /// shell; the mesh emits from both faces either way).
    pub fn normals(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.tris.iter().map(|t| t[3])
    }
}

/// How many of the blocks' values are at most `target`: a compare and a
/// subtraction a block in SSE2 lanes (LLVM keeps a scalar count's lanes
/// apart).
#[inline(always)]
fn count_at_most(blocks: &[[f32; 4]], target: f32) -> usize {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of every x86-64 CPU; each load reads one block's
    // four `f32`s.
    unsafe {
        use std::arch::x86_64::*;
        let t = _mm_set1_ps(target);
        let mut acc = _mm_setzero_si128();
        for b in blocks {
            // A lane's mask is −1 where the value is at most `target`.
            acc = _mm_sub_epi32(acc, _mm_castps_si128(_mm_cmple_ps(_mm_loadu_ps(b.as_ptr()), t)));
        }
        let acc = _mm_add_epi32(acc, _mm_shuffle_epi32::<0b01_00_11_10>(acc));
        let acc = _mm_add_epi32(acc, _mm_shuffle_epi32::<0b10_11_00_01>(acc));
        _mm_cvtsi128_si32(acc) as usize
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        blocks.iter().flatten().filter(|&&c| c <= target).count()
    }
}

/// A sphere that emits `radiance` from its outside, in world space; under a
/// transform that does not scale uniformly, the ellipsoid the transform makes
/// of it.
#[derive(Clone, Debug)]
pub struct LightSphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (of the sphere of the same volume, for an ellipsoid).
    pub radius: f32,
    /// RGB radiance.
    pub radiance: Vec3,
    /// World-space translation over the shutter interval (`MotionBlur`).
    pub motion: Vec3,
    /// The ellipsoid's map from the unit sphere, when the sphere is stretched.
    stretch: Option<Arc<Stretch>>,
}

/// An ellipsoid as `center + L u` over unit vectors `u`. Its points are
/// sampled as the unit sphere's cone seen from `L⁻¹ (p − center)`, mapped by
/// `L`: a linear map takes a direction density `p'(ω')` to
/// `p'(ω') / (|det L| |L⁻¹ ω|³)`, so the sample's density stays exact.
#[derive(Clone, Debug)]
struct Stretch {
    /// `L`: the transform's linear part times the object radius.
    l: Mat3,
    /// `L⁻¹`.
    inv: Mat3,
    /// `|det L|`.
    det: f32,
}

impl LightSphere {
    /// From the object-space sphere and the object's transform.
    pub fn new(center: Vec3, radius: f32, xf: &Transform, radiance: Vec3) -> LightSphere {
        let m = xf.matrix();
        let det = m.determinant().abs();
        let a = Mat3::from_mat4(m);
        // A rotation times a uniform scale keeps the sphere round: AᵀA = s² I.
        let ata = a.transpose() * a;
        let s2 = det.powf(2.0 / 3.0);
        let off = (ata - Mat3::from_diagonal(Vec3::splat(s2)))
            .to_cols_array()
            .iter()
            .fold(0f32, |m, x| m.max(x.abs()));
        let stretch = (off > 1e-5 * s2).then(|| {
            let l = a * radius;
            Arc::new(Stretch { l, inv: l.inverse(), det: l.determinant().abs() })
        });
        LightSphere {
            center: xf.point(center),
            radius: radius * det.cbrt(),
            radiance,
            motion: Vec3::ZERO,
            stretch,
        }
    }

    /// The same light moving by `motion` over the shutter interval.
    pub fn moving(self, motion: Vec3) -> LightSphere {
        LightSphere { motion, ..self }
    }

    /// A direction from `p` towards the sphere from `(u1, u2)`: the unit
    /// direction, the distance to the sphere along it, and its density over
    /// solid angle. A round sphere is sampled uniformly in the cone it
    /// subtends; an ellipsoid as its unit sphere's cone mapped onto it, the
    /// density divided by `|det L| |L⁻¹ ω|³` (`L` its map from the unit
    /// sphere).
    pub fn sample(&self, p: Vec3, u: (f32, f32)) -> Option<(Vec3, f32, f32)> {
        let Some(st) = &self.stretch else { return cone_sample(self.center, self.radius, p, u) };
        let (w, s, pdf) = cone_sample(Vec3::ZERO, 1.0, st.inv * (p - self.center), u)?;
        let lw = st.l * w;
        let len = lw.length();
        Some((lw / len, s * len, pdf * len * len * len / st.det))
    }

    /// Solid-angle density of direction `wi` from `p` under
    /// [`sample`](Self::sample) (0 where no sample goes).
    #[inline]
    pub fn pdf(&self, p: Vec3, wi: Vec3) -> f32 {
        let Some(st) = &self.stretch else { return cone_pdf(self.center, self.radius, p, wi) };
        let w = st.inv * wi;
        let len = w.length();
        if len.is_nan() || len <= 0.0 {
            return 0.0;
        }
        cone_pdf(Vec3::ZERO, 1.0, st.inv * (p - self.center), w / len) / (st.det * len * len * len)
    }

    /// The world-space box of the sphere (or ellipsoid) at rest, as its
    /// lower and upper corners (`motion` not included). An ellipsoid
    /// `c + L u` reaches `|row i of L|` from its centre along axis `i`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let r = match &self.stretch {
            None => Vec3::splat(self.radius),
            Some(st) => Vec3::new(st.l.row(0).length(), st.l.row(1).length(), st.l.row(2).length()),
        };
        (self.center - r, self.center + r)
    }

    /// Where the ray from `o` along the unit `d` enters the sphere (at
    /// rest), if it does: a shadow ray aimed from a surface's offset origin
    /// at a point sampled from the surface itself may pass through the
    /// sphere's rim first, and must stop there, not be blocked by it.
    pub fn entry(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let (oc, d) = match &self.stretch {
            None => ((o - self.center) / self.radius, d / self.radius),
            Some(st) => (st.inv * (o - self.center), st.inv * d),
        };
        // |oc + t d|² = 1, nearest root.
        let (a, b, c) = (d.length_squared(), oc.dot(d), oc.length_squared() - 1.0);
        let disc = b * b - a * c;
        (disc >= 0.0 && c > 0.0).then(|| (-b - disc.sqrt()) / a).filter(|t| *t > 0.0)
    }

    /// The surface point at `u` on the unit sphere and its outward unit
    /// normal, at rest.
    pub fn surface_point(&self, u: Vec3) -> (Vec3, Vec3) {
        match &self.stretch {
            None => (self.center + u * self.radius, u),
            Some(st) => (self.center + st.l * u, (st.inv.transpose() * u).normalize()),
        }
    }
}

/// `cos θmax` and `1 − cos θmax` of the cone a sphere of radius `r` fills
/// seen from a point at squared distance `d2` from its centre; `None` from
/// inside.
#[inline]
fn cone(r: f32, d2: f32) -> Option<(f32, f32)> {
    let sin2 = r * r / d2;
    if sin2 >= 1.0 {
        return None;
    }
    let cos = (1.0 - sin2).sqrt();
    // 1 − cos written without cancellation for small, distant spheres.
    Some((cos, sin2 / (1.0 + cos)))
}

/// A uniform direction from `p` in the cone the sphere `(c, r)` subtends:
/// the unit direction, the distance to the sphere along it, its density.
#[inline]
fn cone_sample(c: Vec3, r: f32, p: Vec3, (u1, u2): (f32, f32)) -> Option<(Vec3, f32, f32)> {
    let to_c = c - p;
    let d2 = to_c.length_squared();
    let (_, one_minus) = cone(r, d2)?;
    let cos = 1.0 - u1 * one_minus;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let (sp, cp) = sin_cos_turns(u2);
    let axis = to_c / d2.sqrt();
    let (t, b) = orthonormal_basis(axis);
    let wi = (t * (sin * cp) + b * (sin * sp) + axis * cos).normalize();
    // Nearest root of |p + s wi − c|² = R²; at the rim the discriminant
    // rounds to or below zero, where the tangent distance is the answer.
    let tc = to_c.dot(wi);
    let disc = r * r - (d2 - tc * tc);
    let dist = tc - disc.max(0.0).sqrt();
    Some((wi, dist.max(0.0), 1.0 / (2.0 * PI * one_minus)))
}

/// The density of `wi` from `p` under [`cone_sample`] (0 outside the cone).
#[inline]
fn cone_pdf(c: Vec3, r: f32, p: Vec3, wi: Vec3) -> f32 {
    let to_c = c - p;
    let d2 = to_c.length_squared();
    match cone(r, d2) {
        Some((cos_max, one_minus)) if to_c.dot(wi) >= cos_max * d2.sqrt() * (1.0 - 1e-6) => {
            1.0 / (2.0 * PI * one_minus)
        }
        _ => 0.0,
    }
}

/// The shape of an object whose shader emits ([`ShadedLight`]).
#[derive(Clone, Debug)]
pub enum ShadedShape {
    /// A mesh, sampled by area (its `radiance` is unused).
    Mesh(LightMesh),
    /// A sphere, sampled by the cone it subtends (its `radiance` is unused).
    Sphere(LightSphere),
}

/// An object whose `DecalMode material` shader defines `emission(s)`: a
/// light whose radiance is known only at points a ray finds. A sample is a
/// point (mesh) or direction (sphere) drawn as for a `LightMesh` or
/// `LightSphere`; the integrator traces a ray towards it and, when the ray's
/// first hit is this object where the sample lies, reads the shader's
/// emission there. A bounce that hits the object is weighed with the same
/// density ([`ShadedLight::pdf`]), so the two techniques stay consistent even
/// where the sample shape and the object differ (an ellipsoid-scaled sphere).
#[derive(Clone, Debug)]
pub struct ShadedLight {
    /// Where samples are drawn.
    pub shape: ShadedShape,
    /// The top-level primitive of the object (what a ray's hit must be on).
    pub prim: u32,
    /// The largest emission component found when the scene was built (by
    /// probing the shader over the surface): a lower bound of the true
    /// maximum, reported, not relied on.
    pub probed_max: f32,
}

impl ShadedLight {
    /// A sample towards the object from the point `p` at shutter `time`:
    /// unit direction, distance to the sampled point (on a sphere, any
    /// first hit on the object counts as the sample), and the density over
    /// solid angle, all measured from `p`.
    #[inline]
    pub fn sample(&self, p: Vec3, time: f32, u: (f32, f32)) -> Option<(Vec3, f32, f32)> {
        match &self.shape {
            ShadedShape::Mesh(l) => {
                let (q, nq, area) = l.point_seen(u, p, time);
                let q = q + l.motion * time;
                let to = q - p;
                let dist = to.length();
                let pdf = LightMesh::pdf_drawn(p, q, nq, area);
                (pdf > 0.0 && pdf.is_finite() && dist > 0.0).then_some((to / dist, dist, pdf))
            }
            ShadedShape::Sphere(l) => l.sample(p - l.motion * time, u),
        }
    }

    /// The density with which [`sample`](Self::sample) from `from` picks the
    /// direction `d` of a ray that hit the object at `q` (geometric normal
    /// `ng`).
    #[inline]
    pub fn pdf(&self, from: Vec3, q: Vec3, ng: Vec3, d: Vec3, time: f32) -> f32 {
        match &self.shape {
            ShadedShape::Mesh(l) => l.pdf(from, q, ng, time),
            ShadedShape::Sphere(l) => l.pdf(from - l.motion * time, d.normalize()),
        }
    }

    /// Probe points on the surface at rest: `n` points spread by a
    /// two-dimensional Halton sequence, each with its outward unit normal.
    pub fn probe_points(&self, n: u32) -> Vec<(Vec3, Vec3)> {
        (0..n)
            .map(|i| {
                let u = (radical_inverse(i, 2), radical_inverse(i, 3));
                match &self.shape {
                    ShadedShape::Mesh(l) => l.point(u),
                    ShadedShape::Sphere(l) => {
                        let z = 1.0 - 2.0 * u.0;
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        let (sp, cp) = sin_cos_turns(u.1);
                        l.surface_point(Vec3::new(r * cp, r * sp, z))
                    }
                }
            })
            .collect()
    }
}

/// The radical inverse of `i` in `base`, in [0, 1).
fn radical_inverse(mut i: u32, base: u32) -> f32 {
    let (mut inv, mut f) = (0.0f64, 1.0f64 / base as f64);
    while i > 0 {
        inv += (i % base) as f64 * f;
        i /= base;
        f /= base as f64;
    }
    inv.min(1.0 - f64::EPSILON) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::test_rng::Rng;

    /// The blocked count with its `+∞` padding picks the triangle a binary
    /// search of the sums picks, at the ends of the sums and between them.
    #[test]
    fn counted_pick_matches_the_binary_search() {
        let corners = (0..10).map(|k| {
            let x = k as f32;
            [Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0 + 0.1 * x, 0.0)]
        });
        let mesh = LightMesh::new(corners, &Transform::IDENTITY, Vec3::ONE).expect("area");
        assert_eq!((mesh.scan.len(), &mesh.scan[2][2..]), (3, &[f32::INFINITY; 2][..]));
        let total = mesh.area();
        let mut us: Vec<f32> = mesh.spans.iter().map(|&(_, hi)| hi / total).collect();
        us.extend((0..64).map(|k| k as f32 / 64.0));
        for u1 in us.into_iter().filter(|u| *u < 1.0) {
            let i = mesh.spans.partition_point(|&(_, hi)| hi <= u1 * total).min(9);
            let (p, _) = mesh.point((u1, 0.5));
            let [a, e1, e2, _] = mesh.tris[i];
            let q = p - a;
            let (b1, b2) = (q.x / e1.x, q.y / e2.y);
            assert!(b1 > -1e-4 && b2 > -1e-4 && b1 + b2 < 1.0 + 1e-4, "u1 {u1}: triangle {i}");
        }
    }

    #[test]
    fn mesh_points_are_uniform_by_area_and_pdf_matches_the_area_form() {
        // Two triangles: the right half of a unit square has area 0.5, a
        // 2×1 triangle beside it area 1, so two draws in three land there.
        let tris = [
            [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)],
            [Vec3::new(5.0, 0.0, 0.0), Vec3::new(7.0, 0.0, 0.0), Vec3::new(5.0, 1.0, 0.0)],
        ];
        let m = LightMesh::new(tris.into_iter(), &Transform::IDENTITY, Vec3::ONE).expect("has area");
        assert!((m.area() - 1.5).abs() < 1e-6);
        let mut rng = Rng(7);
        let n = 30_000;
        let mut second = 0;
        let mut mean_y_first = 0.0;
        let mut firsts = 0;
        for _ in 0..n {
            let (q, normal) = m.point((rng.next(), rng.next()));
            assert!((normal.z.abs() - 1.0).abs() < 1e-6 && q.z.abs() < 1e-6);
            if q.x >= 4.9 {
                second += 1;
                assert!(q.x <= 7.0 + 1e-5 && q.y >= -1e-6 && q.y <= 1.0 - (q.x - 5.0) / 2.0 + 1e-5);
            } else {
                // Inside the first triangle: 0 ≤ y ≤ x ≤ 1.
                assert!(q.y >= -1e-6 && q.y <= q.x + 1e-6 && q.x <= 1.0 + 1e-6);
                mean_y_first += q.y;
                firsts += 1;
            }
        }
        let share = second as f32 / n as f32;
        // Binomial: standard deviation sqrt(p(1-p)/n) ≈ 0.0027; 5 of them.
        assert!((share - 2.0 / 3.0).abs() < 0.014, "share {share}");
        // Centroid of the first triangle has y = 1/3.
        let my = mean_y_first / firsts as f32;
        assert!((my - 1.0 / 3.0).abs() < 0.01, "mean y {my}");
        // pdf: d² / (A cos).
        let p = Vec3::new(0.5, 0.2, 2.0);
        let q = Vec3::new(0.6, 0.3, 0.0);
        let d = q - p;
        let want = d.length_squared() / (1.5 * (d.z.abs() / d.length()));
        assert!((m.pdf(p, q, Vec3::Z, 0.0) - want).abs() < 1e-4 * want);
    }

    #[test]
    fn sphere_cone_samples_hit_the_sphere_and_integrate_its_solid_angle() {
        let s = LightSphere::new(Vec3::new(0.0, 0.0, 3.0), 1.0, &Transform::IDENTITY, Vec3::ONE);
        let p = Vec3::ZERO;
        let mut rng = Rng(11);
        let mut sum_inv_pdf = 0.0f64;
        let n = 20_000;
        for _ in 0..n {
            let (wi, dist, pdf) = s.sample(p, (rng.next(), rng.next())).expect("outside");
            let q = p + wi * dist;
            assert!(((q - s.center).length() - 1.0).abs() < 1e-3, "not on the sphere");
            assert!((s.pdf(p, wi) - pdf).abs() < 1e-3 * pdf);
            sum_inv_pdf += 1.0 / pdf as f64;
        }
        // Solid angle of a sphere of radius 1 at distance 3: 2π(1 − √(8)/3).
        let want = 2.0 * std::f64::consts::PI * (1.0 - 8f64.sqrt() / 3.0);
        assert!((sum_inv_pdf / n as f64 - want).abs() < 1e-4 * want);
        // Away from the cone, and from inside, there is no density.
        assert_eq!(s.pdf(p, Vec3::X), 0.0);
        assert!(s.sample(s.center, (0.5, 0.5)).is_none());
    }

    #[test]
    fn shaded_samples_have_the_density_their_pdf_gives_and_probes_lie_on_the_surface() {
        let square = [
            [Vec3::new(-1.0, 2.0, -1.0), Vec3::new(1.0, 2.0, -1.0), Vec3::new(1.0, 2.0, 1.0)],
            [Vec3::new(1.0, 2.0, 1.0), Vec3::new(-1.0, 2.0, 1.0), Vec3::new(-1.0, 2.0, -1.0)],
        ];
        let mesh = LightMesh::new(square.into_iter(), &Transform::IDENTITY, Vec3::ZERO).expect("has area");
        let sphere = LightSphere::new(Vec3::new(0.0, 3.0, 0.0), 0.5, &Transform::IDENTITY, Vec3::ZERO);
        let p = Vec3::ZERO;
        let mut rng = Rng(5);
        for shape in [ShadedShape::Mesh(mesh), ShadedShape::Sphere(sphere)] {
            let l = ShadedLight { shape, prim: 0, probed_max: 0.0 };
            // The estimate of the solid angle, Σ 1/pdf, against the exact one.
            let (mut sum, n) = (0.0f64, 20_000);
            for _ in 0..n {
                let (wi, dist, pdf) = l.sample(p, 0.0, (rng.next(), rng.next())).expect("in view");
                let q = p + wi * dist.min(1e3);
                let ng = match &l.shape {
                    ShadedShape::Mesh(_) => Vec3::Y,
                    ShadedShape::Sphere(s) => (q - s.center).normalize(),
                };
                assert!((l.pdf(p, q, ng, wi, 0.0) - pdf).abs() <= 1e-3 * pdf);
                sum += 1.0 / pdf as f64;
            }
            let want = match &l.shape {
                // A 2 × 2 square at height 2: 4 asin(a b / sqrt((a² + h²)(b² + h²))), a = b = 1, h = 2.
                ShadedShape::Mesh(_) => 4.0 * (1.0f64 / 5.0).asin(),
                ShadedShape::Sphere(_) => 2.0 * std::f64::consts::PI * (1.0 - (1.0f64 - 0.25 / 9.0).sqrt()),
            };
            let got = sum / n as f64;
            assert!((got - want).abs() < 0.02 * want, "solid angle {got} against {want}");
            for (q, nq) in l.probe_points(64) {
                let off = match &l.shape {
                    ShadedShape::Mesh(_) => (q.y - 2.0).abs() + (nq.y.abs() - 1.0).abs(),
                    ShadedShape::Sphere(s) => {
                        ((q - s.center).length() - s.radius).abs() + (nq.length() - 1.0).abs()
                    }
                };
                assert!(off < 1e-5, "probe {q:?} off the surface by {off}");
            }
        }
    }

    /// A sphere under a non-uniform scale, a rotation and a shear is an
    /// ellipsoid: its samples land on it, `pdf` gives their density, and
    /// `Σ 1/pdf` is its solid angle, counted independently by uniform
    /// directions that hit it.
    #[test]
    fn stretched_sphere_samples_cover_the_ellipsoid_with_their_density() {
        let rot = Transform::rotation(35.0, Vec3::new(1.0, 2.0, 0.5)).expect("rotation");
        let shear = Transform::from_rows([
            1.0, 0.4, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.3, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ])
        .expect("shear");
        let scale = Transform::scaling(Vec3::new(4.0, 0.5, 1.5)).expect("scale");
        let xf = scale.then(&rot).then(&shear).then(&Transform::translation(Vec3::new(0.5, 3.0, -1.0)));
        let s = LightSphere::new(Vec3::new(0.1, 0.2, 0.0), 0.7, &xf, Vec3::ONE);
        assert!(s.stretch.is_some());
        // On the ellipsoid: the object-space point is at the object radius.
        let on = |q: Vec3| (xf.inv_point(q) - Vec3::new(0.1, 0.2, 0.0)).length() / 0.7;
        let mut rng = Rng(3);
        for p in [Vec3::ZERO, Vec3::new(4.0, 3.5, 2.0), Vec3::new(-1.0, 6.0, -3.0)] {
            let n = 40_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let (wi, dist, pdf) = s.sample(p, (rng.next(), rng.next())).expect("outside");
                assert!((on(p + wi * dist) - 1.0).abs() < 2e-3, "sample off the ellipsoid");
                assert!((s.pdf(p, wi) - pdf).abs() <= 1e-3 * pdf, "pdf {} against {pdf}", s.pdf(p, wi));
                sum += 1.0 / f64::from(pdf);
            }
            let got = sum / n as f64;
            // Uniform directions: the share that hits the ellipsoid, times 4π.
            let (mut hits, m) = (0u32, 400_000);
            let (po, c) = (xf.inv_point(p), Vec3::new(0.1, 0.2, 0.0));
            for _ in 0..m {
                let z = 1.0 - 2.0 * rng.next();
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (sp, cp) = sin_cos_turns(rng.next());
                let d = xf.inv_vector(Vec3::new(r * cp, r * sp, z));
                let (oc, a) = (po - c, d.length_squared());
                let (b, cc) = (oc.dot(d), oc.length_squared() - 0.49);
                hits += u32::from(b * b - a * cc >= 0.0 && b < 0.0);
            }
            let frac = f64::from(hits) / m as f64;
            let want = 4.0 * std::f64::consts::PI * frac;
            let se = 4.0 * std::f64::consts::PI * (frac * (1.0 - frac) / m as f64).sqrt();
            assert!((got - want).abs() < 4.0 * se + 2e-3 * want, "solid angle {got} against {want} ± {se}");
            // Directions that miss it have no density.
            let away = (p - xf.point(c)).normalize();
            assert_eq!(s.pdf(p, away), 0.0);
        }
        // A rotation and a uniform scale keep it round.
        let round = LightSphere::new(
            Vec3::ZERO,
            1.0,
            &Transform::scaling(Vec3::splat(2.0)).expect("s").then(&rot),
            Vec3::ONE,
        );
        assert!(round.stretch.is_none() && (round.radius - 2.0).abs() < 1e-5);
    }

    #[test]
    fn sphere_radius_follows_a_uniform_scale() {
        let xf = Transform::scaling(Vec3::splat(2.0)).expect("invertible");
        let s = LightSphere::new(Vec3::X, 0.5, &xf, Vec3::ONE);
        assert!((s.radius - 1.0).abs() < 1e-5 && (s.center - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5);
    }
}
