use super::*;
use crate::noise::testutil::{assert_grad_matches, assert_lipschitz, Lcg};

#[test]
fn ranges_hold_over_many_points() {
    let mut rng = Lcg::new(2);
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for _ in 0..100_000 {
        let p = rng.point4(-300.0, 300.0);
        let v = [noise2(p[0], p[1]), noise3(p[0], p[1], p[2]), noise4(p[0], p[1], p[2], p[3])];
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    for k in 0..3 {
        // Within [-1, 1], and reaching well out towards it (a lost scale factor fails).
        assert!(lo[k] >= -1.0 && hi[k] <= 1.0, "noise{}: [{}, {}]", k + 2, lo[k], hi[k]);
        assert!(lo[k] < -0.6 && hi[k] > 0.6, "noise{}: [{}, {}]", k + 2, lo[k], hi[k]);
    }
}

#[test]
fn zero_at_the_skewed_lattice_origin() {
    // At a simplex vertex d0 = 0 and every other kernel has |d|² >= 0.5.
    assert_eq!(noise2(0.0, 0.0), 0.0);
    assert_eq!(noise3(0.0, 0.0, 0.0), 0.0);
    assert_eq!(noise4(0.0, 0.0, 0.0, 0.0), 0.0);
}

#[test]
fn continuous_across_simplex_boundaries() {
    // With r² = 0.6 in 3D this fails: kernels reach past their simplices.
    assert_lipschitz(noise3, 8.0);
    assert_lipschitz(|x, y, _| noise2(x, y), 8.0);
    assert_lipschitz(|x, y, z| noise4(x, y, z, 0.5 * x - z), 12.0);
    assert_lipschitz(|x, y, z| noise4(y, z, x * 0.3, x + y), 12.0);
}

#[test]
fn gradient_matches_finite_differences() {
    assert_grad_matches(noise3_grad, 1e-3, 2e-3);
    let mut rng = Lcg::new(9);
    for _ in 0..1000 {
        let p = rng.point4(-50.0, 50.0);
        assert_eq!(noise3_grad(p[0], p[1], p[2]).0.to_bits(), noise3(p[0], p[1], p[2]).to_bits());
    }
}

#[test]
fn grad4_has_one_zero_and_covers_all_32() {
    let mut seen = std::collections::HashSet::new();
    for h in 0..=255u8 {
        let g = grad4(h);
        assert_eq!(g.iter().filter(|v| **v == 0.0).count(), 1, "{g:?}");
        seen.insert(g.map(f32::to_bits));
    }
    assert_eq!(seen.len(), 32);
}

#[test]
fn hostile_inputs_do_not_panic() {
    for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, 3e38] {
        let _ = (noise2(v, 0.5), noise3(v, v, 1.0), noise3_grad(0.2, v, v), noise4(v, 1.0, v, v));
    }
}

#[test]
fn deterministic() {
    let mut rng = Lcg::new(13);
    for _ in 0..1000 {
        let p = rng.point4(-1e3, 1e3);
        assert_eq!(noise2(p[0], p[1]).to_bits(), noise2(p[0], p[1]).to_bits());
        assert_eq!(noise4(p[0], p[1], p[2], p[3]).to_bits(), noise4(p[0], p[1], p[2], p[3]).to_bits());
    }
}
