//! The triangle-mesh accelerator: a [`Bvh`] over a mesh's triangles with
//! each leaf's triangles copied into SIMD blocks of four ([`TriBlock`]).
//!
//! The tree is built with the SAH counting a leaf's cost in blocks, so leaves
//! hold 4 or 8 triangles and few lanes sit idle; one block test costs about
//! as much as one scalar triangle test. Copying the vertices (160 bytes per
//! block) instead of following `triangles[i]` into `positions` makes a leaf
//! one contiguous run of memory: the traversal touches a node, then one or
//! two adjacent blocks, and never chases an index. The original triangle
//! index travels along so a hit can be shaded with the mesh's own normals
//! and texture coordinates.
//!
//! Triangles with zero area, a non-finite vertex or a vertex index out of
//! range are dropped at build time: they can never be hit, and leaving them
//! out means the intersection code never has to think about them.

use glam::Vec3;
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
use super::bvh::fused_available;
use super::bvh::{AnyLeaf, Bvh, ClosestLeaf, Traversal};
use super::tri_block::TriBlock;
use super::triangle::{Triangle, WatertightRay};
use crate::math::{Aabb, Ray};

/// A ray–triangle hit.
///
/// `u` and `v` first, side by side: a hit is written field by field during
/// traversal and copied soon after, `t` from a register and the rest from
/// memory, and a copy's 8-byte load of `prim` with `u` spanned two 4-byte
/// stores, which it cannot be forwarded from (it waited for them to
/// retire). Now that load is `u, v`, stored as one word ([`PairHit::uv`](super::tri_block::PairHit::uv)).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct TriHit {
    /// Barycentric coordinate of the triangle's vertex 1.
    pub u: f32,
    /// Barycentric coordinate of the triangle's vertex 2.
    pub v: f32,
    /// Ray parameter, in units of the ray's direction.
    pub t: f32,
    /// Index into the `triangles` given to [`MeshAccel::build`].
    pub prim: u32,
}

/// A triangle mesh ready for ray queries. Immutable, `Send + Sync`.
#[derive(Clone, Debug)]
pub struct MeshAccel {
    bvh: Bvh,
    /// Each leaf's triangles in blocks of four: leaf range `r` is `blocks[r]`.
    blocks: Vec<TriBlock>,
    /// Valid triangles (the used lanes of `blocks`).
    count: usize,
    /// Whether any-hit queries test every block without the tree: a
    /// one-leaf mesh, or one of at most [`FLAT_ANY_BLOCKS`] blocks.
    any_flat: bool,
}

/// The most blocks (two 8-lane pairs, 16 triangles) an any-hit query tests
/// without the mesh's tree: the hw7 Cornell box's light (10 triangles, two
/// leaves) cost a call, a node test and its set-up (about 310 instructions)
/// per shadow ray, against about 130 for its three blocks. The leaf boxes
/// are conservative (a triangle the ray hits lies in a box it enters), so
/// the blocks tested alone block the same rays.
const FLAT_ANY_BLOCKS: usize = 4;

impl MeshAccel {
    /// Builds the accelerator. Invalid triangles (see the module doc) are
    /// skipped, never a panic.
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> MeshAccel {
        let vertex = |i: u32| positions.get(i as usize).copied();
        let tri_of = |k: u32| -> Option<Triangle> {
            let t = triangles.get(k as usize)?;
            let tri = Triangle::new(vertex(t[0])?, vertex(t[1])?, vertex(t[2])?, k);
            (!tri.is_degenerate()).then_some(tri)
        };
        let tri_box =
            |k: usize| tri_of(k as u32).map_or(Aabb::EMPTY, |t| Aabb::from_points(t.v.map(Vec3::from)));
        let mut bvh = Bvh::build_blocked_with(triangles.len(), tri_box, 4);
        // Number the blocks leaf by leaf (serial and cheap), then fill them
        // in parallel.
        let mut groups: Vec<[u32; 4]> = Vec::new();
        let mut lens: Vec<u8> = Vec::new();
        bvh.remap_leaves(|prims| {
            let first = groups.len();
            for chunk in prims.chunks(4) {
                let mut g = [u32::MAX; 4];
                g[..chunk.len()].copy_from_slice(chunk);
                groups.push(g);
                lens.push(chunk.len() as u8);
            }
            first..groups.len()
        });
        let count = lens.iter().map(|&n| n as usize).sum();
        let blocks = groups
            .par_iter()
            .zip(&lens)
            .map(|(g, &n)| {
                // Every primitive in the tree had a non-empty box, so came
                // from a valid triangle.
                let mut tris = [Triangle { v: [[0.0; 3]; 3], prim: 0 }; 4];
                for (t, &k) in tris.iter_mut().zip(&g[..n as usize]) {
                    *t = tri_of(k).expect("BVH holds only valid triangles");
                }
                TriBlock::new(&tris[..n as usize])
            })
            .collect::<Vec<_>>();
        let any_flat = bvh.single_leaf().is_some() || blocks.len() <= FLAT_ANY_BLOCKS;
        MeshAccel { bvh, blocks, count, any_flat }
    }

    /// The closest hit with `t_min < t < t_max`, if any.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<TriHit> {
        self.intersect_culled(ray, t_min, t_max, 0.0)
    }

    /// The closest hit, skipping triangles whose winding normal `n` has
    /// `cull · (n · d) > 0`: `cull = 1` culls back faces, `-1` front faces
    /// (for a mirroring transform), `0` nothing. The facing is checked only
    /// for triangles the ray actually hits, so culling costs next to nothing.
    #[inline]
    pub fn intersect_culled(&self, ray: &Ray, t_min: f32, t_max: f32, cull: f32) -> Option<TriHit> {
        self.intersect_prepared(ray, &WatertightRay::new(ray), t_min, t_max, cull)
    }

    /// [`MeshAccel::intersect_culled`] with the ray's watertight shear
    /// already computed (`wr` must be `WatertightRay::new(ray)`): a scene
    /// whose meshes share one space computes it once per ray, not per mesh.
    #[inline]
    pub fn intersect_prepared(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        t_min: f32,
        t_max: f32,
        cull: f32,
    ) -> Option<TriHit> {
        #[cfg(target_arch = "x86_64")]
        if fused_available() {
            // SAFETY: the CPU has AVX2 and FMA.
            return unsafe { self.intersect_avx2(ray, wr, t_min, t_max, cull) };
        }
        self.intersect_with::<false>(ray, wr, None, t_min, t_max, cull)
    }

    /// [`MeshAccel::intersect_prepared`] compiled for AVX2 and FMA: the
    /// traversal's fused node test, and leaves of two blocks tested as one
    /// 8-lane block pair. Hits are bit for bit those of the 4-lane path.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn intersect_avx2(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        t_min: f32,
        t_max: f32,
        cull: f32,
    ) -> Option<TriHit> {
        self.intersect_with::<true>(ray, wr, None, t_min, t_max, cull)
    }

    /// [`MeshAccel::intersect_prepared`] for a caller compiled for AVX2 and
    /// FMA (`AVX`, after checking `fused_available`) or not: the traversal
    /// and leaf tests inline into the caller's own code. `pre`, when given,
    /// is `ray` already prepared for traversal (by a caller whose own tree
    /// saw the same ray), and is used instead of preparing it again.
    #[inline(always)]
    pub(crate) fn intersect_with<const AVX: bool>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
        cull: f32,
    ) -> Option<TriHit> {
        let mut best = None;
        let blocks = &self.blocks[..];
        match self.bvh.single_leaf() {
            // A small mesh (a wall, a light): its one or two blocks cost no
            // more than the box test would.
            Some(range) => {
                let mut t = t_max;
                leaf_closest::<AVX>(&blocks[range], ray, wr, t_min, &mut t, cull, &mut best);
            }
            None => {
                let leaf = Closest::<AVX> { blocks, ray, wr, t_min, cull, best: &mut best };
                // One walk for both: two inlined copies doubled the frame
                // (two traversal stacks) and the code of the out-of-line
                // callers (`tree_closest_*`).
                let own;
                let tr = match pre {
                    Some(tr) => tr,
                    None => {
                        own = Traversal::new::<AVX>(ray);
                        &own
                    }
                };
                self.bvh.closest_prepared(tr, t_max, leaf);
            }
        }
        best
    }

    /// [`MeshAccel::intersect_with`] for a scene's top-level traversal: a
    /// one-leaf mesh (a wall, a light) is tested inline, a mesh with a tree
    /// of its own out of line, so that the top level's code stays small (see
    /// `bvh::walk`). The same tests, so the same hits.
    #[inline(always)]
    pub(crate) fn intersect_split<const AVX: bool>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
        cull: f32,
    ) -> Option<TriHit> {
        if let Some(range) = self.bvh.single_leaf() {
            let (mut best, mut t) = (None, t_max);
            leaf_closest::<AVX>(&self.blocks[range], ray, wr, t_min, &mut t, cull, &mut best);
            return best;
        }
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: `AVX` callers run only where the CPU has AVX2 and FMA.
            return unsafe { self.tree_closest_avx2(ray, wr, pre, t_min, t_max, cull) };
        }
        self.tree_closest_plain(ray, wr, pre, t_min, t_max, cull)
    }

    /// [`MeshAccel::intersect_with`] out of line, compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    unsafe fn tree_closest_avx2(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
        cull: f32,
    ) -> Option<TriHit> {
        self.intersect_with::<true>(ray, wr, pre, t_min, t_max, cull)
    }

    /// [`MeshAccel::intersect_with`] out of line, without AVX2.
    #[inline(never)]
    fn tree_closest_plain(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
        cull: f32,
    ) -> Option<TriHit> {
        self.intersect_with::<false>(ray, wr, pre, t_min, t_max, cull)
    }

    /// True if some triangle is hit with `t_min < t < t_max` (shadow rays).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.occluded_prepared(ray, &WatertightRay::new(ray), t_min, t_max)
    }

    /// [`MeshAccel::occluded`] with the ray's shear already computed (see
    /// [`MeshAccel::intersect_prepared`]).
    #[inline]
    pub fn occluded_prepared(&self, ray: &Ray, wr: &WatertightRay, t_min: f32, t_max: f32) -> bool {
        #[cfg(target_arch = "x86_64")]
        if fused_available() {
            // SAFETY: the CPU has AVX2 and FMA.
            return unsafe { self.occluded_avx2(ray, wr, t_min, t_max) };
        }
        self.occluded_with::<false>(ray, wr, None, t_min, t_max)
    }

    /// [`MeshAccel::occluded_prepared`] compiled for AVX2 and FMA (see
    /// [`MeshAccel::intersect_avx2`]).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn occluded_avx2(&self, ray: &Ray, wr: &WatertightRay, t_min: f32, t_max: f32) -> bool {
        self.occluded_with::<true>(ray, wr, None, t_min, t_max)
    }

    /// [`MeshAccel::occluded_prepared`] as [`MeshAccel::intersect_with`] is
    /// to [`MeshAccel::intersect_prepared`].
    #[inline(always)]
    pub(crate) fn occluded_with<const AVX: bool>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        let blocks = &self.blocks[..];
        if self.any_flat {
            return leaf_any::<AVX>(blocks, wr, t_min, t_max);
        }
        // One walk for both (see [`MeshAccel::intersect_with`]).
        let own;
        let tr = match pre {
            Some(tr) => tr,
            None => {
                own = Traversal::new::<AVX>(ray);
                &own
            }
        };
        self.bvh.any_prepared(tr, t_max, Any::<AVX> { blocks, wr, t_min })
    }

    /// [`MeshAccel::occluded_with`] as [`MeshAccel::intersect_split`] is
    /// to [`MeshAccel::intersect_with`].
    #[inline(always)]
    pub(crate) fn occluded_split<const AVX: bool>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        if self.any_flat {
            return leaf_any::<AVX>(&self.blocks, wr, t_min, t_max);
        }
        #[cfg(target_arch = "x86_64")]
        if AVX {
            // SAFETY: `AVX` callers run only where the CPU has AVX2 and FMA.
            return unsafe { self.tree_occluded_avx2(ray, wr, pre, t_min, t_max) };
        }
        self.tree_occluded_plain(ray, wr, pre, t_min, t_max)
    }

    /// [`MeshAccel::occluded_with`] out of line, compiled for AVX2 and FMA.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    unsafe fn tree_occluded_avx2(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        self.occluded_with::<true>(ray, wr, pre, t_min, t_max)
    }

    /// [`MeshAccel::occluded_with`] out of line, without AVX2.
    #[inline(never)]
    fn tree_occluded_plain(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        pre: Option<&Traversal>,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        self.occluded_with::<false>(ray, wr, pre, t_min, t_max)
    }

    /// The box around the mesh's (valid) triangles.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// Number of triangles in the accelerator (invalid input triangles are
    /// not counted).
    pub fn triangle_count(&self) -> usize {
        self.count
    }

    /// Number of 4-triangle blocks (some lanes of which may be unused).
    pub fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// The underlying hierarchy.
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Heap memory held by the accelerator.
    pub fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes() + self.blocks.capacity() * size_of::<TriBlock>()
    }
}

/// The closest-hit leaf test of a mesh's traversal.
struct Closest<'a, const AVX: bool> {
    blocks: &'a [TriBlock],
    ray: &'a Ray,
    wr: &'a WatertightRay,
    t_min: f32,
    cull: f32,
    best: &'a mut Option<TriHit>,
}

impl<const AVX: bool> ClosestLeaf for Closest<'_, AVX> {
    #[inline(always)]
    fn test(&mut self, range: std::ops::Range<usize>, t_max: &mut f32) -> bool {
        leaf_closest::<AVX>(&self.blocks[range], self.ray, self.wr, self.t_min, t_max, self.cull, self.best)
    }
}

/// The any-hit leaf test of a mesh's traversal.
struct Any<'a, const AVX: bool> {
    blocks: &'a [TriBlock],
    wr: &'a WatertightRay,
    t_min: f32,
}

impl<const AVX: bool> AnyLeaf for Any<'_, AVX> {
    #[inline(always)]
    fn test(&mut self, range: std::ops::Range<usize>, t_max: f32) -> bool {
        leaf_any::<AVX>(&self.blocks[range], self.wr, self.t_min, t_max)
    }
}

/// Tests a leaf's blocks for the closest hit below `*t_max`, lowering it and
/// recording the hit in `best`; returns whether one was found. With `AVX`
/// (only in code compiled for AVX2) blocks go two at a time through the
/// 8-lane test.
#[inline(always)]
fn leaf_closest<const AVX: bool>(
    blocks: &[TriBlock],
    ray: &Ray,
    wr: &WatertightRay,
    t_min: f32,
    t_max: &mut f32,
    cull: f32,
    best: &mut Option<TriHit>,
) -> bool {
    let mut found = false;
    // Lanes in order, each against the nearest hit so far: the same choice
    // as testing the triangles one by one. (A lane of a pair's second block
    // was tested against the `t_max` from before the first block's hits; a
    // hit that is no longer closer is dropped here, as it would have been
    // there.)
    macro_rules! take {
        ($b:expr, $i:expr, $t:expr, $uv:expr) => {{
            let (b, i, t): (&TriBlock, usize, f32) = ($b, $i, $t);
            // A lane's t passed `t > t_min`, so it is not NaN.
            let skip = t >= *t_max || (cull != 0.0 && cull * b.triangle(i).normal().dot(ray.d) > 0.0);
            if !skip {
                *t_max = t;
                let [u, v] = $uv;
                *best = Some(TriHit { u, v, t, prim: b.prim(i) });
                found = true;
            }
        }};
    }
    let mut rest = blocks;
    #[cfg(target_arch = "x86_64")]
    if AVX {
        let mut pairs = blocks.chunks_exact(2);
        for p in &mut pairs {
            // SAFETY: `AVX` code runs only where the CPU has AVX2.
            let h = unsafe { TriBlock::intersect_pair(&p[0], &p[1], wr, t_min, *t_max) };
            let mut m = h.mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                take!(&p[i / 4], i % 4, h.t[i], h.uv[i]);
            }
        }
        rest = pairs.remainder();
    }
    for b in rest {
        let h = b.intersect(wr, t_min, *t_max);
        let mut m = h.mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            take!(b, i, h.t[i], h.uv[i]);
        }
    }
    found
}

/// Whether some triangle of a leaf's blocks is hit with `t_min < t < t_max`
/// (blocks two at a time with `AVX`, as in [`leaf_closest`]).
#[inline(always)]
fn leaf_any<const AVX: bool>(blocks: &[TriBlock], wr: &WatertightRay, t_min: f32, t_max: f32) -> bool {
    let mut rest = blocks;
    #[cfg(target_arch = "x86_64")]
    if AVX {
        let mut pairs = blocks.chunks_exact(2);
        for p in &mut pairs {
            // SAFETY: `AVX` code runs only where the CPU has AVX2.
            if unsafe { TriBlock::intersect_pair(&p[0], &p[1], wr, t_min, t_max) }.mask != 0 {
                return true;
            }
        }
        rest = pairs.remainder();
    }
    // A loop, not `Iterator::any`: its closure was left out of line.
    for b in rest {
        if b.intersect(wr, t_min, t_max).mask != 0 {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::tests::Rng;

    /// An n×n grid of quads, two triangles each, with random heights: every
    /// interior edge and vertex is shared, and no two neighbours are coplanar.
    /// Slopes stay below 20° so the rays of the leak test, steeper than 50°,
    /// cross the surface instead of grazing a silhouette (where a ray
    /// rounded past a vertex may rightly miss).
    fn bumpy_grid(rng: &mut Rng, n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push(Vec3::new(i as f32 * 0.37, j as f32 * 0.29, rng.range(-0.05, 0.05)));
            }
        }
        let mut t = Vec::new();
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                // Alternate the diagonal so vertices have both 4 and 8 neighbours.
                if (i + j) % 2 == 0 {
                    t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                } else {
                    t.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                    t.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
        }
        (p, t)
    }

    fn brute(pos: &[Vec3], tris: &[[u32; 3]], ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
        let wr = WatertightRay::new(ray);
        let mut best: Option<(f32, u32)> = None;
        for (k, t) in tris.iter().enumerate() {
            let tri = Triangle::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize], k as u32);
            if let Some(h) = wr.intersect(&tri, 0.0, best.map_or(t_max, |b| b.0)) {
                best = Some((h.t, k as u32));
            }
        }
        best
    }

    #[test]
    fn rays_through_shared_edges_and_vertices_never_leak() {
        let mut rng = Rng(11);
        let n = 24;
        let (pos, tris) = bumpy_grid(&mut rng, n);
        let mesh = MeshAccel::build(&pos, &tris);
        assert_eq!(mesh.triangle_count(), tris.len());
        let mut targets = Vec::new();
        // Every interior vertex, exactly.
        for j in 1..n {
            for i in 1..n {
                targets.push(pos[j * (n + 1) + i]);
            }
        }
        // Points on shared edges (as close as f32 gets), from random triangles.
        for _ in 0..20_000 {
            let t = tris[(rng.next_u64() % tris.len() as u64) as usize];
            let e = (rng.next_u64() % 3) as usize;
            let (a, b) = (pos[t[e] as usize], pos[t[(e + 1) % 3] as usize]);
            let s = rng.f();
            let p = a + (b - a) * s;
            let lo = pos[0].truncate();
            let hi = pos[pos.len() - 1].truncate();
            // Edges on the grid's border are not shared: rays may miss there.
            if p.x > lo.x + 1e-3 && p.y > lo.y + 1e-3 && p.x < hi.x - 1e-3 && p.y < hi.y - 1e-3 {
                targets.push(p);
            }
        }
        assert!(targets.len() > 10_000);
        for (k, &p) in targets.iter().enumerate() {
            // Origins above and below, directions deliberately not unit length.
            let o = p + Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(2.0, 4.0))
                * if k % 2 == 0 { 1.0 } else { -1.0 };
            let ray = Ray::new(o, (p - o) * rng.range(0.1, 10.0));
            assert!(brute(&pos, &tris, &ray, f32::INFINITY).is_some(), "ray {k} through {p} leaked");
            let hit = mesh.intersect(&ray, 0.0, f32::INFINITY);
            assert!(hit.is_some(), "ray {k} through shared point {p} lost in the BVH");
            assert!(mesh.occluded(&ray, 0.0, f32::INFINITY), "shadow ray {k} leaked");
        }
    }

    #[test]
    fn closest_hit_matches_brute_force_with_barycentrics() {
        let mut rng = Rng(5);
        // A triangle soup, so hits overlap and ordering matters.
        // Triangles shrunk towards their centroids so rays get between them.
        let pos: Vec<Vec3> = (0..1000)
            .flat_map(|_| {
                let c = [rng.vec(-5.0, 5.0), rng.vec(-5.0, 5.0), rng.vec(-5.0, 5.0)];
                let m = (c[0] + c[1] + c[2]) / 3.0;
                c.map(|v| m + (v - m) * 0.3)
            })
            .collect();
        let tris: Vec<[u32; 3]> = (0..1000u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let mesh = MeshAccel::build(&pos, &tris);
        let mut hits = 0;
        for _ in 0..5000 {
            let ray = Ray::new(rng.vec(-8.0, 8.0), rng.dir() * rng.range(0.5, 2.0));
            let got = mesh.intersect(&ray, 0.0, f32::INFINITY);
            let want = brute(&pos, &tris, &ray, f32::INFINITY);
            assert_eq!(got.map(|h| (h.t, h.prim)), want);
            assert_eq!(mesh.occluded(&ray, 0.0, f32::INFINITY), want.is_some());
            if let Some(h) = got {
                hits += 1;
                let t = tris[h.prim as usize].map(|i| pos[i as usize]);
                let p = t[0] * (1.0 - h.u - h.v) + t[1] * h.u + t[2] * h.v;
                assert!((p - ray.at(h.t)).length() < 1e-3, "barycentrics disagree with t");
                assert!(h.u >= 0.0 && h.v >= 0.0 && h.u + h.v <= 1.0 + 1e-6);
                // t_max and t_min are exclusive bounds.
                assert!(mesh.intersect(&ray, 0.0, h.t).is_none_or(|h2| h2.t < h.t));
                assert!(mesh.intersect(&ray, h.t, f32::INFINITY).is_none_or(|h2| h2.t > h.t));
            }
        }
        assert!(hits > 200, "{hits}");
    }

    #[test]
    fn small_meshes_tested_flat_block_what_brute_force_blocks() {
        // Soups of 9 to 16 triangles: more than one leaf, yet tested by
        // any-hit queries without the tree (`FLAT_ANY_BLOCKS`).
        let mut rng = Rng(23);
        let mut trees = 0;
        for n in 9..=16u32 {
            let pos: Vec<Vec3> = (0..3 * n).map(|_| rng.vec(-2.0, 2.0)).collect();
            let tris: Vec<[u32; 3]> = (0..n).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
            let mesh = MeshAccel::build(&pos, &tris);
            assert!(mesh.any_flat && mesh.block_count() <= FLAT_ANY_BLOCKS);
            trees += mesh.bvh().single_leaf().is_none() as usize;
            for _ in 0..2000 {
                let ray = Ray::new(rng.vec(-4.0, 4.0), rng.dir() * rng.range(0.5, 2.0));
                let t_max = rng.range(0.5, 8.0);
                let want = brute(&pos, &tris, &ray, t_max).is_some();
                assert_eq!(mesh.occluded(&ray, 0.0, t_max), want);
            }
        }
        assert!(trees > 0, "no mesh had a tree of its own");
    }

    #[test]
    fn scaled_directions_scale_t_and_back_faces_hit() {
        let pos = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let mesh = MeshAccel::build(&pos, &[[0, 1, 2]]);
        let front = Ray::new(Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, -2.0));
        assert_eq!(mesh.intersect(&front, 0.0, f32::INFINITY).map(|h| h.t), Some(2.0));
        let back = Ray::new(Vec3::new(0.0, 0.0, -4.0), Vec3::new(0.0, 0.0, 0.5));
        assert_eq!(mesh.intersect(&back, 0.0, f32::INFINITY).map(|h| h.t), Some(8.0));
        assert!(!mesh.occluded(&back, 0.0, 7.9));
        assert!(mesh.occluded(&back, 0.0, 8.1));
    }

    #[test]
    fn degenerate_and_invalid_triangles_never_hit() {
        let pos = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0), // collinear with the two before
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::new(0.0, f32::INFINITY, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let tris = [[0, 1, 2], [0, 0, 1], [1, 1, 1], [0, 3, 5], [0, 4, 5], [0, 1, 99], [u32::MAX, 0, 1]];
        let mesh = MeshAccel::build(&pos, &tris);
        assert_eq!(mesh.triangle_count(), 0);
        assert!(mesh.bounds().is_empty());
        let mut rng = Rng(2);
        for k in 0..2000 {
            // Aim at the degenerate segment, including exactly edge-on.
            let target = Vec3::new(rng.range(-0.5, 2.5), 0.0, 0.0);
            let o = if k % 4 == 0 { Vec3::new(-1.0, 0.0, 0.0) } else { rng.vec(-3.0, 3.0) };
            let ray = Ray::new(o, target - o);
            assert!(mesh.intersect(&ray, 0.0, f32::INFINITY).is_none());
            assert!(!mesh.occluded(&ray, 0.0, f32::INFINITY));
        }
        // The direct test also rejects a degenerate triangle without NaN.
        let wr = WatertightRay::new(&Ray::new(Vec3::new(0.5, 0.0, 1.0), -Vec3::Z));
        assert!(wr.intersect(&Triangle::new(pos[0], pos[1], pos[2], 0), 0.0, f32::INFINITY).is_none());
        // A valid triangle among invalid ones is still found, with its input index.
        let mesh = MeshAccel::build(&pos, &[[0, 1, 2], [0, 1, 5], [0, 3, 5]]);
        assert_eq!(mesh.triangle_count(), 1);
        let hit = mesh.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z), 0.0, 10.0);
        assert_eq!(hit.map(|h| h.prim), Some(1));
        // Zero direction: no hit, no panic.
        assert!(mesh.intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::ZERO), 0.0, 10.0).is_none());
    }

    #[test]
    fn empty_mesh_and_thread_safety() {
        let mesh = MeshAccel::build(&[], &[]);
        assert_eq!(mesh.triangle_count(), 0);
        assert!(mesh.intersect(&Ray::new(Vec3::ZERO, Vec3::X), 0.0, f32::INFINITY).is_none());
        fn send_sync<T: Send + Sync>() {}
        send_sync::<MeshAccel>();
    }
}
