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
//! - **Limits**: leaves hold at most [`MAX_LEAF`] primitives and a tree at
//!   most 2^28 primitives (a leaf reference packs both in 32 bits).

use std::ops::Range;

use glam::{Vec3, Vec3A, Vec4};

use super::bvh_build::{build_binary, Node, SAH_MAX_DEPTH};
pub use super::bvh_build::{BINS, MAX_LEAF};
use crate::math::{Aabb, Ray};

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
fn collapse(b2: &[Node], i: usize, out: &mut Vec<Node4>) -> (u32, usize) {
    let n = &b2[i];
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
            let area = b2[c].bounds().surface_area();
            if !b2[c].is_leaf() && best.is_none_or(|(_, a)| area > a) {
                best = Some((k, area));
            }
        }
        let Some((k, _)) = best else { break };
        let first = b2[kids[k]].first as usize;
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
        let b = &b2[c];
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
        let neg = |a: usize| (inv[a] < 0.0) as usize;
        RayPre {
            o: [0, 1, 2].map(|a| Vec4::splat(ray.o[a])),
            inv: [0, 1, 2].map(|a| Vec4::splat(inv[a])),
            near: [0, 1, 2].map(|a| 2 * a + neg(a)),
            far: [0, 1, 2].map(|a| 2 * a + 1 - neg(a)),
        }
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

    /// The same test for one box (the root of a one-leaf tree).
    fn hit_box(&self, b: &Aabb, t_max: f32) -> bool {
        let mut n = Node4::EMPTY;
        for a in 0..3 {
            n.bounds[2 * a][0] = b.min[a];
            n.bounds[2 * a + 1][0] = b.max[a];
        }
        self.hit(&n, t_max).1 & 1 != 0
    }
}

impl Bvh {
    /// Builds a BVH over the boxes of `prim_bounds`; primitive `i` is the one
    /// with box `prim_bounds[i]`. Boxes that are empty or not finite are left
    /// out (they cannot be hit). An empty input gives a tree nothing hits.
    ///
    /// # Panics
    /// With more than [`MAX_PRIMS`] primitives (a 20 GB mesh).
    pub fn build(prim_bounds: &[Aabb]) -> Bvh {
        assert!(prim_bounds.len() <= MAX_PRIMS, "more than 2^28 primitives in one BVH");
        let Some((b2, prim_order, binary_depth)) = build_binary(prim_bounds) else {
            return Bvh {
                nodes: Vec::new(),
                root: EMPTY,
                bounds: Aabb::EMPTY,
                prim_order: Vec::new(),
                depth: 0,
                binary_depth: 0,
            };
        };
        let bounds = b2[0].bounds();
        // A wide tree has about a third as many nodes as the binary one has
        // inner nodes.
        let mut nodes = Vec::with_capacity(b2.len() / 6 + 1);
        let (root, depth) = collapse(&b2, 0, &mut nodes);
        drop(b2);
        nodes.shrink_to_fit();
        Bvh { nodes, root, bounds, prim_order, depth: depth + 1, binary_depth }
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
        if 3 * self.depth < SMALL_STACK {
            self.closest_with::<SMALL_STACK, F>(ray, t_max, leaf)
        } else {
            self.closest_with::<BIG_STACK, F>(ray, t_max, leaf)
        }
    }

    #[inline(always)]
    fn closest_with<const N: usize, F: FnMut(Range<usize>, &mut f32) -> bool>(
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
                hit |= leaf(leaf_range(cur), &mut t_max);
            } else {
                let n = &nodes[cur as usize];
                let (tn, mut mask) = r.hit(n, t_max);
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
        if 3 * self.depth < SMALL_STACK {
            self.any_with::<SMALL_STACK, F>(ray, t_max, leaf)
        } else {
            self.any_with::<BIG_STACK, F>(ray, t_max, leaf)
        }
    }

    #[inline(always)]
    fn any_with<const N: usize, F: FnMut(Range<usize>, f32) -> bool>(
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
                if leaf(leaf_range(cur), t_max) {
                    return true;
                }
            } else {
                let n = &nodes[cur as usize];
                let (_, mut mask) = r.hit(n, t_max);
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
pub(crate) mod tests {
    use super::*;

    /// A small deterministic generator (SplitMix64), so tests need no crate.
    pub(crate) struct Rng(pub u64);

    impl Rng {
        pub(crate) fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        /// Uniform in [0, 1).
        pub(crate) fn f(&mut self) -> f32 {
            (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
        }
        pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.f()
        }
        pub(crate) fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
            Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
        }
        pub(crate) fn dir(&mut self) -> Vec3 {
            loop {
                let v = self.vec(-1.0, 1.0);
                if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                    return v.normalize();
                }
            }
        }
    }

    fn random_boxes(rng: &mut Rng, n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|_| {
                let c = rng.vec(-10.0, 10.0);
                let h = rng.vec(0.0, 0.6);
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    /// The primitive of these tests is the box itself, hit at its entry distance.
    fn brute_closest(boxes: &[Aabb], ray: &Ray, t_max: f32) -> Option<f32> {
        let inv = ray.d.recip();
        boxes.iter().filter_map(|b| b.hit(ray.o, inv, t_max)).min_by(f32::total_cmp)
    }

    fn bvh_closest(bvh: &Bvh, boxes: &[Aabb], ray: &Ray, t_max: f32) -> Option<f32> {
        let inv = ray.d.recip();
        let mut best = None;
        let hit = bvh.closest(ray, t_max, |range, t| {
            let mut found = false;
            for &p in &bvh.prim_order()[range] {
                if let Some(te) = boxes[p as usize].hit(ray.o, inv, *t) {
                    if best.is_none_or(|b| te < b) {
                        best = Some(te);
                        *t = te;
                        found = true;
                    }
                }
            }
            found
        });
        assert_eq!(hit, best.is_some());
        best
    }

    fn bvh_any(bvh: &Bvh, boxes: &[Aabb], ray: &Ray, t_max: f32) -> bool {
        let inv = ray.d.recip();
        bvh.any(ray, t_max, |range, t| {
            bvh.prim_order()[range].iter().any(|&p| boxes[p as usize].hit(ray.o, inv, t).is_some())
        })
    }

    /// Checks the structural invariants: boxes nest, leaves partition
    /// `prim_order`, which is a permutation of the valid inputs.
    fn check_structure(bvh: &Bvh, boxes: &[Aabb]) {
        let mut covered = vec![false; bvh.prim_order().len()];
        let contains = |o: &Aabb, i: &Aabb| o.min.cmple(i.min).all() && o.max.cmpge(i.max).all();
        let mut leaf = |r: Range<usize>, b: &Aabb| {
            assert!(r.len() <= MAX_LEAF && !r.is_empty());
            for i in r {
                assert!(!covered[i], "prim in two leaves");
                covered[i] = true;
                assert!(contains(b, &boxes[bvh.prim_order()[i] as usize]));
            }
        };
        let mut todo = Vec::new();
        match bvh.root() {
            Child::Leaf(r) => leaf(r, &bvh.bounds()),
            Child::Node(i) => todo.push((i, bvh.bounds())),
            Child::Empty => assert!(bvh.prim_order().is_empty()),
        }
        let mut seen = 0;
        while let Some((i, parent)) = todo.pop() {
            seen += 1;
            let n = &bvh.nodes()[i];
            let mut used = 0;
            for k in 0..4 {
                let b = n.child_bounds(k);
                match n.child(k) {
                    Child::Empty => assert!(b.is_empty()),
                    c => {
                        used += 1;
                        assert!(contains(&parent, &b));
                        match c {
                            Child::Leaf(r) => leaf(r, &b),
                            Child::Node(j) => {
                                assert!(j > i, "depth-first order");
                                todo.push((j, b));
                            }
                            Child::Empty => unreachable!(),
                        }
                    }
                }
            }
            assert!(used >= 2);
        }
        assert_eq!(seen, bvh.node_count(), "every node reachable once");
        assert!(covered.iter().all(|&c| c), "a primitive is in no leaf");
        let mut order = bvh.prim_order().to_vec();
        order.sort_unstable();
        let valid: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| !boxes[i as usize].is_empty() && boxes[i as usize].is_finite())
            .collect();
        assert_eq!(order, valid);
    }

    #[test]
    fn closest_and_any_match_brute_force() {
        let mut rng = Rng(1);
        // Big enough that the parallel build paths run too.
        let mut boxes = random_boxes(&mut rng, 20_000);
        // Boxes that must be skipped: empty, infinite, NaN.
        boxes[7] = Aabb::EMPTY;
        boxes[100] = Aabb::new(Vec3::ZERO, Vec3::splat(f32::INFINITY));
        boxes[2000] = Aabb::new(Vec3::splat(f32::NAN), Vec3::ONE);
        let bvh = Bvh::build(&boxes);
        check_structure(&bvh, &boxes);
        assert_eq!(bvh.prim_order().len(), boxes.len() - 3);
        let valid: Vec<Aabb> = boxes.iter().copied().filter(|b| !b.is_empty() && b.is_finite()).collect();
        let mut hits = 0;
        for i in 0..5000 {
            let o = rng.vec(-15.0, 15.0);
            // Aim at some box half the time so most rays hit something.
            let d = if i % 2 == 0 {
                (valid[i % valid.len()].center() - o) * rng.range(0.2, 3.0)
            } else {
                rng.dir()
            };
            let ray = Ray::new(o, d);
            let t_max = if i % 3 == 0 { rng.range(0.0, 20.0) } else { f32::INFINITY };
            let want = brute_closest(&valid, &ray, t_max);
            assert_eq!(bvh_closest(&bvh, &boxes, &ray, t_max), want, "ray {i}: {ray:?}");
            assert_eq!(bvh_any(&bvh, &boxes, &ray, t_max), want.is_some(), "ray {i}");
            hits += want.is_some() as usize;
        }
        assert!(hits > 1000 && hits < 5000, "test rays should both hit and miss: {hits}");
    }

    #[test]
    fn axis_aligned_rays_along_box_faces_hit() {
        // Zero direction components with the origin on a slab plane: the
        // naive slab test computes 0 * inf = NaN here.
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE), Aabb::new(Vec3::splat(2.0), Vec3::splat(3.0))];
        let bvh = Bvh::build(&boxes);
        let ray = Ray::new(Vec3::new(0.0, 0.5, -1.0), Vec3::Z);
        let mut leaves = 0;
        bvh.closest(&ray, f32::INFINITY, |r, _| {
            leaves += bvh.prim_order()[r].contains(&0) as usize;
            false
        });
        assert_eq!(leaves, 1);
    }

    #[test]
    fn empty_and_single_builds() {
        let empty = Bvh::build(&[]);
        assert_eq!(empty.node_count(), 0);
        assert_eq!(empty.depth(), 0);
        assert!(empty.bounds().is_empty());
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        assert!(!empty.closest(&ray, f32::INFINITY, |_, _| panic!("no leaves")));
        assert!(!empty.any(&ray, f32::INFINITY, |_, _| panic!("no leaves")));
        // Only unusable boxes: also empty.
        assert_eq!(Bvh::build(&[Aabb::EMPTY]).node_count(), 0);

        let b = Aabb::new(Vec3::splat(1.0), Vec3::splat(2.0));
        let one = Bvh::build(&[b]);
        assert_eq!((one.node_count(), one.depth(), one.prim_order()), (0, 1, &[0u32][..]));
        assert_eq!(one.root(), Child::Leaf(0..1));
        assert_eq!(one.bounds(), b);
        let toward = Ray::new(Vec3::ZERO, Vec3::ONE);
        assert!(one.closest(&toward, f32::INFINITY, |r, _| r == (0..1)));
        assert!(one.any(&toward, f32::INFINITY, |r, _| r == (0..1)));
        assert!(!one.any(&toward, 0.5, |_, _| panic!("box is beyond t_max")));
        assert!(!one.closest(&ray, f32::INFINITY, |_, _| panic!("ray misses")));
    }

    #[test]
    fn identical_and_point_boxes_build_shallow_trees() {
        // All centroids equal: no SAH split exists, median splits take over.
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let boxes = vec![b; 10_000];
        let bvh = Bvh::build(&boxes);
        check_structure(&bvh, &boxes);
        assert!(bvh.depth() <= 15, "depth {}", bvh.depth());
        let ray = Ray::new(Vec3::splat(-1.0), Vec3::ONE);
        let mut seen = 0;
        bvh.any(&ray, f32::INFINITY, |r, _| {
            seen += r.len();
            false
        });
        assert_eq!(seen, 10_000, "any() must visit every leaf when no leaf reports a hit");
        // Point boxes (zero-area triangles have them) are valid primitives.
        let pts: Vec<Aabb> =
            (0..100).map(|i| Aabb::new(Vec3::splat(i as f32), Vec3::splat(i as f32))).collect();
        check_structure(&Bvh::build(&pts), &pts);
    }

    #[test]
    fn exponential_spacing_keeps_depth_bounded() {
        // Centroids at 2^i: the SAH peels one primitive off per level, the
        // worst case for depth. The cut-off must keep it within the stack.
        let boxes: Vec<Aabb> = (0..2000)
            .map(|i| {
                let x = 1.02f32.powi(i);
                Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.01, 1.0, 1.0))
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        check_structure(&bvh, &boxes);
        assert!(3 * bvh.depth() < BIG_STACK, "depth {}", bvh.depth());
        let ray = Ray::new(Vec3::new(0.0, 0.5, 0.5), Vec3::X);
        assert_eq!(
            bvh_closest(&bvh, &boxes, &ray, f32::INFINITY),
            brute_closest(&boxes, &ray, f32::INFINITY)
        );
    }

    #[test]
    fn build_is_deterministic_across_thread_counts() {
        let boxes = random_boxes(&mut Rng(7), 50_000);
        let a = Bvh::build(&boxes);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        assert_eq!(a, one.install(|| Bvh::build(&boxes)));
        assert_eq!(a, three.install(|| Bvh::build(&boxes)));
        assert_eq!(size_of::<Node4>(), 128);
    }

    #[test]
    fn sah_beats_one_leaf_per_primitive() {
        // On clustered input the SAH should make multi-primitive leaves and
        // a tree far shallower than a list.
        let boxes = random_boxes(&mut Rng(3), 4096);
        let bvh = Bvh::build(&boxes);
        let leaves = bvh.leaf_count();
        assert!(leaves < 4096 && leaves > 4096 / MAX_LEAF, "{leaves} leaves");
        assert!(bvh.binary_depth() < 40, "depth {}", bvh.binary_depth());
        // The collapse fills nodes; only nodes whose binary children are
        // all leaves stay narrow.
        let slots = bvh.node_count() * 4;
        let used = leaves + bvh.node_count() - 1;
        assert!(used as f32 > 0.7 * slots as f32, "{used} of {slots} child slots used");
    }
}
