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
        assert_eq!(super::nth_luminance(&px, &stats.hist, at).to_bits(), sorted[at].to_bits(), "at {at}");
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
