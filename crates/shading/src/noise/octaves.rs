//! Eight octaves of [`perlin::noise3`] at once, for the fractal sums: each
//! lane of an AVX2 vector is one octave, the point scaled by its own
//! frequency.
//!
//! Every lane performs the scalar `noise3`'s `f32` operations in the same
//! order (IEEE floor, the same masked lattice hash through gathers from a
//! widened copy of the permutation that pairs each entry with the next, the
//! same gradient table, no FMA), so a
//! lane's value is the scalar one bit for bit; `tests` compares them on
//! random, huge, negative-zero and non-finite points. Fractal sums then
//! accumulate the lanes in octave order, as the one-by-one loop does, so fBm
//! and turbulence keep their bits too. Turbulence-heavy volume scripts spend
//! most of a render in `noise3`, and the octaves of one sum are independent,
//! which is what the lanes use.
//!
//! Without AVX2 (detected at run time) the octaves are computed one by one.

use super::perlin::noise3;

/// Lanes per call.
pub(crate) const LANES: usize = 8;

/// `noise3(x·f, y·f, z·f)` for each frequency `f` of `freqs`.
#[inline]
pub(crate) fn noise3_octaves(x: f32, y: f32, z: f32, freqs: &[f32; LANES]) -> [f32; LANES] {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 (which implies AVX) was detected on this CPU.
            return unsafe { avx2::noise3_x8(x, y, z, freqs) };
        }
    }
    freqs.map(|f| noise3(x * f, y * f, z * f))
}

/// `noise3(x, y, z)` with its eight corners in the lanes of one vector.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(crate) unsafe fn noise3_one(x: f32, y: f32, z: f32) -> f32 {
    avx2::noise3_one(x, y, z)
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::LANES;
    use crate::noise::perlin::{self, GRAD3, P};
    use std::arch::x86_64::*;

    /// The permutation widened to `i32` with its next entry in the upper
    /// half: `P[i] | P[i + 1] << 16`. Cell `i + 1` along an axis hashes to
    /// `P[q + i + 1]` (its masked index `(i + 1) & 255` reads the same entry,
    /// `P` repeating every 256), so one gather fetches the hashes of both
    /// neighbours: 7 gathers a call instead of 14.
    static PAIR: [i32; 512] = {
        let mut p = [0i32; 512];
        let mut i = 0;
        while i < 512 {
            p[i] = P[i] as i32 | (P[(i + 1) & 511] as i32) << 16;
            i += 1;
        }
        p
    };

    /// Component `c` of the gradients `0..8` and `8..16` (`permutevar` tables).
    static GRAD_SPLIT: [[[f32; 8]; 2]; 3] = {
        let mut t = [[[0.0f32; 8]; 2]; 3];
        let mut c = 0;
        while c < 3 {
            let mut i = 0;
            while i < 16 {
                t[c][i / 8][i % 8] = GRAD3[i][c];
                i += 1;
            }
            c += 1;
        }
        t
    };

    /// The lattice cell (masked to 0..=255) and the offset in it, as
    /// `perlin::lattice` computes them: `floor`, then a saturating cast, whose
    /// result for `floor ≥ 2³¹` (and +∞) is `i32::MAX`, so 255 after the mask;
    /// the vector cast gives `i32::MIN` there (0 after the mask) and NaN and
    /// −∞ map to 0 in both.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn lattice(v: __m256) -> (__m256i, __m256) {
        let fl = _mm256_floor_ps(v);
        let i = _mm256_cvttps_epi32(fl);
        let big = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OQ>(fl, _mm256_set1_ps(2_147_483_648.0)));
        let i = _mm256_and_si256(_mm256_or_si256(i, big), _mm256_set1_epi32(255));
        (i, _mm256_sub_ps(v, fl))
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn perm2(i: __m256i) -> (__m256i, __m256i) {
        // SAFETY: every index is masked to 0..=511 by the callers.
        let v = _mm256_i32gather_epi32::<4>(PAIR.as_ptr(), i);
        (_mm256_and_si256(v, _mm256_set1_epi32(0xffff)), _mm256_srli_epi32::<16>(v))
    }

    /// `GRAD3[h & 15][c]` per lane.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn grad(c: usize, h: __m256i, high: __m256) -> __m256 {
        let lo = _mm256_loadu_ps(GRAD_SPLIT[c][0].as_ptr());
        let hi = _mm256_loadu_ps(GRAD_SPLIT[c][1].as_ptr());
        _mm256_blendv_ps(_mm256_permutevar8x32_ps(lo, h), _mm256_permutevar8x32_ps(hi, h), high)
    }

    /// The ramp of the corner with hash `h` at offset `(dx, dy, dz)` from it.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn corner(h: __m256i, dx: __m256, dy: __m256, dz: __m256) -> __m256 {
        // Bit 3 of the hash, in each lane's sign bit, picks the upper table.
        let high = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(h));
        let gx = grad(0, h, high);
        let gy = grad(1, h, high);
        let gz = grad(2, h, high);
        add(add(mul(gx, dx), mul(gy, dy)), mul(gz, dz))
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn add(a: __m256, b: __m256) -> __m256 {
        _mm256_add_ps(a, b)
    }
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn sub(a: __m256, b: __m256) -> __m256 {
        _mm256_sub_ps(a, b)
    }
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn mul(a: __m256, b: __m256) -> __m256 {
        _mm256_mul_ps(a, b)
    }

    /// `perlin::fade`, in its order of operations.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn fade(t: __m256) -> __m256 {
        let inner = add(mul(t, sub(mul(t, _mm256_set1_ps(6.0)), _mm256_set1_ps(15.0))), _mm256_set1_ps(10.0));
        mul(mul(mul(t, t), t), inner)
    }

    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn noise3_x8(x: f32, y: f32, z: f32, freqs: &[f32; LANES]) -> [f32; LANES] {
        let f = _mm256_loadu_ps(freqs.as_ptr());
        let (xi, fx) = lattice(mul(_mm256_set1_ps(x), f));
        let (yi, fy) = lattice(mul(_mm256_set1_ps(y), f));
        let (zi, fz) = lattice(mul(_mm256_set1_ps(z), f));
        let m511 = _mm256_set1_epi32(511);
        let idx = |p: __m256i, q: __m256i| _mm256_and_si256(_mm256_add_epi32(p, q), m511);
        // a[i] = P[xs[i]]; b[a + 2b] = P[(a[a] + ys[b]) & 511], both
        // neighbours of each from one gather (`PAIR`).
        let a = perm2(xi);
        let (b0, b2) = perm2(idx(a.0, yi));
        let (b1, b3) = perm2(idx(a.1, yi));
        let b = [b0, b1, b2, b3];
        let zero = _mm256_setzero_ps();
        let one = _mm256_set1_ps(1.0);
        // The scalar code subtracts the corner as a float, 0.0 included
        // (which keeps −0.0 as it is and NaN as NaN).
        let dx = [sub(fx, zero), sub(fx, one)];
        let dy = [sub(fy, zero), sub(fy, one)];
        let dz = [sub(fz, zero), sub(fz, one)];
        let mut n = [zero; 8];
        for k in 0..4 {
            let (ca, cb) = (k & 1, k >> 1);
            let (h0, h1) = perm2(idx(b[k], zi));
            n[k] = corner(h0, dx[ca], dy[cb], dz[0]);
            n[k + 4] = corner(h1, dx[ca], dy[cb], dz[1]);
        }
        let [n000, n100, n010, n110, n001, n101, n011, n111] = n;
        let neg = |v: __m256| _mm256_xor_ps(v, _mm256_set1_ps(-0.0));
        // perlin::ramp_coefficients, left to right as written there.
        let k0 = n000;
        let k1 = sub(n100, n000);
        let k2 = sub(n010, n000);
        let k3 = sub(n001, n000);
        let k4 = add(sub(sub(n000, n100), n010), n110);
        let k5 = add(sub(sub(n000, n010), n001), n011);
        let k6 = add(sub(sub(n000, n100), n001), n101);
        let k7 = add(sub(sub(add(sub(add(add(neg(n000), n100), n010), n110), n001), n101), n011), n111);
        // perlin::blend3.
        let (u, v, w) = (fade(fx), fade(fy), fade(fz));
        let mut s = add(k0, mul(k1, u));
        s = add(s, mul(k2, v));
        s = add(s, mul(k3, w));
        s = add(s, mul(mul(k4, u), v));
        s = add(s, mul(mul(k5, v), w));
        s = add(s, mul(mul(k6, w), u));
        s = add(s, mul(mul(mul(k7, u), v), w));
        let mut out = [0.0f32; LANES];
        _mm256_storeu_ps(out.as_mut_ptr(), s);
        out
    }

    /// `perlin::noise3` at one point: lane `a + 2b + 4c` is corner
    /// `(a, b, c)`, then the scalar code's blend.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn noise3_one(x: f32, y: f32, z: f32) -> f32 {
        // `lattice` on the three coordinates at once (lane 3 unused).
        let v = _mm_setr_ps(x, y, z, 0.0);
        let fl = _mm_floor_ps(v);
        let big = _mm_castps_si128(_mm_cmpge_ps(fl, _mm_set1_ps(2_147_483_648.0)));
        let i = _mm_and_si128(_mm_or_si128(_mm_cvttps_epi32(fl), big), _mm_set1_epi32(255));
        let f = _mm_sub_ps(v, fl);
        let (xi, yi, zi) = (_mm_cvtsi128_si32(i), _mm_extract_epi32::<1>(i), _mm_extract_epi32::<2>(i));
        let mut fs = [0.0f32; 4];
        _mm_storeu_ps(fs.as_mut_ptr(), f);
        let [fx, fy, fz, _] = fs;
        // The hashes through `PAIR` (see there): each entry also serves the
        // neighbour one cell further along the axis. Every index is at most
        // 255 + 255, inside the table.
        let pair = |i: i32| PAIR[i as usize & 511];
        let (lo, hi) = (|w: i32| w & 0xffff, |w: i32| w >> 16);
        let wx = pair(xi);
        let (wy0, wy1) = (pair(lo(wx) + yi), pair(hi(wx) + yi));
        let w =
            _mm_setr_epi32(pair(lo(wy0) + zi), pair(lo(wy1) + zi), pair(hi(wy0) + zi), pair(hi(wy1) + zi));
        let h = _mm256_set_m128i(_mm_srli_epi32::<16>(w), _mm_and_si128(w, _mm_set1_epi32(0xffff)));
        // `fx - a as f32` per corner, 0.0 subtracted too (as the scalar code does).
        let corner_of = |t: f32, c: __m256| sub(_mm256_set1_ps(t), c);
        let dx = corner_of(fx, _mm256_setr_ps(0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0));
        let dy = corner_of(fy, _mm256_setr_ps(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0));
        let dz = corner_of(fz, _mm256_setr_ps(0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0));
        let mut n = [0.0f32; 8];
        _mm256_storeu_ps(n.as_mut_ptr(), corner(h, dx, dy, dz));
        perlin::blend3(perlin::ramp_coefficients(n), perlin::fade(fx), perlin::fade(fy), perlin::fade(fz))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::perlin::noise3_scalar;
    use crate::noise::testutil::Lcg;

    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    fn check(x: f32, y: f32, z: f32, freqs: &[f32; LANES]) {
        let got = noise3_octaves(x, y, z, freqs);
        for (k, f) in freqs.iter().enumerate() {
            let (fx, fy, fz) = (x * f, y * f, z * f);
            let want = noise3_scalar(fx, fy, fz);
            assert!(same(got[k], want), "lane {k} at ({x}, {y}, {z})·{f}: {} vs {want}", got[k]);
            // The one-point noise, corners in lanes.
            let one = noise3(fx, fy, fz);
            assert!(same(one, want), "one point ({fx}, {fy}, {fz}): {one} vs {want}");
        }
    }

    #[test]
    fn lanes_equal_the_scalar_noise_bit_for_bit() {
        let mut rng = Lcg::new(11);
        let octave_freqs = |lac: f32| {
            let mut f = [0.0f32; LANES];
            let mut q = 1.0f32;
            for slot in &mut f {
                *slot = q;
                q *= lac;
            }
            f
        };
        for lac in [2.0, 1.9, 2.17, 3.0, 0.5] {
            let freqs = octave_freqs(lac);
            for _ in 0..20_000 {
                let [x, y, z, _] = rng.point4(-300.0, 300.0);
                check(x, y, z, &freqs);
            }
        }
        // Lattice points, cell edges, negative zero and the saturating cast's
        // corners (2³¹ and beyond, the infinities, NaN).
        let special = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            0.5,
            255.0,
            256.0,
            -256.5,
            8_388_607.5,
            8_388_608.0,
            2_147_483_520.0,
            2_147_483_648.0,
            -2_147_483_648.0,
            3.0e9,
            -3.0e9,
            1e30,
            -1e30,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let freqs = [1.0, 2.0, 0.0, -1.0, 0.5, 1e-30, 3.0e9, f32::INFINITY];
        for &x in &special {
            for &y in &special {
                for &z in &[0.25f32, -0.0, 1e30, f32::NAN, 2_147_483_648.0] {
                    check(x, y, z, &freqs);
                    check(x, y, z, &octave_freqs(2.0));
                }
            }
        }
    }
    /// The fractal sums one octave after another, without lanes: the
    /// reference the lane code must match.
    fn plain(x: f32, y: f32, z: f32, octaves: u32, lac: f32, gain: f32, fold: bool) -> f32 {
        let (mut sum, mut freq, mut amp) = (0.0f32, 1.0f32, 1.0f32);
        for _ in 0..octaves.min(crate::noise::fractal::MAX_OCTAVES) {
            let n = noise3(x * freq, y * freq, z * freq);
            sum += amp * if fold { n.abs() } else { n };
            freq *= lac;
            amp *= gain;
        }
        sum
    }

    #[test]
    fn fractal_sums_keep_their_bits_at_every_octave_count() {
        use crate::noise::fractal::{fbm3, turbulence3};
        let mut rng = Lcg::new(12);
        for octaves in 0..=20 {
            for _ in 0..2_000 {
                let [x, y, z, g] = rng.point4(-50.0, 50.0);
                let (lac, gain) = (1.5 + (g + 50.0) / 50.0, g / 60.0);
                let t = turbulence3(x, y, z, octaves, lac, gain);
                assert!(
                    same(t, plain(x, y, z, octaves, lac, gain, true)),
                    "turbulence {octaves} at {x} {y} {z}"
                );
                let f = fbm3(x, y, z, octaves, lac, gain);
                assert!(same(f, plain(x, y, z, octaves, lac, gain, false)), "fbm {octaves} at {x} {y} {z}");
            }
        }
    }
}
