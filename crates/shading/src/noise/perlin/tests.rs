//! Tests of the improved Perlin noise: Perlin's reference value, the
//! lattice zeros, the ranges, continuity, the analytic gradient, the periodic
//! variant, and hostile input.

use super::*;
use crate::noise::testutil::{assert_grad_matches, assert_lipschitz, Lcg};

#[test]
fn table_is_a_permutation_written_twice() {
    let mut seen = [false; 256];
    for &v in &PERM_256 {
        assert!(!seen[v as usize], "{v} appears twice");
        seen[v as usize] = true;
    }
    assert_eq!(P[..256], P[256..]);
}

#[test]
// 3.14 is the reference's test input, not an approximation of π.
#[allow(clippy::approx_constant)]
fn matches_perlins_reference_value() {
    // The Java reference (and Rosetta Code's check) prints 0.13691995878400012.
    let n = noise3(3.14, 42.0, 7.0);
    assert!((n - 0.136_919_96).abs() < 2e-6, "{n}");
}

#[test]
fn zero_on_the_lattice() {
    for i in -20..20 {
        let (a, b, c, d) = (i as f32, (i * 7 % 13) as f32, (i * 3 - 5) as f32, (-i * 5) as f32);
        assert_eq!(noise1(a), 0.0);
        assert_eq!(noise2(a, b), 0.0);
        assert_eq!(noise3(a, b, c), 0.0);
        assert_eq!(noise4(a, b, c, d), 0.0);
        assert_eq!(pnoise3(a, b, c, 3, 4, 5), 0.0);
    }
}

#[test]
fn ranges_hold_over_many_points() {
    let mut rng = Lcg::new(1);
    let (mut lo, mut hi) = ([f32::MAX; 4], [f32::MIN; 4]);
    for _ in 0..100_000 {
        let p = rng.point4(-300.0, 300.0);
        let v = [noise1(p[0]), noise2(p[0], p[1]), noise3(p[0], p[1], p[2]), noise4(p[0], p[1], p[2], p[3])];
        for k in 0..4 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    let bounds = [1.0, 1.0, 1.04, 1.0];
    for k in 0..4 {
        assert!(lo[k] >= -bounds[k] && hi[k] <= bounds[k], "noise{}: [{}, {}]", k + 1, lo[k], hi[k]);
        // A bound far above what is reached would also be a bug (a lost scale).
        assert!(
            hi[k] > 0.6 * bounds[k] && lo[k] < -0.6 * bounds[k],
            "noise{}: [{}, {}]",
            k + 1,
            lo[k],
            hi[k]
        );
    }
}

#[test]
fn extremes_sit_at_cell_centres_for_1d_and_2d() {
    let max1 = (0..256).map(|i| noise1(i as f32 + 0.5).abs()).fold(0.0, f32::max);
    assert_eq!(max1, 1.0);
    // All four diagonals must point at the centre: 1 in 8⁴ cells, so scan every cell of the period.
    let max2 =
        (0..65536).map(|i| noise2((i % 256) as f32 + 0.5, (i / 256) as f32 + 0.5).abs()).fold(0.0, f32::max);
    assert!((max2 - 1.0).abs() < 1e-6, "{max2}");
}

#[test]
fn continuous() {
    assert_lipschitz(noise3, 4.0);
    assert_lipschitz(|x, y, z| noise4(x, y, z, x - y), 8.0);
    assert_lipschitz(|x, y, _| noise2(x, y), 4.0);
    assert_lipschitz(|x, _, _| noise1(x), 4.0);
}

#[test]
fn gradient_matches_finite_differences() {
    assert_grad_matches(noise3_grad, 1e-3, 2e-3);
}

#[test]
fn gradient_value_is_noise3() {
    let mut rng = Lcg::new(5);
    for _ in 0..1000 {
        let p = rng.point4(-50.0, 50.0);
        assert_eq!(noise3_grad(p[0], p[1], p[2]).0.to_bits(), noise3(p[0], p[1], p[2]).to_bits());
    }
}

#[test]
fn pnoise3_is_periodic_and_matches_noise3_at_period_256() {
    let mut rng = Lcg::new(7);
    for _ in 0..10_000 {
        // Multiples of 1/64 so that adding a period is exact in f32.
        let p = rng.point4(-64.0, 64.0).map(|v| (v * 64.0).round() / 64.0);
        let (px, py, pz) = (3, 5, 7);
        let base = pnoise3(p[0], p[1], p[2], px, py, pz);
        assert_eq!(base, pnoise3(p[0] + 3.0, p[1], p[2], px, py, pz));
        assert_eq!(base, pnoise3(p[0], p[1] - 5.0, p[2], px, py, pz));
        assert_eq!(base, pnoise3(p[0], p[1], p[2] + 14.0, px, py, pz));
        assert_eq!(pnoise3(p[0], p[1], p[2], 256, 256, 256), noise3(p[0], p[1], p[2]));
    }
    // A period below 1 means 1: every cell hashes the same corners.
    assert_eq!(pnoise3(0.25, 0.5, 0.75, 0, -4, 1), pnoise3(7.25, 2.5, -9.25, 1, 1, 1));
}

#[test]
fn hostile_inputs_do_not_panic() {
    for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, 1e30, -1e30] {
        let _ = (noise1(v), noise2(v, 1.5), noise3(0.5, v, v), noise4(v, v, 0.2, v), noise3_grad(v, 0.1, v));
        let _ = pnoise3(v, v, v, i32::MAX, i32::MIN, 0);
    }
}

#[test]
fn periodic_with_the_tables_256() {
    // The permutation repeats every 256 lattice cells, so the noise does;
    // dyadic points keep x + 256 exact in f32.
    let mut rng = Lcg::new(11);
    for _ in 0..1000 {
        let p = rng.point4(-100.0, 100.0).map(|v| (v * 64.0).round() / 64.0);
        assert_eq!(noise3(p[0], p[1], p[2]), noise3(p[0] + 256.0, p[1], p[2] - 256.0), "{p:?}");
        assert_eq!(noise4(p[0], p[1], p[2], p[3]), noise4(p[0], p[1] + 256.0, p[2], p[3] + 512.0), "{p:?}");
    }
}
