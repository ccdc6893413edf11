//! The binary binned-SAH builder behind [`super::Bvh`].
//!
//! Binned SAH (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies") on centroids, [`BINS`] bins on all three axes (fewer for
//! small nodes). A node becomes a leaf when the SAH says splitting costs more
//! than intersecting everything, with [`MAX_LEAF`] as a hard cap.
//!
//! Each subtree is written into a region of the node array reserved in
//! advance: a node over `n` primitives has at most `2n - 2` descendants, so
//! both children's regions are known before either is built. Disjoint regions
//! let `rayon::join` build the two sides in place with no copying, and node
//! positions depend only on the input, never on scheduling: the tree is the
//! same whatever the thread count. Subtrees under `PAR_MIN` primitives are
//! built on one thread with their nodes packed at the start of their region,
//! and the array is allocated zeroed, so the holes are pages never touched
//! and the worst-case reservation costs little resident memory. The tree is
//! then collapsed into wide nodes and dropped.
//!
//! Primitives with empty or non-finite boxes are left out; coincident
//! centroids fall back to a median split; below [`SAH_MAX_DEPTH`] median
//! splits take over, so no input can make the tree deeper than
//! `SAH_MAX_DEPTH + 32`, which the traversal stack is sized for.
//!
//! Binning alternates two sets of bins (merged at the end, bit for bit the
//! same bins): neighbouring references fall in the same bins, and with one
//! set each update would wait for the previous one's store. The index lane
//! of a reference's box is cleared before any arithmetic on it (see
//! `PrimRef::min`), so the build never computes on denormals.

use glam::{Vec3, Vec3A, Vec4};

use luster_core::math::Aabb;

/// Number of centroid bins per axis. 16 gives trees of nearly the SAH cost
/// that 32 does and halves the binning sweep.
pub const BINS: usize = 16;
/// Most primitives in one leaf; more are always split.
pub const MAX_LEAF: usize = 8;
/// Cost of visiting one inner node relative to one primitive test, in the SAH.
const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one primitive test.
pub const INTERSECT_COST: f32 = 1.0;
/// Subtrees with at least this many primitives are built in parallel.
const PAR_MIN: usize = 4096;
/// Nodes with at least this many primitives bin in parallel.
const PAR_BIN_MIN: usize = 1 << 16;
/// Beyond this depth, splits are by object median, which halves the count
/// at each level: depth stays below `SAH_MAX_DEPTH + 32`.
pub const SAH_MAX_DEPTH: usize = 64;
/// One binary node: its box, and either its children (`count == 0`: children at
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

    fn to_bits(self) -> NodeBits {
        let f = |x: f32| x.to_bits();
        [
            f(self.min[0]),
            f(self.min[1]),
            f(self.min[2]),
            self.first,
            f(self.max[0]),
            f(self.max[1]),
            f(self.max[2]),
            self.count,
        ]
    }

    fn from_bits(w: &NodeBits) -> Node {
        let f = f32::from_bits;
        Node { min: [f(w[0]), f(w[1]), f(w[2])], first: w[3], max: [f(w[4]), f(w[5]), f(w[6])], count: w[7] }
    }
}

/// A [`Node`] as stored during the build. Plain integers, so the node array
/// can be allocated zeroed (`vec![[0; 8]; n]` becomes `calloc`): the pages
/// of the reserved region that no node lands in are never touched and never
/// count in the resident memory.
type NodeBits = [u32; 8];

/// The binary tree's nodes, root first, siblings adjacent, with unused slots
/// between subtrees.
pub struct BinaryNodes(Vec<NodeBits>);

impl BinaryNodes {
    /// Node `i`.
    #[inline]
    pub fn get(&self, i: usize) -> Node {
        Node::from_bits(&self.0[i])
    }
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
    /// The lower corner, with the index lane cleared: SSE arithmetic works
    /// on all four lanes, and the index's bits read as a float are a
    /// denormal for every index below 2^23, and each multiply or add on a
    /// denormal takes a slow microcode assist, several per reference per
    /// pass.
    #[inline]
    fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo.with_w(0.0))
    }
    #[inline]
    fn max(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }
    #[inline]
    fn index(&self) -> u32 {
        self.lo.w.to_bits()
    }
    /// The centroid, halved before the sum so that boxes near ±f32::MAX do
    /// not overflow to infinity (halving is exact, so no bin changes).
    #[inline]
    fn centroid(&self) -> Vec3A {
        self.min() * 0.5 + self.max() * 0.5
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

/// Maps a centroid to bin indices on the three axes.
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

#[inline(always)]
fn bin_ref(bins: &mut Bins, r: &PrimRef, binner: &Binner) {
    let b = Bounds { min: r.min(), max: r.max() };
    let idx = binner.bins(r.centroid());
    for axis in 0..3 {
        let bin = &mut bins[axis][idx[axis]];
        bin.bounds = bin.bounds.union(b);
        bin.count += 1;
    }
}

/// References close in memory are close in space and land in the same bins,
/// so with one set of bins each update waits for the previous one's store.
/// Alternating two sets halves that chain; min, max and counts are exact,
/// so the merged bins are the same bits either way.
const TWO_SETS_MIN: usize = 256;

fn bin_refs(refs: &[PrimRef], binner: &Binner) -> Bins {
    let mut bins = EMPTY_BINS;
    if refs.len() < TWO_SETS_MIN {
        for r in refs {
            bin_ref(&mut bins, r, binner);
        }
        return bins;
    }
    let mut other = EMPTY_BINS;
    let mut pairs = refs.chunks_exact(2);
    for p in &mut pairs {
        bin_ref(&mut bins, &p[0], binner);
        bin_ref(&mut other, &p[1], binner);
    }
    for r in pairs.remainder() {
        bin_ref(&mut bins, r, binner);
    }
    merge_bins(bins, &other)
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
        (b.union(Bounds { min: r.min(), max: r.max() }), c.grow(r.centroid()))
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
fn best_split(bins: &Bins, nb: usize, block: u32) -> Option<Split> {
    let blocks = |c: u32| c.div_ceil(block) as f32;
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
            right[i] = (acc, acc.half_area() * blocks(count));
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
            let cost = acc.half_area() * blocks(left_count) + right[i].1;
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
        let c = refs[i].centroid();
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
    /// Primitives the caller tests together (see [`build_binary`]).
    block: u32,
    /// Cost of testing one block against visiting a node (see [`build_binary`]).
    prim_cost: f32,
}

/// The build writes each subtree into a region of the node array reserved
/// in advance: a node over `n` primitives has at most `2n - 2` descendants,
/// so the two children's regions are known before either is built. Disjoint
/// regions let `rayon::join` build both sides in place, and the positions
/// depend only on the input, never on scheduling.
struct Builder;

impl Builder {
    /// Builds the subtree of `task` with its root in `slot` and descendants
    /// in `region`, which starts at global index `base`. Returns its depth
    /// and node count.
    fn build(task: Task, slot: &mut NodeBits, region: &mut [NodeBits], base: usize) -> (usize, usize) {
        if task.refs.len() < PAR_MIN {
            let mut next = 0;
            let (node, depth, count) = Self::build_serial(task, region, base, &mut next);
            *slot = node.to_bits();
            return (depth, count);
        }
        let Task { refs, offset, bounds, cbounds, depth, block, prim_cost } = task;
        let n = refs.len();
        let Some((mid, lb, lcb, rb, rcb)) = Self::split(refs, &bounds, &cbounds, depth, block, prim_cost)
        else {
            *slot = Node::leaf(&bounds, offset, n).to_bits();
            return (depth, 1);
        };
        *slot = Node::inner(&bounds, base).to_bits();
        let (pair, rest) = region.split_at_mut(2);
        let (lslot, rslot) = pair.split_at_mut(1);
        let (lreg, rreg) = rest.split_at_mut(2 * mid - 2);
        let (lrefs, rrefs) = refs.split_at_mut(mid);
        let (lt, rt) = Self::children(lrefs, rrefs, offset, (lb, lcb), (rb, rcb), depth, block, prim_cost);
        let (lbase, rbase) = (base + 2, base + 2 * mid);
        let ((ld, lc), (rd, rc)) = rayon::join(
            || Self::build(lt, &mut lslot[0], lreg, lbase),
            || Self::build(rt, &mut rslot[0], rreg, rbase),
        );
        (ld.max(rd), 1 + lc + rc)
    }

    /// A small subtree, built on one thread with its nodes packed from the
    /// start of `region` (`next` is the first free slot): the rest of the
    /// region, reserved for the worst case, is never written. Returns the
    /// subtree's root node, depth and node count.
    fn build_serial(
        task: Task,
        region: &mut [NodeBits],
        base: usize,
        next: &mut usize,
    ) -> (Node, usize, usize) {
        let Task { refs, offset, bounds, cbounds, depth, block, prim_cost } = task;
        let n = refs.len();
        let Some((mid, lb, lcb, rb, rcb)) = Self::split(refs, &bounds, &cbounds, depth, block, prim_cost)
        else {
            return (Node::leaf(&bounds, offset, n), depth, 1);
        };
        let pair = *next;
        *next += 2;
        let (lrefs, rrefs) = refs.split_at_mut(mid);
        let (lt, rt) = Self::children(lrefs, rrefs, offset, (lb, lcb), (rb, rcb), depth, block, prim_cost);
        let (l, ld, lc) = Self::build_serial(lt, region, base, next);
        region[pair] = l.to_bits();
        let (r, rd, rc) = Self::build_serial(rt, region, base, next);
        region[pair + 1] = r.to_bits();
        (Node::inner(&bounds, base + pair), ld.max(rd), 1 + lc + rc)
    }

    /// The tasks of a split node's two children.
    #[allow(clippy::too_many_arguments)]
    fn children<'a>(
        lrefs: &'a mut [PrimRef],
        rrefs: &'a mut [PrimRef],
        offset: usize,
        (lb, lcb): (Bounds, Bounds),
        (rb, rcb): (Bounds, Bounds),
        depth: usize,
        block: u32,
        prim_cost: f32,
    ) -> (Task<'a>, Task<'a>) {
        let mid = lrefs.len();
        let lt = Task { refs: lrefs, offset, bounds: lb, cbounds: lcb, depth: depth + 1, block, prim_cost };
        let rt = Task {
            refs: rrefs,
            offset: offset + mid,
            bounds: rb,
            cbounds: rcb,
            depth: depth + 1,
            block,
            prim_cost,
        };
        (lt, rt)
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
        block: u32,
        prim_cost: f32,
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
        let Some(s) = best_split(&bins, binner.nb, block) else {
            return (n > MAX_LEAF).then(|| Self::median_split(refs, cbounds));
        };
        let split_cost = TRAVERSAL_COST + prim_cost * s.cost / bounds.half_area().max(f32::MIN_POSITIVE);
        if split_cost >= (n as u32).div_ceil(block) as f32 * prim_cost && n <= MAX_LEAF {
            return None;
        }
        let (mid, lcb, rcb) = partition(refs, |c| binner.bin(c, s.axis) < s.bin);
        if mid == 0 || mid == n {
            // Binning and partition disagree, which only extreme coordinates
            // can cause; an empty child would be a leaf of no primitives.
            return (n > MAX_LEAF).then(|| Self::median_split(refs, cbounds));
        }
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
            a.centroid()[axis].total_cmp(&b.centroid()[axis]).then(a.index().cmp(&b.index()))
        });
        let (l, r) = refs.split_at(mid);
        let ((lb, lcb), (rb, rcb)) = (ref_bounds(l), ref_bounds(r));
        (mid, lb, lcb, rb, rcb)
    }
}

/// The binary tree over primitives `0..n`, primitive `i` having the box
/// `prim_box(i)`: nodes (root first, siblings adjacent, with unused slots
/// between subtrees: the caller collapses it and drops it anyway), the
/// permutation of primitive indices its leaves index into, and its depth.
/// `None` if no primitive has a usable box. Taking the boxes from a function
/// spares the caller an array of them: for a mesh that array would be as big
/// as the references made from it.
///
/// `block` is how many primitives the caller intersects at once (4 for
/// triangles tested four to a SIMD block): the SAH then counts a leaf's cost
/// in blocks, `ceil(n / block)`, as Embree does for its 4-triangle leaves,
/// so leaves fill their blocks instead of leaving lanes idle.
///
/// `prim_cost` is what testing one block costs against visiting a node:
/// [`INTERSECT_COST`] for triangles; more for the objects of a top-level
/// tree, each a mesh with its own tree or an analytic shape, which the SAH
/// then keeps in smaller leaves.
pub(super) fn build_binary(
    n: usize,
    prim_box: &(impl Fn(usize) -> Aabb + Sync),
    block: u32,
    prim_cost: f32,
) -> Option<(BinaryNodes, Vec<u32>, usize)> {
    use rayon::prelude::*;
    // Written in place (an indexed collect); an unusable box is marked with
    // a NaN and removed after, which is rare and then one serial pass.
    let mut refs = Vec::new();
    (0..n)
        .into_par_iter()
        .map(|i| {
            let b = prim_box(i);
            let lo = if !b.is_empty() && b.is_finite() { b.min } else { Vec3::NAN };
            PrimRef { lo: lo.extend(f32::from_bits(i as u32)), hi: b.max.extend(0.0) }
        })
        .collect_into_vec(&mut refs);
    if refs.par_iter().any(|r| r.lo.x.is_nan()) {
        refs.retain(|r| !r.lo.x.is_nan());
    }
    if refs.is_empty() {
        return None;
    }
    let n = refs.len();
    let (bounds, cbounds) = ref_bounds(&refs);
    let mut region: Vec<NodeBits> = vec![[0; 8]; 2 * n - 1];
    let (root, rest) = region.split_at_mut(1);
    let task = Task { refs: &mut refs, offset: 0, bounds, cbounds, depth: 0, block: block.max(1), prim_cost };
    let (depth, _) = Builder::build(task, &mut root[0], rest, 1);
    let mut prim_order = Vec::new();
    refs.par_iter().map(PrimRef::index).collect_into_vec(&mut prim_order);
    Some((BinaryNodes(region), prim_order, depth + 1))
}
