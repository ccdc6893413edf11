//! Fractal sums of [`perlin::noise3`]: fBm, turbulence and Musgrave's ridged
//! multifractal.
//!
//! Octave `i` (from 0) samples the noise at `p·lacunarityⁱ` with amplitude
//! `gainⁱ`; the usual choice is lacunarity 2 and gain 0.5. Octave 0 is the
//! noise itself, unshifted, so one octave equals the base noise exactly.
//! `octaves` is capped at [`MAX_OCTAVES`]: beyond that the frequencies pass
//! below f32 resolution anyway, and a shader cannot make a call loop for long.
//!
//! | function | range, with B ≈ 1.04 the bound of `noise3` and S = Σ\|gain\|ⁱ |
//! |---|---|
//! | [`fbm3`] | [-B·S, B·S] |
//! | [`turbulence3`] | [0, B·S] |
//! | [`ridged3`] | [0, 1] for gain ≥ 0 (normalised, see there); [-1, 1] otherwise |

use super::octaves::{noise3_octaves, LANES};
use super::perlin::{self, noise3};

/// The largest number of octaves any function here sums; more are ignored.
pub const MAX_OCTAVES: u32 = 16;

/// The most octaves [`octave_sum`] computes one by one rather than in lanes:
/// an eight-lane call costs as much however few lanes it uses, more than
/// this many scalar `noise3` calls.
const SCALAR_TAIL: usize = 2;

/// Bound of |[`perlin::noise3`]| used to normalise [`ridged3`] (measured 1.036).
const NOISE3_BOUND: f32 = 1.04;

/// Fractional Brownian motion: Σ gainⁱ · noise3(p·lacunarityⁱ), i < octaves.
///
/// `octaves = 0` gives 0. Not normalised, so the caller keeps control of the
/// amplitude; divide by Σ gainⁱ for a result within the range of `noise3`.
#[inline]
pub fn fbm3(x: f32, y: f32, z: f32, octaves: u32, lacunarity: f32, gain: f32) -> f32 {
    octave_sum(x, y, z, octaves, lacunarity, gain, |n| n)
}

/// Σ gainⁱ · shape(noise3(p·lacunarityⁱ)), summed in octave order (so the
/// bits are those of the plain loop), the octaves computed eight at a time.
/// A tail of at most [`SCALAR_TAIL`] octaves (10-octave turbulence leaves
/// two) is computed one by one, which is cheaper than a mostly empty
/// eight-lane call; each lane equals the scalar `noise3` bit for bit, so the
/// sum does not change.
#[inline(always)]
fn octave_sum(
    x: f32,
    y: f32,
    z: f32,
    octaves: u32,
    lacunarity: f32,
    gain: f32,
    shape: impl Fn(f32) -> f32,
) -> f32 {
    let n = octaves.min(MAX_OCTAVES) as usize;
    let (mut sum, mut freq, mut amp) = (0.0, 1.0, 1.0);
    let mut done = 0;
    while done < n {
        let m = (n - done).min(LANES);
        if m <= SCALAR_TAIL {
            for _ in 0..m {
                sum += amp * shape(noise3(x * freq, y * freq, z * freq));
                freq *= lacunarity;
                amp *= gain;
            }
            break;
        }
        // Unused lanes sample the origin, where the noise is 0.
        let mut freqs = [0.0f32; LANES];
        for f in &mut freqs[..m] {
            *f = freq;
            freq *= lacunarity;
        }
        let values = noise3_octaves(x, y, z, &freqs);
        for v in &values[..m] {
            sum += amp * shape(*v);
            amp *= gain;
        }
        done += m;
    }
    sum
}

/// [`fbm3`] and its exact gradient: Σ gainⁱ·lacunarityⁱ·∇noise3(p·lacunarityⁱ).
#[inline]
pub fn fbm3_grad(x: f32, y: f32, z: f32, octaves: u32, lacunarity: f32, gain: f32) -> (f32, [f32; 3]) {
    let (mut sum, mut grad, mut freq, mut amp) = (0.0, [0.0f32; 3], 1.0, 1.0);
    for _ in 0..octaves.min(MAX_OCTAVES) {
        let (n, g) = perlin::noise3_grad(x * freq, y * freq, z * freq);
        sum += amp * n;
        // Chain rule: the octave is sampled at p·freq.
        for (acc, gk) in grad.iter_mut().zip(g) {
            *acc += amp * freq * gk;
        }
        freq *= lacunarity;
        amp *= gain;
    }
    (sum, grad)
}

/// Perlin's turbulence: Σ gainⁱ · |noise3(p·lacunarityⁱ)|, never negative for
/// gain ≥ 0. The absolute value folds each octave at its zero set, which is
/// what draws the sharp dark veins of marble and fire.
#[inline]
pub fn turbulence3(x: f32, y: f32, z: f32, octaves: u32, lacunarity: f32, gain: f32) -> f32 {
    octave_sum(x, y, z, octaves, lacunarity, gain, f32::abs)
}

/// Musgrave's ridged multifractal ("Texturing and Modeling", 3rd ed., ch. 16).
///
/// Each octave's signal is `(offset − |noise3|)²`: a sharp crest where the
/// noise crosses zero. From the second octave on the signal is multiplied by a
/// weight `clamp(2·previous signal, 0, 1)`, Musgrave's feedback with his gain
/// of 2, so detail piles up on the ridges and the valleys stay smooth.
///
/// Unlike Musgrave's spectral exponent `H`, the amplitude of octave `i` is
/// `gainⁱ`, as in [`fbm3`], so `gain` means the same thing in every function
/// here (his `H` is `−log(gain)/log(lacunarity)`; `H = 1` at lacunarity 2 is
/// gain 0.5). Typical: offset 1, lacunarity 2, gain 0.5.
///
/// Normalisation: the sum is divided by Σ|gainⁱ| · max(offset², (B − offset)²),
/// the largest a signal can be with |noise3| ≤ B = 1.04, so the result is in
/// [0, 1] for gain ≥ 0 (and in [-1, 1] for a negative gain) whatever the
/// offset. `octaves = 0` gives 0.
#[inline]
pub fn ridged3(x: f32, y: f32, z: f32, octaves: u32, lacunarity: f32, gain: f32, offset: f32) -> f32 {
    let (mut sum, mut norm, mut freq, mut amp, mut weight) = (0.0, 0.0, 1.0, 1.0, 1.0);
    let peak = (offset * offset).max((NOISE3_BOUND - offset) * (NOISE3_BOUND - offset));
    for _ in 0..octaves.min(MAX_OCTAVES) {
        let ridge = offset - noise3(x * freq, y * freq, z * freq).abs();
        let signal = ridge * ridge * weight;
        sum += amp * signal;
        norm += amp.abs();
        weight = (signal * 2.0).clamp(0.0, 1.0);
        freq *= lacunarity;
        amp *= gain;
    }
    if norm == 0.0 {
        0.0
    } else {
        sum / (norm * peak)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::testutil::{assert_grad_matches, assert_lipschitz, Lcg};

    #[test]
    fn one_octave_is_the_base_noise() {
        let mut rng = Lcg::new(3);
        for _ in 0..10_000 {
            let [x, y, z, _] = rng.point4(-100.0, 100.0);
            let n = noise3(x, y, z);
            assert_eq!(fbm3(x, y, z, 1, 2.0, 0.5), n);
            assert_eq!(fbm3_grad(x, y, z, 1, 2.0, 0.5), perlin::noise3_grad(x, y, z));
            assert_eq!(turbulence3(x, y, z, 1, 2.0, 0.5), n.abs());
            let r = ridged3(x, y, z, 1, 2.0, 0.5, 1.0);
            assert!((r - (1.0 - n.abs()).powi(2)).abs() < 1e-6, "{r} vs {n}");
        }
    }

    #[test]
    fn ranges_hold_over_many_points() {
        let mut rng = Lcg::new(4);
        let s: f32 = (0..4).map(|i| 0.5f32.powi(i)).sum();
        let (mut fbm_max, mut turb_min, mut turb_max) = (0.0f32, f32::MAX, 0.0f32);
        let (mut ridge_min, mut ridge_max) = (f32::MAX, f32::MIN);
        for _ in 0..100_000 {
            let [x, y, z, offset] = rng.point4(-100.0, 100.0);
            fbm_max = fbm_max.max(fbm3(x, y, z, 4, 2.0, 0.5).abs());
            let t = turbulence3(x, y, z, 4, 2.0, 0.5);
            turb_min = turb_min.min(t);
            turb_max = turb_max.max(t);
            let r = ridged3(x, y, z, 4, 2.0, 0.5, 1.0);
            // Any offset keeps the normalised result in [0, 1].
            let r2 = ridged3(x, y, z, 4, 2.0, 0.5, offset / 100.0);
            ridge_min = ridge_min.min(r).min(r2);
            ridge_max = ridge_max.max(r).max(r2);
        }
        assert!(fbm_max <= 1.04 * s && fbm_max > 0.5, "{fbm_max}");
        assert!(turb_min >= 0.0 && turb_max <= 1.04 * s && turb_max > 0.5, "[{turb_min}, {turb_max}]");
        assert!(ridge_min >= 0.0 && ridge_max <= 1.0 && ridge_max > 0.5, "[{ridge_min}, {ridge_max}]");
    }

    #[test]
    fn zero_octaves_and_the_cap() {
        assert_eq!(fbm3(0.3, 0.2, 0.1, 0, 2.0, 0.5), 0.0);
        assert_eq!(ridged3(0.3, 0.2, 0.1, 0, 2.0, 0.5, 1.0), 0.0);
        let capped = fbm3(0.3, 0.2, 0.1, MAX_OCTAVES, 2.0, 0.5);
        assert_eq!(fbm3(0.3, 0.2, 0.1, u32::MAX, 2.0, 0.5), capped);
        assert_eq!(turbulence3(0.3, 0.2, 0.1, u32::MAX, 2.0, 0.5), turbulence3(0.3, 0.2, 0.1, 16, 2.0, 0.5));
    }

    #[test]
    fn continuous_and_gradient_exact() {
        assert_lipschitz(|x, y, z| fbm3(x, y, z, 4, 2.0, 0.5), 12.0);
        assert_lipschitz(|x, y, z| turbulence3(x, y, z, 4, 2.0, 0.5), 12.0);
        assert_lipschitz(|x, y, z| ridged3(x, y, z, 4, 2.0, 0.5, 1.0), 12.0);
        // Octave 4 has 8× the frequency, so f''' grows by up to 8³·gain³ = 64:
        // a 4× smaller step keeps the truncation error within the budget.
        assert_grad_matches(|x, y, z| fbm3_grad(x, y, z, 4, 2.0, 0.5), 2.5e-4, 5e-3);
    }

    #[test]
    fn hostile_inputs_do_not_panic() {
        for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX] {
            let _ = fbm3(v, 0.0, v, 16, v, v);
            let _ = fbm3_grad(v, 0.0, v, 16, v, v);
            let _ = turbulence3(0.5, v, 1.0, u32::MAX, 1e30, 2.0);
            let _ = ridged3(v, v, v, 16, v, v, v);
        }
    }
}
