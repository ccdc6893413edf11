//! Judging a Monte Carlo image against the course's by its noise: per-block
//! z-scores with the variance measured by a second render with another seed,
//! and the mean luminance in standard errors. The suite (for every
//! multi-sample image: hw3, hw4, hw7) and the golden tests use this one
//! implementation.
//!
//! For each block of `block`×`block` pixels and each channel,
//! `z = (m_ours − m_ref) / σ` with `m` the block means. Our per-pixel noise
//! is measured by `second`, the same render with the next seed:
//! `(a − a')²/2` estimates a pixel's variance, so `Σ (a − a')² / (2 n²)`
//! estimates the variance of the block mean of `n` pixels, at exactly the
//! sample count rendered. The course's image is a Monte Carlo estimate too,
//! at its own count. Where the course rendered the scene twice (hw7's 2020
//! and 2022 images) its block variance `σ²_ref` is measured from the two
//! ([`RefNoise`], [`block_z_measured`]); from one image it cannot be, and it
//! is taken as ours scaled by [`ref_variance_ratio`]: `σ²_ref = ratio ·
//! σ²_ours`. So `σ² = σ²_ours + σ²_ref + floor²`. Noise
//! alone gives `z ~ N(0, 1)` whatever the count; a bias — a light of the
//! wrong size, a wrong pdf, a misplaced object — adds `(bias/σ)²` to z²
//! where it is, and shows at any count.
//!
//! The mean luminance (Rec. 709 weights) over the judged blocks is tested
//! the same way: its standard error is `sqrt(Σ (Y − Y')² / 2 · (1 + ratio)) /
//! N` over their `N` pixels, so a global bias too small for any block (light
//! counted twice at one bounce, a lost factor of a BSDF) still shows. That
//! error is floored (below), since a stratified render of a mostly smooth
//! image can measure a standard error far below anything visible.
//!
//! Two spaces, by what the course's image holds:
//! * [`Space::Display`] — an 8-bit PNG (hw3, hw4): 8×8 blocks, and a floor
//!   of half an 8-bit level per block, because both images are truncated to
//!   8 bits, so even a converged block may differ by that without a bias;
//!   the mean luminance's standard error is floored at an eighth of a level,
//!   so that the 4-σ bar accepts half a level (the offset truncation alone
//!   can give: a noisy pixel truncates half a level down on average, a
//!   converged one by its own fraction). Blocks where the course's image is
//!   clipped at white and our two renders differ are left out: clamping a
//!   noisy estimate darkens it
//!   (`E[min(X, 1)] < min(E[X], 1)`), the more the fewer its samples, so a
//!   few-sample render is darker there for its count, not for its renderer.
//! * [`Space::Linear`] — the course's `.exr` beside its `.png` (hw7): linear
//!   radiance, 16×16 blocks (path-traced radiance is heavy-tailed, so a block
//!   mean needs more samples before it is near normal), a floor of 10⁻³ of
//!   the reference's mean luminance or [`LINEAR_RELATIVE_FLOOR`] of the
//!   block's own mean, whichever is larger; the mean luminance's standard
//!   error floored at 0.25% of the reference's, so the 4-σ bar accepts 1%.
//!   Noisy blocks showing a light are left out: a block where a reference
//!   pixel is above [`EMITTER_FACTOR`] times the mean luminance holds an
//!   emitter's edge, where a sub-pixel difference in where the edge falls outweighs
//!   all else and has no noise to excuse it. The tone-mapped `.png` is not
//!   judged so: the photographic operator's key and burn-out percentile are
//!   computed from the noisy image itself, so the course's 100-spp PNG and
//!   ours at a few spp are mapped by different curves.

pub use super::ref_noise::RefNoise;
use luster_core::image::Rgb32Image;

/// |z| beyond which a block counts as an outlier: a normal variable passes
/// it with probability 6·10⁻⁷, so even 30,000 blocks × 3 channels of pure
/// noise expect less than one.
pub const Z_OUTLIER: f64 = 5.0;

/// Block edge in display space.
pub const DISPLAY_BLOCK: u32 = 8;
/// Block edge in linear space.
pub const LINEAR_BLOCK: u32 = 16;
/// A reference pixel above this many times the reference's mean luminance
/// shows a light (linear space only). The hw7 Cornell boxes' lights are
/// 20–40× their image's mean; lit surfaces stay under 7×.
pub const EMITTER_FACTOR: f64 = 10.0;

/// Smallest standard deviation of a block mean in linear space, as a share
/// of the reference's block mean: where a wall meets the ceiling, or a
/// shadow's edge crosses a block, a sub-pixel difference between two
/// renderers (pixel filter, where a ray starts) biases the block by a
/// percent or so (the top corners of the hw7 Cornell boxes show it), which
/// no sample count removes and no eye sees.
pub const LINEAR_RELATIVE_FLOOR: f64 = 0.005;

/// The course references' variance per sample relative to ours, where only
/// one course image exists (hw3, hw4): measured at the course's full counts
/// on hw3 (1.2× on `cornellbox_area`, 2.5× on `metal_glass_plates`, 4× on
/// `spheres_dof`: our samples are stratified, the course's are not); the
/// largest, so a noisier reference is never mistaken for a bias. It ties the
/// bar to our sampler: a better-stratified one lowers ours, not the
/// course's. Where the course has two renders (hw7) their difference
/// measures it instead ([`RefNoise`]): 0.66–4.2× ours there.
pub const REF_NOISE_PER_SAMPLE: f64 = 4.0;

/// The reference's variance of a block mean relative to ours, for our render
/// of `spp` samples and the reference's `ref_spp`: a Monte Carlo estimate's
/// variance falls as one over its sample count, so the reference's is ours
/// times [`REF_NOISE_PER_SAMPLE`] times `spp / ref_spp`.
pub fn ref_variance_ratio(spp: u32, ref_spp: u32) -> f64 {
    REF_NOISE_PER_SAMPLE * f64::from(spp.max(1)) / f64::from(ref_spp.max(1))
}

/// What the values of the compared images are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Space {
    /// Display values in [0, 1] of 8-bit images.
    Display,
    /// Linear radiance.
    Linear,
}

impl Space {
    /// `display` or `linear`.
    pub fn name(self) -> &'static str {
        match self {
            Space::Display => "display",
            Space::Linear => "linear",
        }
    }
}

/// How noise is modelled for one comparison.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseModel {
    /// The space of the values.
    pub space: Space,
    /// Block edge in pixels.
    pub block: u32,
    /// The reference's variance relative to ours (see [`ref_variance_ratio`]).
    pub ref_ratio: f64,
    /// Smallest standard deviation of a block mean, in the images' units.
    pub floor: f64,
    /// Smallest standard deviation of a block mean as a share of the
    /// reference's block mean.
    pub relative_floor: f64,
    /// Reference values above this leave a block out of the judgement when
    /// our two renders differ in it: a light in linear space, white
    /// clipping in display space.
    pub left_out_above: f64,
    /// Smallest standard error of the mean luminance, in the images' units.
    pub mean_floor: f64,
    /// Smallest standard error of the mean luminance as a share of the
    /// reference's.
    pub relative_mean_floor: f64,
}

impl NoiseModel {
    /// For 8-bit images: our render of `spp` samples against a reference of
    /// `ref_spp`.
    pub fn display(spp: u32, ref_spp: u32) -> NoiseModel {
        NoiseModel {
            space: Space::Display,
            block: DISPLAY_BLOCK,
            ref_ratio: ref_variance_ratio(spp, ref_spp),
            floor: 0.5 / 255.0,
            relative_floor: 0.0,
            left_out_above: 254.5 / 255.0,
            mean_floor: 0.5 / 255.0 / 4.0,
            relative_mean_floor: 0.0,
        }
    }

    /// For linear radiance against `reference`.
    pub fn linear(spp: u32, ref_spp: u32, reference: &Rgb32Image) -> NoiseModel {
        let n = reference.pixels.len().max(1) as f64;
        let mean = reference.pixels.iter().map(|p| luminance(*p)).sum::<f64>() / n;
        let mean = if mean.is_finite() && mean > 0.0 { mean } else { 1.0 };
        NoiseModel {
            space: Space::Linear,
            block: LINEAR_BLOCK,
            ref_ratio: ref_variance_ratio(spp, ref_spp),
            floor: 1e-3 * mean,
            relative_floor: LINEAR_RELATIVE_FLOOR,
            left_out_above: EMITTER_FACTOR * mean,
            mean_floor: 0.0,
            relative_mean_floor: 0.01 / 4.0,
        }
    }
}

/// The verdict's numbers (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockZ {
    /// The space the images were compared in.
    pub space: Space,
    /// Block edge in pixels.
    pub block: u32,
    /// Mean of z² over every block and channel: 1 for an unbiased image,
    /// more where a bias adds to it.
    pub mean_z2: f64,
    /// Share of blocks and channels with |z| > [`Z_OUTLIER`]: a local bias.
    pub outliers: f64,
    /// Largest |z|.
    pub max_abs_z: f64,
    /// Blocks × channels tested.
    pub count: usize,
    /// Blocks left out: showing a light (linear), or clipped at white in
    /// the reference (display).
    pub left_out: usize,
    /// Our mean luminance minus the reference's, in standard errors.
    pub luminance_z: f64,
    /// Mean luminance of ours and of the reference.
    pub mean_luminance: [f64; 2],
    /// The reference's variance of a block mean relative to ours, summed
    /// over the judged blocks and channels, at the two counts compared.
    pub ref_variance: f64,
    /// Whether the reference's noise was measured from a second course
    /// render ([`RefNoise`]) rather than scaled from ours.
    pub ref_measured: bool,
}

/// Rec. 709 luminance of an RGB triple; non-finite values count as 0.
pub(super) fn luminance(p: [f32; 3]) -> f64 {
    let y = 0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2]);
    if y.is_finite() {
        y
    } else {
        0.0
    }
}

fn finite(v: f32) -> f64 {
    if v.is_finite() {
        f64::from(v)
    } else {
        0.0
    }
}

/// Judges `ours` against `reference` by the noise `second` (ours with the
/// next seed) measures, the reference's taken as ours scaled by the model's
/// `ref_ratio` (see the module documentation). `None` when the sizes differ
/// or no whole block fits.
pub fn block_z(
    ours: &Rgb32Image,
    second: &Rgb32Image,
    reference: &Rgb32Image,
    model: &NoiseModel,
) -> Option<BlockZ> {
    judge(ours, Some(second), reference, model, None)
}

/// [`block_z`] with the reference's own noise measured from a second course
/// render (see [`RefNoise`]) instead of scaled from ours. `None` also when
/// `course` was measured on other blocks or another size.
pub fn block_z_measured(
    ours: &Rgb32Image,
    second: &Rgb32Image,
    reference: &Rgb32Image,
    model: &NoiseModel,
    course: &RefNoise,
) -> Option<BlockZ> {
    judge(ours, Some(second), reference, model, Some(course))
}

/// The judgement: our block variance from `second`, or, without it, from
/// `course` (two images of the same renderer); the reference's from
/// `course`, or ours times the model's ratio.
pub(super) fn judge(
    ours: &Rgb32Image,
    second: Option<&Rgb32Image>,
    reference: &Rgb32Image,
    model: &NoiseModel,
    course: Option<&RefNoise>,
) -> Option<BlockZ> {
    let same = |b: &Rgb32Image| {
        (b.width, b.height) == (ours.width, ours.height) && b.pixels.len() == ours.pixels.len()
    };
    let k = model.block.max(1);
    let (bw, bh) = (ours.width / k, ours.height / k);
    let fits = course.is_none_or(|r| r.fits(ours.width, ours.height, k));
    if !second.is_none_or(same) || !same(reference) || bw == 0 || bh == 0 || !fits {
        return None;
    }
    if second.is_none() && course.is_none() {
        return None;
    }
    let n = f64::from(k * k);
    let (mut sum_z2, mut outliers, mut max_abs_z, mut count, mut left_out) =
        (0.0, 0usize, 0.0f64, 0usize, 0usize);
    let (mut var_ours_sum, mut var_ref_sum) = (0.0, 0.0);
    // Luminance sums over the judged blocks: ours, the reference's, and the
    // variances the two add to the sum of the luminance.
    let (mut lum_ours, mut lum_ref, mut lum_var, mut pixels) = (0.0, 0.0, 0.0, 0usize);
    for by in 0..bh {
        for bx in 0..bw {
            let (mut diff, mut noise, mut sum_ref) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
            let (mut la, mut lr, mut ln) = (0.0, 0.0, 0.0);
            let mut excluded = false;
            for y in by * k..(by + 1) * k {
                for x in bx * k..(bx + 1) * k {
                    let i = (y * ours.width + x) as usize;
                    for c in 0..3 {
                        let (a, r) = (finite(ours.pixels[i][c]), finite(reference.pixels[i][c]));
                        // Two images of one renderer are judged alike: a
                        // light (or a firefly) in either leaves the block out,
                        // so that leaving it out cannot favour one of them.
                        excluded |=
                            r > model.left_out_above || (second.is_none() && a > model.left_out_above);
                        diff[c] += a - r;
                        sum_ref[c] += r;
                        if let Some(s) = second {
                            noise[c] += (a - finite(s.pixels[i][c])).powi(2);
                        }
                    }
                    let a = luminance(ours.pixels[i]);
                    la += a;
                    lr += luminance(reference.pixels[i]);
                    if let Some(s) = second {
                        ln += (a - luminance(s.pixels[i])).powi(2);
                    }
                }
            }
            let var_ours: [f64; 3] = std::array::from_fn(|c| match (second, course) {
                (Some(_), _) => noise[c] / (2.0 * n * n),
                (None, Some(r)) => r.variance(bx, by, c),
                (None, None) => 0.0,
            });
            // Where the reference is clipped (or a light) but our block is
            // the same in both renders, there is no noise to excuse a
            // difference, and none to bias it: judged as any block.
            if excluded && var_ours.iter().any(|&v| v > 0.0) {
                left_out += 1;
                continue;
            }
            let lum_var_ours = if second.is_some() {
                ln / 2.0
            } else {
                course.map_or(0.0, |r| r.luminance_variance(bx, by))
            };
            let lum_var_ref = course.map_or(lum_var_ours * model.ref_ratio, |r| r.luminance_variance(bx, by));
            (lum_ours, lum_ref, lum_var, pixels) = (
                lum_ours + la,
                lum_ref + lr,
                lum_var + lum_var_ours + lum_var_ref,
                pixels + k as usize * k as usize,
            );
            for c in 0..3 {
                let var_ref = course.map_or(var_ours[c] * model.ref_ratio, |r| r.variance(bx, by, c));
                (var_ours_sum, var_ref_sum) = (var_ours_sum + var_ours[c], var_ref_sum + var_ref);
                let floor = model.floor.max(model.relative_floor * (sum_ref[c] / n).abs());
                let z = (diff[c] / n) / (var_ours[c] + var_ref + floor * floor).sqrt();
                sum_z2 += z * z;
                outliers += usize::from(z.abs() > Z_OUTLIER);
                max_abs_z = max_abs_z.max(z.abs());
                count += 1;
            }
        }
    }
    let m = pixels.max(1) as f64;
    let (mean_ours, mean_ref) = (lum_ours / m, lum_ref / m);
    let floor = model.mean_floor.max(model.relative_mean_floor * mean_ref.abs());
    let se = (lum_var.sqrt() / m).max(floor);
    Some(BlockZ {
        space: model.space,
        block: k,
        mean_z2: if count == 0 { 0.0 } else { sum_z2 / count as f64 },
        outliers: if count == 0 { 0.0 } else { outliers as f64 / count as f64 },
        max_abs_z,
        count,
        left_out,
        luminance_z: (mean_ours - mean_ref) / se,
        mean_luminance: [mean_ours, mean_ref],
        ref_variance: if var_ours_sum > 0.0 { var_ref_sum / var_ours_sum } else { 0.0 },
        ref_measured: course.is_some(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> Rgb32Image {
        let pixels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| [f(x, y); 3]).collect();
        Rgb32Image { width: w, height: h, pixels, encoding: luster_core::image::Encoding::Srgb }
    }

    /// A noisy flat grey, ±20 levels per pixel from a fixed generator.
    fn noisy_images(count: usize) -> Vec<Rgb32Image> {
        let mut state = 7u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / f64::from(1u32 << 31)) as f32 - 0.5
        };
        (0..count)
            .map(|_| {
                let v: Vec<f32> = (0..64 * 64).map(|_| 0.5 + 40.0 / 255.0 * rnd()).collect();
                image(64, 64, move |x, y| v[(y * 64 + x) as usize])
            })
            .collect()
    }

    #[test]
    fn noise_alone_gives_unit_z_and_a_bias_does_not() {
        let v = noisy_images(3);
        let (a, b, reference) = (&v[0], &v[1], &v[2]);
        let model = NoiseModel { ref_ratio: 1.0, ..NoiseModel::display(4, 4) };
        let z = block_z(a, b, reference, &model).unwrap();
        assert_eq!((z.count, z.left_out), (64 * 3, 0));
        assert!(z.mean_z2 > 0.5 && z.mean_z2 < 1.6 && z.outliers == 0.0, "{z:?}");
        assert!(z.luminance_z.abs() < 4.0, "{z:?}");
        // The same noise on a reference 4 levels darker in one quarter: a bias
        // of about twice the block mean's noise there (σ ≈ 2 levels).
        let biased = image(64, 64, |x, y| {
            let i = (y * 64 + x) as usize;
            reference.pixels[i][0] - if x < 32 && y < 32 { 4.0 / 255.0 } else { 0.0 }
        });
        let zb = block_z(a, b, &biased, &model).unwrap();
        assert!(zb.mean_z2 > z.mean_z2 + 0.6, "{zb:?} against {z:?}");
        // Two levels everywhere are lost in each block's noise but not in the
        // mean of the whole image.
        let dim = image(64, 64, |x, y| reference.pixels[(y * 64 + x) as usize][0] - 2.0 / 255.0);
        let zd = block_z(a, b, &dim, &model).unwrap();
        assert!(zd.luminance_z > 4.0, "{zd:?}");
        assert_eq!(block_z(a, b, &image(8, 8, |_, _| 0.0), &model), None);
    }

    #[test]
    fn noisy_linear_blocks_showing_a_light_are_left_out_and_a_wrong_light_is_not() {
        let v = noisy_images(3);
        // A light of 30× the mean in one 16×16 block. Ours is 1% brighter
        // and its edge column falls differently in each seed (the light's
        // edge, antialiased): no noise excuses the difference, and a
        // sub-pixel shift is no bias, so the block must not count.
        let light = |img: &Rgb32Image, gain: f32, edge: f32| {
            image(64, 64, |x, y| match (x, y) {
                (15, 0..16) => edge,
                (0..16, 0..16) => 15.0 * gain,
                _ => img.pixels[(y * 64 + x) as usize][0],
            })
        };
        let r = light(&v[2], 1.0, 7.0);
        let model = NoiseModel::linear(4, 100, &r);
        assert_eq!(model.block, LINEAR_BLOCK);
        let z = block_z(&light(&v[0], 1.01, 6.0), &light(&v[1], 1.01, 8.0), &r, &model).unwrap();
        assert_eq!((z.left_out, z.count), (1, 15 * 3));
        assert!(z.mean_z2 < 2.0 && z.outliers == 0.0, "{z:?}");
        // A light 10% too bright, the same in both seeds: a bias, judged.
        let z = block_z(&light(&v[0], 1.1, 7.0), &light(&v[1], 1.1, 7.0), &r, &model).unwrap();
        assert_eq!((z.left_out, z.count), (0, 16 * 3));
        assert!(z.outliers > 0.0, "{z:?}");
        assert_eq!(ref_variance_ratio(9, 36), 1.0);
    }
}
