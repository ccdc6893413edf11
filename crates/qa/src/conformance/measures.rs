//! What the conformance bars measure besides PSNR, FLIP and the noise
//! judgement of [`noise`](super::noise): the PSNR of 8×8 block means (shown
//! in reports), and the luma statistics of images that can only match in
//! look (see `thresholds.rs`).

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
    pub fn of(
        ours: &luster_core::image::Rgb32Image,
        reference: &luster_core::image::Rgb32Image,
    ) -> StatsPair {
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
pub fn coarse_psnr(a: &luster_core::image::Rgb32Image, b: &luster_core::image::Rgb32Image) -> Option<f64> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use luster_core::image::Rgb32Image;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Rgb32Image {
        let pixels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| [f(x, y); 3]).collect();
        Rgb32Image { width: w, height: h, pixels, encoding: luster_core::image::Encoding::Srgb }
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
}
