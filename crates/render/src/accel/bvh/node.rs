//! The wide node of [`super::Bvh`] and the ray–node tests: eight child boxes
//! side by side (structure of arrays), tested against one ray at once.
//!
//! Two tests exist for the same node layout, chosen at run time:
//! - **AVX2 + FMA**: one 8-lane test, each slab plane computed as one fused
//!   `b * inv - o * inv`, with the rounding of the precomputed `o * inv`
//!   covered by a margin of two ulps taken outwards. It may let through a
//!   box the plain test culls (by a few ulps), never the reverse.
//! - **SSE** (any x86-64, and the reference): the node as two 4-lane halves,
//!   `(b - o) * inv` per plane.
//!
//! Either way the near plane of each slab is chosen once per ray from the
//! direction's signs, so a test is three plane distances per bound with no
//! min/max of the two slab distances, and the exit distance is widened by a
//! few ulps (Ize 2013, "Robust BVH Ray Traversal") so a ray grazing a shared
//! box face, as rays through a shared triangle edge do, is never lost.

use std::ops::Range;

use glam::{Vec3, Vec3A, Vec4};

use luster_core::math::{Aabb, Ray};

/// Children per node.
pub const WIDTH: usize = 8;
/// Marks a child reference as a leaf: `LEAF | first << 3 | (count - 1)`.
pub(super) const LEAF: u32 = 1 << 31;
/// An unused child slot; its box is empty, so it is never entered.
pub(super) const EMPTY: u32 = u32::MAX;
/// `1 + 2 * gamma(3)` (pbrt's conservative slab-test factor): the exit
/// distance is scaled by it so rounding never culls a box the ray touches.
const SLAB_EXPAND: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// An 8-wide node: its children's boxes as structure of arrays and their
/// references. 256 bytes, four cache lines, each row 32-byte aligned for
/// one AVX load.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node8 {
    /// Rows: min x, max x, min y, max y, min z, max z; one lane per child.
    pub(super) bounds: [[f32; WIDTH]; 6],
    /// Node index, leaf reference (`LEAF` bit set) or `EMPTY`.
    pub(super) child: [u32; WIDTH],
}

impl Node8 {
    pub(super) const EMPTY: Node8 = Node8 {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
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

    /// Sets child `k`'s box.
    pub(super) fn set_bounds(&mut self, k: usize, b: &Aabb) {
        for axis in 0..3 {
            self.bounds[2 * axis][k] = b.min[axis];
            self.bounds[2 * axis + 1][k] = b.max[axis];
        }
    }

    /// Row `row` as four-lane halves.
    #[inline(always)]
    fn half(&self, row: usize, h: usize) -> Vec4 {
        let r = &self.bounds[row];
        Vec4::new(r[4 * h], r[4 * h + 1], r[4 * h + 2], r[4 * h + 3])
    }
}

/// A one-node tree's root with its bound rows reordered for each of the
/// eight direction-sign masks ([`RayPre::signs`]): the near planes of x, y
/// and z, then the far planes. The fused test then reads the rows at fixed
/// offsets instead of looking up six offsets per query (every query of a
/// small scene's top level tests this node and no other). The same rows, so
/// the same operations on the same values.
#[derive(Clone, Debug, PartialEq)]
#[repr(C, align(64))]
pub(super) struct SignedRoot {
    rows: [[[f32; WIDTH]; 6]; 8],
    /// The root's children ([`Node8::child`]), copied (and copied again where
    /// the leaves are renumbered) so that the walk reads this one block
    /// and tests no node count, without reading `nodes[0]` as well.
    pub(super) child: [u32; WIDTH],
}

impl SignedRoot {
    pub(super) fn new(n: &Node8) -> Box<SignedRoot> {
        let rows = std::array::from_fn(|s| {
            std::array::from_fn(|i| {
                let near = 2 * (i % 3) + (s >> (i % 3) & 1);
                n.bounds[if i < 3 { near } else { near ^ 1 }]
            })
        });
        Box::new(SignedRoot { rows, child: n.child })
    }
}

/// A child slot of a [`Node8`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Child {
    /// An inner node, by index.
    Node(usize),
    /// A leaf: a range of [`super::Bvh::prim_order`].
    Leaf(Range<usize>),
    /// Unused.
    Empty,
}

#[inline(always)]
pub(super) fn leaf_range(r: u32) -> Range<usize> {
    let first = ((r & !LEAF) >> 3) as usize;
    first..first + (r & 7) as usize + 1
}

pub(super) fn decode(r: u32) -> Child {
    match r {
        EMPTY => Child::Empty,
        r if r & LEAF != 0 => Child::Leaf(leaf_range(r)),
        r => Child::Node(r as usize),
    }
}

/// Ray data the node test needs, computed once per traversal. Kept as
/// vectors, not arrays: the traversals broadcast them from registers, where
/// arrays would go through the stack and their reloads, wider than the
/// stores that wrote them, would wait for those stores to retire.
#[derive(Clone, Copy)]
pub(super) struct RayPre {
    o: Vec3A,
    inv: Vec3A,
    /// For the fused test `b * inv + c`: `c = -o * inv`, moved down (near
    /// planes) or up (far planes) by more than its rounding error.
    c_near: Vec3A,
    c_far: Vec3A,
    /// Bit `a` set where the direction's axis `a` is negative: that axis's
    /// near plane is then the box's maximum (row `2a + 1` of
    /// [`Node8::bounds`]), its far plane the minimum. One mask and not six
    /// row indices: fewer bytes to build and carry per query.
    signs: u32,
    /// Whether `c_near` and `c_far` are finite, so the fused test applies.
    pub(super) fused_ok: bool,
}

impl RayPre {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> RayPre {
        // A zero direction component would make 0 * inf = NaN for a box face
        // through the origin; a tiny stand-in keeps it finite with the same
        // answer.
        let d = Vec3A::from(ray.d);
        let tiny = Vec3A::splat(1e-30);
        let d = Vec3A::select(d.abs().cmplt(tiny), tiny.copysign(d), d);
        let inv = d.recip();
        let signs = inv.cmplt(Vec3A::ZERO).bitmask();
        // `b * inv - o * inv` in one rounding of a fused multiply-add, where
        // `o * inv` was rounded once before: that product's error is
        // absolute, up to half an ulp of it, and cancellation can make it
        // large next to the result. A margin of two ulps, taken outwards,
        // covers it and the rounding of the margin itself; the relative
        // errors left are the ones `SLAB_EXPAND` already covers.
        // Read a lane at a time: `Vec3A::from` would load `o` and `d.x` as
        // one 16-byte word, and the callers write a ray field by field (`x, y`,
        // then `z`, then the direction), so that load would wait for those
        // stores to retire.
        // SAFETY: reads of the fields of `ray`.
        let lane = |x: &f32| unsafe { std::ptr::read_volatile(x) };
        let o = Vec3A::new(lane(&ray.o.x), lane(&ray.o.y), lane(&ray.o.z));
        let oi = o * inv;
        let pad = oi.abs() * (2.0 * f32::EPSILON);
        let (cn, cf) = (-oi - pad, -oi + pad);
        let fused_ok = (cn.is_finite_mask() & cf.is_finite_mask()).all();
        RayPre { o, inv, c_near: cn, c_far: cf, signs, fused_ok }
    }

    /// The row of [`Node8::bounds`] holding axis `a`'s near plane.
    #[inline(always)]
    fn near(&self, a: usize) -> usize {
        2 * a + (self.signs >> a & 1) as usize
    }

    /// The row holding axis `a`'s far plane.
    #[inline(always)]
    fn far(&self, a: usize) -> usize {
        self.near(a) ^ 1
    }

    /// [`RayPre::hit`] as one 8-lane test with one fused multiply-add per
    /// plane instead of a subtraction and a multiplication. It may let
    /// through a box the plain test culls (by a few ulps), never the
    /// reverse, so the primitives found and the hits reported are the same.
    ///
    /// The traversals run it as [`FusedRay::hit`], with the per-ray
    /// constants broadcast once; this per-node form is the reference the
    /// tests check that one against, lane for lane.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA, and `self.fused_ok` must hold.
    #[cfg(all(target_arch = "x86_64", test))]
    #[inline(always)]
    pub(super) unsafe fn hit_fused(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
        use std::arch::x86_64::*;
        let b = &n.bounds;
        let row = |r: usize| _mm256_load_ps(b[r].as_ptr());
        let s = _mm256_set1_ps;
        let (inv, cn, cf) = (&self.inv, &self.c_near, &self.c_far);
        let near = [self.near(0), self.near(1), self.near(2)];
        let far = [self.far(0), self.far(1), self.far(2)];
        let plane = |r: usize, a: usize, c: f32| _mm256_fmadd_ps(row(r), s(inv[a]), s(c));
        let tn = _mm256_max_ps(
            _mm256_max_ps(plane(near[0], 0, cn[0]), plane(near[1], 1, cn[1])),
            _mm256_max_ps(plane(near[2], 2, cn[2]), _mm256_setzero_ps()),
        );
        let tf = _mm256_min_ps(
            _mm256_min_ps(plane(far[0], 0, cf[0]), plane(far[1], 1, cf[1])),
            plane(far[2], 2, cf[2]),
        );
        let tf = _mm256_min_ps(_mm256_mul_ps(tf, s(SLAB_EXPAND)), s(t_max));
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32;
        let mut out = [0.0f32; WIDTH];
        _mm256_storeu_ps(out.as_mut_ptr(), tn);
        (out, mask)
    }

    /// The node test a traversal runs for this ray: fused where the
    /// traversal was compiled for it (`FUSED`) and this ray allows it.
    #[inline(always)]
    pub(super) fn node_test<const FUSED: bool>(&self) -> NodeTest {
        #[cfg(target_arch = "x86_64")]
        if FUSED && self.fused_ok {
            // SAFETY: `FUSED` traversals are only entered after detecting
            // AVX2 and FMA (`fused_available`).
            return NodeTest::Fused(unsafe { FusedRay::new(self) });
        }
        NodeTest::Plain
    }

    /// Entry distances of the eight children and the mask of those the ray
    /// meets within `[0, t_max]`, as two 4-lane halves.
    #[inline(always)]
    pub(super) fn hit(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
        let half = |h: usize| {
            let slab =
                |row: usize, a: usize| (n.half(row, h) - Vec4::splat(self.o[a])) * Vec4::splat(self.inv[a]);
            let tn =
                slab(self.near(0), 0).max(slab(self.near(1), 1)).max(slab(self.near(2), 2).max(Vec4::ZERO));
            let tf = slab(self.far(0), 0).min(slab(self.far(1), 1)).min(slab(self.far(2), 2));
            let tf = (tf * SLAB_EXPAND).min(Vec4::splat(t_max));
            (tn, tn.cmple(tf).bitmask())
        };
        let ((lo, ml), (hi, mh)) = (half(0), half(1));
        let (lo, hi) = (lo.to_array(), hi.to_array());
        ([lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]], ml | mh << 4)
    }

    /// The same test for one box (the root of a one-leaf tree), one lane
    /// wide: the operations of [`RayPre::hit`] on lane 0.
    #[inline(always)]
    pub(super) fn hit_box(&self, b: &Aabb, t_max: f32) -> bool {
        // Row `2a` of a node is axis a's minimum, row `2a + 1` its maximum.
        let (lo, hi) = (b.min.to_array(), b.max.to_array());
        let bound = |row: usize| if row % 2 == 0 { lo[row / 2] } else { hi[row / 2] };
        let slab = |row: usize, a: usize| (bound(row) - self.o[a]) * self.inv[a];
        let tn = slab(self.near(0), 0).max(slab(self.near(1), 1)).max(slab(self.near(2), 2).max(0.0));
        let tf = slab(self.far(0), 0).min(slab(self.far(1), 1)).min(slab(self.far(2), 2));
        tn <= (tf * SLAB_EXPAND).min(t_max)
    }
}

/// The node test chosen once per traversal ([`RayPre::node_test`]).
// It lives in one traversal's registers and stack frame: boxing the large
// variant would put an indirection into every node test.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy)]
pub(super) enum NodeTest {
    /// [`RayPre::hit`].
    Plain,
    /// [`FusedRay::hit`].
    #[cfg(target_arch = "x86_64")]
    Fused(FusedRay),
}

impl NodeTest {
    /// Entry distances and hit mask of `n`'s children (see [`RayPre::hit`]).
    #[inline(always)]
    pub(super) fn hit(&self, r: &RayPre, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
        match self {
            NodeTest::Plain => r.hit(n, t_max),
            // SAFETY: a `FusedRay` exists only where the CPU has AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            NodeTest::Fused(f) => unsafe { f.hit(n, t_max) },
        }
    }

    /// [`NodeTest::hit`] of the root of a one-node tree (`nodes`), whose
    /// rows `root` holds reordered by sign.
    #[inline(always)]
    pub(super) fn hit_root(
        &self,
        r: &RayPre,
        nodes: &[Node8],
        root: &SignedRoot,
        t_max: f32,
    ) -> ([f32; WIDTH], u32) {
        match self {
            NodeTest::Plain => r.hit(&nodes[0], t_max),
            // SAFETY: a `FusedRay` exists only where the CPU has AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            NodeTest::Fused(f) => unsafe { f.hit_rows(&root.rows[f.signs & 7], t_max) },
        }
    }
}

/// The fused test's per-ray constants, broadcast to eight lanes once per
/// traversal rather than at every node, with the near and far rows as
/// offsets into a node, so that a node test neither re-broadcasts them from
/// the [`RayPre`] nor bounds-checks six row indices.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(super) struct FusedRay {
    inv: [std::arch::x86_64::__m256; 3],
    c_near: [std::arch::x86_64::__m256; 3],
    c_far: [std::arch::x86_64::__m256; 3],
    /// Offsets in `f32`s of each axis's near row, then of each far row,
    /// from a node's start: an entry of [`ROWS`], chosen by a table lookup
    /// rather than computed row by row.
    rows: &'static [u8; 6],
    /// [`RayPre::signs`], to pick a [`SignedRoot`]'s rows.
    signs: usize,
}

/// [`FusedRay::rows`] for each [`RayPre::signs`].
#[cfg(target_arch = "x86_64")]
const ROWS: [[u8; 6]; 8] = {
    let mut t = [[0u8; 6]; 8];
    let mut s = 0;
    while s < 8 {
        let mut a = 0;
        while a < 3 {
            let near = 2 * a + (s >> a & 1);
            t[s][a] = (near * WIDTH) as u8;
            t[s][3 + a] = ((near ^ 1) * WIDTH) as u8;
            a += 1;
        }
        s += 1;
    }
    t
};

#[cfg(target_arch = "x86_64")]
impl FusedRay {
    /// # Safety
    /// The CPU must have AVX2 and FMA, and `r.fused_ok` must hold.
    #[inline(always)]
    unsafe fn new(r: &RayPre) -> FusedRay {
        use std::arch::x86_64::_mm256_set1_ps;
        // One lane at a time: left free, LLVM loads `c_far`'s y and z as
        // one 8-byte word from the middle of the 16 bytes `RayPre::new` has
        // just stored, which the store buffer cannot forward, and the load
        // then waits for the store to retire.
        // SAFETY: a read of a field of `r`.
        let s = |x: &f32| _mm256_set1_ps(unsafe { std::ptr::read_volatile(x) });
        let (inv, cn, cf) = (&r.inv, &r.c_near, &r.c_far);
        FusedRay {
            inv: [s(&inv.x), s(&inv.y), s(&inv.z)],
            c_near: [s(&cn.x), s(&cn.y), s(&cn.z)],
            c_far: [s(&cf.x), s(&cf.y), s(&cf.z)],
            rows: &ROWS[(r.signs & 7) as usize],
            signs: r.signs as usize,
        }
    }

    /// `RayPre::hit_fused` (kept for the tests) with the constants broadcast beforehand: the
    /// same operations on the same values, so the same lanes.
    ///
    /// Not itself compiled for AVX2 (`#[target_feature]` forbids
    /// `#[inline(always)]`, and LLVM would not inline it otherwise): it is
    /// only called from traversals compiled for AVX2 and FMA, where it and
    /// the intrinsics inline.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[inline(always)]
    unsafe fn hit(&self, n: &Node8, t_max: f32) -> ([f32; WIDTH], u32) {
        let b = n.bounds.as_ptr().cast::<f32>();
        // SAFETY: the offsets are rows 0 to 5 of the node's six rows.
        self.planes(self.rows.map(|off| b.add(off as usize)), t_max)
    }

    /// The fused test on six rows of eight bounds, each 32-byte aligned:
    /// the near planes of x, y and z, then their far planes.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA; each pointer must point to a row.
    #[inline(always)]
    unsafe fn planes(&self, rows: [*const f32; 6], t_max: f32) -> ([f32; WIDTH], u32) {
        use std::arch::x86_64::*;
        let (inv, cn, cf) = (&self.inv, &self.c_near, &self.c_far);
        let plane = |i: usize, a: usize, c: __m256| _mm256_fmadd_ps(_mm256_load_ps(rows[i]), inv[a], c);
        let tn = _mm256_max_ps(
            _mm256_max_ps(plane(0, 0, cn[0]), plane(1, 1, cn[1])),
            _mm256_max_ps(plane(2, 2, cn[2]), _mm256_setzero_ps()),
        );
        let tf = _mm256_min_ps(_mm256_min_ps(plane(3, 0, cf[0]), plane(4, 1, cf[1])), plane(5, 2, cf[2]));
        let tf = _mm256_min_ps(_mm256_mul_ps(tf, _mm256_set1_ps(SLAB_EXPAND)), _mm256_set1_ps(t_max));
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32;
        let mut out = [0.0f32; WIDTH];
        _mm256_storeu_ps(out.as_mut_ptr(), tn);
        (out, mask)
    }
}

#[cfg(target_arch = "x86_64")]
impl FusedRay {
    /// [`FusedRay::hit`] on rows already in near-then-far order (a
    /// [`SignedRoot`]'s for this ray's signs): the same planes, fused with
    /// the same constants, in the same order.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[inline(always)]
    unsafe fn hit_rows(&self, rows: &[[f32; WIDTH]; 6], t_max: f32) -> ([f32; WIDTH], u32) {
        // SAFETY: each row is 32-byte aligned (a `SignedRoot` is 64-byte
        // aligned, a row 32 bytes).
        self.planes(std::array::from_fn(|i| rows[i].as_ptr()), t_max)
    }
}

/// Which node test the traversal uses on this CPU (for benchmark reports).
pub fn node_test_isa() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    if fused_available() {
        return "AVX2+FMA, 8 lanes";
    }
    "SSE, 2 x 4 lanes"
}

/// Whether this CPU runs the AVX2 + FMA traversal (detected once; the
/// standard library caches the answer).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn fused_available() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}
