//! A bounding-volume hierarchy over primitive boxes: built as a binary
//! binned-SAH tree (`bvh_build`), collapsed into a 4-wide tree for
//! traversal, traversed front to back.
//!
//! The same [`Bvh`] serves both levels of the renderer: triangles inside a
//! mesh (see [`super::MeshAccel`]) and instances or analytic shapes at the top.
//! It knows only boxes; what a primitive *is* stays with the caller, who gets
//! leaf ranges into [`Bvh::prim_order`] and intersects them in a closure.
//! Because the traversal is generic over that closure it is monomorphized per
//! primitive type and the leaf test inlines into the loop, the way a
//! hand-written traversal would.
//!
//! # Design
//! - **Why 4-wide**: a node holds its four children's boxes side by side
//!   (structure of arrays), so one ray tests all four with a handful of
//!   4-lane SSE operations, where a binary tree needs two scalar-ish tests per
//!   level and twice the levels. This is the layout of Embree's single-ray
//!   kernels; on the 1.3M-triangle benchmark mesh it is about 1.4x as fast
//!   as the binary tree it is collapsed from (1.5x on a 62k-triangle course
//!   mesh). Each node is 128 bytes, cache-line aligned, in
//!   depth-first order.
//! - **Collapse**: each wide node takes a binary node's children and keeps
//!   opening the one with the largest surface area (the one rays are most
//!   likely to enter) until it has four, so the SAH's choices survive.
//! - **Traversal**: the near plane of each slab is chosen once per ray from
//!   the direction's signs, so a node test is three subtract-multiplies per
//!   bound and no min/max of the two slab distances. Children are visited
//!   nearest first; a fixed stack keeps each deferred child's entry distance
//!   so anything behind a hit found meanwhile is dropped without being
//!   fetched. The exit distance is widened by a few ulps (Ize 2013, "Robust
//!   BVH Ray Traversal") so a ray grazing a shared box face, as rays through
//!   a shared triangle edge do, is never lost to rounding.
//! - **AVX2 and FMA**: where the CPU has them (detected at run time, SSE
//!   otherwise), the whole traversal, leaf test included, is compiled for
//!   them, and the node test computes each plane as one fused
//!   `b * inv - o * inv` with a margin for the rounding of `o * inv`. The
//!   fused test may let a box through that the plain one culls, never the
//!   reverse, and the leaf test is the same code (Rust never fuses on its
//!   own), so hits are bit for bit those of the SSE path. On the bumpy-sphere
//!   benchmark this path traces 1.3-1.7x the rays per second.
//! - **Limits**: leaves hold at most [`MAX_LEAF`] primitives and a tree at
//!   most 2^28 primitives (a leaf reference packs both in 32 bits).

use std::ops::Range;

use glam::{Vec3, Vec3A, Vec4};

use super::bvh_build::{build_binary, BinaryNodes, INTERSECT_COST, SAH_MAX_DEPTH};
pub use super::bvh_build::{BINS, MAX_LEAF};
use crate::math::{Aabb, Ray};

/// SAH cost of testing one top-level object, against one node visit (see
/// [`Bvh::build_objects`]).
const OBJECT_COST: f32 = 4.0;
/// Marks a child reference as a leaf: `LEAF | first << 3 | (count - 1)`.
const LEAF: u32 = 1 << 31;
/// An unused child slot; its box is empty, so it is never entered.
const EMPTY: u32 = u32::MAX;
/// Most primitives a tree can hold, from the leaf-reference packing.
pub const MAX_PRIMS: usize = 1 << 28;
/// `1 + 2 * gamma(3)` (pbrt's conservative slab-test factor): the exit
/// distance is scaled by it so rounding never culls a box the ray touches.
const SLAB_EXPAND: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);
/// Stack for shallow trees (`3 * depth + 1 <= SMALL_STACK`): most trees, and
/// clearing a small stack per ray is measurably cheaper.
const SMALL_STACK: usize = 64;
/// Stack for any tree: a 4-wide node defers at most three children, and the
/// wide tree is no deeper than the binary one.
const BIG_STACK: usize = 3 * (SAH_MAX_DEPTH + 33) + 1;

/// A 4-wide node: its children's boxes as structure of arrays and their
/// references.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node4 {
    /// Rows: min x, max x, min y, max y, min z, max z; one lane per child.
    bounds: [[f32; 4]; 6],
    /// Node index, leaf reference (`LEAF` bit set) or `EMPTY`.
    child: [u32; 4],
}

impl Node4 {
    const EMPTY: Node4 = Node4 {
        bounds: [
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
        ],
        child: [EMPTY; 4],
    };

    /// The box of child `k`.
    pub fn child_bounds(&self, k: usize) -> Aabb {
        let b = &self.bounds;
        Aabb::new(Vec3::new(b[0][k], b[2][k], b[4][k]), Vec3::new(b[1][k], b[3][k], b[5][k]))
    }

    /// What child `k` is.
    pub fn child(&self, k: usize) -> Child {
        decode(self.child[k])
    }
}

/// A child slot of a [`Node4`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Child {
    /// An inner node, by index.
    Node(usize),
    /// A leaf: a range of [`Bvh::prim_order`].
    Leaf(Range<usize>),
    /// Unused.
    Empty,
}

#[inline(always)]
fn leaf_range(r: u32) -> Range<usize> {
    let first = ((r & !LEAF) >> 3) as usize;
    first..first + (r & 7) as usize + 1
}

fn decode(r: u32) -> Child {
    match r {
        EMPTY => Child::Empty,
        r if r & LEAF != 0 => Child::Leaf(leaf_range(r)),
        r => Child::Node(r as usize),
    }
}

/// A bounding-volume hierarchy. See the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node4>,
    /// Reference to the root: node 0, or a leaf for tiny trees.
    root: u32,
    bounds: Aabb,
    prim_order: Vec<u32>,
    /// Levels of the wide tree.
    depth: usize,
    /// Levels of the binary tree it came from.
    binary_depth: usize,
}

/// Collapses the binary subtree at `i` into wide nodes appended to `out`;
/// returns its reference and the wide depth below it.
fn collapse(b2: &BinaryNodes, i: usize, out: &mut Vec<Node4>) -> (u32, usize) {
    let n = b2.get(i);
    if n.is_leaf() {
        return (LEAF | n.first << 3 | (n.count - 1), 0);
    }
    let mut kids = [n.first as usize, n.first as usize + 1, 0, 0];
    let mut len = 2;
    while len < 4 {
        // Open the inner child with the largest area; strict `>` keeps the
        // first of equals, so the result is deterministic.
        let mut best: Option<(usize, f32)> = None;
        for (k, &c) in kids[..len].iter().enumerate() {
            let c = b2.get(c);
            let area = c.bounds().surface_area();
            if !c.is_leaf() && best.is_none_or(|(_, a)| area > a) {
                best = Some((k, area));
            }
        }
        let Some((k, _)) = best else { break };
        let first = b2.get(kids[k]).first as usize;
        kids.copy_within(k + 1..len, k + 2);
        kids[k] = first;
        kids[k + 1] = first + 1;
        len += 1;
    }
    let slot = out.len();
    out.push(Node4::EMPTY);
    let mut node = Node4::EMPTY;
    let mut depth = 0;
    for (k, &c) in kids[..len].iter().enumerate() {
        let (r, d) = collapse(b2, c, out);
        node.child[k] = r;
        depth = depth.max(d);
        let b = b2.get(c);
        for axis in 0..3 {
            node.bounds[2 * axis][k] = b.min[axis];
            node.bounds[2 * axis + 1][k] = b.max[axis];
        }
    }
    out[slot] = node;
    (slot as u32, depth + 1)
}

/// Ray data the node test needs, computed once per traversal.
#[derive(Clone, Copy)]
struct RayPre {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    /// Row of [`Node4::bounds`] holding each axis's near and far plane.
    near: [usize; 3],
    far: [usize; 3],
    /// For the fused test `b * inv + c`: `c = -o * inv`, moved down (near
    /// planes) or up (far planes) by more than its rounding error.
    c_near: [Vec4; 3],
    c_far: [Vec4; 3],
    /// Whether `c_near` and `c_far` are finite, so the fused test applies.
    fused_ok: bool,
}

impl RayPre {
    #[inline(always)]
    fn new(ray: &Ray) -> RayPre {
        // A zero direction component would make 0 * inf = NaN for a box face
        // through the origin; a tiny stand-in keeps it finite with the same
        // answer.
        let d = Vec3A::from(ray.d);
        let tiny = Vec3A::splat(1e-30);
        let d = Vec3A::select(d.abs().cmplt(tiny), tiny.copysign(d), d);
        let inv = d.recip();
        // Written out instead of `[0, 1, 2].map(..)`: the array maps were
        // not inlined and cost as much as a node test per traversal.
        let (nx, ny, nz) = ((inv.x < 0.0) as usize, (inv.y < 0.0) as usize, (inv.z < 0.0) as usize);
        // `b * inv - o * inv` in one rounding of a fused multiply-add, where
        // `o * inv` was rounded once before: that product's error is
        // absolute, up to half an ulp of it, and cancellation can make it
        // large next to the result. A margin of two ulps, taken outwards,
        // covers it and the rounding of the margin itself; the relative
        // errors left are the ones `SLAB_EXPAND` already covers.
        let oi = Vec3A::from(ray.o) * inv;
        let pad = oi.abs() * (2.0 * f32::EPSILON);
        let (cn, cf) = (-oi - pad, -oi + pad);
        let fused_ok = cn.is_finite() && cf.is_finite();
        RayPre {
            o: [Vec4::splat(ray.o.x), Vec4::splat(ray.o.y), Vec4::splat(ray.o.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [nx, 2 + ny, 4 + nz],
            far: [1 - nx, 3 - ny, 5 - nz],
            c_near: [Vec4::splat(cn.x), Vec4::splat(cn.y), Vec4::splat(cn.z)],
            c_far: [Vec4::splat(cf.x), Vec4::splat(cf.y), Vec4::splat(cf.z)],
            fused_ok,
        }
    }

    /// [`RayPre::hit`] with one fused multiply-add per plane instead of a
    /// subtraction and a multiplication. It may let through a box the
    /// plain test culls (by a few ulps), never the reverse, so the
    /// primitives found and the hits reported are the same.
    ///
    /// # Safety
    /// The CPU must have FMA, and `self.fused_ok` must hold.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    unsafe fn hit_fused(&self, n: &Node4, t_max: f32) -> (Vec4, u32) {
        let b = &n.bounds;
        let (inv, cn, cf) = (&self.inv, &self.c_near, &self.c_far);
        let (near, far) = (&self.near, &self.far);
        let tn = fmadd(b[near[0]], inv[0], cn[0])
            .max(fmadd(b[near[1]], inv[1], cn[1]))
            .max(fmadd(b[near[2]], inv[2], cn[2]).max(Vec4::ZERO));
        let tf = fmadd(b[far[0]], inv[0], cf[0])
            .min(fmadd(b[far[1]], inv[1], cf[1]))
            .min(fmadd(b[far[2]], inv[2], cf[2]));
        let tf = (tf * SLAB_EXPAND).min(Vec4::splat(t_max));
        (tn, tn.cmple(tf).bitmask())
    }

    /// The node test, fused where the traversal was compiled for it (`FUSED`)
    /// and this ray allows it.
    #[inline(always)]
    fn hit_with<const FUSED: bool>(&self, n: &Node4, t_max: f32) -> (Vec4, u32) {
        #[cfg(target_arch = "x86_64")]
        if FUSED && self.fused_ok {
            // SAFETY: `FUSED` traversals are only entered after detecting
            // AVX2 and FMA (`fused_available`).
            return unsafe { self.hit_fused(n, t_max) };
        }
        self.hit(n, t_max)
    }

    /// Entry distances of the four children and the mask of those the ray
    /// meets within `[0, t_max]`.
    #[inline(always)]
    fn hit(&self, n: &Node4, t_max: f32) -> (Vec4, u32) {
        let b = &n.bounds;
        let slab = |row: usize, a: usize| (Vec4::from_array(b[row]) - self.o[a]) * self.inv[a];
        let tn = slab(self.near[0], 0).max(slab(self.near[1], 1)).max(slab(self.near[2], 2).max(Vec4::ZERO));
        let tf = slab(self.far[0], 0).min(slab(self.far[1], 1)).min(slab(self.far[2], 2));
        let tf = (tf * SLAB_EXPAND).min(Vec4::splat(t_max));
        (tn, tn.cmple(tf).bitmask())
    }

    /// The same test for one box (the root of a one-leaf tree), one lane
    /// wide: the operations of [`RayPre::hit`] on lane 0.
    #[inline(always)]
    fn hit_box(&self, b: &Aabb, t_max: f32) -> bool {
        // Row `2a` of a node is axis a's minimum, row `2a + 1` its maximum.
        let (lo, hi) = (b.min.to_array(), b.max.to_array());
        let bound = |row: usize| if row % 2 == 0 { lo[row / 2] } else { hi[row / 2] };
        let slab = |row: usize, a: usize| (bound(row) - self.o[a].x) * self.inv[a].x;
        let tn = slab(self.near[0], 0).max(slab(self.near[1], 1)).max(slab(self.near[2], 2).max(0.0));
        let tf = slab(self.far[0], 0).min(slab(self.far[1], 1)).min(slab(self.far[2], 2));
        tn <= (tf * SLAB_EXPAND).min(t_max)
    }
}

/// `a * b + c` in one rounding, four lanes.
///
/// # Safety
/// The CPU must have FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
unsafe fn fmadd(a: [f32; 4], b: Vec4, c: Vec4) -> Vec4 {
    use std::arch::x86_64::_mm_fmadd_ps;
    Vec4::from(_mm_fmadd_ps(Vec4::from_array(a).into(), b.into(), c.into()))
}

/// Which node test the traversal uses on this CPU (for benchmark reports).
pub fn node_test_isa() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    if fused_available() {
        return "AVX2+FMA";
    }
    "SSE"
}

/// Whether this CPU runs the AVX2 + FMA traversal (detected once; the
/// standard library caches the answer).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn fused_available() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

impl Bvh {
    /// Builds a BVH over the boxes of `prim_bounds`; primitive `i` is the one
    /// with box `prim_bounds[i]`. Boxes that are empty or not finite are left
    /// out (they cannot be hit). An empty input gives a tree nothing hits.
    ///
    /// # Panics
    /// With more than [`MAX_PRIMS`] primitives (a 20 GB mesh).
    pub fn build(prim_bounds: &[Aabb]) -> Bvh {
        Bvh::build_blocked(prim_bounds, 1)
    }

    /// [`Bvh::build`] for a caller that intersects `block` primitives at a
    /// time: the SAH prices a leaf by its number of blocks, so leaves come
    /// out with (up to [`MAX_LEAF`]) primitives filling whole blocks.
    pub fn build_blocked(prim_bounds: &[Aabb], block: u32) -> Bvh {
        Bvh::build_blocked_with(prim_bounds.len(), |i| prim_bounds[i], block)
    }

    /// [`Bvh::build_blocked`] over `n` primitives whose boxes come from
    /// `prim_box(i)`, called once each (in parallel), so the caller need not
    /// hold an array of boxes.
    pub fn build_blocked_with(n: usize, prim_box: impl Fn(usize) -> Aabb + Sync, block: u32) -> Bvh {
        Bvh::build_costed(n, &prim_box, block, INTERSECT_COST)
    }

    /// [`Bvh::build`] for the top level of a scene, whose primitives are
    /// objects: a mesh's own traversal or an analytic shape costs several
    /// node visits, so the SAH splits down to small leaves and a ray tests
    /// only the objects whose boxes it crosses. (Priced like a triangle, the
    /// eight objects of a Cornell box made one leaf, and every ray tested
    /// all of them.)
    pub fn build_objects(prim_bounds: &[Aabb]) -> Bvh {
        Bvh::build_costed(prim_bounds.len(), &|i| prim_bounds[i], 1, OBJECT_COST)
    }

    fn build_costed(n: usize, prim_box: &(impl Fn(usize) -> Aabb + Sync), block: u32, prim_cost: f32) -> Bvh {
        assert!(n <= MAX_PRIMS, "more than 2^28 primitives in one BVH");
        let Some((b2, prim_order, binary_depth)) = build_binary(n, prim_box, block, prim_cost) else {
            return Bvh {
                nodes: Vec::new(),
                root: EMPTY,
                bounds: Aabb::EMPTY,
                prim_order: Vec::new(),
                depth: 0,
                binary_depth: 0,
            };
        };
        let bounds = b2.get(0).bounds();
        // A wide tree has about a third as many nodes as the binary one has
        // inner nodes, which are fewer than half the primitives.
        let mut nodes = Vec::with_capacity(prim_order.len() / 6 + 1);
        let (root, depth) = collapse(&b2, 0, &mut nodes);
        drop(b2);
        nodes.shrink_to_fit();
        Bvh { nodes, root, bounds, prim_order, depth: depth + 1, binary_depth }
    }

    /// Replaces every leaf's range, in depth-first order, by `f(prims)`,
    /// where `prims` are the leaf's entries of [`Bvh::prim_order`]: for a
    /// caller that regroups each leaf's primitives into its own storage
    /// (SIMD blocks). `f` must return a non-empty range of at most
    /// [`MAX_LEAF`] items starting below [`MAX_PRIMS`]. The tree then no
    /// longer indexes `prim_order`, which is emptied.
    pub fn remap_leaves(&mut self, mut f: impl FnMut(&[u32]) -> Range<usize>) {
        let order = std::mem::take(&mut self.prim_order);
        let mut enc = |r: u32| -> u32 {
            if r == EMPTY || r & LEAF == 0 {
                return r;
            }
            let new = f(&order[leaf_range(r)]);
            assert!(!new.is_empty() && new.len() <= MAX_LEAF && new.start < MAX_PRIMS, "bad leaf remap");
            LEAF | (new.start as u32) << 3 | (new.len() as u32 - 1)
        };
        if self.nodes.is_empty() {
            self.root = enc(self.root);
        } else {
            // Nodes are in depth-first order, so leaves are numbered in the
            // order a traversal tends to meet them: neighbours stay close.
            for n in &mut self.nodes {
                for c in &mut n.child {
                    *c = enc(*c);
                }
            }
        }
    }

    /// The root's range when the whole tree is one leaf. Its caller may
    /// test that leaf without the box test: a leaf of at most [`MAX_LEAF`]
    /// primitives costs about what the box test does.
    #[inline]
    pub fn single_leaf(&self) -> Option<Range<usize>> {
        (self.root != EMPTY && self.root & LEAF != 0).then(|| leaf_range(self.root))
    }

    /// The permutation of input primitive indices that leaf ranges index
    /// into. Shorter than the input if some boxes were empty.
    pub fn prim_order(&self) -> &[u32] {
        &self.prim_order
    }

    /// The box around everything (empty for an empty tree).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Number of (4-wide) nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The wide nodes, root first, for inspection and tests.
    pub fn nodes(&self) -> &[Node4] {
        &self.nodes
    }

    /// What the root is.
    pub fn root(&self) -> Child {
        decode(self.root)
    }

    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        if self.nodes.is_empty() {
            return (self.root != EMPTY) as usize;
        }
        let is_leaf = |&r: &u32| r != EMPTY && r & LEAF != 0;
        self.nodes.iter().map(|n| n.child.iter().filter(|r| is_leaf(r)).count()).sum()
    }

    /// Levels of the wide tree (1 for a single leaf, 0 for an empty tree).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Levels of the binary SAH tree the wide one was collapsed from.
    pub fn binary_depth(&self) -> usize {
        self.binary_depth
    }

    /// Heap memory used by the tree.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node4>() + self.prim_order.capacity() * size_of::<u32>()
    }

    /// Closest-hit traversal. `leaf(range, &mut t_max)` must test the
    /// primitives at `range` of [`Bvh::prim_order`] (or of data reordered to
    /// match it), lower `t_max` to the nearest hit closer than it, and return
    /// whether it found one. Leaves are visited roughly front to back and
    /// those entirely behind the current `t_max` are skipped. Returns whether
    /// any call reported a hit.
    #[inline]
    pub fn closest<F: FnMut(Range<usize>, &mut f32) -> bool>(&self, ray: &Ray, t_max: f32, leaf: F) -> bool {
        #[cfg(target_arch = "x86_64")]
        if fused_available() {
            // SAFETY: the CPU has AVX2 and FMA.
            return unsafe { self.closest_fused(ray, t_max, leaf) };
        }
        self.closest_plain::<false, F>(ray, t_max, leaf)
    }

    /// [`Bvh::closest`] compiled for AVX2 and FMA, leaf test included (which
    /// changes nothing in its results: Rust never fuses a multiply and an
    /// add on its own).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn closest_fused<F: FnMut(Range<usize>, &mut f32) -> bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        leaf: F,
    ) -> bool {
        self.closest_plain::<true, F>(ray, t_max, leaf)
    }

    #[inline(always)]
    fn closest_plain<const FUSED: bool, F: FnMut(Range<usize>, &mut f32) -> bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        leaf: F,
    ) -> bool {
        if 3 * self.depth < SMALL_STACK {
            self.closest_with::<SMALL_STACK, FUSED, F>(ray, t_max, leaf)
        } else {
            self.closest_with::<BIG_STACK, FUSED, F>(ray, t_max, leaf)
        }
    }

    #[inline(always)]
    fn closest_with<const N: usize, const FUSED: bool, F: FnMut(Range<usize>, &mut f32) -> bool>(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut leaf: F,
    ) -> bool {
        let r = RayPre::new(ray);
        let mut cur = self.root;
        if cur & LEAF != 0 {
            // Empty tree, or one leaf.
            return cur != EMPTY && r.hit_box(&self.bounds, t_max) && leaf(leaf_range(cur), &mut t_max);
        }
        let nodes = &self.nodes[..];
        // Entries: child reference in the low half, entry distance's bits in
        // the high half.
        let mut stack = [0u64; N];
        let mut sp = 0;
        let mut hit = false;
        loop {
            if cur & LEAF != 0 {
                // An unused slot is never a leaf, even if the box test let it
                // through (a NaN ray passes every comparison as a hit).
                if cur != EMPTY {
                    hit |= leaf(leaf_range(cur), &mut t_max);
                }
            } else {
                let n = &nodes[cur as usize];
                let (tn, mut mask) = r.hit_with::<FUSED>(n, t_max);
                if mask != 0 {
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        cur = n.child[first];
                        continue;
                    }
                    // Two or more: sort by entry distance, push all but the
                    // nearest (farthest first), descend into the nearest.
                    let tn = tn.to_array();
                    let mut k = [(0.0f32, 0u32); 4];
                    k[0] = (tn[first], n.child[first]);
                    let mut len = 1;
                    while mask != 0 {
                        let i = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let mut j = len;
                        while j > 0 && k[j - 1].0 < tn[i] {
                            k[j] = k[j - 1];
                            j -= 1;
                        }
                        k[j] = (tn[i], n.child[i]);
                        len += 1;
                    }
                    for &(t, c) in &k[..len - 1] {
                        stack[sp] = (t.to_bits() as u64) << 32 | c as u64;
                        sp += 1;
                    }
                    cur = k[len - 1].1;
                    continue;
                }
            }
            // Pop the next deferred child that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return hit;
                }
                sp -= 1;
                let e = stack[sp];
                if f32::from_bits((e >> 32) as u32) <= t_max {
                    cur = e as u32;
                    break;
                }
            }
        }
    }

    /// Any-hit traversal for shadow rays: `leaf(range, t_max)` returns true if
    /// some primitive at `range` blocks the ray before `t_max`; the traversal
    /// stops at the first such leaf.
    #[inline]
    pub fn any<F: FnMut(Range<usize>, f32) -> bool>(&self, ray: &Ray, t_max: f32, leaf: F) -> bool {
        #[cfg(target_arch = "x86_64")]
        if fused_available() {
            // SAFETY: the CPU has AVX2 and FMA.
            return unsafe { self.any_fused(ray, t_max, leaf) };
        }
        self.any_plain::<false, F>(ray, t_max, leaf)
    }

    /// [`Bvh::any`] compiled for AVX2 and FMA (see [`Bvh::closest_fused`]).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn any_fused<F: FnMut(Range<usize>, f32) -> bool>(&self, ray: &Ray, t_max: f32, leaf: F) -> bool {
        self.any_plain::<true, F>(ray, t_max, leaf)
    }

    #[inline(always)]
    fn any_plain<const FUSED: bool, F: FnMut(Range<usize>, f32) -> bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        leaf: F,
    ) -> bool {
        if 3 * self.depth < SMALL_STACK {
            self.any_with::<SMALL_STACK, FUSED, F>(ray, t_max, leaf)
        } else {
            self.any_with::<BIG_STACK, FUSED, F>(ray, t_max, leaf)
        }
    }

    #[inline(always)]
    fn any_with<const N: usize, const FUSED: bool, F: FnMut(Range<usize>, f32) -> bool>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut leaf: F,
    ) -> bool {
        let r = RayPre::new(ray);
        let mut cur = self.root;
        if cur & LEAF != 0 {
            return cur != EMPTY && r.hit_box(&self.bounds, t_max) && leaf(leaf_range(cur), t_max);
        }
        let nodes = &self.nodes[..];
        let mut stack = [0u32; N];
        let mut sp = 0;
        loop {
            if cur & LEAF != 0 {
                if cur != EMPTY && leaf(leaf_range(cur), t_max) {
                    return true;
                }
            } else {
                let n = &nodes[cur as usize];
                let (_, mut mask) = r.hit_with::<FUSED>(n, t_max);
                if mask != 0 {
                    // Order does not matter for "any": take the first, defer the rest.
                    cur = n.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        stack[sp] = n.child[mask.trailing_zeros() as usize];
                        sp += 1;
                        mask &= mask - 1;
                    }
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            cur = stack[sp];
        }
    }
}

#[cfg(test)]
pub(crate) mod tests;
