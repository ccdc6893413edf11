//! A bounding-volume hierarchy over primitive boxes: built as a binary
//! binned-SAH tree (`bvh_build`), collapsed into an 8-wide tree for
//! traversal, traversed front to back.
//!
//! The same [`Bvh`] serves both levels of the renderer: triangles inside a
//! mesh (see [`super::MeshAccel`]) and instances or analytic shapes at the top.
//! It knows only boxes; what a primitive *is* stays with the caller, who gets
//! leaf ranges into [`Bvh::prim_order`] and intersects them in a closure
//! ([`Bvh::closest`], [`Bvh::any`]) or, on the renderer's hot paths, in a
//! `ClosestLeaf`/`AnyLeaf` implementation. Because the traversal is
//! generic over the leaf test it is monomorphized per primitive type and the
//! leaf test inlines into the loop, the way a hand-written traversal would.
//!
//! # Design
//! - **Why 8-wide**: a node holds its eight children's boxes side by side
//!   (structure of arrays, [`Node8`]), so one ray tests all eight with one
//!   8-lane AVX2 test (two 4-lane halves with SSE only), where a binary tree
//!   needs a test per child and three times the levels. This is the layout
//!   of Embree's single-ray kernels on AVX2 CPUs. Nodes are in depth-first
//!   order.
//! - **Collapse**: each wide node takes a binary node's children and keeps
//!   opening the one with the largest surface area (the one rays are most
//!   likely to enter) until it has eight, so the SAH's choices survive.
//! - **Traversal**: children are visited nearest first (a compare for two,
//!   an insertion sort for more); a stack keeps each deferred child's entry
//!   distance so anything behind a hit found meanwhile is dropped without
//!   being fetched.
//! - **AVX2 and FMA**: where the CPU has them (detected at run time, SSE
//!   otherwise), the whole traversal, leaf test included, is compiled for
//!   them with the fused node test of `node`. The leaf test is the same
//!   code (Rust never fuses on its own), so hits are bit for bit those of
//!   the SSE path.
//! - **Limits**: leaves hold at most [`MAX_LEAF`] primitives and a tree at
//!   most 2^28 primitives (a leaf reference packs both in 32 bits).

use std::ops::Range;

use super::bvh_build::{build_binary, BinaryNodes, INTERSECT_COST, SAH_MAX_DEPTH};
pub use super::bvh_build::{BINS, MAX_LEAF};
use luster_core::math::{Aabb, Ray};

mod node;
mod walk;

#[cfg(target_arch = "x86_64")]
pub(crate) use node::fused_available;
use node::{decode, leaf_range, NodeTest, RayPre, SignedRoot, EMPTY, LEAF};
pub use node::{node_test_isa, Child, Node8, WIDTH};

/// SAH cost of testing one top-level object, against one node visit (see
/// [`Bvh::build_objects`]).
const OBJECT_COST: f32 = 4.0;
/// Most primitives a tree can hold, from the leaf-reference packing.
pub const MAX_PRIMS: usize = 1 << 28;
/// Traversal stack for any tree: a node defers at most `WIDTH - 1`
/// children, and the wide tree is no deeper than the binary one. Left
/// uninitialised, so its size costs nothing per ray.
const STACK: usize = (WIDTH - 1) * (SAH_MAX_DEPTH + 33) + 1;

/// A closest-hit leaf test: `test(range, &mut t_max)` tests the primitives
/// at `range`, lowers `t_max` to the nearest hit closer than it and returns
/// whether it found one. A trait and not a closure so that an implementation
/// can mark its body `#[inline(always)]`: a closure's body is its own
/// function, compiled for the CPU features of the function it is written
/// in, and once LLVM stops inlining it into a bigger AVX2 caller its SIMD
/// code stays out of line.
pub(crate) trait ClosestLeaf {
    /// Tests one leaf.
    fn test(&mut self, range: Range<usize>, t_max: &mut f32) -> bool;
}

/// An any-hit leaf test: `test(range, t_max)` returns whether some primitive
/// at `range` blocks the ray before `t_max` (see [`ClosestLeaf`]).
pub(crate) trait AnyLeaf {
    /// Tests one leaf.
    fn test(&mut self, range: Range<usize>, t_max: f32) -> bool;
}

/// A ray prepared for traversal: the node test's per-ray constants (the
/// reciprocal direction and what the fused test derives from it). A ray
/// that meets several trees in the same space (the top level, then a mesh
/// that needs no transform) prepares them once for all of them: the same
/// values, so the same boxes entered. Kept small (four vectors and a few
/// bits): each traversal broadcasts what its node test needs into its own
/// registers, where a prepared copy of the broadcasts would go through the
/// stack at every query.
#[derive(Clone, Copy)]
pub(crate) struct Traversal {
    r: RayPre,
}

impl Traversal {
    /// Prepares `ray` for a traversal compiled for AVX2 and FMA (`FUSED`,
    /// after checking [`fused_available`]) or not.
    #[inline(always)]
    pub(crate) fn new<const FUSED: bool>(ray: &Ray) -> Traversal {
        let mut r = RayPre::new(ray);
        // From here on `fused_ok` also says that the traversal was compiled
        // for the fused test (see `Traversal::test`).
        r.fused_ok &= FUSED;
        Traversal { r }
    }

    /// The node test of a traversal of this ray.
    #[inline(always)]
    fn test(&self) -> NodeTest {
        // `fused_ok` holds only for a `FUSED` traversal (see `new`).
        self.r.node_test::<true>()
    }
}

/// A closure as a leaf test, for callers off the hot paths.
struct FnLeaf<F>(F);

impl<F: FnMut(Range<usize>, &mut f32) -> bool> ClosestLeaf for FnLeaf<F> {
    #[inline(always)]
    fn test(&mut self, range: Range<usize>, t_max: &mut f32) -> bool {
        (self.0)(range, t_max)
    }
}

impl<F: FnMut(Range<usize>, f32) -> bool> AnyLeaf for FnLeaf<F> {
    #[inline(always)]
    fn test(&mut self, range: Range<usize>, t_max: f32) -> bool {
        (self.0)(range, t_max)
    }
}

/// A bounding-volume hierarchy. See the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node8>,
    /// Reference to the root: node 0, or a leaf for tiny trees.
    root: u32,
    bounds: Aabb,
    prim_order: Vec<u32>,
    /// Levels of the wide tree.
    depth: usize,
    /// Levels of the binary tree it came from.
    binary_depth: usize,
    /// The root reordered by sign ([`SignedRoot`]) when it is the only node.
    signed_root: Option<Box<SignedRoot>>,
}

/// Collapses the binary subtree at `i` into wide nodes appended to `out`;
/// returns its reference and the wide depth below it.
fn collapse(b2: &BinaryNodes, i: usize, out: &mut Vec<Node8>) -> (u32, usize) {
    let n = b2.get(i);
    if n.is_leaf() {
        return (LEAF | n.first << 3 | (n.count - 1), 0);
    }
    let mut kids = [0usize; WIDTH];
    kids[0] = n.first as usize;
    kids[1] = n.first as usize + 1;
    let mut len = 2;
    while len < WIDTH {
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
    out.push(Node8::EMPTY);
    let mut node = Node8::EMPTY;
    let mut depth = 0;
    for (k, &c) in kids[..len].iter().enumerate() {
        let (r, d) = collapse(b2, c, out);
        node.child[k] = r;
        depth = depth.max(d);
        node.set_bounds(k, &b2.get(c).bounds());
    }
    out[slot] = node;
    (slot as u32, depth + 1)
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
    /// eight objects of a Cornell box would make one leaf, and every ray
    /// would test all of them.)
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
                signed_root: None,
            };
        };
        let bounds = b2.get(0).bounds();
        // A wide tree has about a third as many nodes as the binary one has
        // inner nodes, which are fewer than half the primitives.
        let mut nodes = Vec::with_capacity(prim_order.len() / 6 + 1);
        let (root, depth) = collapse(&b2, 0, &mut nodes);
        drop(b2);
        nodes.shrink_to_fit();
        let signed_root = match &nodes[..] {
            [n] => Some(SignedRoot::new(n)),
            _ => None,
        };
        Bvh { nodes, root, bounds, prim_order, depth: depth + 1, binary_depth, signed_root }
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
            if let Some(r) = &mut self.signed_root {
                r.child = self.nodes[0].child;
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

    /// Number of (8-wide) nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The wide nodes, root first, for inspection and tests.
    pub fn nodes(&self) -> &[Node8] {
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
        self.nodes.capacity() * size_of::<Node8>()
            + self.prim_order.capacity() * size_of::<u32>()
            + self.signed_root.as_ref().map_or(0, |_| size_of::<SignedRoot>())
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
            return unsafe { self.closest_fused(ray, t_max, FnLeaf(leaf)) };
        }
        self.closest_plain::<false, _>(ray, t_max, FnLeaf(leaf))
    }

    /// [`Bvh::closest`] compiled for AVX2 and FMA, leaf test included (which
    /// changes nothing in its results: Rust never fuses a multiply and an
    /// add on its own).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn closest_fused<L: ClosestLeaf>(&self, ray: &Ray, t_max: f32, leaf: L) -> bool {
        self.closest_plain::<true, L>(ray, t_max, leaf)
    }

    #[inline(always)]
    fn closest_plain<const FUSED: bool, L: ClosestLeaf>(&self, ray: &Ray, t_max: f32, leaf: L) -> bool {
        self.closest_prepared(&Traversal::new::<FUSED>(ray), t_max, leaf)
    }

    #[inline(always)]
    fn any_plain<const FUSED: bool, L: AnyLeaf>(&self, ray: &Ray, t_max: f32, leaf: L) -> bool {
        self.any_prepared(&Traversal::new::<FUSED>(ray), t_max, leaf)
    }

    /// Any-hit traversal for shadow rays: `leaf(range, t_max)` returns true if
    /// some primitive at `range` blocks the ray before `t_max`; the traversal
    /// stops at the first such leaf.
    #[inline]
    pub fn any<F: FnMut(Range<usize>, f32) -> bool>(&self, ray: &Ray, t_max: f32, leaf: F) -> bool {
        #[cfg(target_arch = "x86_64")]
        if fused_available() {
            // SAFETY: the CPU has AVX2 and FMA.
            return unsafe { self.any_fused(ray, t_max, FnLeaf(leaf)) };
        }
        self.any_plain::<false, _>(ray, t_max, FnLeaf(leaf))
    }

    /// [`Bvh::any`] compiled for AVX2 and FMA (see [`Bvh::closest_fused`]).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn any_fused<L: AnyLeaf>(&self, ray: &Ray, t_max: f32, leaf: L) -> bool {
        self.any_plain::<true, L>(ray, t_max, leaf)
    }
}

#[cfg(test)]
pub(crate) mod tests;
