//! Sine and cosine of an angle given in turns (`2π · u`), the angle every
//! direction sampler draws: a bounce's azimuth, a point on a light's disc or
//! cone. The samplers need both, for `u` in `[0, 1)`, a few times a path.
//!
//! libm's `sincosf` handles any argument, which costs it a call, a range
//! reduction by `π/2` in extended precision and branches on the argument's
//! size, none of which a sampler's `u` needs. An angle in turns reduces
//! exactly: the nearest quarter turn `q/4` is subtracted from `u` without
//! rounding (the two are within a factor of two of each other), and what is
//! left, an eighth of a turn at most, is turned into radians with one
//! rounding. Two polynomials on `[−π/4, π/4]` (Cephes' `sinf` and `cosf`
//! coefficients, accurate to single precision there) then give the sine and
//! cosine, and the quadrant swaps and negates them without a branch.
//!
//! Reads no scene parameters.

use std::f32::consts::TAU;

/// `(sin 2πu, cos 2πu)` for any finite `u`; exact at whole quarter turns,
/// and within 2·10⁻⁷ of the true values elsewhere (the tests check every
/// quarter of a turn densely). Meant for `u` in `[0, 1)`: past a few
/// thousand turns the quarter-turn grid is coarser than `f32`'s spacing and
/// accuracy falls off.
#[inline(always)]
pub fn sin_cos_turns(u: f32) -> (f32, f32) {
    let q = super::round(u * 4.0);
    // Exact: `u` and `q/4` are within a factor of two unless `q` is 0.
    let x = (u - q * 0.25) * TAU;
    let z = x * x;
    let s = x + x * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * -1.951_529_6e-4));
    let c = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
    // The quadrant, modulo 4 also for negative `u`.
    let k = (q as i32) & 3;
    let (s, c) = if k & 1 == 0 { (s, c) } else { (c, s) };
    let sin = if k & 2 == 0 { s } else { -s };
    let cos = if (k + 1) & 2 == 0 { c } else { -c };
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against `f64` over a dense grid of a turn and beyond, with the
    /// quarter turns and their neighbours, and for negative `u`.
    #[test]
    fn matches_double_precision() {
        let mut worst = 0.0f64;
        let n = 1 << 20;
        let mut check = |u: f32| {
            let (s, c) = sin_cos_turns(u);
            let a = std::f64::consts::TAU * f64::from(u);
            let e = (f64::from(s) - a.sin()).abs().max((f64::from(c) - a.cos()).abs());
            worst = worst.max(e);
        };
        for i in 0..=n {
            let u = i as f32 / n as f32;
            check(u);
            check(-u);
            check(u + 1.0);
        }
        for q in 0..=8 {
            let u = q as f32 * 0.125;
            for k in 1..64 {
                let mut v = u;
                for _ in 0..k {
                    v = v.next_up();
                }
                check(v);
                let mut w = u;
                for _ in 0..k {
                    w = w.next_down();
                }
                check(w);
            }
        }
        assert!(worst < 2e-7, "largest error {worst:e}");
    }

    #[test]
    fn exact_at_quarter_turns() {
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(0.25), (1.0, 0.0));
        assert_eq!(sin_cos_turns(0.5), (0.0, -1.0));
        assert_eq!(sin_cos_turns(0.75), (-1.0, 0.0));
        assert_eq!(sin_cos_turns(-0.25), (-1.0, 0.0));
        assert_eq!(sin_cos_turns(1.0), (0.0, 1.0));
    }

    /// Unit length to within the error bound, so directions built from it
    /// need no normalising.
    #[test]
    fn on_the_unit_circle() {
        for i in 0..100_000 {
            let (s, c) = sin_cos_turns(i as f32 / 100_000.0);
            assert!((s * s + c * c - 1.0).abs() < 5e-7);
        }
    }
}
