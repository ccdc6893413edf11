//! Which of a dielectric's two rays to trace, and with what weight.
//!
//! The course's Whitted model sends both a reflected ray weighted by the
//! Fresnel reflectance `F` and a refracted one weighted by `1 - F`. Nested
//! glass then branches at every interface: `2^depth` rays per camera ray
//! (hw3 wine_glass, `MaxRecursionDepth` 6 at 900 samples per pixel, took 869 s
//! that way). When the camera takes more than one sample per pixel, the
//! samples average the image anyway, so each sample follows one branch,
//! reflection with probability `F` and refraction with `1 - F`, weighted 1:
//! the expected value is the same `F L_r + (1 - F) L_t` (an unbiased
//! estimator, Russian roulette's choice between two branches), and a sample
//! costs one path instead of a tree. With one sample per pixel the course's
//! images need both rays, so that case keeps the deterministic split. The
//! path tracer's dielectrics choose the same way (a path through glass under
//! Russian roulette was otherwise a tree followed in full).
//!
//! Reads no scene parameters itself: `F` comes from the material's
//! `RefractionIndex`, the sample count from the camera's `NumSamples` (or
//! `--spp`).

use crate::render::sampler::PixelSampler;

/// Weights of the reflected and the refracted ray for a dielectric
/// interface with Fresnel reflectance `f`; a weight of 0 means "do not
/// trace". `refracts` is false under total internal reflection.
#[inline]
pub fn branch_weights(f: f32, refracts: bool, sampler: &mut PixelSampler) -> (f32, f32) {
    if !refracts {
        return (f, 0.0);
    }
    if sampler.count() <= 1 {
        return (f, 1.0 - f);
    }
    if sampler.next_1d() < f {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_traces_both_rays_with_fresnel_weights() {
        let mut s = PixelSampler::new(0, 3, 4, 0, 1);
        assert_eq!(branch_weights(0.25, true, &mut s), (0.25, 0.75));
        assert_eq!(branch_weights(1.0, false, &mut s), (1.0, 0.0));
    }

    #[test]
    fn many_samples_choose_one_ray_with_fresnel_probability() {
        // Over the samples of a pixel the choice is stratified, so the share
        // of reflections matches F to within one sample.
        let n = 256;
        for f in [0.04f32, 0.3, 0.5, 0.9] {
            let mut refl = 0;
            for i in 0..n {
                let mut s = PixelSampler::new(7, 11, 13, i, n);
                match branch_weights(f, true, &mut s) {
                    (1.0, 0.0) => refl += 1,
                    (0.0, 1.0) => {}
                    w => panic!("not a single branch of weight 1: {w:?}"),
                }
            }
            let expect = f * n as f32;
            assert!((refl as f32 - expect).abs() <= 1.5, "F {f}: {refl} reflections of {n}");
        }
        // Total internal reflection always reflects, at full weight.
        let mut s = PixelSampler::new(0, 0, 0, 5, 16);
        assert_eq!(branch_weights(1.0, false, &mut s), (1.0, 0.0));
    }
}
