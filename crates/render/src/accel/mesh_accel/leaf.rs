//! The leaf tests of a mesh's traversal: a leaf's triangle blocks against
//! the ray, for the closest hit (in lane order, as testing the triangles one
//! by one would choose) or for any hit. Two blocks at a time through the
//! 8-lane test where the caller is compiled for AVX2. Reads no scene
//! parameters.

use super::TriHit;
use crate::accel::bvh::{AnyLeaf, ClosestLeaf};
use crate::accel::tri_block::TriBlock;
use crate::accel::triangle::WatertightRay;
use luster_core::math::Ray;

/// The closest-hit leaf test of a mesh's traversal.
pub(super) struct Closest<'a, const AVX: bool> {
    pub(super) blocks: &'a [TriBlock],
    pub(super) ray: &'a Ray,
    pub(super) wr: &'a WatertightRay,
    pub(super) t_min: f32,
    pub(super) cull: f32,
    pub(super) best: &'a mut Option<TriHit>,
}

impl<const AVX: bool> ClosestLeaf for Closest<'_, AVX> {
    #[inline(always)]
    fn test(&mut self, range: std::ops::Range<usize>, t_max: &mut f32) -> bool {
        leaf_closest::<AVX>(&self.blocks[range], self.ray, self.wr, self.t_min, t_max, self.cull, self.best)
    }
}

/// The any-hit leaf test of a mesh's traversal.
pub(super) struct Any<'a, const AVX: bool> {
    pub(super) blocks: &'a [TriBlock],
    pub(super) wr: &'a WatertightRay,
    pub(super) t_min: f32,
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
pub(super) fn leaf_closest<const AVX: bool>(
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
pub(super) fn leaf_any<const AVX: bool>(
    blocks: &[TriBlock],
    wr: &WatertightRay,
    t_min: f32,
    t_max: f32,
) -> bool {
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
    // A loop, not `Iterator::any`: its closure can be left out of line.
    for b in rest {
        if b.intersect(wr, t_min, t_max).mask != 0 {
            return true;
        }
    }
    false
}
