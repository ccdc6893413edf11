//! A binary bounding-volume hierarchy over primitive boxes, built with the
//! binned surface-area heuristic and traversed front to back.
//!
//! The same [`Bvh`] serves both levels of the renderer: triangles inside a mesh
//! (see [`super::MeshAccel`]) and instances or analytic shapes at the top. It
//! knows only boxes; what a primitive *is* stays with the caller, who gets leaf
//! ranges into [`Bvh::prim_order`] and intersects them in a closure. Because the
//! traversal is generic over that closure it is monomorphized per primitive
//! type and the leaf test inlines into the loop, the way a hand-written
//! traversal would.
//!
//! # Design
//! - **Build**: binned SAH (Wald 2007) on centroids, [`BINS`] bins on all three
//!   axes. A node becomes a leaf when the SAH says splitting costs more than
//!   intersecting everything (with [`MAX_LEAF`] as a hard cap). Subtrees above
//!   [`PAR_MIN`] primitives are built with `rayon::join`, and the biggest nodes
//!   bin in parallel too, so a million triangles build in a fraction of a
//!   second on two cores. Every split decision depends only on the input, so
//!   the node array is identical whatever the thread count.
//! - **Layout**: 32-byte nodes in one flat array. Siblings are stored next to
//!   each other (an inner node points at its first child; the second is the
//!   next slot), because the traversal always tests both children of a node:
//!   one fetch brings both boxes. The array is in depth-first order.
//! - **Traversal**: an explicit fixed stack that remembers each deferred node's
//!   entry distance, so nodes behind a hit found meanwhile are dropped without
//!   being fetched; the nearer child is visited first. The slab test widens
//!   its exit distance by a few ulps (Ize 2013, "Robust BVH Ray Traversal") so
//!   a ray grazing a shared box face, as rays through a shared triangle edge
//!   do, is never lost to rounding.
//! - **Robustness**: primitives whose box is empty or not finite are left out
//!   of the tree (and of `prim_order`); coincident centroids fall back to a
//!   median split; the SAH recursion is cut at [`SAH_MAX_DEPTH`] and median
//!   splits take over, so the tree can never outgrow the traversal stack.

use std::ops::Range;

use glam::{Vec3, Vec3A, Vec4};

use crate::math::{Aabb, Ray};

/// Number of centroid bins per axis. 16 is within a percent or two of 32 in
/// SAH cost on the meshes we measured and halves the binning sweep.
pub const BINS: usize = 16;
/// Most primitives in one leaf; more are always split.
pub const MAX_LEAF: usize = 8;
/// Cost of visiting one inner node relative to one primitive test, in the SAH.
const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one primitive test.
const INTERSECT_COST: f32 = 1.0;
/// Subtrees with at least this many primitives are built in parallel.
const PAR_MIN: usize = 4096;
/// Nodes with at least this many primitives bin in parallel.
const PAR_BIN_MIN: usize = 1 << 16;
/// Beyond this depth, splits are by object median: that halves the count at
/// each level, so depth stays below `SAH_MAX_DEPTH + 32 < STACK`.
const SAH_MAX_DEPTH: usize = 64;
/// Traversal stack size; see [`SAH_MAX_DEPTH`].
const STACK: usize = 128;
/// `1 + 2 * gamma(3)` (pbrt's conservative slab-test factor): the exit distance
/// is scaled by it so rounding in the slab test never culls a box the ray
/// touches.
const SLAB_EXPAND: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// One node: its box, and either its children (`count == 0`: children at
/// `first` and `first + 1`) or its primitives (`prim_order[first..first+count]`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct Node {
    /// Lower corner of the node's box.
    pub min: [f32; 3],
    /// First child (inner node) or first primitive (leaf).
    pub first: u32,
    /// Upper corner of the node's box.
    pub max: [f32; 3],
    /// Number of primitives; 0 for an inner node.
    pub count: u32,
}

impl Node {
    /// True for a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count != 0
    }

    /// The node's box.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from(self.min), Vec3::from(self.max))
    }

    fn leaf(b: &Bounds, first: usize, count: usize) -> Node {
        Node { min: b.min.to_array(), first: first as u32, max: b.max.to_array(), count: count as u32 }
    }

    fn inner(b: &Bounds, first_child: usize) -> Node {
        Node { min: b.min.to_array(), first: first_child as u32, max: b.max.to_array(), count: 0 }
    }
}

/// A bounding-volume hierarchy. See the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    prim_order: Vec<u32>,
    depth: usize,
}

/// A box in SIMD registers, for the build.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    #[inline]
    fn union(self, o: Bounds) -> Bounds {
        Bounds { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    #[inline]
    fn grow(self, p: Vec3A) -> Bounds {
        Bounds { min: self.min.min(p), max: self.max.max(p) }
    }

    /// Half the surface area: the SAH only compares ratios.
    #[inline]
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// A primitive during the build: its box, with the input index in `lo.w`
/// (as bits) so a reference is 32 bytes and partitions move one thing.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    lo: Vec4,
    hi: Vec4,
}

impl PrimRef {
    #[inline]
    fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }
    #[inline]
    fn max(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }
    #[inline]
    fn index(&self) -> u32 {
        self.lo.w.to_bits()
    }
    /// Twice the centroid: binning is scale-free, so the halving is skipped.
    #[inline]
    fn centroid2(&self) -> Vec3A {
        self.min() + self.max()
    }
}

/// Per-bin accumulators for one axis.
#[derive(Clone, Copy)]
struct Bin {
    bounds: Bounds,
    count: u32,
}

type Bins = [[Bin; BINS]; 3];

const EMPTY_BINS: Bins = [[Bin { bounds: Bounds::EMPTY, count: 0 }; BINS]; 3];

/// Maps a (doubled) centroid to bin indices on the three axes.
#[derive(Clone, Copy)]
struct Binner {
    origin: Vec3A,
    scale: Vec3A,
    /// Bins in use: fewer for small nodes, where the fixed cost of sweeping
    /// empty bins would dominate and a coarse choice loses almost nothing.
    nb: usize,
}

impl Binner {
    fn new(cb: &Bounds, n: usize) -> Binner {
        let nb = n.clamp(4, BINS);
        let ext = cb.max - cb.min;
        // A flat axis gets scale 0: everything lands in bin 0 and the axis
        // offers no split.
        let scale =
            Vec3A::select(ext.cmpgt(Vec3A::ZERO), Vec3A::splat(nb as f32 * (1.0 - 1e-6)) / ext, Vec3A::ZERO);
        Binner { origin: cb.min, scale, nb }
    }

    #[inline]
    fn bins(&self, c2: Vec3A) -> [usize; 3] {
        let b = ((c2 - self.origin) * self.scale).clamp(Vec3A::ZERO, Vec3A::splat((self.nb - 1) as f32));
        // `min` proves the index in range to the compiler as well.
        [(b.x as usize).min(BINS - 1), (b.y as usize).min(BINS - 1), (b.z as usize).min(BINS - 1)]
    }

    #[inline]
    fn bin(&self, c2: Vec3A, axis: usize) -> usize {
        let b = (c2[axis] - self.origin[axis]) * self.scale[axis];
        (b.clamp(0.0, (self.nb - 1) as f32)) as usize
    }
}

fn bin_refs(refs: &[PrimRef], binner: &Binner) -> Bins {
    let mut bins = EMPTY_BINS;
    for r in refs {
        let b = Bounds { min: r.min(), max: r.max() };
        let idx = binner.bins(r.centroid2());
        for axis in 0..3 {
            let bin = &mut bins[axis][idx[axis]];
            bin.bounds = bin.bounds.union(b);
            bin.count += 1;
        }
    }
    bins
}

fn merge_bins(mut a: Bins, b: &Bins) -> Bins {
    for axis in 0..3 {
        for i in 0..BINS {
            a[axis][i].bounds = a[axis][i].bounds.union(b[axis][i].bounds);
            a[axis][i].count += b[axis][i].count;
        }
    }
    a
}

/// Box and centroid box of a set of references.
fn ref_bounds(refs: &[PrimRef]) -> (Bounds, Bounds) {
    let fold = |(b, c): (Bounds, Bounds), r: &PrimRef| {
        (b.union(Bounds { min: r.min(), max: r.max() }), c.grow(r.centroid2()))
    };
    if refs.len() >= PAR_BIN_MIN {
        use rayon::prelude::*;
        refs.par_chunks(PAR_BIN_MIN / 4)
            .map(|ch| ch.iter().fold((Bounds::EMPTY, Bounds::EMPTY), fold))
            .reduce(|| (Bounds::EMPTY, Bounds::EMPTY), |a, b| (a.0.union(b.0), a.1.union(b.1)))
    } else {
        refs.iter().fold((Bounds::EMPTY, Bounds::EMPTY), fold)
    }
}

/// The chosen split of a node.
struct Split {
    axis: usize,
    /// References binned below this index go left.
    bin: usize,
    /// Sum of half-area times count of the two sides.
    cost: f32,
    left: Bounds,
    right: Bounds,
}

/// Sweeps the bins for the cheapest split.
fn best_split(bins: &Bins, nb: usize) -> Option<Split> {
    let mut best: Option<Split> = None;
    for (axis, bins) in bins.iter().enumerate() {
        let bins = &bins[..nb];
        // Right-to-left sweep: box and area*count of everything from i on.
        let mut right = [(Bounds::EMPTY, 0.0f32); BINS];
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for i in (1..nb).rev() {
            acc = acc.union(bins[i].bounds);
            count += bins[i].count;
            right[i] = (acc, acc.half_area() * count as f32);
        }
        let total = count + bins[0].count;
        let mut acc = Bounds::EMPTY;
        let mut left_count = 0u32;
        for i in 1..nb {
            acc = acc.union(bins[i - 1].bounds);
            left_count += bins[i - 1].count;
            if left_count == 0 || left_count == total {
                continue;
            }
            let cost = acc.half_area() * left_count as f32 + right[i].1;
            // Strict `<` keeps the first of equal candidates: determinism.
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Split { axis, bin: i, cost, left: acc, right: right[i].0 });
            }
        }
    }
    best
}

/// In-place partition that also gathers the centroid boxes of both sides.
/// Returns the number of references for which `left` holds.
fn partition(refs: &mut [PrimRef], mut left: impl FnMut(Vec3A) -> bool) -> (usize, Bounds, Bounds) {
    let (mut i, mut j) = (0, refs.len());
    let (mut lc, mut rc) = (Bounds::EMPTY, Bounds::EMPTY);
    // Each reference is classified exactly once: the one swapped to `j` is
    // already known to go right.
    while i < j {
        let c = refs[i].centroid2();
        if left(c) {
            lc = lc.grow(c);
            i += 1;
        } else {
            rc = rc.grow(c);
            j -= 1;
            refs.swap(i, j);
        }
    }
    (i, lc, rc)
}

/// What the builder knows about a node before deciding its fate.
struct Task<'a> {
    refs: &'a mut [PrimRef],
    /// Position of `refs` in the whole reference array.
    offset: usize,
    bounds: Bounds,
    cbounds: Bounds,
    depth: usize,
}

/// The build writes each subtree into a region of the node array reserved
/// in advance: a node over `n` primitives has at most `2n - 2` descendants,
/// so the two children's regions are known before either is built. Disjoint
/// regions let `rayon::join` build both sides in place, and the positions
/// depend only on the input, never on scheduling. A final pass compacts the
/// holes away.
struct Builder;

impl Builder {
    /// Builds the subtree of `task` with its root in `slot` and descendants
    /// in `region`, which starts at global index `base`. Returns its depth
    /// and node count.
    fn build(task: Task, slot: &mut Node, region: &mut [Node], base: usize) -> (usize, usize) {
        let Task { refs, offset, bounds, cbounds, depth } = task;
        let n = refs.len();
        let Some((mid, lb, lcb, rb, rcb)) = Self::split(refs, &bounds, &cbounds, depth) else {
            *slot = Node::leaf(&bounds, offset, n);
            return (depth, 1);
        };
        *slot = Node::inner(&bounds, base);
        let (pair, rest) = region.split_at_mut(2);
        let (lslot, rslot) = pair.split_at_mut(1);
        let (lreg, rreg) = rest.split_at_mut(2 * mid - 2);
        let (lrefs, rrefs) = refs.split_at_mut(mid);
        let lt = Task { refs: lrefs, offset, bounds: lb, cbounds: lcb, depth: depth + 1 };
        let rt = Task { refs: rrefs, offset: offset + mid, bounds: rb, cbounds: rcb, depth: depth + 1 };
        let (lbase, rbase) = (base + 2, base + 2 * mid);
        let ((ld, lc), (rd, rc)) = if n >= PAR_MIN {
            rayon::join(
                || Self::build(lt, &mut lslot[0], lreg, lbase),
                || Self::build(rt, &mut rslot[0], rreg, rbase),
            )
        } else {
            (Self::build(lt, &mut lslot[0], lreg, lbase), Self::build(rt, &mut rslot[0], rreg, rbase))
        };
        (ld.max(rd), 1 + lc + rc)
    }

    /// Decides whether to split and partitions `refs` if so, returning the
    /// size of the left part and the boxes and centroid boxes of both sides;
    /// `None` makes a leaf.
    #[allow(clippy::type_complexity)]
    fn split(
        refs: &mut [PrimRef],
        bounds: &Bounds,
        cbounds: &Bounds,
        depth: usize,
    ) -> Option<(usize, Bounds, Bounds, Bounds, Bounds)> {
        let n = refs.len();
        if n <= 1 {
            return None;
        }
        let binner = Binner::new(cbounds, n);
        if binner.scale == Vec3A::ZERO || depth >= SAH_MAX_DEPTH {
            // No centroid split exists (or the tree is suspiciously deep):
            // split in the middle if the leaf would be too big.
            return (n > MAX_LEAF).then(|| Self::median_split(refs, cbounds));
        }
        let bins = if n >= PAR_BIN_MIN {
            use rayon::prelude::*;
            refs.par_chunks(PAR_BIN_MIN / 4)
                .map(|ch| bin_refs(ch, &binner))
                .reduce(|| EMPTY_BINS, |a, b| merge_bins(a, &b))
        } else {
            bin_refs(refs, &binner)
        };
        let Some(s) = best_split(&bins, binner.nb) else {
            return (n > MAX_LEAF).then(|| Self::median_split(refs, cbounds));
        };
        let split_cost = TRAVERSAL_COST + INTERSECT_COST * s.cost / bounds.half_area().max(f32::MIN_POSITIVE);
        if split_cost >= n as f32 * INTERSECT_COST && n <= MAX_LEAF {
            return None;
        }
        let (mid, lcb, rcb) = partition(refs, |c| binner.bin(c, s.axis) < s.bin);
        Some((mid, s.left, lcb, s.right, rcb))
    }

    /// Splits at the median along the widest centroid axis.
    #[allow(clippy::type_complexity)]
    fn median_split(refs: &mut [PrimRef], cbounds: &Bounds) -> (usize, Bounds, Bounds, Bounds, Bounds) {
        let axis = (cbounds.max - cbounds.min).max_position();
        let mid = refs.len() / 2;
        // Ties broken by input index, so the result does not depend on the
        // selection algorithm's internals.
        refs.select_nth_unstable_by(mid, |a, b| {
            a.centroid2()[axis].total_cmp(&b.centroid2()[axis]).then(a.index().cmp(&b.index()))
        });
        let (l, r) = refs.split_at(mid);
        let ((lb, lcb), (rb, rcb)) = (ref_bounds(l), ref_bounds(r));
        (mid, lb, lcb, rb, rcb)
    }

    /// Copies the reachable nodes of `src` into depth-first order, children
    /// pairs in the order they are reached.
    fn compact(src: &[Node], count: usize) -> Vec<Node> {
        let mut out = Vec::with_capacity(count);
        out.push(src[0]);
        // (index in src, index in out) of inner nodes whose children are due.
        let mut stack = vec![(0usize, 0usize)];
        while let Some((s, o)) = stack.pop() {
            if src[s].is_leaf() {
                continue;
            }
            let c = src[s].first as usize;
            let oc = out.len();
            out[o].first = oc as u32;
            out.push(src[c]);
            out.push(src[c + 1]);
            // Right pushed first so the left subtree is laid out first.
            stack.push((c + 1, oc + 1));
            stack.push((c, oc));
        }
        out
    }
}

/// Ray data the slab test needs, computed once per traversal.
#[derive(Clone, Copy)]
struct RayInv {
    o: Vec3A,
    inv_d: Vec3A,
}

impl RayInv {
    #[inline]
    fn new(ray: &Ray) -> RayInv {
        // A zero direction component would make 0 * inf = NaN in the slab test
        // for a box face through the origin; a tiny stand-in keeps it finite
        // and gives the same answer.
        let d = Vec3A::from(ray.d);
        let tiny = Vec3A::splat(1e-30);
        let d = Vec3A::select(d.abs().cmplt(tiny), tiny.copysign(d), d);
        RayInv { o: Vec3A::from(ray.o), inv_d: d.recip() }
    }

    /// Entry distance into `n`'s box if the ray meets it within `[0, t_max]`.
    #[inline(always)]
    fn hit(&self, n: &Node, t_max: f32) -> Option<f32> {
        let t0 = (Vec3A::from_array(n.min) - self.o) * self.inv_d;
        let t1 = (Vec3A::from_array(n.max) - self.o) * self.inv_d;
        let tmin = t0.min(t1).max_element().max(0.0);
        let tmax = t0.max(t1).min_element() * SLAB_EXPAND;
        (tmin <= tmax.min(t_max)).then_some(tmin)
    }
}

impl Bvh {
    /// Builds a BVH over the boxes of `prim_bounds`; primitive `i` is the one
    /// with box `prim_bounds[i]`. Boxes that are empty or not finite are left
    /// out (they cannot be hit). Never panics; an empty input gives a tree
    /// that nothing hits.
    pub fn build(prim_bounds: &[Aabb]) -> Bvh {
        assert!(prim_bounds.len() <= u32::MAX as usize, "more than 2^32 primitives");
        let mut refs: Vec<PrimRef> = prim_bounds
            .iter()
            .enumerate()
            .filter(|(_, b)| !b.is_empty() && b.is_finite())
            .map(|(i, b)| PrimRef { lo: b.min.extend(f32::from_bits(i as u32)), hi: b.max.extend(0.0) })
            .collect();
        if refs.is_empty() {
            // No nodes at all: the traversals check for this once, so the
            // hot loop never meets a node without primitives.
            return Bvh { nodes: Vec::new(), prim_order: Vec::new(), depth: 0 };
        }
        let n = refs.len();
        let (bounds, cbounds) = ref_bounds(&refs);
        let mut region = vec![Node::inner(&Bounds::EMPTY, 0); 2 * n - 1];
        let (root, rest) = region.split_at_mut(1);
        let task = Task { refs: &mut refs, offset: 0, bounds, cbounds, depth: 0 };
        let (depth, count) = Builder::build(task, &mut root[0], rest, 1);
        let nodes = Builder::compact(&region, count);
        drop(region);
        let prim_order = refs.iter().map(PrimRef::index).collect();
        Bvh { nodes, prim_order, depth: depth + 1 }
    }

    /// The permutation of input primitive indices that leaf ranges index
    /// into. Shorter than the input if some boxes were empty.
    pub fn prim_order(&self) -> &[u32] {
        &self.prim_order
    }

    /// The box around everything (empty for an empty tree).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, Node::bounds)
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The node array (root first), for inspection and tests.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Number of levels (1 for a single leaf, 0 for an empty tree).
    pub fn depth(&self) -> usize {
        self.depth
    }

    /// Heap memory used by the tree.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * size_of::<Node>() + self.prim_order.capacity() * size_of::<u32>()
    }

    /// Closest-hit traversal. `leaf(range, &mut t_max)` must test the
    /// primitives at `range` of [`Bvh::prim_order`] (or of data reordered to
    /// match it), lower `t_max` to the nearest hit closer than it, and return
    /// whether it found one. Leaves are visited roughly front to back and
    /// those entirely behind the current `t_max` are skipped. Returns whether
    /// any call reported a hit.
    #[inline]
    pub fn closest<F: FnMut(Range<usize>, &mut f32) -> bool>(
        &self,
        ray: &Ray,
        mut t_max: f32,
        mut leaf: F,
    ) -> bool {
        let r = RayInv::new(ray);
        let nodes = &self.nodes[..];
        let Some(root) = nodes.first() else {
            return false;
        };
        if root.is_leaf() {
            return r.hit(root, t_max).is_some() && leaf(Self::range(root), &mut t_max);
        }
        if r.hit(root, t_max).is_none() {
            return false;
        }
        let mut stack = [(0u32, 0.0f32); STACK];
        let mut sp = 0;
        let mut hit = false;
        let mut node = root;
        loop {
            if node.is_leaf() {
                hit |= leaf(Self::range(node), &mut t_max);
            } else {
                let c = node.first as usize;
                let (a, b) = (&nodes[c], &nodes[c + 1]);
                match (r.hit(a, t_max), r.hit(b, t_max)) {
                    (Some(ta), Some(tb)) => {
                        let (near, far, tfar) = if ta <= tb { (a, c + 1, tb) } else { (b, c, ta) };
                        stack[sp] = (far as u32, tfar);
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next deferred node that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return hit;
                }
                sp -= 1;
                let (i, t) = stack[sp];
                if t <= t_max {
                    node = &nodes[i as usize];
                    break;
                }
            }
        }
    }

    /// Any-hit traversal for shadow rays: `leaf(range, t_max)` returns true if
    /// some primitive at `range` blocks the ray before `t_max`; the traversal
    /// stops at the first such leaf.
    #[inline]
    pub fn any<F: FnMut(Range<usize>, f32) -> bool>(&self, ray: &Ray, t_max: f32, mut leaf: F) -> bool {
        let r = RayInv::new(ray);
        let nodes = &self.nodes[..];
        let Some(root) = nodes.first() else {
            return false;
        };
        if r.hit(root, t_max).is_none() {
            return false;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 0;
        let mut node = root;
        loop {
            if node.is_leaf() {
                if leaf(Self::range(node), t_max) {
                    return true;
                }
            } else {
                let c = node.first as usize;
                let (a, b) = (&nodes[c], &nodes[c + 1]);
                match (r.hit(a, t_max).is_some(), r.hit(b, t_max).is_some()) {
                    (true, true) => {
                        stack[sp] = c as u32 + 1;
                        sp += 1;
                        node = a;
                        continue;
                    }
                    (true, false) => {
                        node = a;
                        continue;
                    }
                    (false, true) => {
                        node = b;
                        continue;
                    }
                    (false, false) => {}
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            node = &nodes[stack[sp] as usize];
        }
    }

    #[inline(always)]
    fn range(n: &Node) -> Range<usize> {
        n.first as usize..(n.first + n.count) as usize
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
        let nodes = bvh.nodes();
        let mut covered = vec![false; bvh.prim_order().len()];
        let contains = |outer: &Node, inner: &Aabb| {
            let o = outer.bounds();
            o.min.cmple(inner.min).all() && o.max.cmpge(inner.max).all()
        };
        for n in nodes {
            if n.is_leaf() {
                assert!(n.count as usize <= MAX_LEAF);
                for (i, &p) in bvh.prim_order()[Bvh::range(n)].iter().enumerate() {
                    assert!(!covered[n.first as usize + i], "prim in two leaves");
                    covered[n.first as usize + i] = true;
                    assert!(contains(n, &boxes[p as usize]));
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    assert!(c > 0 && c < nodes.len());
                    assert!(contains(n, &nodes[c].bounds()));
                }
            }
        }
        assert!(covered.iter().all(|&c| c), "a primitive is in no leaf");
        let mut order = bvh.prim_order().to_vec();
        order.sort_unstable();
        order.dedup();
        assert_eq!(order.len(), bvh.prim_order().len());
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
        assert_eq!((one.node_count(), one.depth(), one.prim_order()), (1, 1, &[0u32][..]));
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
        assert!(bvh.depth() < STACK, "depth {}", bvh.depth());
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
        assert_eq!(size_of::<Node>(), 32);
    }

    #[test]
    fn sah_beats_one_leaf_per_primitive() {
        // On clustered input the SAH should make multi-primitive leaves and
        // a tree far shallower than a list.
        let boxes = random_boxes(&mut Rng(3), 4096);
        let bvh = Bvh::build(&boxes);
        let leaves = bvh.nodes().iter().filter(|n| n.is_leaf()).count();
        assert!(leaves < 4096 && leaves > 4096 / MAX_LEAF, "{leaves} leaves");
        assert!(bvh.depth() < 40, "depth {}", bvh.depth());
        assert_eq!(bvh.node_count(), 2 * leaves - 1);
    }
}
