//! What tone mapping needs to know about the whole image before it maps a
//! pixel: the log-average luminance (Reinhard et al. 2002, eq. 1) and, for a
//! burn-out percentage, the luminance at a given rank.
//!
//! One parallel pass ([`Stats::of`]) sums `ln(δ + Y)` over fixed blocks (so
//! the sum's bits do not depend on the thread count) and, with a burn-out,
//! counts each `Y` into a histogram of its top bits and keeps the luminances.
//! [`nth_luminance`] then finds the bucket holding the rank from the
//! histogram and selects inside it among the kept luminances only, so the
//! selection never sorts the image nor computes a luminance twice.

use super::{split_batch, vector, BATCH};
use crate::math::Vec3;
use rayon::prelude::*;
use std::mem::MaybeUninit;

/// The δ of Reinhard et al.'s log-average, keeping black pixels finite.
const LOG_DELTA: f64 = 1e-5;

/// Pixels whose log-luminances share one of the log-average's partial sums:
/// pixel `i` of a block adds to sum `i % LANES`, in order. Fixed, so the
/// sum's bits do not depend on how the passes are vectorized. [`BATCH`] is a
/// multiple of it.
const LANES: usize = 8;

/// Pixels per block of the log-average's partial sums. The blocks are fixed
/// and summed in order, so the result does not depend on the thread count.
const LOG_BLOCK: usize = 4096;

/// Buckets of the luminance histogram: the top 16 bits of an `f32`. For
/// non-negative numbers the bit patterns order like the values, so a bucket
/// holds a contiguous range of luminance, and a fine one, so that the
/// selection inside the percentile's bucket has few values to look at.
/// [`luminance`] is never negative (nor -0), so the sign bit is clear and
/// half the buckets are enough.
const BUCKET_SHIFT: u32 = 16;
const BUCKETS: usize = 1 << (31 - BUCKET_SHIFT);

/// What the mapping needs from the whole image, gathered in one pass.
pub(super) struct Stats {
    /// `Σ ln(δ + Y)` over all pixels.
    pub(super) log_sum: f64,
    /// Pixels per [`BUCKETS`] bucket of `Y` (empty without a burn-out).
    pub(super) hist: Vec<u32>,
    /// Every pixel's `Y`, in pixel order (empty without a burn-out): the
    /// percentile's selection reads these 4 bytes a pixel instead of
    /// computing the luminance again from 12.
    pub(super) lum: Vec<f32>,
}

/// Per task of [`Stats::of`]: each block's sum (by block index) and the histogram.
type Part = (Vec<(usize, f64)>, Vec<u32>);

impl Stats {
    /// The statistics of `pixels`; the histogram and the luminances only
    /// `with_hist` (a burn-out).
    pub(super) fn of(pixels: &[Vec3], with_hist: bool) -> Stats {
        let avx2 = vector::avx2();
        let (sums, hist, lum) = if with_hist {
            // Not zeroed first: every block writes each of its values.
            let mut lum: Vec<f32> = Vec::with_capacity(pixels.len());
            let slots = &mut lum.spare_capacity_mut()[..pixels.len()];
            let blocks = pixels.par_chunks(LOG_BLOCK).zip(slots.par_chunks_mut(LOG_BLOCK));
            let (sums, hist) = gather(blocks.map(|(b, l)| (b, Some(l))), true, avx2);
            // SAFETY: `block_stats` wrote the luminance of every pixel of
            // its block into the block's slots, and the blocks cover them.
            unsafe { lum.set_len(pixels.len()) };
            (sums, hist, lum)
        } else {
            let (sums, hist) = gather(pixels.par_chunks(LOG_BLOCK).map(|b| (b, None)), false, avx2);
            (sums, hist, Vec::new())
        };
        Stats { log_sum: sums.iter().map(|&(_, s)| s).sum(), hist, lum }
    }
}

/// The blocks' sums in block order, and the summed histogram.
fn gather<'a>(
    blocks: impl IndexedParallelIterator<Item = (&'a [Vec3], Option<&'a mut [MaybeUninit<f32>]>)>,
    with_hist: bool,
    avx2: bool,
) -> (Vec<(usize, f64)>, Vec<u32>) {
    let (mut sums, hist) = blocks
        .enumerate()
        .fold(
            || -> Part { (Vec::new(), if with_hist { vec![0u32; BUCKETS] } else { Vec::new() }) },
            |(mut sums, mut hist), (i, (block, lum))| {
                let hist_of_block = with_hist.then_some(hist.as_mut_slice());
                let sum = if avx2 {
                    // SAFETY: `vector::avx2` found AVX2 on this processor.
                    unsafe { block_stats_avx2(block, hist_of_block, lum) }
                } else {
                    block_stats(block, hist_of_block, lum)
                };
                sums.push((i, sum));
                (sums, hist)
            },
        )
        .reduce(
            || (Vec::new(), Vec::new()),
            |(mut sa, mut ha), (sb, hb)| {
                sa.extend(sb);
                if ha.is_empty() {
                    ha = hb;
                } else if !hb.is_empty() {
                    ha.iter_mut().zip(&hb).for_each(|(a, b)| *a += b);
                }
                (sa, ha)
            },
        );
    sums.sort_unstable_by_key(|&(i, _)| i);
    (sums, hist)
}

/// [`block_stats`] compiled for AVX2.
///
/// # Safety
/// The processor must have AVX2 ([`vector::avx2`]).
#[cfg_attr(target_arch = "x86_64", target_feature(enable = "avx2"))]
unsafe fn block_stats_avx2(
    block: &[Vec3],
    hist: Option<&mut [u32]>,
    lum: Option<&mut [MaybeUninit<f32>]>,
) -> f64 {
    block_stats(block, hist, lum)
}

/// One block's `Σ ln(δ + Y)`, as [`LANES`] running sums added up at the end;
/// counts the block's luminances into `hist` and keeps them in `lum` (as
/// long as the block) when given. The batch arrays live here, once a block,
/// so they are not zeroed for every batch.
#[inline(always)]
fn block_stats(
    block: &[Vec3],
    mut hist: Option<&mut [u32]>,
    mut lum: Option<&mut [MaybeUninit<f32>]>,
) -> f64 {
    let mut acc = [0.0f64; LANES];
    let mut rgb = [[0.0f32; BATCH]; 3];
    let mut y = [0.0f32; BATCH];
    let mut logs = [0.0f64; BATCH];
    for (k, px) in block.chunks(BATCH).enumerate() {
        let n = px.len();
        split_batch(px, &mut rgb);
        luminance_batch(&rgb, &mut y[..n]);
        for (l, &y) in logs[..n].iter_mut().zip(&y[..n]) {
            *l = ln(LOG_DELTA as f32 + y);
        }
        // Batches start at multiples of LANES, so lane k of each group of
        // LANES is pixel i with i % LANES == k. Whole groups first: with a
        // fixed length the sums stay in registers (with `chunks(LANES)`
        // they would go through memory, a store and a reload each group).
        let mut groups = logs[..n].chunks_exact(LANES);
        for group in &mut groups {
            acc.iter_mut().zip(group).for_each(|(a, l)| *a += l);
        }
        acc.iter_mut().zip(groups.remainder()).for_each(|(a, l)| *a += l);
        if let Some(hist) = hist.as_deref_mut() {
            let hist = &mut hist[..BUCKETS];
            for &y in &y[..n] {
                // Luminance is never negative, so the index is below
                // BUCKETS; the mask only spares a bounds check.
                hist[(y.to_bits() >> BUCKET_SHIFT) as usize & (BUCKETS - 1)] += 1;
            }
        }
        if let Some(lum) = lum.as_deref_mut() {
            lum[k * BATCH..][..n].iter_mut().zip(&y[..n]).for_each(|(l, &y)| {
                l.write(y);
            });
        }
    }
    acc.iter().sum()
}

/// [`luminance`] of the first `y.len()` pixels of `rgb`, with the same arithmetic.
#[inline(always)]
pub(super) fn luminance_batch(rgb: &[[f32; BATCH]; 3], y: &mut [f32]) {
    let [r, g, b] = rgb;
    for (((y, &r), &g), &b) in y.iter_mut().zip(r).zip(g).zip(b) {
        *y = luminance(Vec3::new(r, g, b));
    }
}

/// `ln x` for positive, finite, normal `x`, in `f64`, within 1e-12 of the
/// exact value: branch-free, so a batch of them runs as vector code (where
/// libm's `logf` is a call per pixel). `x` is `2^e · m` with `m` in
/// [√½, √2), and `ln m = 2 atanh t`, `t = (m − 1) / (m + 1)`,
/// `|t| ≤ 0.172`, by its series to `t¹³` (the next term is below 6e-13).
#[inline(always)]
pub(super) fn ln(x: f32) -> f64 {
    /// The bits of √½ as an `f32`: where the mantissa range starts.
    const SQRT_HALF: u32 = 0x3F35_04F3;
    let u = x.to_bits().wrapping_sub(SQRT_HALF);
    let e = (u as i32) >> 23;
    let m = f64::from(f32::from_bits((u & 0x007F_FFFF) + SQRT_HALF));
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let series = 1.0
        + t2 * (1.0 / 3.0
            + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0 + t2 * (1.0 / 11.0 + t2 * (1.0 / 13.0))))));
    f64::from(e) * std::f64::consts::LN_2 + 2.0 * t * series
}

/// Luminances [`nth_luminance`] tests at once for one of the bucket's.
const SCAN_GROUP: usize = 32;

/// The `at`-th smallest of the luminances `lum` (in `f32::total_cmp`
/// order), as a full sort would give it: `hist` (see [`Stats`]) finds the
/// bucket holding rank `at`, and only that bucket's values are selected in.
pub(super) fn nth_luminance(lum: &[f32], hist: &[u32], at: usize) -> f32 {
    let (mut below, mut bucket) = (0usize, 0u32);
    for (i, &c) in hist.iter().enumerate() {
        if below + c as usize > at {
            bucket = i as u32;
            break;
        }
        below += c as usize;
    }
    let in_bucket = |y: &f32| y.to_bits() >> BUCKET_SHIFT == bucket;
    let parts: Vec<Vec<f32>> = lum
        .par_chunks(LOG_BLOCK)
        .map(|block| {
            // Most groups hold none of the bucket's values: a test of the
            // whole group (vector code, no branch a value) passes them by.
            let mut inside = Vec::new();
            for group in block.chunks(SCAN_GROUP) {
                if group.iter().fold(false, |any, y| any | in_bucket(y)) {
                    inside.extend(group.iter().copied().filter(in_bucket));
                }
            }
            inside
        })
        .collect();
    let mut inside: Vec<f32> = parts.concat();
    *inside.select_nth_unstable_by(at - below, f32::total_cmp).1
}

/// Luminance of linear sRGB primaries (Rec. 709 weights), non-finite and
/// negative values counted as 0.
#[inline(always)]
pub fn luminance(p: Vec3) -> f32 {
    let y = 0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z;
    if y.is_finite() && y > 0.0 {
        y
    } else {
        0.0
    }
}
