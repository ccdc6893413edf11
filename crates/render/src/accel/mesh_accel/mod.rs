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
use super::bvh::{Bvh, Traversal};
use super::tri_block::TriBlock;
use super::triangle::{Triangle, WatertightRay};
use leaf::{leaf_any, leaf_closest, Any, Closest};
use luster_core::math::{Aabb, Ray};

mod leaf;

/// A ray–triangle hit.
///
/// `u` and `v` first, side by side: a hit is written field by field during
/// traversal and copied soon after, `t` from a register and the rest from
/// memory. A copy's 8-byte load of `prim` with `u` would span two 4-byte
/// stores, which it cannot be forwarded from (it would wait for them to
/// retire); this way that load is `u, v`, stored as one word
/// ([`PairHit::uv`](super::tri_block::PairHit::uv)).
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
/// without the mesh's tree: for a light like the hw7 Cornell box's (10
/// triangles, two leaves), a call, a node test and its set-up per shadow ray
/// cost more than testing its three blocks outright. The leaf boxes
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
                // One walk for both: two inlined copies would double the
                // frame (two traversal stacks) and the code of the
                // out-of-line callers (`tree_closest_*`).
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

#[cfg(test)]
mod tests;
