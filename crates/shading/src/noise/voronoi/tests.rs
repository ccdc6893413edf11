//! Tests of the cellular noise: F1 and F2 against a brute-force search in
//! every metric, their ranges, cell ids, jitter, and hostile input.

use super::*;
use crate::noise::testutil::Lcg;

const METRICS: [Metric; 3] = [Metric::Euclidean, Metric::Manhattan, Metric::Chebyshev];

fn distance(metric: Metric, a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    match metric {
        Metric::Euclidean => (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(),
        Metric::Manhattan => d[0].abs() + d[1].abs() + d[2].abs(),
        Metric::Chebyshev => d[0].abs().max(d[1].abs()).max(d[2].abs()),
    }
}

/// F1 and F2 by brute force over a 7³ block: slow, but plainly exhaustive.
/// Distances are taken from p's offset in its cell, as voronoi3 does, so
/// the two agree to rounding rather than to the ulp of p's coordinates.
fn brute_force(p: [f32; 3], metric: Metric, jitter: f32) -> (f32, f32) {
    let base = p.map(f32::floor);
    let frac = [p[0] - base[0], p[1] - base[1], p[2] - base[2]];
    let mut ds = Vec::new();
    for n in 0..343 {
        let o = [n % 7 - 3, n / 7 % 7 - 3, n / 49 - 3];
        let (_, local) = feature([0, 1, 2].map(|k| base[k] as i32 + o[k]), jitter);
        ds.push(distance(metric, frac, [0, 1, 2].map(|k| o[k] as f32 + local[k])));
    }
    ds.sort_by(f32::total_cmp);
    (ds[0], ds[1])
}

#[test]
fn matches_brute_force_and_stays_in_range() {
    let mut rng = Lcg::new(17);
    let bounds = [(3f32.sqrt(), 6f32.sqrt()), (3.0, 4.0), (1.0, 2.0)];
    for i in 0..30_000 {
        let p = rng.point4(-100.0, 100.0);
        let (metric, (b1, b2)) = (METRICS[i % 3], bounds[i % 3]);
        let jitter = [1.0, 0.7, 0.0][i / 3 % 3];
        let c = voronoi3(p[0], p[1], p[2], metric, jitter);
        let (f1, f2) = brute_force([p[0], p[1], p[2]], metric, jitter);
        assert!(
            (c.f1 - f1).abs() < 1e-5 && (c.f2 - f2).abs() < 1e-5,
            "{metric:?} at {p:?}: {c:?} vs {f1} {f2}"
        );
        assert!(0.0 <= c.f1 && c.f1 <= c.f2 && c.f1 <= b1 && c.f2 <= b2, "{metric:?}: {c:?}");
        // p1 is the point F1 was measured to (to the ulp of coordinates ~100).
        assert!((distance(metric, [p[0], p[1], p[2]], c.p1) - c.f1).abs() < 1e-4);
    }
}

#[test]
fn ranges_2d() {
    let mut rng = Lcg::new(18);
    let bounds = [(2f32.sqrt(), 5f32.sqrt()), (2.0, 3.0), (1.0, 2.0)];
    for i in 0..100_000 {
        let p = rng.point4(-100.0, 100.0);
        let c = voronoi2(p[0], p[1], METRICS[i % 3], 1.0);
        let (b1, b2) = bounds[i % 3];
        assert!(0.0 <= c.f1 && c.f1 <= c.f2 && c.f1 <= b1 && c.f2 <= b2, "{:?}: {c:?}", METRICS[i % 3]);
        assert_eq!(c.p1[2], 0.0);
        let d = [p[0] - c.p1[0], p[1] - c.p1[1]];
        if METRICS[i % 3] == Metric::Euclidean {
            assert!(((d[0] * d[0] + d[1] * d[1]).sqrt() - c.f1).abs() < 1e-4);
        }
    }
}

#[test]
fn zero_at_the_feature_point_and_one_id_per_cell() {
    let mut rng = Lcg::new(19);
    for i in 0..20_000 {
        let p = rng.point4(-50.0, 50.0);
        let metric = METRICS[i % 3];
        let c = voronoi3(p[0], p[1], p[2], metric, 1.0);
        let at = voronoi3(c.p1[0], c.p1[1], c.p1[2], metric, 1.0);
        // p1 is rebuilt from the cell each time, so it may move by an ulp.
        let moved = (0..3).map(|k| (at.p1[k] - c.p1[k]).abs()).fold(0.0, f32::max);
        assert!(at.f1 < 1e-5 && at.id == c.id && moved < 1e-5, "{c:?} vs {at:?}");
        // Every cell is star-shaped around its point in any norm (triangle
        // inequality), so the segment from p to p1 stays in p's cell.
        let t = 0.05 + 0.95 * rng.next_f32();
        let q: [f32; 3] = core::array::from_fn(|k| p[k] + t * (c.p1[k] - p[k]));
        assert_eq!(voronoi3(q[0], q[1], q[2], metric, 1.0).id, c.id, "{metric:?} at {p:?}, t = {t}");
    }
}

#[test]
fn metrics_order_chebyshev_euclidean_manhattan() {
    // Pointwise Chebyshev <= Euclidean <= Manhattan, so the order statistics
    // F1 and F2 keep that order too.
    let mut rng = Lcg::new(20);
    for _ in 0..20_000 {
        let p = rng.point4(-50.0, 50.0);
        let [e, m, c] = METRICS.map(|metric| voronoi3(p[0], p[1], p[2], metric, 1.0));
        assert!(c.f1 <= e.f1 + 1e-6 && e.f1 <= m.f1 + 1e-6, "{c:?} {e:?} {m:?}");
        assert!(c.f2 <= e.f2 + 1e-6 && e.f2 <= m.f2 + 1e-6, "{c:?} {e:?} {m:?}");
        let [e, m, c] = METRICS.map(|metric| voronoi2(p[0], p[1], metric, 1.0));
        assert!(c.f1 <= e.f1 + 1e-6 && e.f1 <= m.f1 + 1e-6);
    }
}

#[test]
fn zero_jitter_is_the_grid_of_cell_centres() {
    let c = voronoi3(2.3, -0.2, 7.9, Metric::Euclidean, 0.0);
    assert_eq!(c.p1, [2.5, -0.5, 7.5]);
    assert!((c.f1 - (0.04f32 + 0.09 + 0.16).sqrt()).abs() < 1e-6);
    // NaN jitter counts as 0, and jitter above 1 as 1.
    assert_eq!(voronoi2(2.3, -0.2, Metric::Euclidean, f32::NAN).p1, [2.5, -0.5, 0.0]);
    assert_eq!(
        voronoi3(0.1, 0.2, 0.3, Metric::Manhattan, 9.0),
        voronoi3(0.1, 0.2, 0.3, Metric::Manhattan, 1.0)
    );
}

#[test]
fn metric_from_u32() {
    for m in METRICS {
        assert_eq!(Metric::from_u32(m as u32), Some(m));
    }
    assert_eq!(Metric::from_u32(3), None);
    assert_eq!(Metric::from_u32(u32::MAX), None);
}

#[test]
fn hostile_inputs_do_not_panic() {
    for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, 3e9, -3e9] {
        for m in METRICS {
            let c = voronoi3(v, 0.5, v, m, v);
            assert!(c.f1.is_nan() || c.f1.is_finite(), "{c:?}");
            let _ = voronoi2(v, v, m, 0.5);
        }
    }
}
