//! Simplex noise in 2D, 3D and 4D, after Stefan Gustavson's "Simplex noise
//! demystified" (2005) and his 2012 reference code.
//!
//! Space is skewed so that the simplices (triangles, tetrahedra, 5-cells)
//! become the halves, sixths, … of unit cubes; each point then sums n + 1
//! radial kernels `max(0, r² − |d|²)⁴ · (g · d)` instead of Perlin's 2ⁿ corner
//! blends, which is cheaper in 3D and much cheaper in 4D and has no
//! axis-aligned grid look. The hash is Perlin's permutation; the gradients are
//! his twelve cube edges (2D uses their x, y parts) and, in 4D, the 32
//! hypercube edge midpoints.
//!
//! The kernel radius is r² = 0.5 in every dimension, not Gustavson's 0.6 in
//! 3D and 4D: with 0.6 a kernel reaches past the simplices that share its
//! vertex, and the noise jumps by up to ~1e-3 on simplex boundaries (visible in
//! a bump-mapped gradient). The scale factors were measured for r² = 0.5 by
//! hill-climbing from 2–3·10⁵ random starts per dimension, so that each range
//! is [-1, 1]: the largest |value| found is 0.9979 (2D), 0.9990 (3D) and
//! 0.9988 (4D).

use super::perlin::{GRAD3, P};

/// Radius² of every kernel; see the module doc for why not 0.6.
const R2: f32 = 0.5;

// 1 / (largest unscaled |value| found): 2D 0.014256, 3D 0.013007, 4D 0.015929.
// Gustavson's own 70 is right in 2D, where his radius was already 0.5.
const SCALE2: f32 = 70.0;
const SCALE3: f32 = 76.8;
const SCALE4: f32 = 62.7;

/// Masks a skewed cell coordinate to a table index; any float is safe.
#[inline(always)]
fn cell(v: f32) -> (f32, usize) {
    let fl = luster_core::math::floor(v);
    (fl, (fl as i32 & 255) as usize)
}

/// One corner's kernel and its gradient: t⁴(g·d), t⁴g − 8t³(g·d)d with
/// t = r² − |d|², both zero outside the radius.
#[inline(always)]
fn kernel<const N: usize>(d: [f32; N], g: [f32; N]) -> (f32, [f32; N]) {
    let mut dd = 0.0;
    let mut gd = 0.0;
    for k in 0..N {
        dd += d[k] * d[k];
        gd += g[k] * d[k];
    }
    let t = R2 - dd;
    if t <= 0.0 {
        return (0.0, [0.0; N]);
    }
    let t2 = t * t;
    let t4 = t2 * t2;
    let mut grad = [0.0; N];
    for k in 0..N {
        grad[k] = t4 * g[k] - 8.0 * t2 * t * gd * d[k];
    }
    (t4 * gd, grad)
}

/// 2D simplex noise, in [-1, 1].
#[inline]
pub fn noise2(x: f32, y: f32) -> f32 {
    const F2: f32 = 0.366_025_42; // (√3 − 1) / 2
    const G2: f32 = 0.211_324_87; // (3 − √3) / 6
    let s = (x + y) * F2;
    let ((i, ii), (j, jj)) = (cell(x + s), cell(y + s));
    let t = (i + j) * G2;
    let d0 = [x - (i - t), y - (j - t)];
    // The lower or the upper triangle of the skewed square.
    let o = if d0[0] > d0[1] { [1, 0] } else { [0, 1] };
    let d1 = [d0[0] - o[0] as f32 + G2, d0[1] - o[1] as f32 + G2];
    let d2 = [d0[0] - 1.0 + 2.0 * G2, d0[1] - 1.0 + 2.0 * G2];
    let g = |a: usize, b: usize| {
        let g = GRAD3[(P[ii + a + P[jj + b] as usize] % 12) as usize];
        [g[0], g[1]]
    };
    let n = kernel(d0, g(0, 0)).0 + kernel(d1, g(o[0], o[1])).0 + kernel(d2, g(1, 1)).0;
    SCALE2 * n
}

/// 3D simplex noise, in [-1, 1].
#[inline]
pub fn noise3(x: f32, y: f32, z: f32) -> f32 {
    noise3_grad(x, y, z).0
}

/// [`noise3`] and its exact analytic gradient ∂n/∂(x, y, z).
#[inline]
pub fn noise3_grad(x: f32, y: f32, z: f32) -> (f32, [f32; 3]) {
    const F3: f32 = 1.0 / 3.0;
    const G3: f32 = 1.0 / 6.0;
    let s = (x + y + z) * F3;
    let ((i, ii), (j, jj), (k, kk)) = (cell(x + s), cell(y + s), cell(z + s));
    let t = (i + j + k) * G3;
    let d0 = [x - (i - t), y - (j - t), z - (k - t)];
    // Which of the cube's six tetrahedra: walk the axes in decreasing order of d0.
    let (o1, o2) = if d0[0] >= d0[1] {
        if d0[1] >= d0[2] {
            ([1, 0, 0], [1, 1, 0])
        } else if d0[0] >= d0[2] {
            ([1, 0, 0], [1, 0, 1])
        } else {
            ([0, 0, 1], [1, 0, 1])
        }
    } else if d0[1] < d0[2] {
        ([0, 0, 1], [0, 1, 1])
    } else if d0[0] < d0[2] {
        ([0, 1, 0], [0, 1, 1])
    } else {
        ([0, 1, 0], [1, 1, 0])
    };
    let corners = [[0, 0, 0], o1, o2, [1, 1, 1]];
    let mut value = 0.0;
    let mut grad = [0.0; 3];
    for (c, o) in corners.into_iter().enumerate() {
        let d = [0, 1, 2].map(|a| d0[a] - o[a] as f32 + c as f32 * G3);
        let h = P[ii + o[0] + P[jj + o[1] + P[kk + o[2]] as usize] as usize] % 12;
        let (n, g) = kernel(d, GRAD3[h as usize]);
        value += n;
        for a in 0..3 {
            grad[a] += g[a];
        }
    }
    (SCALE3 * value, grad.map(|g| SCALE3 * g))
}

/// The 4D gradient `h mod 32`: the axis `h / 8` is 0, the other three are ±1
/// with the signs in the low three bits.
#[inline(always)]
fn grad4(h: u8) -> [f32; 4] {
    let h = h & 31;
    let zero = (h >> 3) as usize;
    let mut g = [0.0; 4];
    let mut bit = 0;
    for (axis, v) in g.iter_mut().enumerate() {
        if axis != zero {
            *v = if h >> bit & 1 != 0 { -1.0 } else { 1.0 };
            bit += 1;
        }
    }
    g
}

/// 4D simplex noise, in [-1, 1]. For animated 3D noise pass time as `w`.
#[inline]
pub fn noise4(x: f32, y: f32, z: f32, w: f32) -> f32 {
    const F4: f32 = 0.309_017; // (√5 − 1) / 4
    const G4: f32 = 0.138_196_6; // (5 − √5) / 20
    let s = (x + y + z + w) * F4;
    let ((i, ii), (j, jj), (k, kk), (l, ll)) = (cell(x + s), cell(y + s), cell(z + s), cell(w + s));
    let t = (i + j + k + l) * G4;
    let d0 = [x - (i - t), y - (j - t), z - (k - t), w - (l - t)];
    // Gustavson's ranking: an axis with rank r is stepped at corners 4 − r … 3,
    // so the corners walk the axes from the largest offset to the smallest.
    let mut rank = [0usize; 4];
    for a in 0..4 {
        for b in a + 1..4 {
            if d0[a] > d0[b] {
                rank[a] += 1;
            } else {
                rank[b] += 1;
            }
        }
    }
    let mut value = 0.0;
    for c in 0..5usize {
        // Corner c has stepped along every axis whose rank is at least 4 − c.
        let o = rank.map(|r| usize::from(r + c >= 4));
        let d = [0, 1, 2, 3].map(|a| d0[a] - o[a] as f32 + c as f32 * G4);
        let h = P[ii + o[0] + P[jj + o[1] + P[kk + o[2] + P[ll + o[3]] as usize] as usize] as usize];
        value += kernel(d, grad4(h)).0;
    }
    SCALE4 * value
}

#[cfg(test)]
mod tests {
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
    fn near_a_vertex_only_its_own_kernel_counts() {
        // At (0.1, 0) and (0, 0.1) (and likewise in 3D) the other corners lie
        // beyond r² = 0.5, so the value is SCALE · (0.5 − 0.01)⁴ · 0.1 · g_axis
        // for the origin's gradient g (the hash of cell 0).
        let t4 = (0.5f32 - 0.01).powi(4);
        let g2 = GRAD3[(P[P[0] as usize] % 12) as usize];
        assert!((noise2(0.1, 0.0) - SCALE2 * t4 * 0.1 * g2[0]).abs() < 1e-6);
        assert!((noise2(0.0, 0.1) - SCALE2 * t4 * 0.1 * g2[1]).abs() < 1e-6);
        let g3 = GRAD3[(P[P[P[0] as usize] as usize] % 12) as usize];
        for axis in 0..3 {
            let mut p = [0.0f32; 3];
            p[axis] = 0.1;
            let want = SCALE3 * t4 * 0.1 * g3[axis];
            assert!((noise3(p[0], p[1], p[2]) - want).abs() < 1e-6, "axis {axis}");
        }
    }
}
