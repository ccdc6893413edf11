//! Four triangles stored side by side (structure of arrays) and tested
//! against one ray at once with 4-lane SIMD: the watertight test of
//! [`super::triangle`], lane by lane.
//!
//! Each lane performs exactly the scalar test's `f32` operations in the same
//! order (no fused multiply-add, a true division for `1 / det`), and a lane
//! whose edge function is exactly zero is redone by the scalar test with its
//! `f64` fallback. So a block finds the same hits, bit for bit, as testing
//! its triangles one by one; it only tests them four at a time. Unused
//! lanes hold NaN vertices, which fail every comparison.

use glam::Vec4;

use super::triangle::{Triangle, WatertightRay};

/// Four triangles: `p[vertex][axis]` holds that coordinate for each lane,
/// and `prim` each lane's input index (`u32::MAX` for an unused lane).
/// 160 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct TriBlock {
    p: [[Vec4; 3]; 3],
    prim: [u32; 4],
}

/// The lanes a block test hit, with their distances and barycentrics.
#[derive(Clone, Copy, Debug)]
pub struct BlockHit {
    /// Bit `i` set if lane `i` hit within the interval.
    pub mask: u32,
    /// Ray parameter per lane.
    pub t: [f32; 4],
    /// Barycentrics of vertices 1 and 2 per lane, side by side (see
    /// [`PairHit::uv`]).
    pub uv: [[f32; 2]; 4],
}

impl TriBlock {
    /// Packs up to four triangles; missing lanes are unused.
    pub fn new(tris: &[Triangle]) -> TriBlock {
        debug_assert!(tris.len() <= 4);
        let mut p = [[[f32::NAN; 4]; 3]; 3];
        let mut prim = [u32::MAX; 4];
        for (lane, t) in tris.iter().take(4).enumerate() {
            for (vert, v) in t.v.iter().enumerate() {
                for axis in 0..3 {
                    p[vert][axis][lane] = v[axis];
                }
            }
            prim[lane] = t.prim;
        }
        TriBlock { p: p.map(|v| v.map(Vec4::from_array)), prim }
    }

    /// The triangle in `lane` (only meaningful for a used lane).
    pub fn triangle(&self, lane: usize) -> Triangle {
        let v = |k: usize| [self.p[k][0][lane], self.p[k][1][lane], self.p[k][2][lane]];
        Triangle { v: [v(0), v(1), v(2)], prim: self.prim[lane] }
    }

    /// Input index of the triangle in `lane`.
    #[inline(always)]
    pub fn prim(&self, lane: usize) -> u32 {
        self.prim[lane]
    }

    /// Tests all four lanes for a hit with `t_min < t < t_max`.
    #[inline(always)]
    pub fn intersect(&self, r: &WatertightRay, t_min: f32, t_max: f32) -> BlockHit {
        let (kx, ky, kz) = (r.kx, r.ky, r.kz);
        let (ox, oy, oz) = (Vec4::splat(r.o[kx]), Vec4::splat(r.o[ky]), Vec4::splat(r.o[kz]));
        let (sx, sy, sz) = (Vec4::splat(r.sx), Vec4::splat(r.sy), Vec4::splat(r.sz));
        // Vertices relative to the origin, permuted so the ray runs along z,
        // then sheared: the scalar test's `a`, `b`, `c` and their x, y.
        let rel = |k: usize| {
            let p = &self.p[k];
            let (x, y, z) = (p[kx] - ox, p[ky] - oy, p[kz] - oz);
            (x + sx * z, y + sy * z, z)
        };
        let (ax, ay, a2) = rel(0);
        let (bx, by, b2) = rel(1);
        let (cx, cy, c2) = rel(2);
        let mut e0 = bx * cy - by * cx;
        let mut e1 = cx * ay - cy * ax;
        let mut e2 = ax * by - ay * bx;
        let zero = (e0.cmpeq(Vec4::ZERO) | e1.cmpeq(Vec4::ZERO) | e2.cmpeq(Vec4::ZERO)).bitmask();
        if zero != 0 {
            (e0, e1, e2) = edges_f64(zero, [ax, ay, bx, by, cx, cy], [e0, e1, e2]);
        }
        let neg = e0.cmplt(Vec4::ZERO) | e1.cmplt(Vec4::ZERO) | e2.cmplt(Vec4::ZERO);
        let pos = e0.cmpgt(Vec4::ZERO) | e1.cmpgt(Vec4::ZERO) | e2.cmpgt(Vec4::ZERO);
        let inside = !(neg & pos);
        if inside.bitmask() == 0 {
            // Most blocks a ray reaches miss on the edge test: skip the
            // division. Lanes that pass are computed in full.
            return BlockHit { mask: 0, t: [0.0; 4], uv: [[0.0; 2]; 4] };
        }
        let det = e0 + e1 + e2;
        let t_scaled = e0 * (sz * a2) + e1 * (sz * b2) + e2 * (sz * c2);
        let inv = Vec4::ONE / det;
        let t = t_scaled * inv;
        // `t > t_min && t < t_max` is false for NaN (from a NaN lane or a
        // zero determinant), as in the scalar test.
        let ok = inside
            & det.cmpne(Vec4::ZERO)
            & det.cmpeq(det)
            & t.cmpgt(Vec4::splat(t_min))
            & t.cmplt(Vec4::splat(t_max));
        let mask = ok.bitmask();
        if mask == 0 {
            return BlockHit { mask, t: [0.0; 4], uv: [[0.0; 2]; 4] };
        }
        let (u, v) = ((e1 * inv).to_array(), (e2 * inv).to_array());
        BlockHit { mask, t: t.to_array(), uv: std::array::from_fn(|i| [u[i], v[i]]) }
    }
}

/// The lanes two blocks hit when tested together ([`TriBlock::intersect_pair`]):
/// lanes 0–3 are the first block's, 4–7 the second's.
#[derive(Clone, Copy, Debug)]
pub struct PairHit {
    /// Bit `i` set if lane `i` hit within the interval.
    pub mask: u32,
    /// Ray parameter per lane.
    pub t: [f32; 8],
    /// Barycentrics of vertices 1 and 2 per lane, side by side: a hit's
    /// pair is copied as one 8-byte word into [`TriHit`](super::mesh_accel::TriHit),
    /// whose readers load it whole. From two arrays it would be written as
    /// two 4-byte stores, which an 8-byte load cannot be forwarded from: it
    /// would wait for them to retire, at every closest hit.
    pub uv: [[f32; 2]; 8],
}

impl TriBlock {
    /// [`TriBlock::intersect`] of two blocks at once with 8-lane AVX: each
    /// lane performs the same `f32` operations in the same order (separate
    /// multiplies and adds, a true division), so every lane's hit is bit for
    /// bit the 4-lane test's, and so the scalar test's. Half a leaf's block
    /// tests, where a leaf holds two blocks.
    ///
    /// Not itself compiled for AVX (`#[target_feature]` forbids
    /// `#[inline(always)]`): only called from code compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub unsafe fn intersect_pair(
        a: &TriBlock,
        b: &TriBlock,
        r: &WatertightRay,
        t_min: f32,
        t_max: f32,
    ) -> PairHit {
        use std::arch::x86_64::*;
        let (kx, ky, kz) = (r.kx, r.ky, r.kz);
        let s = _mm256_set1_ps;
        let (ox, oy, oz) = (s(r.o[kx]), s(r.o[ky]), s(r.o[kz]));
        let (sx, sy, sz) = (s(r.sx), s(r.sy), s(r.sz));
        // Macros rather than closures: a closure is a function of its own,
        // compiled without AVX, which LLVM need not inline.
        macro_rules! row {
            ($k:expr, $axis:expr) => {
                _mm256_insertf128_ps::<1>(
                    _mm256_castps128_ps256(__m128::from(a.p[$k][$axis])),
                    __m128::from(b.p[$k][$axis]),
                )
            };
        }
        macro_rules! sub {
            ($x:expr, $y:expr) => {
                _mm256_sub_ps($x, $y)
            };
        }
        macro_rules! mul {
            ($x:expr, $y:expr) => {
                _mm256_mul_ps($x, $y)
            };
        }
        macro_rules! add {
            ($x:expr, $y:expr) => {
                _mm256_add_ps($x, $y)
            };
        }
        macro_rules! rel {
            ($k:expr) => {{
                let (x, y, z) = (sub!(row!($k, kx), ox), sub!(row!($k, ky), oy), sub!(row!($k, kz), oz));
                (add!(x, mul!(sx, z)), add!(y, mul!(sy, z)), z)
            }};
        }
        let (ax, ay, a2) = rel!(0);
        let (bx, by, b2) = rel!(1);
        let (cx, cy, c2) = rel!(2);
        let mut e0 = sub!(mul!(bx, cy), mul!(by, cx));
        let mut e1 = sub!(mul!(cx, ay), mul!(cy, ax));
        let mut e2 = sub!(mul!(ax, by), mul!(ay, bx));
        let zero = _mm256_setzero_ps();
        macro_rules! cmp {
            ($op:ident, $x:expr) => {
                _mm256_cmp_ps::<$op>($x, zero)
            };
        }
        let is_zero = _mm256_movemask_ps(_mm256_or_ps(
            _mm256_or_ps(cmp!(_CMP_EQ_OQ, e0), cmp!(_CMP_EQ_OQ, e1)),
            cmp!(_CMP_EQ_OQ, e2),
        ));
        if is_zero != 0 {
            let v = [ax, ay, bx, by, cx, cy].map(to_array8);
            let [f0, f1, f2] = edges_f64_8(is_zero as u32, v, [e0, e1, e2].map(to_array8));
            (e0, e1, e2) = (from_array8(f0), from_array8(f1), from_array8(f2));
        }
        let neg =
            _mm256_or_ps(_mm256_or_ps(cmp!(_CMP_LT_OQ, e0), cmp!(_CMP_LT_OQ, e1)), cmp!(_CMP_LT_OQ, e2));
        let pos =
            _mm256_or_ps(_mm256_or_ps(cmp!(_CMP_GT_OQ, e0), cmp!(_CMP_GT_OQ, e1)), cmp!(_CMP_GT_OQ, e2));
        // Lanes with both signs are outside; NaN lanes have neither, as in
        // the 4-lane test, and fail on the determinant below.
        let outside = _mm256_and_ps(neg, pos);
        if _mm256_movemask_ps(outside) == 0xff {
            return PairHit { mask: 0, t: [0.0; 8], uv: [[0.0; 2]; 8] };
        }
        let det = add!(add!(e0, e1), e2);
        let t_scaled = add!(add!(mul!(e0, mul!(sz, a2)), mul!(e1, mul!(sz, b2))), mul!(e2, mul!(sz, c2)));
        let inv = _mm256_div_ps(s(1.0), det);
        let t = mul!(t_scaled, inv);
        let ok = _mm256_andnot_ps(
            outside,
            _mm256_and_ps(
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_NEQ_UQ>(det, zero), _mm256_cmp_ps::<_CMP_EQ_OQ>(det, det)),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GT_OQ>(t, s(t_min)),
                    _mm256_cmp_ps::<_CMP_LT_OQ>(t, s(t_max)),
                ),
            ),
        );
        let mask = _mm256_movemask_ps(ok) as u32;
        if mask == 0 {
            return PairHit { mask, t: [0.0; 8], uv: [[0.0; 2]; 8] };
        }
        let (u, v) = (mul!(e1, inv), mul!(e2, inv));
        // Lanes 0 1 4 5 and 2 3 6 7 interleaved, then halves regrouped.
        let (lo, hi) = (_mm256_unpacklo_ps(u, v), _mm256_unpackhi_ps(u, v));
        let uv = [_mm256_permute2f128_ps::<0x20>(lo, hi), _mm256_permute2f128_ps::<0x31>(lo, hi)];
        // SAFETY: two vectors of eight floats are 32 bytes of plain floats
        // each, as are eight pairs.
        let uv: [[f32; 2]; 8] = std::mem::transmute(uv);
        PairHit { mask, t: to_array8(t), uv }
    }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn to_array8(x: std::arch::x86_64::__m256) -> [f32; 8] {
    // SAFETY: both are 32 bytes of plain floats.
    unsafe { std::mem::transmute(x) }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn from_array8(x: [f32; 8]) -> std::arch::x86_64::__m256 {
    // SAFETY: both are 32 bytes of plain floats.
    unsafe { std::mem::transmute(x) }
}

/// [`edges_f64`] for the eight lanes of [`TriBlock::intersect_pair`].
#[cold]
#[inline(never)]
fn edges_f64_8(zero: u32, v: [[f32; 8]; 6], e: [[f32; 8]; 3]) -> [[f32; 8]; 3] {
    let [ax, ay, bx, by, cx, cy] = v;
    let [mut f0, mut f1, mut f2] = e;
    let f = |x: f32| x as f64;
    let mut m = zero;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        f0[i] = (f(bx[i]) * f(cy[i]) - f(by[i]) * f(cx[i])) as f32;
        f1[i] = (f(cx[i]) * f(ay[i]) - f(cy[i]) * f(ax[i])) as f32;
        f2[i] = (f(ax[i]) * f(by[i]) - f(ay[i]) * f(bx[i])) as f32;
    }
    [f0, f1, f2]
}

/// The lanes of `zero`, on an edge in `f32`, decided in `f64` as in the
/// scalar test; the other lanes of `e` are returned as they are. Rare, and
/// kept out of line so the block test stays small enough to inline.
#[cold]
#[inline(never)]
fn edges_f64(zero: u32, v: [Vec4; 6], e: [Vec4; 3]) -> (Vec4, Vec4, Vec4) {
    let [ax, ay, bx, by, cx, cy] = v.map(|x| x.to_array());
    let [mut f0, mut f1, mut f2] = e.map(|x| x.to_array());
    let f = |x: f32| x as f64;
    let mut m = zero;
    while m != 0 {
        let i = m.trailing_zeros() as usize;
        m &= m - 1;
        f0[i] = (f(bx[i]) * f(cy[i]) - f(by[i]) * f(cx[i])) as f32;
        f1[i] = (f(cx[i]) * f(ay[i]) - f(cy[i]) * f(ax[i])) as f32;
        f2[i] = (f(ax[i]) * f(by[i]) - f(ay[i]) * f(bx[i])) as f32;
    }
    (Vec4::from_array(f0), Vec4::from_array(f1), Vec4::from_array(f2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::tests::Rng;
    use luster_core::math::{Ray, Vec3};

    #[test]
    fn lanes_agree_bit_for_bit_with_the_scalar_test() {
        let mut rng = Rng(17);
        let mut hits = 0;
        for k in 0..20_000 {
            let n = 1 + k % 4;
            let tris: Vec<Triangle> = (0..n)
                .map(|i| {
                    // Some triangles share vertices exactly, so some rays
                    // cross shared edges and exercise the f64 fallback.
                    let a = rng.vec(-2.0, 2.0);
                    Triangle::new(
                        a,
                        rng.vec(-2.0, 2.0),
                        if i % 2 == 0 { a + Vec3::X } else { rng.vec(-2.0, 2.0) },
                        i as u32,
                    )
                })
                .collect();
            let block = TriBlock::new(&tris);
            let o = rng.vec(-4.0, 4.0);
            // Aim at a vertex or an edge midpoint now and then.
            let target = match k % 3 {
                0 => Vec3::from(tris[0].v[1]),
                1 => (Vec3::from(tris[0].v[0]) + Vec3::from(tris[0].v[1])) * 0.5,
                _ => rng.vec(-2.0, 2.0),
            };
            let ray = Ray::new(o, (target - o) * rng.range(0.2, 3.0));
            let wr = WatertightRay::new(&ray);
            let t_max = if k % 5 == 0 { rng.range(0.1, 2.0) } else { f32::INFINITY };
            let got = block.intersect(&wr, 0.0, t_max);
            for (lane, tri) in tris.iter().enumerate() {
                let want = wr.intersect(tri, 0.0, t_max);
                assert_eq!(got.mask >> lane & 1 == 1, want.is_some(), "case {k} lane {lane}");
                if let Some(h) = want {
                    hits += 1;
                    assert_eq!(
                        (got.t[lane].to_bits(), got.uv[lane][0].to_bits(), got.uv[lane][1].to_bits()),
                        (h.t.to_bits(), h.u.to_bits(), h.v.to_bits())
                    );
                }
                assert_eq!(block.triangle(lane), *tri);
            }
            assert_eq!(got.mask >> n, 0, "unused lanes never hit");
        }
        assert!(hits > 5000, "{hits}");
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn pair_lanes_agree_bit_for_bit_with_the_block_test() {
        if !std::arch::is_x86_feature_detected!("avx") {
            eprintln!("no AVX on this CPU: the pair test is never used here");
            return;
        }
        let mut rng = Rng(29);
        let mut hits = 0;
        for k in 0..20_000 {
            // Two blocks of 1-4 triangles sharing vertices, so some rays
            // cross shared edges (the f64 fallback) and some lanes are unused.
            let a = rng.vec(-2.0, 2.0);
            let tri = |rng: &mut Rng, i: u32| {
                Triangle::new(
                    a,
                    rng.vec(-2.0, 2.0),
                    if i % 2 == 0 { a + Vec3::Y } else { rng.vec(-2.0, 2.0) },
                    i,
                )
            };
            let (n0, n1) = (1 + k % 4, 1 + (k / 4) % 4);
            let t0: Vec<Triangle> = (0..n0 as u32).map(|i| tri(&mut rng, i)).collect();
            let t1: Vec<Triangle> = (0..n1 as u32).map(|i| tri(&mut rng, 4 + i)).collect();
            let (b0, b1) = (TriBlock::new(&t0), TriBlock::new(&t1));
            let o = rng.vec(-4.0, 4.0);
            let target = match k % 3 {
                0 => a,
                1 => (Vec3::from(t1[0].v[1]) + a) * 0.5,
                _ => rng.vec(-2.0, 2.0),
            };
            let wr = WatertightRay::new(&Ray::new(o, (target - o) * rng.range(0.2, 3.0)));
            let t_max = if k % 5 == 0 { rng.range(0.1, 2.0) } else { f32::INFINITY };
            // SAFETY: AVX was detected above.
            let got = unsafe { TriBlock::intersect_pair(&b0, &b1, &wr, 0.0, t_max) };
            for (half, b) in [&b0, &b1].into_iter().enumerate() {
                let want = b.intersect(&wr, 0.0, t_max);
                assert_eq!(got.mask >> (4 * half) & 0xf, want.mask, "case {k} block {half}");
                for lane in 0..4 {
                    if want.mask >> lane & 1 == 1 {
                        hits += 1;
                        let i = 4 * half + lane;
                        assert_eq!(
                            (got.t[i].to_bits(), got.uv[i][0].to_bits(), got.uv[i][1].to_bits()),
                            (want.t[lane].to_bits(), want.uv[lane][0].to_bits(), want.uv[lane][1].to_bits()),
                            "case {k} lane {i}"
                        );
                    }
                }
            }
        }
        assert!(hits > 5000, "{hits}");
    }
}
