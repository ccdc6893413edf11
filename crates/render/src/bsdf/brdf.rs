//! BRDFs: the reflection models a material can name with `BRDF="id"` (hw6
//! `<BRDFs>`), each able to evaluate `f(wi, wo)`, importance-sample an
//! incoming direction and give that sample's density, in the local shading
//! frame (`+z` the normal; `wi` towards the light, `wo` towards the viewer).
//! The diffuse and specular colours come in per call, so textures and
//! shaders that change a material's `kd`/`ks` at a point keep working.
//!
//! Sampling picks the diffuse part (cosine-weighted) or the specular lobe with
//! probabilities proportional to the luminance of `kd` and `ks`, and
//! [`Brdf::pdf`] is the matching mixture density.

use super::phong::{Lobe, PhongFamily, Variant};
use super::sampling::{cosine_weighted, power_cosine_pdf};
use super::torrance_sparrow::TorranceSparrow;
use luster_core::math::Vec3;
use luster_scene::description::{BrdfDesc, BrdfKind};

/// A reflection model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Brdf {
    /// Phong or Blinn-Phong, original, modified or normalized.
    Phong(PhongFamily),
    /// Torrance-Sparrow microfacets.
    TorranceSparrow(TorranceSparrow),
}

/// A direction drawn by [`Brdf::sample`].
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// The incoming direction, local frame.
    pub wi: Vec3,
    /// `f(wi, wo)`.
    pub f: Vec3,
    /// Density of `wi` per unit solid angle (the full mixture's).
    pub pdf: f32,
}

impl Brdf {
    /// The BRDF a description names, on a material whose Blinn-Phong exponent
    /// (used when the BRDF gives none) and complex index of refraction are given.
    pub fn from_desc(d: &BrdfDesc, phong_exponent: f32, eta: f32, k: f32) -> Brdf {
        let exponent = d.exponent.unwrap_or(phong_exponent);
        let variant = if d.normalized { Variant::Normalized } else { Variant::Modified };
        match d.kind {
            BrdfKind::OriginalPhong => {
                Brdf::Phong(PhongFamily { lobe: Lobe::Phong, variant: Variant::Original, exponent })
            }
            BrdfKind::ModifiedPhong => Brdf::Phong(PhongFamily { lobe: Lobe::Phong, variant, exponent }),
            BrdfKind::OriginalBlinnPhong => {
                Brdf::Phong(PhongFamily { lobe: Lobe::BlinnPhong, variant: Variant::Original, exponent })
            }
            BrdfKind::ModifiedBlinnPhong => {
                Brdf::Phong(PhongFamily { lobe: Lobe::BlinnPhong, variant, exponent })
            }
            BrdfKind::TorranceSparrow => {
                Brdf::TorranceSparrow(TorranceSparrow { exponent, kd_fresnel: d.kd_fresnel, eta, k })
            }
        }
    }

    /// `f(wi, wo)`, local frame.
    #[inline]
    pub fn eval(&self, kd: Vec3, ks: Vec3, wi: Vec3, wo: Vec3) -> Vec3 {
        match self {
            Brdf::Phong(b) => b.eval(kd, ks, wi, wo),
            Brdf::TorranceSparrow(b) => b.eval(kd, ks, wi, wo),
        }
    }

    /// Draws `wi` for a viewer at `wo` from `choice` (picks the part) and `u`.
    /// `None` when the drawn direction falls below the surface.
    #[inline]
    pub fn sample(&self, kd: Vec3, ks: Vec3, wo: Vec3, choice: f32, u: (f32, f32)) -> Option<Sample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if choice < diffuse_probability(kd, ks) {
            cosine_weighted(u)
        } else {
            match self {
                Brdf::Phong(b) => b.sample_lobe(wo, u),
                Brdf::TorranceSparrow(b) => b.sample_lobe(wo, u),
            }
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(kd, ks, wo, wi);
        (pdf > 0.0).then(|| Sample { wi, f: self.eval(kd, ks, wi, wo), pdf })
    }

    /// Density of [`sample`](Self::sample) at `wi`.
    #[inline]
    pub fn pdf(&self, kd: Vec3, ks: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let pd = diffuse_probability(kd, ks);
        // Without a specular part the lobe has weight zero: skip its `powf`.
        let lobe = match self {
            _ if pd >= 1.0 => 0.0,
            Brdf::Phong(b) => b.lobe_pdf(wo, wi),
            Brdf::TorranceSparrow(b) => b.lobe_pdf(wo, wi),
        };
        pd * power_cosine_pdf(1.0, wi.z) + (1.0 - pd) * lobe
    }
}

impl Brdf {
    /// This BRDF as [`DiffuseOnly`] on a material of colours `kd` and `ks`,
    /// where it is one.
    #[inline(always)]
    pub fn diffuse_only(&self, kd: Vec3, ks: Vec3) -> Option<DiffuseOnly<'_>> {
        match self {
            // `d / (d + 0)` is exactly 1 for a finite `d > 0`, so the mixture
            // always takes the diffuse part and its lobe weighs nothing.
            Brdf::Phong(phong) if ks == Vec3::ZERO && diffuse_probability(kd, ks) == 1.0 => {
                Some(DiffuseOnly { brdf: self, phong })
            }
            _ => None,
        }
    }

    /// [`diffuse_only`](Self::diffuse_only) for a material whose
    /// [`Traits::diffuse_only`](crate::material::Traits::diffuse_only) says
    /// it is one: the colour tests were made once, when the traits were.
    #[inline(always)]
    pub fn assume_diffuse_only(&self) -> Option<DiffuseOnly<'_>> {
        match self {
            Brdf::Phong(phong) => Some(DiffuseOnly { brdf: self, phong }),
            _ => None,
        }
    }
}

/// A Phong-family BRDF on a material without specular colour and with some
/// diffuse colour (every wall of the course's Cornell boxes): its value and
/// density need only the cosines of the two directions, and its sample is
/// the cosine-weighted one. The same operations as [`Brdf::eval`],
/// [`Brdf::pdf`] and [`Brdf::sample`], inlined, so the same bits.
#[derive(Clone, Copy, Debug)]
pub struct DiffuseOnly<'a> {
    brdf: &'a Brdf,
    phong: &'a PhongFamily,
}

impl DiffuseOnly<'_> {
    /// `f` for directions at cosines `cos_i` (light) and `cos_o` (viewer).
    #[inline(always)]
    pub fn eval(&self, kd: Vec3, ks: Vec3, cos_i: f32, cos_o: f32) -> Vec3 {
        self.phong.eval_diffuse(kd, ks, cos_i, cos_o)
    }

    /// The density [`Brdf::sample`] draws a light direction at cosine
    /// `cos_i` with (`1 · p_cos + 0 · p_lobe`, the same bits as `p_cos`).
    #[inline(always)]
    pub fn pdf(&self, cos_o: f32, cos_i: f32) -> f32 {
        diffuse_pdf(cos_o, cos_i)
    }

    /// [`Brdf::sample`]: the mixture's choice always falls on the diffuse
    /// part (the chance is 1) unless `choice` is not below 1.
    #[inline(always)]
    pub fn sample(&self, kd: Vec3, ks: Vec3, wo: Vec3, choice: f32, u: (f32, f32)) -> Option<Sample> {
        if choice.partial_cmp(&1.0) != Some(std::cmp::Ordering::Less) {
            return self.brdf.sample(kd, ks, wo, choice, u);
        }
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_weighted(u);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo.z, wi.z);
        (pdf > 0.0).then(|| Sample { wi, f: self.eval(kd, ks, wi.z, wo.z), pdf })
    }
}

/// [`DiffuseOnly::pdf`], for a caller that knows the material is one.
#[inline(always)]
pub fn diffuse_pdf(cos_o: f32, cos_i: f32) -> f32 {
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return 0.0;
    }
    power_cosine_pdf(1.0, cos_i)
}

/// Chance of sampling the diffuse part: its share of `kd + ks` by luminance.
#[inline]
fn diffuse_probability(kd: Vec3, ks: Vec3) -> f32 {
    let w = Vec3::new(0.2126, 0.7152, 0.0722);
    let (d, s) = (kd.max(Vec3::ZERO).dot(w), ks.max(Vec3::ZERO).dot(w));
    if d + s <= 0.0 {
        0.5
    } else {
        d / (d + s)
    }
}
