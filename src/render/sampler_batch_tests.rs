//! The memo's AVX2 lanes against the scalar sampler's parts: the
//! permutation where its final sum wraps, and the grid's exact division.

use super::super::{permute, Span};
use super::lanes;

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
