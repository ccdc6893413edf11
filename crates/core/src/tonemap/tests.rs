//! Tests of the tone mapping: the course's clamp, the operators, the
//! quantizer tables, the luminance statistics, and the batched mapping
//! against its one-pixel reference.

use super::*;

fn grey(y: f32) -> Vec3 {
    Vec3::splat(y)
}

#[test]
fn course_clamp_truncates_and_zeroes_nan() {
    let px = [Vec3::new(-3.0, 12.9, 300.0), Vec3::new(f32::NAN, 254.99, f32::INFINITY)];
    assert_eq!(course_rgb8(&px), [0, 12, 255, 0, 254, 255]);
}

#[test]
fn course_codes_of_a_large_film_keep_their_pixels_order() {
    let px: Vec<Vec3> =
        (0..10_001).map(|i| Vec3::new(i as f32 * 0.37 - 20.0, (i % 300) as f32, 1e9)).collect();
    let want: Vec<u8> = px
        .iter()
        .flat_map(|p| p.to_array().map(|c| if c.is_nan() { 0 } else { c.clamp(0.0, 255.0) as u8 }))
        .collect();
    assert_eq!(course_rgb8(&px), want);
}

#[test]
fn photographic_maps_the_log_average_to_key_over_one_plus_key() {
    // A uniform image: every pixel is the log-average (up to δ).
    let px = vec![grey(37.0); 16];
    let out = Tonemap::COURSE_DEFAULT.apply(&px);
    let expect = ((0.18f32 / 1.18).powf(1.0 / 2.2) * 255.0) as u8;
    assert!(out.iter().all(|&c| c == expect), "{out:?} vs {expect}");
}

#[test]
fn the_scale_does_not_matter_only_ratios() {
    let px: Vec<Vec3> = (0..64).map(|i| Vec3::new(i as f32, (i * 3 % 7) as f32, 0.5)).collect();
    let bright: Vec<Vec3> = px.iter().map(|p| *p * 1000.0).collect();
    let t = Tonemap { burn_percent: 5.0, ..Tonemap::COURSE_DEFAULT };
    let (a, b) = (t.apply(&px), t.apply(&bright));
    assert!(a.iter().zip(&b).all(|(x, y)| x.abs_diff(*y) <= 1));
}

#[test]
fn burn_out_makes_the_top_percentile_white() {
    // 100 pixels of rising luminance; 1% burn: the brightest is L_white.
    let px: Vec<Vec3> = (1..=100).map(|i| grey(i as f32)).collect();
    let t = Tonemap { burn_percent: 1.0, ..Tonemap::COURSE_DEFAULT };
    let out = t.apply(&px);
    assert_eq!(&out[297..], &[255, 255, 255]);
    assert!(out[3 * 90] < 255);
    let plain = Tonemap::COURSE_DEFAULT.apply(&px);
    assert!(plain[297] < 255, "without burn-out nothing reaches white");
    assert!(out[150] > plain[150], "burn-out brightens the middle");
}

#[test]
fn saturation_zero_is_grey_and_one_keeps_ratios() {
    let px = vec![Vec3::new(2.0, 1.0, 0.5), grey(1.0)];
    let g = Tonemap { saturation: 0.0, ..Tonemap::COURSE_DEFAULT }.apply(&px);
    assert!(g[0] == g[1] && g[1] == g[2]);
    let c = Tonemap::COURSE_DEFAULT.apply(&px);
    assert!(c[0] > c[1] && c[1] > c[2]);
}

#[test]
fn curves_reach_white_where_documented() {
    assert!((Operator::Aces.curve(ACES_WHITE, None) - 1.0).abs() < 1e-5);
    assert!(Operator::Aces.curve(ACES_WHITE * 0.9, None) < 1.0);
    assert!((Operator::Filmic.curve(FILMIC_W / FILMIC_BIAS, None) - 1.0).abs() < 1e-5);
    assert_eq!(Operator::Photographic.curve(3.0, Some(3.0)), 1.0);
    assert_eq!(Operator::Photographic.curve(1.0, None), 0.5);
    for op in [Operator::Photographic, Operator::Aces, Operator::Filmic] {
        let mut last = -1.0;
        for i in 0..200 {
            let v = op.curve(i as f32 * 0.05, None);
            assert!(v >= last && (0.0..=1.0).contains(&v), "{op:?} not monotone in [0,1]");
            last = v;
        }
    }
}

#[test]
fn srgb_gamma_and_operator_names() {
    let px = vec![grey(1.0); 4];
    let t = Tonemap { gamma: Gamma::Srgb, ..Tonemap::COURSE_DEFAULT };
    let v = 0.18f32 / 1.18;
    let expect = ((1.055 * v.powf(1.0 / 2.4) - 0.055) * 255.0) as u8;
    assert_eq!(t.apply(&px)[0], expect);
    assert_eq!(Operator::parse(" aces "), Some(Operator::Aces));
    assert_eq!(Operator::parse("Photographic"), Some(Operator::Photographic));
    assert_eq!(Operator::parse("Drago"), None);
}

#[test]
fn black_and_non_finite_pixels_stay_black() {
    let px = vec![Vec3::ZERO, Vec3::splat(f32::NAN), grey(1.0)];
    let out = Tonemap::DISPLAY.apply(&px);
    assert_eq!(&out[..6], &[0; 6]);
    assert!(out[6] > 0);
}

#[test]
fn the_quantizer_table_agrees_with_the_formula() {
    for gamma in [Gamma::Power(2.2), Gamma::Power(1.0), Gamma::Power(0.1), Gamma::Srgb] {
        let q = Quantizer::new(gamma);
        // Below 1: at exactly 1 the sRGB formula gives 0.99999994 in f32 and
        // so code 254; the table gives white its 255.
        for i in 0..200_000 {
            let c = i as f32 / 200_000.0;
            assert_eq!(q.code(c), to_byte(gamma.encode(c)), "{gamma:?} at {c}");
        }
        // Spread over every octave, where the bins are.
        for i in 0..200_000u32 {
            let c = f32::from_bits(0x3000_0000 + i * ((0x3F80_0000 - 0x3000_0000) / 200_000));
            assert_eq!(q.code(c), to_byte(gamma.encode(c)), "{gamma:?} at {c}");
        }
        assert_eq!((q.code(-1.0), q.code(1.0), q.code(7.0), q.code(f32::NAN)), (0, 255, 255, 0));
        // Both ways of stepping past the edges are covered.
        assert_eq!(q.one_step, gamma != Gamma::Power(0.1), "{gamma:?}");
    }
}

/// The values where a quantizer's answer can change: around every edge,
/// every bin's lower end, 2⁻²⁴ and 1, and values outside [0, 1].
fn quantizer_probes(q: &Quantizer) -> Vec<f32> {
    let around = |bits: u32| (bits.saturating_sub(3)..=bits.saturating_add(3)).map(f32::from_bits);
    let mut v: Vec<f32> =
        q.edges.iter().filter(|e| e.is_finite()).flat_map(|e| around(e.to_bits())).collect();
    v.extend((0..=BINS as u32).flat_map(|i| around(LOW_BITS + (i << BIN_SHIFT))));
    v.extend(around(LOW_BITS).chain(around(1.0f32.to_bits())).chain(around(1)));
    v.extend([0.0, -0.0, -1e-30, -1.0, 2.0, f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY]);
    v
}

#[test]
fn the_packed_table_answers_as_the_two_tables_do() {
    let quantizers = [
        Quantizer::new(Gamma::Power(2.2)),
        Quantizer::new(Gamma::Power(1.0)),
        Quantizer::new(Gamma::Srgb),
        Quantizer::rounding(Gamma::Srgb),
        Quantizer::rounding(Gamma::Power(2.2)),
    ];
    for q in quantizers {
        assert!(!q.packed.is_empty(), "every gamma above 0.3 packs");
        let general = Quantizer {
            edges: q.edges,
            start: q.start.clone(),
            white: q.white,
            one_step: true,
            packed: Vec::new(),
        };
        for c in quantizer_probes(&q) {
            assert_eq!(q.code(c), general.code(c), "at {c:e} ({:#x})", c.to_bits());
        }
    }
    assert!(Quantizer::new(Gamma::Power(0.1)).packed.is_empty(), "two edges share a bin: the general path");
}

#[test]
fn percentile_by_histogram_matches_a_full_sort() {
    // Zeros, ties, values spread over many octaves and some in one bucket.
    let mut x = 0x2545_f491u32;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    };
    let px: Vec<Vec3> = (0..100_000)
        .map(|i| match i % 5 {
            0 => Vec3::ZERO,
            1 => grey(1.5),
            2 => Vec3::new(1.5 + (next() % 1000) as f32 * 1e-7, 1.5, 1.5),
            _ => Vec3::new(1.0, 0.5, 2.0) * (next() % 1_000_000) as f32 * 10f32.powi((next() % 9) as i32 - 4),
        })
        .collect();
    let stats = Stats::of(&px, true);
    let mut sorted: Vec<f32> = px.iter().map(|&p| luminance(p)).collect();
    sorted.sort_by(f32::total_cmp);
    for at in [0, 1, 19_999, 20_000, 50_000, 98_999, 99_999] {
        assert_eq!(
            super::nth_luminance(&stats.lum, &stats.hist, at).to_bits(),
            sorted[at].to_bits(),
            "at {at}"
        );
    }
    // Scaling after selecting gives the scaled values' own rank.
    for scale in [0.37f32, 1e-3, 3.7e4] {
        let mut scaled: Vec<f32> = sorted.iter().map(|&y| y * scale).collect();
        scaled.sort_by(f32::total_cmp);
        for at in [20_000, 50_000, 98_999] {
            assert_eq!((sorted[at] * scale).to_bits(), scaled[at].to_bits(), "scale {scale} at {at}");
        }
    }
}

#[test]
fn the_log_average_does_not_depend_on_the_thread_count() {
    let px: Vec<Vec3> = (0..50_000).map(|i| grey(((i * 7919) % 1013) as f32 * 0.37 + 1e-3)).collect();
    let with = |n| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
        pool.install(|| Stats::of(&px, true))
    };
    let (one, three) = (with(1), with(3));
    assert_eq!(one.log_sum.to_bits(), three.log_sum.to_bits());
    assert_eq!(one.hist, three.hist);
    assert_eq!(one.hist.iter().map(|&c| c as usize).sum::<usize>(), px.len());
}

#[test]
fn the_branch_free_log_is_within_1e_12_of_the_exact_one() {
    // Every octave the log-average meets (δ + Y from 1e-5 up to f32::MAX),
    // with mantissas spread over [1, 2), and the √½ and √2 seams.
    let mut x = 0x9e37_79b9u32;
    let mut v: Vec<f32> = (0..100_000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            f32::from_bits(0x3727_C5AC + x % (0x7F7F_FFFF - 0x3727_C5AC))
        })
        .collect();
    v.extend([1e-5, 1.0, 0.5, 2.0, std::f32::consts::SQRT_2, std::f32::consts::FRAC_1_SQRT_2, f32::MAX]);
    v.extend([0x3F35_04F2u32, 0x3F35_04F3, 0x3FB5_04F3, 0x3FB5_04F4].map(f32::from_bits));
    for x in v {
        let (l, exact) = (ln(x), f64::from(x).ln());
        assert!((l - exact).abs() <= 1e-12 * exact.abs().max(1.0), "ln {x:e}: {l} against {exact}");
    }
}

/// The mapping written one pixel at a time: the reference the batched lane
/// code must match bit for bit.
fn map_one_pixel_at_a_time(t: &Tonemap, px: &[Vec3]) -> Vec<u8> {
    let burn = t.burn_percent > 0.0;
    let q = Quantizer::new(t.gamma);
    let stats = Stats::of(px, burn);
    let scale = (f64::from(t.key) / (stats.log_sum / px.len() as f64).exp()) as f32;
    let l_white = burn.then(|| {
        let n = px.len();
        let at = (((1.0 - f64::from(t.burn_percent) / 100.0) * n as f64) as usize).min(n - 1);
        (nth_luminance(&stats.lum, &stats.hist, at) * scale).max(f32::MIN_POSITIVE)
    });
    let mut out = Vec::new();
    for &p in px {
        let y = luminance(p);
        if y > 0.0 {
            let yo = t.operator.curve(y * scale, l_white);
            let ratio = (p * (1.0 / y)).max(Vec3::ZERO);
            let c = if t.saturation == 1.0 { ratio } else { ratio.powf(t.saturation) } * yo;
            out.extend([q.code(c.x), q.code(c.y), q.code(c.z)]);
        } else {
            out.extend([0, 0, 0]);
        }
    }
    out
}

#[test]
fn the_lanes_map_as_one_pixel_at_a_time_did() {
    let mut x = 0x1234_5678u32;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        x
    };
    // A length that leaves a remainder in the last chunk and the last lanes;
    // black, non-finite, negative, denormal (its reciprocal is infinite) and
    // very bright pixels, and colours of every saturation.
    let px: Vec<Vec3> = (0..2 * 4096 + 3 * 256 + 13)
        .map(|i| match i % 97 {
            0 => Vec3::ZERO,
            1 => Vec3::new(f32::NAN, 1.0, 1.0),
            2 => Vec3::new(f32::INFINITY, 0.0, 1.0),
            3 => Vec3::new(-2.0, 5.0, 0.0),
            4 => Vec3::new(1e-44, 0.0, 0.0),
            5 if i < 97 => Vec3::splat(1e30),
            _ => {
                let mut c = || (next() % 10_000) as f32 * 1e-3 * 10f32.powi((next() % 7) as i32 - 3);
                Vec3::new(c(), c(), c())
            }
        })
        .collect();
    for operator in [Operator::Photographic, Operator::Aces, Operator::Filmic] {
        for (burn_percent, saturation, gamma) in
            [(0.0, 1.0, Gamma::Power(2.2)), (1.0, 1.0, Gamma::Srgb), (2.5, 0.6, Gamma::Power(0.1))]
        {
            let t = Tonemap { operator, key: 0.3, burn_percent, saturation, gamma };
            let want = map_one_pixel_at_a_time(&t, &px);
            assert!(want.iter().any(|&c| c > 0 && c < 255), "{t:?}: a test that sees codes");
            assert!(t.apply(&px) == want, "{t:?}");
            // The portable build too, where the processor has AVX2 (the
            // other tests see the portable build only when it does not).
            vector::PORTABLE_ONLY.store(true, std::sync::atomic::Ordering::Relaxed);
            let portable = t.apply(&px);
            vector::PORTABLE_ONLY.store(false, std::sync::atomic::Ordering::Relaxed);
            assert!(portable == want, "{t:?}, portable build");
        }
    }
}
