//! What the conformance bars measure besides PSNR and FLIP: per-block
//! z-scores of a multi-sample image against the reference, with the variance
//! taken from a second render with another seed; the PSNR of 8×8 block means
//! (shown in reports); and the luma statistics of images that can only match
//! in look (see `thresholds.rs`).

/// Edge of the blocks whose means the coarse test compares: 8×8 pixels cut
/// uncorrelated noise by 64× in variance (18 dB) and still resolve a bias
/// confined to a tenth of an 800-pixel image.
pub const COARSE: u32 = 8;

/// Luma statistics of an image's non-black pixels (Rec. 709 weights on
/// display values, 0–1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageStats {
    /// Mean luma.
    pub mean: f64,
    /// Standard deviation of luma: the image's contrast.
    pub contrast: f64,
}

/// Our image's statistics beside the reference's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StatsPair {
    /// Ours.
    pub ours: ImageStats,
    /// The reference's.
    pub reference: ImageStats,
}

impl StatsPair {
    /// Statistics of two same-size images over the pixels where either is
    /// not black: the textured surfaces, not the empty background whose
    /// share would otherwise dominate both numbers.
    pub fn of(ours: &crate::image::Rgb32Image, reference: &crate::image::Rgb32Image) -> StatsPair {
        let luma =
            |p: &[f32; 3]| 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
        let pairs: Vec<(f64, f64)> = ours
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| (luma(a), luma(b)))
            .filter(|(a, b)| a.max(*b) > 0.5 / 255.0)
            .collect();
        let n = pairs.len().max(1) as f64;
        let stats = |pick: fn(&(f64, f64)) -> f64| {
            let mean = pairs.iter().map(pick).sum::<f64>() / n;
            let var = pairs.iter().map(|p| (pick(p) - mean).powi(2)).sum::<f64>() / n;
            ImageStats { mean, contrast: var.sqrt() }
        };
        StatsPair { ours: stats(|p| p.0), reference: stats(|p| p.1) }
    }

    /// Absolute difference of the means.
    pub fn mean_diff(&self) -> f64 {
        (self.ours.mean - self.reference.mean).abs()
    }

    /// Relative difference of the contrasts.
    pub fn contrast_diff(&self) -> f64 {
        (self.ours.contrast - self.reference.contrast).abs() / self.reference.contrast.max(1e-6)
    }
}

/// PSNR (peak 1) between the means of `COARSE`×`COARSE` blocks of two
/// same-size images; a partial block at the right or bottom edge is dropped.
/// `None` when the sizes differ or no whole block fits.
pub fn coarse_psnr(a: &crate::image::Rgb32Image, b: &crate::image::Rgb32Image) -> Option<f64> {
    if (a.width, a.height) != (b.width, b.height) || a.pixels.len() != b.pixels.len() {
        return None;
    }
    let (bw, bh) = (a.width / COARSE, a.height / COARSE);
    if bw == 0 || bh == 0 {
        return None;
    }
    let mut sum_sq = 0.0f64;
    for by in 0..bh {
        for bx in 0..bw {
            let mut d = [0.0f64; 3];
            for y in by * COARSE..(by + 1) * COARSE {
                for x in bx * COARSE..(bx + 1) * COARSE {
                    let i = (y * a.width + x) as usize;
                    for (c, dc) in d.iter_mut().enumerate() {
                        *dc += f64::from(a.pixels[i][c]) - f64::from(b.pixels[i][c]);
                    }
                }
            }
            let n = f64::from(COARSE * COARSE);
            sum_sq += d.iter().map(|v| (v / n).powi(2)).sum::<f64>();
        }
    }
    let mse = sum_sq / (3.0 * f64::from(bw * bh));
    Some(if mse > 0.0 { -10.0 * mse.log10() } else { f64::INFINITY })
}

/// Per-block z-scores of our image against the reference (see [`block_z`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockZ {
    /// Mean of z² over every block and channel: 1 plus the reference's share
    /// of the noise for an unbiased image, more where a bias adds to it.
    pub mean_z2: f64,
    /// Share of blocks and channels with |z| > [`Z_OUTLIER`]: a local bias.
    pub outliers: f64,
    /// Largest |z|.
    pub max_abs_z: f64,
    /// Blocks × channels tested.
    pub count: usize,
}

/// |z| beyond which a block counts as an outlier: a normal variable passes
/// it with probability 6·10⁻⁷, so even 30,000 blocks × 3 channels of pure
/// noise expect less than one.
pub const Z_OUTLIER: f64 = 5.0;

/// Smallest standard deviation of a block mean, in 8-bit levels: both images
/// are rounded to 8 bits, so even a converged block may differ by about
/// half a level without any bias.
const Z_FLOOR_LEVELS: f64 = 0.5;

/// Per-block z-scores of `ours` against `reference`, judged by our own noise.
///
/// For each `COARSE`×`COARSE` block and channel, `z = (m_ours − m_ref) / σ`
/// with `m` the block means. Our per-pixel noise is measured by `second`,
/// the same render with another seed: `(a − a')²/2` estimates a pixel's
/// variance, so `Σ (a − a')² / (2 n²)` estimates the variance of the block
/// mean of `n` pixels, at exactly the sample count rendered. The reference
/// is a Monte Carlo estimate too, with its own noise that we cannot measure:
/// it is taken as ours scaled by `ref_variance_ratio` (its per-sample
/// variance relative to ours times our sample count over its count).
/// `σ² = σ²_ours (1 + ref_variance_ratio) + floor²`, with a floor of half an
/// 8-bit level. Noise alone gives z ~ N(0, 1); a bias gives large |z| where it
/// is, however few samples were rendered. `None` when the sizes differ or no
/// whole block fits.
pub fn block_z(
    ours: &crate::image::Rgb32Image,
    second: &crate::image::Rgb32Image,
    reference: &crate::image::Rgb32Image,
    ref_variance_ratio: f64,
) -> Option<BlockZ> {
    let same = |b: &crate::image::Rgb32Image| {
        (b.width, b.height) == (ours.width, ours.height) && b.pixels.len() == ours.pixels.len()
    };
    if !same(second) || !same(reference) {
        return None;
    }
    let (bw, bh) = (ours.width / COARSE, ours.height / COARSE);
    if bw == 0 || bh == 0 {
        return None;
    }
    let n = f64::from(COARSE * COARSE);
    let floor2 = (Z_FLOOR_LEVELS / 255.0).powi(2);
    let (mut sum_z2, mut outliers, mut max_abs_z, mut count) = (0.0, 0usize, 0.0f64, 0usize);
    for by in 0..bh {
        for bx in 0..bw {
            let (mut diff, mut noise) = ([0.0f64; 3], [0.0f64; 3]);
            for y in by * COARSE..(by + 1) * COARSE {
                for x in bx * COARSE..(bx + 1) * COARSE {
                    let i = (y * ours.width + x) as usize;
                    for c in 0..3 {
                        let a = f64::from(ours.pixels[i][c]);
                        diff[c] += a - f64::from(reference.pixels[i][c]);
                        noise[c] += (a - f64::from(second.pixels[i][c])).powi(2);
                    }
                }
            }
            for c in 0..3 {
                let var_ours = noise[c] / (2.0 * n * n);
                let z = (diff[c] / n) / (var_ours * (1.0 + ref_variance_ratio) + floor2).sqrt();
                sum_z2 += z * z;
                outliers += usize::from(z.abs() > Z_OUTLIER);
                max_abs_z = max_abs_z.max(z.abs());
                count += 1;
            }
        }
    }
    Some(BlockZ {
        mean_z2: sum_z2 / count as f64,
        outliers: outliers as f64 / count as f64,
        max_abs_z,
        count,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Rgb32Image;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Rgb32Image {
        let pixels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| [f(x, y); 3]).collect();
        Rgb32Image { width: w, height: h, pixels, encoding: crate::image::Encoding::Srgb }
    }

    #[test]
    fn block_means_see_a_bias_and_not_noise() {
        let base = image(32, 24, |x, y| 0.2 + 0.01 * (x + y) as f32);
        // ±6/255 of checkerboard noise: a poor full-resolution PSNR, but it
        // averages out over every 8×8 block.
        let noisy = image(32, 24, |x, y| {
            0.2 + 0.01 * (x + y) as f32 + if (x + y) % 2 == 0 { 0.0235 } else { -0.0235 }
        });
        assert!(coarse_psnr(&base, &noisy).is_some_and(|p| p > 80.0));
        // A uniform 2/255 offset is a bias: it stays, at 20·log10(255/2) dB.
        let biased = image(32, 24, |x, y| 0.2 + 0.01 * (x + y) as f32 + 2.0 / 255.0);
        let p = coarse_psnr(&base, &biased).unwrap_or(f64::INFINITY);
        assert!((p - 42.1).abs() < 0.1, "{p}");
        assert_eq!(coarse_psnr(&base, &image(4, 4, |_, _| 0.0)), None);
    }

    #[test]
    fn block_z_scores_find_a_bias_that_noise_does_not_hide() {
        // Two seeds of a noisy flat grey: a pseudo-random ±20-level noise per pixel.
        let mut state = 7u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / f64::from(1u32 << 31)) as f32 - 0.5
        };
        let mut noisy = || {
            let v: Vec<f32> = (0..64 * 64).map(|_| 0.5 + 40.0 / 255.0 * rnd()).collect();
            image(64, 64, move |x, y| v[(y * 64 + x) as usize])
        };
        let (a, b, reference) = (noisy(), noisy(), noisy());
        let z = block_z(&a, &b, &reference, 1.0).unwrap();
        assert_eq!(z.count, 64 * 3);
        assert!(z.mean_z2 > 0.5 && z.mean_z2 < 1.6 && z.outliers == 0.0, "{z:?}");
        // The same noise on a reference 4 levels darker in one quarter: a bias
        // of about twice the block mean's noise there (σ ≈ 2 levels).
        let biased = image(64, 64, |x, y| {
            let i = (y * 64 + x) as usize;
            reference.pixels[i][0] - if x < 32 && y < 32 { 4.0 / 255.0 } else { 0.0 }
        });
        let zb = block_z(&a, &b, &biased, 1.0).unwrap();
        assert!(zb.mean_z2 > z.mean_z2 + 0.6, "{zb:?} against {z:?}");
        assert_eq!(block_z(&a, &b, &image(8, 8, |_, _| 0.0), 1.0), None);
    }
}
