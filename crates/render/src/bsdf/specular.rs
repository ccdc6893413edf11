//! The perfectly specular lobes: mirror and conductor reflection, and a
//! dielectric's Fresnel-weighted reflection and refraction, each moved by
//! the course's glossy roughness ([`glossy`]).
//!
//! A dielectric in the course's Whitted model sends a reflected ray weighted
//! by the Fresnel reflectance `F` and a refracted one weighted by `1 − F`, so
//! nested glass branches into `2^depth` rays per camera ray. When a camera
//! takes more than one sample per pixel, each sample follows one branch
//! instead, reflection with probability `F` and refraction with `1 − F`,
//! weighted 1 ([`branch_weights`]): the same expected value `F L_r + (1 − F) L_t`
//! (Russian roulette's choice between two branches) for the cost of one path.
//! At one sample per pixel the course's images need both rays, so that case
//! keeps the split. Both integrators choose this way.
//!
//! Scene parameters: the material's `type` (mirror, conductor, dielectric),
//! `RefractionIndex`, `AbsorptionIndex`, `AbsorptionCoefficient`,
//! `MirrorReflectance` and `Roughness`; the sample count from the camera's
//! `NumSamples` (or `--spp`).

use crate::render::sampler::PixelSampler;
use luster_core::math::Vec3;

/// The perfectly specular (delta) part of a material, beside its diffuse
/// and glossy reflection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specular {
    /// None.
    None,
    /// Perfect reflection weighted by the mirror reflectance.
    Mirror,
    /// Fresnel-weighted reflection and refraction, Beer absorption inside.
    Dielectric {
        /// Index of refraction.
        ior: f32,
        /// Absorption per unit distance travelled inside.
        absorption: Vec3,
    },
    /// Reflection weighted by the mirror reflectance and the conductor Fresnel term.
    Conductor {
        /// Real part of the index.
        n: f32,
        /// Imaginary part of the index.
        k: f32,
    },
}

/// Mirror reflection of `d` about the unit normal `n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

/// The direction refracted from `d` through the unit normal `n` facing it,
/// for `eta = n₁/n₂`, `cos_i = −d·n` and the transmitted cosine `cos_t`
/// (from [`fresnel::dielectric`](super::fresnel::dielectric)).
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32, cos_i: f32, cos_t: f32) -> Vec3 {
    (d * eta + n * (eta * cos_i - cos_t)).normalize()
}

/// `dir` moved by the course's glossy model: `dir + r (ξ₁ - ½) u + r (ξ₂ - ½) v`
/// in the frame `(u, v)` of [`glossy_frame`], renormalized; `dir` itself when `r` is 0.
#[inline]
pub fn glossy(dir: Vec3, roughness: f32, sampler: &mut PixelSampler) -> Vec3 {
    if roughness <= 0.0 {
        return dir;
    }
    let (u, v) = glossy_frame(dir);
    let (a, b) = sampler.next_2d();
    (dir + (u * (a - 0.5) + v * (b - 0.5)) * roughness).normalize()
}

/// The course's frame around a unit direction `r`: `r'` is `r` with its
/// component of smallest magnitude set to 1 (the first such when two tie),
/// `u = normalize(r × r')` and `v = r × u`. Only the frame's turn about `r`
/// matters (the offsets are symmetric), and this rule fixes it: another
/// orthonormal pair (Duff et al.'s, say) turns the square of offsets, and
/// hw3 `cornellbox_brushed_metal`'s copper sphere then no longer matches the
/// course's image.
#[inline]
pub fn glossy_frame(r: Vec3) -> (Vec3, Vec3) {
    let a = r.abs();
    let mut rp = r;
    if a.x <= a.y && a.x <= a.z {
        rp.x = 1.0;
    } else if a.y <= a.z {
        rp.y = 1.0;
    } else {
        rp.z = 1.0;
    }
    let u = r.cross(rp).normalize();
    (u, r.cross(u))
}

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

    #[test]
    fn the_glossy_frame_is_orthonormal_and_turned_as_the_courses() {
        for r in [
            Vec3::X,
            -Vec3::Y,
            Vec3::Z,
            Vec3::new(0.81, 0.46, -0.34).normalize(),
            Vec3::new(-0.2, 0.9, 0.1).normalize(),
            Vec3::new(1e-4, -1.0, 1e-4).normalize(),
        ] {
            let (u, v) = glossy_frame(r);
            assert!((u.length() - 1.0).abs() < 1e-5 && (v.length() - 1.0).abs() < 1e-5, "{r}");
            assert!(u.dot(r).abs() < 1e-5 && v.dot(r).abs() < 1e-5 && u.dot(v).abs() < 1e-5, "{r}");
        }
        // Along z the course's square is axis-aligned; off the axes its
        // `u` lies in the plane of `r` and the axis of `r`'s smallest
        // component (here z), unlike Duff et al.'s frame.
        let (u, _) = glossy_frame(Vec3::Z);
        assert!(u.x.abs() < 1e-6 && u.z.abs() < 1e-6, "{u}");
        let r = Vec3::new(0.81, 0.46, -0.34).normalize();
        let (u, _) = glossy_frame(r);
        let (d, _) = luster_core::math::orthonormal_basis(r);
        let rp = Vec3::new(r.x, r.y, 1.0);
        assert!(u.dot(rp).abs() < 1e-5, "u {u} not perpendicular to r' {rp}");
        assert!(d.dot(u).abs() < 0.99, "this test cannot tell the two frames apart");
    }
}
