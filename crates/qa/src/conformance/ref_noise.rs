//! The course's own noise, measured where it rendered one scene twice.
//!
//! The hw7 folder holds the course's 2020 and 2022 renders of the same path
//! and direct-lighting scenes, each at the scene's `NumSamples`, with
//! independent random numbers. Their difference is pure course noise, so it
//! measures the variance of the reference's block means directly, at the
//! reference's own count and with the reference's own sampler, instead of
//! assuming it is [`REF_NOISE_PER_SAMPLE`](super::noise::REF_NOISE_PER_SAMPLE)
//! times ours: an assumption that fails whenever our sampler improves
//! (a stratified sequence lowers our variance, never the course's).
//!
//! Per block of `k`×`k` pixels and channel, `s = Σ (a − b)² / (2 n²)` (n =
//! k² pixels) is the block mean's variance if the pixels' errors are
//! independent: n degrees of freedom, local. The course's errors are not
//! quite independent (neighbouring pixels' differences correlate by 0.1–0.2
//! on `cornellbox_jaroslav_glossy_area_sphere`, whose block means then vary
//! 3× more than `s` says), so `s` is scaled by one factor per image,
//! `κ = median(d² / s) / median(χ²₁)` over the block-channels, where `d² =
//! (m_a − m_b)² / 2` is the one-degree-of-freedom estimate from the block
//! means themselves. The median keeps a region where the two years' scenes
//! differ (a changed index of refraction) from inflating κ; κ is at least 1,
//! since `s` is what independent pixels give and a renderer that draws each
//! pixel's samples on its own cannot do better than that.
//!
//! The two years' XML files are not always the same scene (`path_glass`
//! gained a point light and changed its glass's index in 2022; `diffuse.exr`
//! switched to cosine sampling), so the suite uses a pair only where the two
//! images agree under the measured noise: see [`RefNoise::agreement`].

use super::noise::{luminance, BlockZ, NoiseModel};
use luster_core::image::Rgb32Image;

/// Median of χ² with one degree of freedom: the median of z² for a unit
/// normal z.
const CHI2_1_MEDIAN: f64 = 0.454_936_4;

/// The variance of each block mean of one course image, measured from two.
#[derive(Clone, Debug, PartialEq)]
pub struct RefNoise {
    /// Block edge in pixels.
    pub block: u32,
    /// Image size.
    pub size: (u32, u32),
    /// The correlation factor κ applied (see the module documentation).
    pub kappa: f64,
    /// Variance of each block-channel mean of one image, row-major blocks,
    /// three channels each, κ applied.
    variance: Vec<f64>,
    /// Per block, `κ Σ (Y_a − Y_b)² / 2`: the variance one image's pixels
    /// add to the sum of its luminance.
    luminance: Vec<f64>,
}

impl RefNoise {
    /// Measures the noise of two renders of one scene at one count, in
    /// `block`×`block` blocks. `None` when the sizes differ or no block fits.
    pub fn measure(a: &Rgb32Image, b: &Rgb32Image, block: u32) -> Option<RefNoise> {
        let k = block.max(1);
        let (bw, bh) = (a.width / k, a.height / k);
        let same = (a.width, a.height) == (b.width, b.height) && a.pixels.len() == b.pixels.len();
        if !same || bw == 0 || bh == 0 || a.pixels.len() != (a.width * a.height) as usize {
            return None;
        }
        let n = f64::from(k * k);
        let mut variance = Vec::with_capacity((bw * bh * 3) as usize);
        let mut luminance_var = Vec::with_capacity((bw * bh) as usize);
        let mut ratios = Vec::with_capacity((bw * bh * 3) as usize);
        for by in 0..bh {
            for bx in 0..bw {
                let (mut sq, mut diff, mut lum) = ([0.0f64; 3], [0.0f64; 3], 0.0);
                for y in by * k..(by + 1) * k {
                    for x in bx * k..(bx + 1) * k {
                        let i = (y * a.width + x) as usize;
                        for c in 0..3 {
                            let d = finite(a.pixels[i][c]) - finite(b.pixels[i][c]);
                            sq[c] += d * d;
                            diff[c] += d;
                        }
                        lum += (luminance(a.pixels[i]) - luminance(b.pixels[i])).powi(2);
                    }
                }
                for c in 0..3 {
                    let s = sq[c] / (2.0 * n * n);
                    if s > 0.0 {
                        ratios.push((diff[c] / n).powi(2) / 2.0 / s);
                    }
                    variance.push(s);
                }
                luminance_var.push(lum / 2.0);
            }
        }
        let kappa = (median(&mut ratios) / CHI2_1_MEDIAN).max(1.0);
        variance.iter_mut().for_each(|v| *v *= kappa);
        luminance_var.iter_mut().for_each(|v| *v *= kappa);
        Some(RefNoise { block: k, size: (a.width, a.height), kappa, variance, luminance: luminance_var })
    }

    /// The variance of block `(bx, by)`'s mean in channel `c`.
    pub(super) fn variance(&self, bx: u32, by: u32, c: usize) -> f64 {
        self.variance[((by * (self.size.0 / self.block) + bx) * 3) as usize + c]
    }

    /// What block `(bx, by)` adds to the variance of the sum of one image's
    /// luminance.
    pub(super) fn luminance_variance(&self, bx: u32, by: u32) -> f64 {
        self.luminance[(by * (self.size.0 / self.block) + bx) as usize]
    }

    /// Whether this noise fits a judgement of `width`×`height` images in
    /// `block`-pixel blocks.
    pub(super) fn fits(&self, width: u32, height: u32, block: u32) -> bool {
        self.size == (width, height) && self.block == block
    }

    /// The two measured images judged against each other with this noise
    /// (`z = (m_a − m_b) / sqrt(2 V + floor²)`): pure noise passes the
    /// suite's bar; a pair of images of different scenes does not, and then
    /// the pair cannot stand for the reference's noise. `None` when `a` and
    /// `b` do not fit this measurement or the model's blocks.
    pub fn agreement(&self, a: &Rgb32Image, b: &Rgb32Image, model: &NoiseModel) -> Option<BlockZ> {
        super::noise::judge(a, None, b, model, Some(self))
    }
}

/// The reference's noise measured from `other`, a second course render of
/// `reference`'s scene at its count, when the two agree within it under the
/// suite's noise-aware bar (see [`RefNoise::agreement`]); `None` otherwise,
/// and the judgement falls back to scaling ours.
pub fn measured_if_agreeing(
    reference: &Rgb32Image,
    other: &Rgb32Image,
    model: &NoiseModel,
) -> Option<RefNoise> {
    let noise = RefNoise::measure(reference, other, model.block)?;
    let agree = noise.agreement(other, reference, model)?;
    super::STOCHASTIC.bar_in(model.space).z_ok(Some(&agree)).then_some(noise)
}

fn finite(v: f32) -> f64 {
    if v.is_finite() {
        f64::from(v)
    } else {
        0.0
    }
}

/// Median of `v` (reordered); 0 when empty.
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::conformance::noise::{block_z, block_z_measured};

    /// Uniform noise of amplitude `amp` around 1.0, from a fixed generator;
    /// with `cell` > 1 every `cell`×`cell` group of pixels shares one draw
    /// (noise correlated between neighbours, as the course's sphere-light
    /// renders have it).
    fn noisy(seed: u64, amp: f32, cell: u32) -> Rgb32Image {
        let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut draws = (0..128 * 128)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 33) as f64 / f64::from(1u32 << 31)) as f32 - 0.5
            })
            .collect::<Vec<_>>();
        if cell > 1 {
            draws =
                (0..128 * 128).map(|i| draws[((i / 128) / cell * 128 + (i % 128) / cell) as usize]).collect();
        }
        let pixels = draws.iter().map(|d| [1.0 + amp * d; 3]).collect();
        Rgb32Image { width: 128, height: 128, pixels, encoding: luster_core::image::Encoding::Linear }
    }

    fn model(reference: &Rgb32Image, spp: u32, ref_spp: u32) -> NoiseModel {
        NoiseModel { relative_floor: 0.0, ..NoiseModel::linear(spp, ref_spp, reference) }
    }

    #[test]
    fn independent_noise_needs_no_correction_and_two_renders_agree() {
        let (a, b) = (noisy(1, 0.4, 1), noisy(2, 0.4, 1));
        let m = model(&a, 100, 100);
        let n = RefNoise::measure(&a, &b, m.block).unwrap();
        assert!(n.kappa < 1.3, "{n:?}");
        let z = n.agreement(&a, &b, &m).unwrap();
        assert!(z.mean_z2 > 0.6 && z.mean_z2 < 1.5 && z.outliers == 0.0, "{z:?}");
        assert!(measured_if_agreeing(&a, &b, &m).is_some());
        assert_eq!(RefNoise::measure(&a, &noisy(3, 0.4, 1), 200), None);
    }

    #[test]
    fn correlated_pixels_are_measured_by_the_block_means() {
        // 2×2 pixels share each draw: a block mean varies 4× more than
        // independent pixels of the same variance would make it.
        let (a, b) = (noisy(1, 0.4, 2), noisy(2, 0.4, 2));
        let m = model(&a, 100, 100);
        let n = RefNoise::measure(&a, &b, m.block).unwrap();
        assert!(n.kappa > 2.5 && n.kappa < 6.0, "{n:?}");
        let z = n.agreement(&a, &b, &m).unwrap();
        assert!(z.mean_z2 < 2.0 && z.outliers == 0.0, "{z:?}");
    }

    #[test]
    fn two_years_of_different_scenes_do_not_stand_for_noise() {
        let (a, b) = (noisy(1, 0.4, 1), noisy(2, 0.4, 1));
        // One quarter 5% brighter in the second image: about 5 of the
        // noise's standard deviations per block.
        let pixels = b.pixels.iter().enumerate().map(|(i, p)| {
            if i % 128 < 64 && i / 128 < 64 {
                p.map(|v| v * 1.05)
            } else {
                *p
            }
        });
        let other = Rgb32Image { pixels: pixels.collect(), ..b.clone() };
        let m = model(&a, 100, 100);
        assert!(measured_if_agreeing(&a, &other, &m).is_none());
    }

    #[test]
    fn a_less_noisy_render_is_judged_against_the_references_own_noise() {
        // Ours at the reference's count, with a quarter of its variance (a
        // well-stratified sampler against independent samples): the scaled
        // rule (`REF_NOISE_PER_SAMPLE`) takes the reference's variance as 4×
        // ours, so exactly as large as it is, and a sampler twice as good
        // again breaks it; the measured noise does not depend on ours at all.
        let (r, r2) = (noisy(1, 0.4, 1), noisy(2, 0.4, 1));
        let (a, b) = (noisy(3, 0.2, 1), noisy(4, 0.2, 1));
        let (a2, b2) = (noisy(3, 0.1, 1), noisy(4, 0.1, 1));
        let m = model(&r, 100, 100);
        let course = RefNoise::measure(&r, &r2, m.block).unwrap();
        for (x, y) in [(&a, &b), (&a2, &b2)] {
            let z = block_z_measured(x, y, &r, &m, &course).unwrap();
            assert!(z.mean_z2 < 1.5 && z.outliers == 0.0 && z.ref_measured, "{z:?}");
        }
        let old = block_z(&a2, &b2, &r, &m).unwrap();
        assert!(old.mean_z2 > 2.0, "{old:?}");
        // Ours 2% too bright: 2.5 standard deviations of each block's
        // difference, and 8 of the mean luminance's (its floored error).
        let bright = |img: &Rgb32Image| Rgb32Image {
            pixels: img.pixels.iter().map(|p| p.map(|v| v * 1.02)).collect(),
            ..img.clone()
        };
        let z = block_z_measured(&bright(&a), &bright(&b), &r, &m, &course).unwrap();
        assert!(z.mean_z2 > 4.0 && z.luminance_z > 6.0, "{z:?}");
        assert_eq!(block_z_measured(&a, &b, &r, &NoiseModel { block: 8, ..m }, &course), None);
    }
}
