//! Tests of the sampler: stratification, independence between dimensions
//! and pixels, repeatability, and the single-sample draws' fixed values.

use super::*;

#[test]
fn span_divides_exactly() {
    // The multiplication's quotient and remainder against the hardware's,
    // at the ends of the range and on a spread of numerators.
    let mut a = 0x1234_5678u32;
    for len in (1u32..=1100).chain([4095, 4096, 65_537, 1 << 31, u32::MAX]) {
        let span = Span::new(len);
        let check = |a: u32| {
            assert_eq!(span.rem(a), a % len, "{a} % {len}");
            assert_eq!(span.div(a), a / len, "{a} / {len}");
        };
        for x in [0, 1, len - 1, len, len.wrapping_add(1), u32::MAX - 1, u32::MAX] {
            check(x);
        }
        for _ in 0..200 {
            a ^= a << 13;
            a ^= a >> 17;
            a ^= a << 5;
            check(a);
        }
        // The mask is `len − 1` with every bit below its highest set.
        let mut w = len - 1;
        for shift in [1, 2, 4, 8, 16] {
            w |= w >> shift;
        }
        assert_eq!(span.mask, w, "mask of {len}");
    }
}

#[test]
fn permute_is_a_permutation() {
    for l in [1u32, 2, 3, 7, 16, 100, 400] {
        for p in [0u32, 1, 0xdead_beef] {
            let mut seen = vec![false; l as usize];
            for i in 0..l {
                let j = permute(i, Span::new(l), p) as usize;
                assert!(!seen[j], "l={l} p={p}: {j} twice");
                seen[j] = true;
            }
        }
    }
}

#[test]
fn cmj_stratifies_rows_columns_and_cells() {
    for n in [4u32, 16, 100, 400, 7, 50] {
        let pts: Vec<(f32, f32)> = (0..n).map(|s| cmj(s, n, 1234)).collect();
        // Each of the n horizontal strips holds exactly one point.
        let mut rows: Vec<u32> = pts.iter().map(|p| (p.1 * n as f32) as u32).collect();
        rows.sort_unstable();
        assert_eq!(rows, (0..n).collect::<Vec<_>>(), "n={n}");
        // And each of the m columns holds about n/m points.
        let m = (n as f32).sqrt() as u32;
        let mut cols = vec![0u32; m as usize];
        for p in &pts {
            assert!((0.0..1.0).contains(&p.0) && (0.0..1.0).contains(&p.1));
            cols[(p.0 * m as f32) as usize] += 1;
        }
        assert!(cols.iter().all(|&c| c >= n / m - 1 && c <= n.div_ceil(m)), "n={n}: {cols:?}");
    }
}

#[test]
fn dimensions_differ_and_samples_repeat_exactly() {
    let mut a = PixelSampler::new(7, 3, 4, 5, 16);
    let mut b = PixelSampler::new(7, 3, 4, 5, 16);
    let (p0, p1) = (a.next_2d(), a.next_2d());
    assert_ne!(p0, p1);
    assert_eq!(b.next_2d(), p0);
    assert_eq!(b.next_2d(), p1);
    let mut c = PixelSampler::new(8, 3, 4, 5, 16);
    assert_ne!(c.next_2d(), p0);
}

/// A pixel's sampler moved to another sample, and a skipped call, give
/// the draws of a sampler made for that sample and of a call made and
/// discarded, for every kind of call (stratified, independent, one sample).
#[test]
fn samples_of_a_pixel_and_skipped_calls_keep_their_draws() {
    for count in [1u32, 2, 7, 16, 100, 900] {
        let pixel = PixelSampler::new(5, 17, 3, 0, count);
        for index in [0, 1, count / 2, count - 1, count, count + 3] {
            let (mut a, mut b) = (pixel.at(index), PixelSampler::new(5, 17, 3, index, count));
            a.stratify_first(5);
            b.stratify_first(5);
            for call in 0..8 {
                if call % 3 == 1 {
                    a.skip();
                    b.next_1d();
                } else {
                    assert_eq!(a.next_2d(), b.next_2d(), "count {count} sample {index} call {call}");
                }
            }
            assert_eq!(a.next_1d(), b.next_1d());
        }
    }
}

#[test]
fn calls_past_the_stratified_ones_are_uniform_and_repeatable() {
    // 4096 draws of a late call over samples and pixels: each of 16 bins
    // per axis holds 256 ± 5 standard deviations (√(256·15/16) ≈ 15.5).
    for count in [7u32, 1] {
        let mut bins = [[0u32; 16]; 3];
        for i in 0..4096u32 {
            let mut s = PixelSampler::new(3, i % 64, i / 64, i % count, count);
            s.stratify_first(2);
            let first = s.next_2d();
            let mut again = PixelSampler::new(3, i % 64, i / 64, i % count, count);
            assert_eq!(again.next_2d(), first, "stratified calls unchanged");
            for _ in 0..4 {
                s.next_1d();
            }
            let (a, b) = s.next_2d();
            let c = s.next_1d();
            for (k, v) in [a, b, c].into_iter().enumerate() {
                assert!((0.0..1.0).contains(&v));
                bins[k][(v * 16.0) as usize] += 1;
            }
        }
        for (k, axis) in bins.iter().enumerate() {
            assert!(axis.iter().all(|&n| n.abs_diff(256) < 78), "count {count} axis {k}: {axis:?}");
        }
    }
    let draw = || {
        let mut s = PixelSampler::new(9, 1, 2, 3, 16);
        s.stratify_first(0);
        (s.next_2d(), s.next_1d())
    };
    assert_eq!(draw(), draw());
}

#[test]
fn one_d_dimension_is_stratified() {
    let n = 64;
    let mut v: Vec<u32> =
        (0..n).map(|i| (PixelSampler::new(1, 2, 3, i, n).next_1d() * n as f32) as u32).collect();
    v.sort_unstable();
    assert_eq!(v, (0..n).collect::<Vec<_>>());
}

/// The first `n` 2D points of dimension `dim` in pixel `(x, y)`.
fn points(seed: u32, x: u32, y: u32, dim: u32, n: u32) -> Vec<(f32, f32)> {
    (0..n)
        .map(|i| {
            let mut s = PixelSampler::new(seed, x, y, i, n);
            for _ in 0..dim {
                s.next_2d();
            }
            s.next_2d()
        })
        .collect()
}

/// χ² of `pts` over a `cols × rows` grid against equal expected counts.
fn chi2(pts: &[(f32, f32)], cols: u32, rows: u32) -> f64 {
    let mut cells = vec![0u32; (cols * rows) as usize];
    for &(a, b) in pts {
        assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b), "{a} {b}");
        cells[((b * rows as f32) as u32 * cols + (a * cols as f32) as u32) as usize] += 1;
    }
    let e = pts.len() as f64 / cells.len() as f64;
    cells.iter().map(|&c| (c as f64 - e).powi(2) / e).sum()
}

#[test]
fn sampler_points_keep_cmj_strata_at_the_course_counts() {
    // Through the sampler (reciprocal cell sizes, one-hash jitter): one
    // point per row of 1/n and an even spread over the m × ⌈n/m⌉ cells.
    for n in [16u32, 100, 400, 900] {
        for (px, dim) in [(0u32, 0u32), (5, 1), (17, 3)] {
            let pts = points(3, px, px + 1, dim, n);
            assert_eq!(chi2(&pts, 1, n), 0.0, "n={n} rows");
            let m = (n as f32).sqrt() as u32;
            assert_eq!(chi2(&pts, m, n.div_ceil(m)), 0.0, "n={n} cells");
        }
    }
}

#[test]
fn dimensions_and_neighbouring_pixels_are_independent() {
    // Pairs drawn across 4096 pixels of 16 samples: the joint histogram of
    // two dimensions (or one dimension in two neighbouring pixels) over 8×8
    // cells has χ² ≈ 63 ± 11 when independent; a shared pattern gives
    // thousands.
    let n = 16;
    let mut pairs: [Vec<(f32, f32)>; 3] = Default::default();
    for p in 0..4096u32 {
        let (x, y) = (p % 64, p / 64);
        let a = points(2, x, y, 0, n);
        let b = points(2, x, y, 1, n);
        let right = points(2, x + 1, y, 0, n);
        for i in 0..n as usize {
            pairs[0].push((a[i].0, b[i].0));
            pairs[1].push((a[i].1, b[i].1));
            pairs[2].push((a[i].0, right[i].0));
        }
    }
    for (k, pts) in pairs.iter().enumerate() {
        let c = chi2(pts, 8, 8);
        assert!(c < 63.0 + 6.0 * 11.2, "pair {k}: χ² {c}");
    }
}

#[test]
fn single_sample_draws_keep_their_earlier_values() {
    // The single-sample draws' fixed values, so 1-spp images keep their
    // bytes.
    let mut s = PixelSampler::new(0, 3, 4, 0, 1);
    assert_eq!(s.next_2d(), (OLD[0], OLD[1]));
    assert_eq!(s.next_1d(), OLD[2]);
    s.stratify_first(0);
    assert_eq!(s.next_2d(), (OLD[3], OLD[4]));
    assert_eq!(s.next_1d(), OLD[5]);
}

const OLD: [f32; 6] = [
    f32::from_bits(0x3f77_8286),
    f32::from_bits(0x3f62_1a89),
    f32::from_bits(0x3f3f_3390),
    f32::from_bits(0x3e0a_1688),
    f32::from_bits(0x3d7d_8d20),
    f32::from_bits(0x3de7_acf8),
];

/// The calls sample `index` makes in [`batched_draws_equal_the_scalar_ones`]:
/// the camera's, then a path whose length and kinds of draw vary with the
/// sample (so a dimension is 1D for some samples and 2D for others, and
/// deep dimensions are reached by only some), then independent draws.
fn draws(s: &mut PixelSampler, index: u32) -> Vec<(f32, f32)> {
    let mut out = vec![s.next_2d(), (s.next_1d(), 0.0)];
    s.skip();
    let h = hash2(index, 0x51ed);
    for call in 0..(h % 7) {
        if (h >> call) & 1 == 0 {
            out.push(s.next_2d());
        } else {
            out.push((s.next_1d(), 1.0));
        }
    }
    s.stratify_first(s.calls() + 1 + h % 3);
    for _ in 0..4 {
        out.push(s.next_2d());
        out.push((s.next_1d(), 2.0));
    }
    out
}

/// Samples drawn in runs through the per-thread memo and its AVX2 lanes
/// give the scalar formula's values bit for bit: every count kind (one
/// sample, a grid of one column, squares, primes, past 4096), the render
/// loop's passes and runs that start and end mid-pixel, and pixels and
/// counts interleaved so the memo's entries are replaced.
#[test]
fn batched_draws_equal_the_scalar_ones() {
    for count in [1u32, 2, 3, 5, 16, 17, 100, 900, 1000, 4097] {
        let mut runs = Vec::new();
        let mut taken = 0;
        while taken < count {
            let n = taken.max(1).min(count.div_ceil(8)).min(count - taken);
            runs.push(taken..taken + n);
            taken += n;
        }
        runs.extend([count / 3..count / 3 + 21, count - 1..count, count / 2..count, 0..count]);
        for (seed, x, y) in [(0u32, 0u32, 0u32), (7, 13, 5), (0xdead_beef, 799, 3)] {
            let pixel = PixelSampler::new(seed, x, y, 0, count);
            let other = PixelSampler::new(seed, x + 1, y, 0, count + 1);
            for run in &runs {
                let (batched, others) = (pixel.batched(run.clone()), other.batched(run.clone()));
                #[cfg(target_arch = "x86_64")]
                if count > 1
                    && run.end.min(count) >= run.start + 3
                    && std::arch::is_x86_feature_detected!("avx2")
                {
                    assert_eq!(batched.batch_end, run.end.min(count), "count {count}: batched");
                }
                for index in run.start..run.end.min(count) {
                    let want = draws(&mut PixelSampler::new(seed, x, y, index, count), index);
                    assert_eq!(draws(&mut batched.at(index), index), want, "count {count} sample {index}");
                    if index % 5 == 0 {
                        let want = draws(&mut PixelSampler::new(seed, x + 1, y, index, count + 1), index);
                        assert_eq!(draws(&mut others.at(index), index), want, "interleaved");
                    }
                }
            }
        }
    }
}
