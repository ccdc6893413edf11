//! The Perlin noise of the METU CENG795 lectures, which the course's `perlin`
//! texture is defined by.
//!
//! The lecture's recipe, followed literally:
//!
//! * 16 gradients `G`: the twelve cube edges (±1, ±1, 0), (±1, 0, ±1),
//!   (0, ±1, ±1) and the repeats (1, 1, 0), (−1, 1, 0), (0, −1, 1), (0, −1, −1)
//!   that Perlin's paper uses to make the count a power of two;
//! * a permutation `P` of 0..15 and φ(i) = P[i mod 16] (non-negative modulo, so
//!   negative lattice coordinates work);
//! * the gradient at lattice point (i, j, k) is G[φ(i + φ(j + φ(k)))];
//! * noise(p) = Σ over the 8 corners (i, j, k) of p's cell of
//!   (G_ijk · v)·w(vx)·w(vy)·w(vz), with v = p − (i, j, k) and the weight
//!   w(t) = −6|t|⁵ + 15|t|⁴ − 10|t|³ + 1 (1 at the corner, 0 one cell away).
//!
//! The result is 0 at every lattice point and lies in [-1, 1] as the lecture
//! says, up to a sliver: it is exactly ±1 at a cell centre whose eight
//! gradients all point at it, and hill-climbing from all 16³ distinct cells
//! (8 starts each) found a peak of ±1.0030 slightly off such a centre (Perlin's
//! improved noise, with his 256-entry table, peaks at 1.0364 the same way).
//! Clamping would break the exact gradient, so the value is left as it is.
//!
//! The lecture leaves the shuffle of `P` to each student, so every student's
//! noise, and so the course's reference images, use a different table: a
//! texture built on this noise reproduces the look (scale, contrast, the
//! `patchy`/`vein` conversions) but not the reference pixels. The table here
//! is one fixed shuffle, [`PERM`].

/// The gradient table G of the lecture, in its order.
pub const GRADIENTS: [[f32; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [0.0, -1.0, -1.0],
];

/// The permutation P of 0..15 used here: one fixed shuffle, chosen once (any
/// shuffle is as valid; the course's reference renderer used its own).
pub const PERM: [u8; 16] = [3, 12, 7, 0, 14, 9, 5, 10, 1, 15, 6, 11, 2, 13, 8, 4];

/// φ(i) = P[i mod 16] with the modulo taken non-negative.
#[inline(always)]
fn phi(i: i32) -> i32 {
    PERM[i.rem_euclid(16) as usize] as i32
}

/// w(t) and dw/dt. The lecture writes w with |t|; the derivative carries
/// sign(t), and all three terms vanish at t = 0, so w is C² there too.
#[inline(always)]
fn weight(t: f32) -> (f32, f32) {
    let a = t.abs();
    let a3 = a * a * a;
    let w = 1.0 - a3 * (a * (a * 6.0 - 15.0) + 10.0);
    let dw = -30.0 * a * a * (a - 1.0) * (a - 1.0);
    (w, if t < 0.0 { -dw } else { dw })
}

/// The course's Perlin noise at (x, y, z), in [-1, 1] (measured peak ±1.0030).
#[inline]
pub fn noise(x: f32, y: f32, z: f32) -> f32 {
    // The derivative terms are dead once inlined and are optimised away.
    noise_grad(x, y, z).0
}

/// [`noise`] and its exact analytic gradient ∂n/∂(x, y, z).
#[inline]
pub fn noise_grad(x: f32, y: f32, z: f32) -> (f32, [f32; 3]) {
    let base = [x, y, z].map(luster_core::math::floor);
    // Saturating casts keep any float in range; wrapping adds keep i + 1 and
    // i + φ(…) from overflowing, and 2³² is a multiple of 16, so φ is unchanged.
    let cell = base.map(|b| b as i32);
    let mut value = 0.0;
    let mut grad = [0.0f32; 3];
    for corner in 0..8 {
        let o = [corner & 1, corner >> 1 & 1, corner >> 2 & 1];
        let (i, j, k) = (cell[0].wrapping_add(o[0]), cell[1].wrapping_add(o[1]), cell[2].wrapping_add(o[2]));
        let g = GRADIENTS[phi(i.wrapping_add(phi(j.wrapping_add(phi(k))))) as usize];
        let v = [x - base[0] - o[0] as f32, y - base[1] - o[1] as f32, z - base[2] - o[2] as f32];
        let dot = g[0] * v[0] + g[1] * v[1] + g[2] * v[2];
        let ((wx, dwx), (wy, dwy), (wz, dwz)) = (weight(v[0]), weight(v[1]), weight(v[2]));
        let w = wx * wy * wz;
        value += dot * w;
        // Product rule: the ramp's slope g, and the weights' own derivatives.
        grad[0] += g[0] * w + dot * dwx * wy * wz;
        grad[1] += g[1] * w + dot * wx * dwy * wz;
        grad[2] += g[2] * w + dot * wx * wy * dwz;
    }
    (value, grad)
}

/// The course's `perlin` texture at `p` (object space), as the built-in map
/// computes it: `octaves` octaves (at least one) at frequencies `scale · 2ⁱ`
/// with weights `2⁻ⁱ`, each octave's absolute value when `absval`
/// (turbulence), the sum divided by the weights' sum, and for the linear
/// conversion mapped from [-1, 1] to [0, 1]. The Lua `course_perlin`
/// built-in calls this, so a script reproduces the map bit for bit.
pub fn texture_value(p: [f32; 3], scale: f32, octaves: u32, absval: bool) -> f32 {
    let (mut sum, mut weight, mut total, mut freq) = (0.0f32, 1.0f32, 0.0f32, scale);
    for _ in 0..octaves.max(1) {
        let n = noise(p[0] * freq, p[1] * freq, p[2] * freq);
        sum += weight * if absval { n.abs() } else { n };
        total += weight;
        weight *= 0.5;
        freq *= 2.0;
    }
    let s = sum / total;
    if absval {
        s
    } else {
        (s + 1.0) * 0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::testutil::{assert_grad_matches, assert_lipschitz, Lcg};

    #[test]
    fn perm_is_a_permutation_of_0_to_15() {
        let mut sorted = PERM;
        sorted.sort_unstable();
        assert_eq!(sorted, core::array::from_fn(|i| i as u8));
    }

    #[test]
    fn phi_wraps_negative_indices() {
        assert_eq!(phi(-1), PERM[15] as i32);
        assert_eq!(phi(-16), PERM[0] as i32);
        assert_eq!(phi(17), PERM[1] as i32);
        assert_eq!(phi(i32::MIN), PERM[0] as i32);
    }

    #[test]
    fn weight_is_the_lectures_polynomial() {
        for t in [-1.0f32, -0.75, -0.3, 0.0, 0.2, 0.5, 1.0] {
            let a = t.abs();
            let expected = -6.0 * a.powi(5) + 15.0 * a.powi(4) - 10.0 * a.powi(3) + 1.0;
            assert!((weight(t).0 - expected).abs() < 1e-6, "w({t})");
        }
        assert_eq!(weight(0.0).0, 1.0);
        assert_eq!(weight(1.0).0, 0.0);
        assert_eq!(weight(-1.0).0, 0.0);
    }

    #[test]
    fn zero_on_the_lattice_and_in_range() {
        for i in -30..30 {
            assert_eq!(noise(i as f32, (i * 7 % 11) as f32, (5 - i) as f32), 0.0);
        }
        let mut rng = Lcg::new(21);
        let (mut lo, mut hi) = (f32::MAX, f32::MIN);
        for _ in 0..100_000 {
            let p = rng.point4(-300.0, 300.0);
            let n = noise(p[0], p[1], p[2]);
            lo = lo.min(n);
            hi = hi.max(n);
        }
        assert!(lo >= -1.003 && hi <= 1.003 && lo < -0.6 && hi > 0.6, "[{lo}, {hi}]");
    }

    #[test]
    fn cell_centres_reach_but_never_pass_one() {
        // At a centre each weight is w(½)³ = 1/8 and each |G·v| <= 1 (two
        // components of ½), so |noise| <= 1; the 16³ cells are all the distinct
        // ones, and with this table some of them have all eight G·v = ±1.
        let mut best = 0.0f32;
        for c in 0..16 * 16 * 16 {
            let p = [(c % 16) as f32 + 0.5, (c / 16 % 16) as f32 + 0.5, (c / 256) as f32 + 0.5];
            best = best.max(noise(p[0], p[1], p[2]).abs());
        }
        assert_eq!(best, 1.0);
    }

    #[test]
    fn continuous_and_gradient_exact() {
        assert_lipschitz(noise, 4.0);
        assert_grad_matches(noise_grad, 1e-3, 2e-3);
    }

    #[test]
    fn hostile_inputs_do_not_panic() {
        for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, 2.2e9, -2.2e9] {
            let _ = (noise(v, 0.5, v), noise_grad(v, v, v), noise(0.5, v, 0.25));
        }
    }

    #[test]
    fn known_values_of_the_lectures_formula() {
        // Computed in double precision by a separate Python transcription of
        // the lecture's recipe with this PERM and GRADIENTS.
        for (p, want) in [
            ([0.5, 0.5, 0.5], -0.375),
            ([0.25, 0.75, 0.125], -0.254_422_75),
            ([-3.3, 7.6, 2.2], -0.557_544_7),
        ] {
            let n = noise(p[0], p[1], p[2]);
            assert!((n - want).abs() < 2e-6, "noise{p:?} = {n}, expected {want}");
        }
    }

    #[test]
    fn periodic_with_the_tables_16() {
        // φ repeats every 16, so the noise does; dyadic points keep x + 16 exact.
        let mut rng = Lcg::new(31);
        for _ in 0..1000 {
            let p = rng.point4(-100.0, 100.0).map(|v| (v * 64.0).round() / 64.0);
            let n = noise(p[0], p[1], p[2]);
            assert_eq!(n, noise(p[0] + 16.0, p[1], p[2]), "{p:?}");
            assert_eq!(n, noise(p[0], p[1] - 16.0, p[2] + 32.0), "{p:?}");
        }
    }
}
