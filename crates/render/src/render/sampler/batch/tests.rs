//! The memo's AVX2 lanes against the scalar sampler's parts: the
//! permutation where its final sum wraps, and the grid's exact division.

use super::super::{permute, PixelSampler, Span};
use super::lanes;
use super::SLOTS;

/// The lanes' permutation against the scalar one where the final
/// `(i + p) mod l` wraps past 2³² (patterns near `u32::MAX`, which
/// hashed pixels almost never give), and on lengths of every kind.
#[test]
fn lane_permutation_is_the_scalar_one() {
    if !std::arch::is_x86_feature_detected!("avx2") {
        return;
    }
    for len in [2u32, 3, 10, 16, 17, 30, 100, 900, 1000, 4097, 65_537, 1 << 20] {
        let near_top = (0..40).map(|d| u32::MAX - d);
        let near_wrap = (0..40).map(|d| (u32::MAX - len).wrapping_add(d));
        for p in near_top.chain(near_wrap).chain([0, 1, 0x8000_0000, 0x7fff_ffff, 0x1234_5678]) {
            for first in [0, len / 2, len.saturating_sub(16)] {
                let slots: [u32; 16] = std::array::from_fn(|i| (first + i as u32).min(len - 1));
                // SAFETY: AVX2 was detected above.
                let got = unsafe { lanes::permute_slots(slots, Span::new(len), p) };
                let want = slots.map(|i| permute(i, Span::new(len), p));
                assert_eq!(got, want, "len {len} p {p:#x}");
            }
        }
    }
}

/// `s / m` by `⌈2³² / m⌉` is exact for every `s < n` of every grid
/// side `m` the memo batches (the bound is `s · m < 2³²`).
#[test]
fn grid_division_by_multiplication_is_exact() {
    for m in 2u32..=1024 {
        let magic = u64::from(u32::MAX / m + 1);
        let n = (m + 1) * (m + 1) - 1;
        for s in (0..n.min(4096)).chain(n.saturating_sub(4096)..n) {
            assert_eq!(((u64::from(s) * magic) >> 32) as u32, s / m, "{s} / {m}");
        }
    }
}

/// The memo's entry for `key` as `(owner, first, len, used)`.
fn entry(s: &PixelSampler, key: u32) -> (u64, u32, u32, bool) {
    // SAFETY: the memo is this thread's and nothing else holds a reference
    // to it during this read.
    let memo = unsafe { &*(*s.memo).get() };
    let slot = key as usize % SLOTS;
    let t = memo.tags[slot];
    (t.owner, t.first, t.len, memo.used[slot])
}

/// The render loop's order: pixel after pixel, a pass of sixteen samples
/// each, drawing three 2D dimensions and one 1D. From the second pixel on,
/// the first batch fills all four at once (their entries belong to the
/// new pixel as soon as its first sample has drawn its first dimension);
/// a dimension a pixel filled ahead but never drew is not filled ahead for
/// the next; and every value is the scalar formula's.
#[test]
fn a_pixels_first_batch_fills_the_dimensions_the_pixel_before_drew() {
    if !std::arch::is_x86_feature_detected!("avx2") {
        return;
    }
    let (count, run) = (100u32, 16u32..32);
    // Dimensions 0, 2 and 3 are 2D, 1 is 1D; pixels from the fourth on
    // stop drawing dimension 3.
    let rest = |s: &mut PixelSampler, pixel: u32| -> Vec<(f32, f32)> {
        let mut out = vec![(s.next_1d(), 0.0), s.next_2d()];
        if pixel < 3 {
            out.push(s.next_2d());
        }
        out
    };
    let draw = |s: &mut PixelSampler, pixel: u32| -> Vec<(f32, f32)> {
        let mut out = vec![s.next_2d()];
        out.extend(rest(s, pixel));
        out
    };
    let key2 = |dim: u32| dim * 2 + 1;
    for pixel in 0..6u32 {
        let base = PixelSampler::new(9, pixel, 4, 0, count).batched(run.clone());
        for index in run.clone() {
            let mut s = base.at(index);
            let mut scalar = PixelSampler::new(9, pixel, 4, index, count);
            if index == run.start && pixel >= 1 {
                // The first draw of the pixel: the others come with it.
                let first = s.next_2d();
                assert_eq!(first, scalar.next_2d(), "pixel {pixel}");
                let owner = base.owner;
                for key in [key2(2), key2(1) - 1] {
                    assert_eq!(entry(&base, key).0, owner, "pixel {pixel}: key {key} filled ahead");
                    assert_eq!(entry(&base, key).1, index);
                }
                let third = entry(&base, key2(3));
                if pixel <= 3 {
                    assert_eq!(third.0, owner, "pixel {pixel}: dimension 3 drawn by the pixel before");
                } else {
                    assert_ne!(third.0, owner, "pixel {pixel}: dimension 3 not drawn since pixel 2");
                }
                assert_eq!(rest(&mut s, pixel), rest(&mut scalar, pixel), "pixel {pixel} sample {index}");
                continue;
            }
            assert_eq!(draw(&mut s, pixel), draw(&mut scalar, pixel), "pixel {pixel} sample {index}");
        }
        if pixel == 3 {
            // Filled ahead at this pixel's start, never drawn.
            assert!(!entry(&base, key2(3)).3, "dimension 3 marked unused");
        }
    }
}
