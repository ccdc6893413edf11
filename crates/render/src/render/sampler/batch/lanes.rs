//! The memo's CMJ arithmetic in AVX2 lanes ([`super`]): eight samples to
//! a vector, each lane doing the scalar formula's integer and `f32`
//! operations in the same order, so the same values bit for bit. Reads no
//! scene parameters.

use super::super::{hash2, PixelSampler, Span, ONE_MINUS_EPS};
use super::{Values, LANES};
use std::arch::x86_64::*;

type V = __m256i;

/// Largest walk (its mask plus one) whose steps are looked up in a
/// table ([`permute`]).
const TABLE: usize = 16;

#[inline]
#[target_feature(enable = "avx2")]
fn splat(a: u32) -> V {
    _mm256_set1_epi32(a as i32)
}

#[inline]
#[target_feature(enable = "avx2")]
fn xor(a: V, b: V) -> V {
    _mm256_xor_si256(a, b)
}

#[inline]
#[target_feature(enable = "avx2")]
fn mul(a: V, b: u32) -> V {
    _mm256_mullo_epi32(a, splat(b))
}

/// `a ^= (a & w) >> S`.
#[inline]
#[target_feature(enable = "avx2")]
fn fold<const S: i32>(a: V, w: V) -> V {
    xor(a, _mm256_srli_epi32::<S>(_mm256_and_si256(a, w)))
}

/// `a - len` in the lanes where `a ≥ len` (all values below 2³¹).
#[inline]
#[target_feature(enable = "avx2")]
fn reduce(a: V, len: V) -> V {
    _mm256_sub_epi32(a, _mm256_andnot_si256(_mm256_cmpgt_epi32(len, a), len))
}

/// The high 32 bits of `a · b` in every lane.
#[inline]
#[target_feature(enable = "avx2")]
fn mul_high(a: V, b: u32) -> V {
    let b = splat(b);
    let even = _mm256_srli_epi64::<32>(_mm256_mul_epu32(a, b));
    let odd = _mm256_mul_epu32(_mm256_srli_epi64::<32>(a), b);
    _mm256_blend_epi32::<0b1010_1010>(even, odd)
}

/// One step of [`super::super::permute`]'s walk from `x`, under the
/// mask `w` and the permutation's seed `p`.
#[inline]
#[target_feature(enable = "avx2")]
fn walk(x: V, w: V, p: u32) -> V {
    let mut i = mul(xor(x, splat(p)), 0xe170_893d);
    i = fold::<4>(xor(i, splat(p >> 16)), w);
    i = mul(xor(i, splat(p >> 8)), 0x0929_eb3f);
    i = fold::<1>(xor(i, splat(p >> 23)), w);
    i = fold::<2>(mul(i, 1 | (p >> 27)), w);
    i = _mm256_and_si256(mul(i, 0x9e50_1cc3), w);
    xor(i, _mm256_srli_epi32::<5>(i))
}

/// [`super::super::permute`] of every lane of `K` groups of `N`
/// vectors, group `k` under `(ls[k], ps[k])`: the walk goes on until
/// every lane is in range, a lane that is keeps its value, and the final
/// `(i + p) mod l` is taken by compares, not a division. Each step of a
/// walk is a chain of multiplications whose latency, not their number,
/// bounds it: the groups are independent, so they walk in one loop,
/// with the same values as one at a time.
///
/// Always inlined, so not itself compiled for AVX2 (`#[target_feature]`
/// forbids `#[inline(always)]`): called, its groups would go through memory.
///
/// # Safety
/// The processor must have AVX2; only called from code compiled for it.
#[inline(always)]
unsafe fn permute<const N: usize, const K: usize>(
    mut cur: [[V; N]; K],
    ls: [Span; K],
    ps: [u32; K],
) -> [[V; N]; K] {
    // SAFETY: the caller runs where the processor has AVX2.
    unsafe {
        let zero = _mm256_setzero_si256();
        let (mut w, mut len) = ([zero; K], [zero; K]);
        // A length of one has one value, 0: nothing to walk.
        let mut done = [[zero; N]; K];
        // A walk over at most sixteen values (the grid's axes at the
        // course's counts) looks its steps up in a table of the step
        // function, two vectors made by two steps' work: a lookup
        // is far shorter than a step's chain of five
        // multiplications. The same function, so the same values.
        let mut table = [[zero; 2]; K];
        let mut small = [false; K];
        for k in 0..K {
            (w[k], len[k]) = (splat(ls[k].mask), splat(ls[k].len));
            if ls[k].len <= 1 {
                done[k] = [_mm256_set1_epi32(-1); N];
            } else if ls[k].mask < TABLE as u32 {
                small[k] = true;
                table[k] = [
                    walk(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), w[k], ps[k]),
                    walk(_mm256_setr_epi32(8, 9, 10, 11, 12, 13, 14, 15), w[k], ps[k]),
                ];
            }
        }
        for k in 0..K {
            if !small[k] {
                continue;
            }
            loop {
                let mut all = -1;
                for v in 0..N {
                    let i = look_up(table[k], cur[k][v]);
                    cur[k][v] = _mm256_blendv_epi8(i, cur[k][v], done[k][v]);
                    done[k][v] = _mm256_or_si256(done[k][v], _mm256_cmpgt_epi32(len[k], i));
                    all &= _mm256_movemask_epi8(done[k][v]);
                }
                if all == -1 {
                    break;
                }
            }
        }
        loop {
            let mut all = -1;
            for k in 0..K {
                if small[k] || ls[k].len <= 1 {
                    continue;
                }
                for v in 0..N {
                    let i = walk(cur[k][v], w[k], ps[k]);
                    cur[k][v] = _mm256_blendv_epi8(i, cur[k][v], done[k][v]);
                    done[k][v] = _mm256_or_si256(done[k][v], _mm256_cmpgt_epi32(len[k], i));
                    all &= _mm256_movemask_epi8(done[k][v]);
                }
            }
            if all == -1 {
                break;
            }
        }
        for ((group, l), p) in cur.iter_mut().zip(ls).zip(ps) {
            for i in group.iter_mut() {
                *i = if l.len <= 1 { zero } else { offset(*i, l, p) };
            }
        }
        cur
    }
}

/// Entry `x` (below [`TABLE`]) of a walk's step table, per lane.
#[inline]
#[target_feature(enable = "avx2")]
fn look_up(table: [V; 2], x: V) -> V {
    let lo = _mm256_castsi256_ps(_mm256_permutevar8x32_epi32(table[0], x));
    let hi = _mm256_castsi256_ps(_mm256_permutevar8x32_epi32(table[1], x));
    // Bit 3 of the index, moved to the sign, picks the upper vector.
    let upper = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(x));
    _mm256_castps_si256(_mm256_blendv_ps(lo, hi, upper))
}

/// The walk's end, `i < l`, to `(i + p) mod l`: `i + p mod l`, less
/// `2³² mod l` where the 32-bit sum wraps, brought into range.
#[inline]
#[target_feature(enable = "avx2")]
fn offset(i: V, l: Span, p: u32) -> V {
    let len = splat(l.len);
    let below_wrap = u32::MAX - p;
    let wrap = if below_wrap >= 1 << 31 { 0 } else { l.len - ((u32::MAX % l.len + 1) % l.len) };
    let (pl, wrap_add) = (splat(p % l.len), splat(wrap));
    let wraps = _mm256_cmpgt_epi32(i, splat(below_wrap));
    let r = _mm256_add_epi32(_mm256_add_epi32(i, pl), _mm256_and_si256(wraps, wrap_add));
    reduce(reduce(r, len), len)
}

/// [`super::super::hash2`] of every lane with the same `b`.
#[inline]
#[target_feature(enable = "avx2")]
fn hash2_lanes(a: V, b: u32) -> V {
    let mut h = xor(a, splat(b.wrapping_mul(0x9e37_79b9).rotate_left(15)));
    h = xor(h, _mm256_srli_epi32::<16>(h));
    h = mul(h, 0x85eb_ca6b);
    h = xor(h, _mm256_srli_epi32::<13>(h));
    h = mul(h, 0xc2b2_ae35);
    xor(h, _mm256_srli_epi32::<16>(h))
}

/// [`super::super::rand_float`] of every lane under `p`.
#[inline]
#[target_feature(enable = "avx2")]
fn rand_float_lanes(i: V, p: u32) -> __m256 {
    let mut i = xor(i, splat(p));
    i = xor(i, _mm256_srli_epi32::<17>(i));
    i = xor(i, _mm256_srli_epi32::<10>(i));
    i = mul(i, 0xb365_34e5);
    i = xor(i, _mm256_srli_epi32::<12>(i));
    i = xor(i, _mm256_srli_epi32::<21>(i));
    i = mul(i, 0x93fc_4795);
    i = xor(i, splat(0xdf6e_307f));
    i = xor(i, _mm256_srli_epi32::<17>(i));
    i = mul(i, 1 | (p >> 18));
    unit_lanes(_mm256_srli_epi32::<8>(i), 1.0 / (1u32 << 24) as f32)
}

/// Lanes below 2²⁴ as floats, times `scale`.
#[inline]
#[target_feature(enable = "avx2")]
fn unit_lanes(a: V, scale: f32) -> __m256 {
    _mm256_mul_ps(_mm256_cvtepi32_ps(a), _mm256_set1_ps(scale))
}

/// The values of `dims[..count]`, up to [`GROUP`](super::GROUP)
/// dimensions of the same kind (2D or not), for `len` samples from
/// `s.index`, filled at once: their walks overlap (see [`permute`]).
///
/// # Safety
/// The processor must have AVX2.
#[target_feature(enable = "avx2")]
pub(super) fn fill_group(
    s: &PixelSampler,
    dims: [u32; super::GROUP],
    count: usize,
    two_d: bool,
    len: usize,
) -> [Values; super::GROUP] {
    let [a, b] = dims;
    let mut out = [[[0.0; 2]; LANES]; super::GROUP];
    macro_rules! run {
        ($k:literal, $k2:literal, $dims:expr) => {{
            let got = match (two_d, len > LANES / 2) {
                (true, true) => fill_k::<2, $k, $k2, true>(s, $dims, len),
                (true, false) => fill_k::<1, $k, $k2, true>(s, $dims, len),
                (false, true) => fill_k::<2, $k, $k2, false>(s, $dims, len),
                (false, false) => fill_k::<1, $k, $k2, false>(s, $dims, len),
            };
            out[..$k].copy_from_slice(&got);
        }};
    }
    if count == 1 {
        run!(1, 2, [a]);
    } else {
        run!(2, 4, [a, b]);
    }
    out
}

/// The values of `K` dimensions in `N` vectors each; `K2` is `2K`
/// (the grid's axes of every 2D dimension walk together).
#[inline]
#[target_feature(enable = "avx2")]
fn fill_k<const N: usize, const K: usize, const K2: usize, const TWO_D: bool>(
    s: &PixelSampler,
    dims: [u32; K],
    len: usize,
) -> [Values; K] {
    debug_assert_eq!(K2, 2 * K);
    let mut out = [[[0.0; 2]; LANES]; K];
    let ps = dims.map(|d| hash2(s.pixel_hash, d));
    // Lanes past the run repeat its last sample: a walk started out of
    // range need not come back into it, and one in range would only
    // lengthen the walk of them all.
    let first = _mm256_add_epi32(splat(s.index), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    let last = splat(s.index + len as u32 - 1);
    let slots: [V; N] =
        std::array::from_fn(|v| _mm256_min_epu32(_mm256_add_epi32(first, splat(8 * v as u32)), last));
    let top = _mm256_set1_ps(ONE_MINUS_EPS);
    let inv_n = _mm256_set1_ps(s.inv_n);
    if !TWO_D {
        // SAFETY: this function is compiled for AVX2.
        let perm = unsafe { permute([slots; K], [s.n; K], ps) };
        for k in 0..K {
            for v in 0..N {
                let r = rand_float_lanes(slots[v], ps[k] ^ 0x9e37_79b9);
                let x = _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(perm[k][v]), r), inv_n);
                store(&mut out[k], v, _mm256_min_ps(x, top), top);
            }
        }
        return out;
    }
    let (m, rows) = (s.cols, s.rows);
    // SAFETY: this function is compiled for AVX2.
    let perm = unsafe { permute([slots; K], [s.n; K], ps.map(|p| p.wrapping_mul(0x5163_3e2d))) };
    // `s / m` and `s % m` by `⌈2³² / m⌉`: exact while `s · m < 2³²`.
    let (col, row): ([[V; N]; K], [[V; N]; K]) = if m.len == 1 {
        ([[_mm256_setzero_si256(); N]; K], perm)
    } else {
        let magic = u32::MAX / m.len + 1;
        let row = perm.map(|p| p.map(|a| mul_high(a, magic)));
        let col = std::array::from_fn(|k| {
            std::array::from_fn(|v| _mm256_sub_epi32(perm[k][v], mul(row[k][v], m.len)))
        });
        (col, row)
    };
    let axes: [[V; N]; K2] = std::array::from_fn(|i| if i < K { col[i] } else { row[i - K] });
    let spans: [Span; K2] = std::array::from_fn(|i| if i < K { m } else { rows });
    let seeds: [u32; K2] = std::array::from_fn(|i| {
        if i < K {
            ps[i].wrapping_mul(0x68bc_21eb)
        } else {
            ps[i - K].wrapping_mul(0x02e5_be93)
        }
    });
    // SAFETY: as above.
    let sxy = unsafe { permute(axes, spans, seeds) };
    let (kf, inv_mk) = (_mm256_set1_ps(rows.len as f32), _mm256_set1_ps(s.inv_mk));
    for k in 0..K {
        for v in 0..N {
            let (sx, sy, pv) = (sxy[k][v], sxy[K + k][v], perm[k][v]);
            let j = hash2_lanes(pv, ps[k]);
            let jx = unit_lanes(_mm256_srli_epi32::<16>(j), 1.0 / 65_536.0);
            let jy = unit_lanes(_mm256_and_si256(j, splat(0xffff)), 1.0 / 65_536.0);
            let cell = _mm256_add_ps(_mm256_mul_ps(_mm256_cvtepi32_ps(sx), kf), _mm256_cvtepi32_ps(sy));
            let x = _mm256_mul_ps(_mm256_add_ps(cell, jx), inv_mk);
            let y = _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(pv), jy), inv_n);
            store(&mut out[k], v, _mm256_min_ps(x, top), _mm256_min_ps(y, top));
        }
    }
    out
}

/// [`permute`] of sixteen values, for the tests.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(test)]
#[target_feature(enable = "avx2")]
pub(super) fn permute_slots(slots: [u32; 16], l: Span, p: u32) -> [u32; 16] {
    let mut out = [0u32; 16];
    let vs: [V; 2] = std::array::from_fn(|v| {
        // SAFETY: eight u32 from `slots`, unaligned loads allowed.
        unsafe { _mm256_loadu_si256(slots[8 * v..].as_ptr().cast()) }
    });
    // SAFETY: this function is compiled for AVX2.
    let [perm] = unsafe { permute([vs], [l], [p]) };
    for (v, r) in perm.into_iter().enumerate() {
        // SAFETY: eight u32 into `out`.
        unsafe { _mm256_storeu_si256(out[8 * v..].as_mut_ptr().cast(), r) };
    }
    out
}

/// Writes the pairs `(x, y)` of vector `v`.
#[inline]
#[target_feature(enable = "avx2")]
fn store(out: &mut Values, v: usize, x: __m256, y: __m256) {
    // Lanes 0 1 4 5 and 2 3 6 7 interleaved, then their halves in order.
    let (lo, hi) = (_mm256_unpacklo_ps(x, y), _mm256_unpackhi_ps(x, y));
    let first = _mm256_permute2f128_ps::<0x20>(lo, hi);
    let second = _mm256_permute2f128_ps::<0x31>(lo, hi);
    let out = &mut out[8 * v..8 * v + 8];
    // SAFETY: `out` holds eight pairs, sixteen floats; unaligned stores
    // are allowed.
    unsafe {
        _mm256_storeu_ps(out.as_mut_ptr().cast(), first);
        _mm256_storeu_ps(out.as_mut_ptr().add(4).cast(), second);
    }
}
